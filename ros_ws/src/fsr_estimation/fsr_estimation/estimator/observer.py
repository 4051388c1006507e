"""Momentum-based external wrench observer (docs/model.md §3.8, report exercise 3).

Discrete recursion (all states zero at k = 0), with ``K_1 .. K_r`` from
:func:`fsr_estimation.estimator.filter_design.gain_chain` and ``q``, ``b`` from
:mod:`fsr_estimation.estimator.momentum`:

    gamma_1[k+1] = gamma_1[k] + K_1 ((q[k+1] - q[k]) - T_s (w_hat[k] + b_k))
    gamma_j[k+1] = gamma_j[k] + K_j T_s (gamma_{j-1}[k] - w_hat[k]),   j = 2..r
    w_hat[k+1]   = gamma_r[k+1]

``w_hat = [f_e; tau_e]``: force [N] in world NED, torque [N m] in Euler-angle (eta) coordinates. In the body
frame (comparable with ``wrench_truth``): force ``R_b^T f_e``, torque ``Q(eta)^-T tau_e``.
Mass estimate: ``m_model + f_e,z / g`` (NED: a lighter vehicle than the model needs less thrust, the
residual force points up, ``f_e,z < 0``, so ``dm < 0``).

Two paths give the same numbers: :class:`MomentumObserver` (sample by sample: the Python shell of the compiled
core, :mod:`fsr_estimation.core.observer_step`, which the nodes and the in-process loop run) and
:func:`estimate_log` (a whole log at C speed with ``scipy.signal.sosfilt``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from fsr_estimation.core import observer_step as core
from fsr_estimation.estimator.filter_design import cascade_sections, check_filter_parameters, gain_chain
from fsr_estimation.estimator.momentum import observer_input
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.checks import symmetric_positive_definite
from fsr_sim.model.so3 import euler_rate_matrix, rotation_from_euler_zyx


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
    """Sample-by-sample momentum observer; :meth:`update` once per control period (the compiled core's
    :func:`~fsr_estimation.core.observer_step.observer_update`).

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
        self.params = core.ObserverParams(self.mass, np.ascontiguousarray(self.inertia),
                                          np.array(self.gains, dtype=float), self.sample_time, self.gravity)
        self.state = core.new_observer_state(self.r)

    @property
    def samples(self) -> int:
        """Samples taken since the start or the last :meth:`reset`."""
        return int(self.state.samples[0])

    def reset(self) -> None:
        """Forget all history: the next :meth:`update` is sample k = 0 again (estimate zero)."""
        core.reset_observer(self.state)

    def update(self, velocity_world: ArrayLike, euler_zyx: ArrayLike, euler_rates: ArrayLike,
               force_body: ArrayLike, torque_body: ArrayLike) -> np.ndarray:
        """Take sample k and return ``w_hat[k] = [f_e (world NED) [N]; tau_e (eta coords) [N m]]``, shape (6,).

        velocity_world (3,) [m/s] NED; euler_zyx (3,) [rad]; euler_rates (3,) [rad/s]; force_body,
        torque_body (3,) [N, N m] body FRD: the actuator wrench at sample k (used from the next sample on).
        """
        core.observer_update(self.params, self.state, _vector(velocity_world), _vector(euler_zyx),
                             _vector(euler_rates), _vector(force_body), _vector(torque_body))
        return self.state.estimate.copy()

    @property
    def estimate(self) -> np.ndarray:
        """The latest ``w_hat`` (a new array), shape (6,)."""
        return self.state.estimate.copy()

    def wrench_body(self) -> tuple[np.ndarray, np.ndarray]:
        """Latest estimate in body FRD: (force ``R_b^T f_e`` [N], torque ``Q^-T tau_e`` [N m]), as ``wrench_truth``."""
        force, torque = core.wrench_body(self.params, self.state)
        return np.array(force), np.array(torque)

    @property
    def mass_estimate(self) -> float:
        """``m_model + f_e,z / g`` [kg]."""
        return float(core.mass_estimate(self.params, self.state))


def _vector(values: ArrayLike) -> tuple[float, float, float]:
    """A 3-vector (array, list or tuple) as a tuple of Python floats (the core's argument type)."""
    x, y, z = values.tolist() if isinstance(values, np.ndarray) else values
    return float(x), float(y), float(z)


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
