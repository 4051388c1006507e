"""Filter design of the momentum observer (docs/model.md §3.8): ``G(s) = c0^r / (s + c0)^r`` on each channel.

The denominator ``(s + c0)^r = s^r + d_{r-1} s^{r-1} + ... + d_0`` has ``d_j = binom(r, j) c0^(r-j)``.
The observer realises it as a chain of ``r`` integrators with gains ``K_1 .. K_r`` defined backwards:
``K_r = d_{r-1}``, ``K_{r-1} = d_{r-2} / K_r``, ..., ``K_1 = d_0 / (K_r ... K_2)``, so that
``K_j K_{j+1} ... K_r = d_{j-1}`` and the whole chain multiplies to ``d_0 = c0^r``.

The discrete recursion (forward Euler with sample time ``T_s``) is exactly ``G((z - 1) / T_s)``:
``r`` repeated poles at ``z = 1 - c0 T_s``. It is stable only for ``0 < c0 T_s < 2``.
"""

from __future__ import annotations

from math import comb

import numpy as np


def check_filter_parameters(c0: float, r: int, sample_time: float | None = None) -> None:
    """Raise ``ValueError`` naming the parameter unless ``c0 > 0``, integer ``r >= 1`` and, if a sample
    time [s] is given, ``T_s > 0`` and ``c0 T_s < 2`` (the discrete poles ``1 - c0 T_s`` inside the unit circle).
    """
    if isinstance(c0, bool) or not np.isfinite(c0) or c0 <= 0.0:
        raise ValueError(f"c0: must be a finite number > 0 [rad/s], got {c0!r}")
    if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r < 1:
        raise ValueError(f"r: must be an integer >= 1, got {r!r}")
    if sample_time is not None:
        if not np.isfinite(sample_time) or sample_time <= 0.0:
            raise ValueError(f"sample_time: must be a finite number > 0 [s], got {sample_time!r}")
        if c0 * sample_time >= 2.0:
            raise ValueError(
                f"c0: c0 * sample_time = {c0 * sample_time:g} >= 2 makes the discrete observer unstable "
                f"(c0 = {c0}, sample_time = {sample_time}); use c0 < {2.0 / sample_time:g}"
            )


def denominator_coefficients(c0: float, r: int) -> np.ndarray:
    """Coefficients ``[d_0, d_1, ..., d_{r-1}, 1]`` of ``(s + c0)^r`` (index j multiplies ``s^j``).

    c0: filter bandwidth [rad/s] > 0; r: filter order >= 1. Returns shape (r + 1,).
    """
    check_filter_parameters(c0, r)
    return np.array([comb(r, j) * float(c0) ** (r - j) for j in range(r + 1)])


def gain_chain(c0: float, r: int) -> np.ndarray:
    """Gains ``[K_1, ..., K_r]`` of the observer's integrator chain (docs/model.md §3.8), shape (r,).

    ``K_r = d_{r-1}`` and ``K_j = d_{j-1} / (K_{j+1} ... K_r)``; ``prod(K) = c0^r``; ``r = 1`` gives ``K_1 = c0``.
    """
    d = denominator_coefficients(c0, r)
    gains = np.empty(r)
    tail = 1.0  # K_{j+1} ... K_r
    for j in range(r, 0, -1):
        gains[j - 1] = d[j - 1] / tail
        tail *= gains[j - 1]
    return gains


def cascade_sections(c0: float, r: int, sample_time: float) -> np.ndarray:
    """The discrete observer as ``r`` first-order sections for ``scipy.signal.sosfilt``, shape (r, 6).

    From the input ``u[k] = (q[k+1] - q[k]) - T_s b_k`` to the estimate ``w_hat[k]`` the recursion is
    ``H(z) = (1 / T_s) * (a z^-1 / (1 - p z^-1))^r`` with ``a = c0 T_s`` and ``p = 1 - a``; the ``1 / T_s``
    is folded into the first section. Each section is well conditioned (unlike the expanded polynomial
    ``(1 - p z^-1)^r``, whose direct-form realisation amplifies rounding for repeated poles near 1).
    """
    check_filter_parameters(c0, r, sample_time)
    a = c0 * sample_time
    sections = np.zeros((r, 6))
    sections[:, 1] = a  # b1: one sample delay per section
    sections[:, 3] = 1.0
    sections[:, 4] = -(1.0 - a)
    sections[0, 1] = a / sample_time
    return sections
