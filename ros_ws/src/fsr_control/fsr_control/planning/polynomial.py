"""7th-order (septic) polynomials in normalised time: rest-to-rest motion, or given (docs/model.md §3.5).

A channel ``x(t)`` over ``t in [t0, t0 + T]`` is written in ``tau = (t - t0) / T``:

    x(tau) = sum_{k=0}^{7} c_k tau^k,      d^n x / dt^n = x^(n)(tau) / T^n.

Rest-to-rest (position, velocity, acceleration and jerk zero at both ends) from ``x0`` to ``xf`` is
``x = x0 + (xf - x0) s(tau)`` with ``s = 35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7``. A plan that starts
while moving (a goal received mid-flight) keeps the start's velocity ``v0``, acceleration ``a0`` and
jerk ``j0``: ``c_0..c_3 = x0, v0 T, a0 T^2 / 2, j0 T^3 / 6`` and ``c_4..c_7`` bring ``x`` to rest at ``xf``.
After the end the channel holds ``xf`` with every derivative exactly zero.
"""

from __future__ import annotations

import numpy as np

from fsr_control.core.reference import DEGREE, DERIVATIVES, polynomial_derivatives

REST_TO_REST = np.array((0.0, 0.0, 0.0, 0.0, 35.0, -84.0, 70.0, -20.0))

# d^n/dtau^n of tau^k is falling(k, n) tau^(k-n): row n holds falling(k, n) for k = 0..7.
_FALLING = np.array([[float(np.prod(np.arange(k - n + 1, k + 1))) if k >= n else 0.0 for k in range(8)]
                     for n in range(DERIVATIVES)])
# End conditions at tau = 1 on c_4..c_7 (value and derivatives 1..3).
_END_INVERSE = np.linalg.inv(_FALLING[:4, 4:])


def _derivative_coefficients(coefficients: np.ndarray, durations: np.ndarray) -> np.ndarray:
    """(DERIVATIVES, channels, 8): row n holds the coefficients of ``d^n x / dt^n`` in powers of each channel's
    tau (``durations`` (channels,) [s])."""
    out = np.zeros((DERIVATIVES, coefficients.shape[0], DEGREE + 1))
    for n in range(DERIVATIVES):
        scaled = coefficients[:, n:] * _FALLING[n, n:] / durations[:, None]**n
        out[n, :, : DEGREE + 1 - n] = scaled
    return out


class SepticSegment:
    """Several channels of one 7th-order segment, evaluated together.

    duration: [s], one for every channel or shape (c,), one per channel (each channel has its own ``tau``
    and arrives at its own end); start: array-like, shape (c,), the values at ``t0``; goal: shape (c,), the
    values at rest at the end; start_rates: optional shape (3, c), the start's 1st..3rd time derivatives
    (default: at rest). ``duration`` / ``end_time`` are the longest channel's.
    """

    def __init__(
        self,
        start_time: float,
        duration: float | np.ndarray,
        start: np.ndarray,
        goal: np.ndarray,
        start_rates: np.ndarray | None = None,
    ) -> None:
        start = np.asarray(start, dtype=float)
        goal = np.asarray(goal, dtype=float)
        durations = np.broadcast_to(np.asarray(duration, dtype=float), start.shape).copy()
        if not np.all(durations > 0.0):
            raise ValueError(f"segment duration must be > 0 s, got {duration}")
        self.start_time = float(start_time)
        self.durations = durations
        self.duration = float(durations.max())
        self.end_time = self.start_time + self.duration
        self.goal = goal.copy()
        coefficients = np.zeros((start.size, DEGREE + 1))
        coefficients[:, 0] = start
        if start_rates is None:
            coefficients += np.outer(goal - start, REST_TO_REST)
        else:
            rates = np.asarray(start_rates, dtype=float).reshape(3, start.size)
            for n in range(1, 4):
                coefficients[:, n] = rates[n - 1] * durations**n / _FALLING[n, n]
            # Remaining end conditions: x(1) = goal, x'(1) = x''(1) = x'''(1) = 0.
            residual = -coefficients[:, :4] @ _FALLING[:4, :4].T
            residual[:, 0] += goal
            coefficients[:, 4:] = residual @ _END_INVERSE.T
        self._set(coefficients)

    @classmethod
    def from_coefficients(cls, start_time: float, duration: float, coefficients: np.ndarray,
                          goal: np.ndarray) -> SepticSegment:
        """A segment of given ``coefficients`` (c, 8) in ``tau`` over ``duration`` [s] (a minimum-snap segment,
        not at rest at its end), holding ``goal`` (c,) after its end."""
        segment = cls.__new__(cls)
        segment.start_time = float(start_time)
        segment.durations = np.full(len(goal), float(duration))
        segment.duration = float(duration)
        segment.end_time = segment.start_time + segment.duration
        segment.goal = np.array(goal, dtype=float)
        segment._set(np.array(coefficients, dtype=float))
        return segment

    def _set(self, coefficients: np.ndarray) -> None:
        self.coefficients = coefficients
        self.table = np.ascontiguousarray(_derivative_coefficients(coefficients, self.durations))

    def evaluate(self, t: float) -> np.ndarray:
        """Shape (5, c): value and time derivatives 1..4 at ``t`` [s] (clamped to the segment's start), by the
        compiled core (:func:`fsr_control.core.reference.polynomial_derivatives`)."""
        out = np.empty((DERIVATIVES, len(self.goal)))
        polynomial_derivatives(self.table, self.goal, self.start_time, self.durations, float(t), out)
        return out
