"""Momentum-based external wrench observer (SPEC §3.8, report exercise 3).

Discrete recursion (all states zero at k = 0), with ``K_1 .. K_r`` from
:func:`fsr_estimation.core.filter_design.gain_chain` and ``q``, ``b`` from :mod:`fsr_estimation.core.momentum`:

    gamma_1[k+1] = gamma_1[k] + K_1 ((q[k+1] - q[k]) - T_s (w_hat[k] + b_k))
    gamma_j[k+1] = gamma_j[k] + K_j T_s (gamma_{j-1}[k] - w_hat[k]),   j = 2..r
    w_hat[k+1]   = gamma_r[k+1]

``w_hat = [f_e; tau_e]``: force [N] in world NED, torque [N m] in Euler-angle (eta) coordinates. In the body
frame (comparable with ``wrench_truth``): force ``R_b^T f_e``, torque ``Q(eta)^-T tau_e``.
Mass estimate: ``m_model + f_e,z / g`` (NED: a lighter vehicle than the model needs less thrust, the
residual force points up, ``f_e,z < 0``, so ``dm < 0``).

Two paths give the same numbers: :class:`MomentumObserver` (sample by sample, for the node) and
:func:`estimate_log` (a whole log at C speed with ``scipy.signal.sosfilt``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from fsr_estimation.core.filter_design import cascade_sections, check_filter_parameters, gain_chain
from fsr_estimation.core.momentum import GRAVITY, observer_input
from fsr_sim.model.checks import symmetric_positive_definite
from fsr_sim.model.so3 import (
    euler_rate_derivative_rows,
    euler_rate_matrix,
    euler_rate_rows,
    euler_rate_transpose_solve3,
    mat_t_mat3,
    mat_t_vec3,
    mat_vec3,
    rotation_from_euler_zyx,
    rotation_rows_from_euler_zyx,
)


def checked_model(mass: float, inertia: ArrayLike) -> tuple[float, np.ndarray]:
    """(mass [kg] > 0, inertia 3x3 [kg m^2] symmetric positive definite); a 3-vector is the diagonal."""
    if isinstance(mass, bool) or not np.isfinite(mass) or mass <= 0.0:
        raise ValueError(f"mass: must be a finite number > 0 [kg], got {mass!r}")
    return float(mass), symmetric_positive_definite(inertia, "inertia")


@dataclass(frozen=True)
class ObserverModel:
    """The nominal model the observer uses: mass [kg] and body inertia (3, 3) [kg m^2]."""

    mass: float
    inertia: np.ndarray
    gravity: float = GRAVITY

    def __post_init__(self) -> None:
        mass, inertia = checked_model(self.mass, self.inertia)
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "inertia", inertia)


class MomentumObserver:
    """Sample-by-sample momentum observer; :meth:`update` once per control period.

    mass [kg], inertia (3,) diagonal or (3, 3) [kg m^2], c0 [rad/s] > 0, r >= 1, sample_time [s]
    (``c0 * sample_time < 2``). All working arrays are allocated here; :meth:`update` reuses them.
    """

    def __init__(self, mass: float, inertia: ArrayLike, c0: float, r: int, sample_time: float,
                 gravity: float = GRAVITY) -> None:
        check_filter_parameters(c0, r, sample_time)
        self.mass, self.inertia = checked_model(mass, inertia)
        self.c0 = float(c0)
        self.r = int(r)
        self.sample_time = float(sample_time)
        self.gravity = float(gravity)
        self.gains = gain_chain(c0, r)
        self._gains = [float(gain) for gain in self.gains]
        self._weight = self.mass * self.gravity  # the z entry of m g e_3 (NED)
        self._inertia_rows = self.inertia.tolist()  # symmetric: I^T = I
        # Plain float lists, not small arrays: one update per 1 kHz step, where numpy's per-call cost dominates.
        self._gamma = [[0.0] * 6 for _ in range(self.r)]
        self._estimate = [0.0] * 6
        self._previous_momentum = [0.0] * 6
        self._previous_rate = [0.0] * 6  # b_{k-1}
        identity = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
        self._mass_rows = ((0.0,) * 3,) * 3  # M(eta[k-1]), rows
        self._rotation_rows = identity  # R_b of the latest sample, rows
        self._rate_rows = identity  # Q(eta) of the latest sample, rows
        self._eta = (0.0, 0.0)  # roll, pitch of the latest sample [rad]
        self.samples = 0

    def reset(self) -> None:
        """Forget all history: the next :meth:`update` is sample k = 0 again (estimate zero)."""
        self._gamma = [[0.0] * 6 for _ in range(self.r)]
        self._estimate = [0.0] * 6
        self.samples = 0

    def update(self, velocity_world: ArrayLike, euler_zyx: ArrayLike, euler_rates: ArrayLike,
               force_body: ArrayLike, torque_body: ArrayLike) -> np.ndarray:
        """Take sample k and return ``w_hat[k] = [f_e (world NED) [N]; tau_e (eta coords) [N m]]``, shape (6,).

        velocity_world (3,) [m/s] NED; euler_zyx (3,) [rad]; euler_rates (3,) [rad/s]; force_body,
        torque_body (3,) [N, N m] body FRD: the actuator wrench at sample k (used from the next sample on).
        """
        eta = _floats(euler_zyx)
        eta_dot = _floats(euler_rates)
        mass = self.mass
        vx, vy, vz = _floats(velocity_world)
        linear = [mass * vx, mass * vy, mass * vz]
        if self.samples == 0:
            self._store_sample_terms(eta, eta_dot, force_body, torque_body)  # q[0] uses M(eta[0])
            momentum = linear + list(mat_vec3(self._mass_rows, eta_dot))
        else:
            momentum = linear + list(mat_vec3(self._mass_rows, eta_dot))  # M(eta[k-1]) eta_dot[k]
            self._step(momentum)
            self._store_sample_terms(eta, eta_dot, force_body, torque_body)
        self._previous_momentum = momentum
        self.samples += 1
        return np.array(self._estimate)

    def _step(self, momentum: list[float]) -> None:
        """One step of the gamma chain from w_hat[k-1] to w_hat[k] (states updated last to first so
        that each uses its predecessor's previous value)."""
        ts, gains, gamma, previous = self.sample_time, self._gains, self._gamma, self._estimate
        residual = [(q - q_old) - ts * (w + b) for q, q_old, w, b in
                    zip(momentum, self._previous_momentum, previous, self._previous_rate, strict=True)]
        for j in range(self.r - 1, 0, -1):
            gain = gains[j] * ts
            gamma[j] = [g + gain * (g_before - w) for g, g_before, w in zip(gamma[j], gamma[j - 1], previous,
                                                                             strict=True)]
        gain = gains[0]
        gamma[0] = [g + gain * u for g, u in zip(gamma[0], residual, strict=True)]
        self._estimate = list(gamma[self.r - 1])

    def _store_sample_terms(self, eta: list[float], eta_dot: list[float], force_body: ArrayLike,
                            torque_body: ArrayLike) -> None:
        """b_k, M(eta[k]), R_b,k and Q_k for the next step and for :meth:`wrench_body`.

        Lean form of the same quantities as :mod:`fsr_estimation.core.momentum` (on Python floats with the
        single-sample functions of :mod:`fsr_sim.model.so3`): ``M = Q^T I_b Q`` and
        ``C^T eta_dot = Q_dot^T I_b omega``, because the other term of ``C^T eta_dot``,
        ``(Q^T S(omega) I_b Q)^T eta_dot = -Q^T I_b (omega x omega)``, is zero.
        """
        phi, theta, psi = eta
        rotation = rotation_rows_from_euler_zyx(phi, theta, psi)
        rate = euler_rate_rows(phi, theta)
        rate_dot = euler_rate_derivative_rows(phi, theta, eta_dot[0], eta_dot[1])
        inertia = self._inertia_rows
        inertia_omega = mat_vec3(inertia, mat_vec3(rate, eta_dot))  # I_b omega
        fx, fy, fz = mat_vec3(rotation, _floats(force_body))
        cx, cy, cz = mat_t_vec3(rate_dot, inertia_omega)  # C^T eta_dot
        tx, ty, tz = mat_t_vec3(rate, _floats(torque_body))  # Q^T tau_b
        self._previous_rate = [fx, fy, fz + self._weight, cx + tx, cy + ty, cz + tz]
        self._mass_rows = mat_t_mat3(rate, mat_t_mat3(inertia, rate))  # Q^T (I_b Q), I_b symmetric
        self._rotation_rows, self._rate_rows, self._eta = rotation, rate, (phi, theta)

    @property
    def estimate(self) -> np.ndarray:
        """The latest ``w_hat`` (a new array), shape (6,)."""
        return np.array(self._estimate)

    @property
    def estimate_values(self) -> tuple[float, ...]:
        """The latest ``w_hat`` as six floats (no array: for per-step callers)."""
        return tuple(self._estimate)

    def wrench_body(self) -> tuple[np.ndarray, np.ndarray]:
        """Latest estimate in body FRD: (force ``R_b^T f_e`` [N], torque ``Q^-T tau_e`` [N m]), as ``wrench_truth``."""
        estimate = self._estimate
        force = np.array(mat_t_vec3(self._rotation_rows, estimate[:3]))
        torque = np.array(euler_rate_transpose_solve3(*self._eta[:2], estimate[3:]))
        return force, torque

    @property
    def mass_estimate(self) -> float:
        """``m_model + f_e,z / g`` [kg]."""
        return self.mass + self._estimate[2] / self.gravity


def _floats(values: ArrayLike) -> list[float]:
    """A 3-vector (array, list or tuple) as a list of Python floats."""
    return values.tolist() if isinstance(values, np.ndarray) else [float(v) for v in values]


def filter_observer_input(u: ArrayLike, c0: float, r: int, sample_time: float) -> np.ndarray:
    """Whole-log observer output from ``u[k] = (q[k+1] - q[k]) - T_s b_k`` (N, 6): ``w_hat`` (N, 6).

    ``w_hat[0] = 0``; equal to the recursion of :class:`MomentumObserver` up to rounding.
    """
    from scipy.signal import sosfilt  # here, not at the top: importing scipy.signal costs every node ~1 s

    return sosfilt(cascade_sections(c0, r, sample_time), np.asarray(u, dtype=float), axis=0)


def estimate_log(velocity_world: ArrayLike, eta: ArrayLike, eta_dot: ArrayLike, force_body: ArrayLike,
                 torque_body: ArrayLike, *, model: ObserverModel, c0: float, r: int,
                 sample_time: float) -> np.ndarray:
    """Observer estimate ``w_hat`` (N, 6) over a whole log (arrays (N, 3) as in :meth:`MomentumObserver.update`)."""
    check_filter_parameters(c0, r, sample_time)
    u = observer_input(model.mass, model.inertia, velocity_world, eta, eta_dot, force_body, torque_body,
                       sample_time, model.gravity)
    return filter_observer_input(u, c0, r, sample_time)


def body_frame_wrench(estimate: ArrayLike, eta: ArrayLike) -> np.ndarray:
    """Whole-log ``w_hat`` (N, 6) in body FRD: ``[R_b^T f_e ; Q^-T tau_e]`` (N, 6), as ``wrench_truth``."""
    w = np.asarray(estimate, dtype=float)
    eta = np.asarray(eta, dtype=float)
    out = np.empty_like(w)
    out[:, :3] = np.einsum("kji,kj->ki", rotation_from_euler_zyx(eta), w[:, :3])
    rate_t = np.swapaxes(euler_rate_matrix(eta), -1, -2)
    out[:, 3:] = np.linalg.solve(rate_t, w[:, 3:, None])[..., 0]
    return out
