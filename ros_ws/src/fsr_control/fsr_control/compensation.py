"""Disturbance rejection: the controller cancels the external wrench its own momentum observer estimates.

``controller.compensation: estimate`` (default ``none``) gives the flight controller a
:class:`WrenchCompensator`. It runs a :class:`fsr_estimation.core.observer.MomentumObserver` *inside the
controller*, on the controller's nominal model (mass ``m_c``, inertia ``I_c``: the scenario's vehicle), fed
with the controller's own input (``odom``) and its own output (the body wrench commanded after allocation,
what ``wrench_cmd`` carries), with the scenario's ``estimator.c0`` and ``estimator.r``.

**Timing.** At ``t_k`` the law uses the estimate stamped ``t_(k-1)``: ``w_hat[k-1]``, computed at the end of
step ``k-1`` from the state and the command of ``t_(k-1)`` (the estimator node's pairing). The observer lives
in the controller's process, so the estimate is always there when it is needed: deterministic by
construction, the node graph and the in-process loop compute the same numbers, and no estimate can be late
(``late_estimates`` is 0). A stamp step that is not one control period (a gap) resets the observer.

**One model.** The observer estimates relative to the model it is given. With the plant
``m a = m g e3 + R f_a + f_ext`` (world NED, ``e3`` down) and the observer on ``m_c``, the estimate converges to

    f_hat = f_ext + (R f_a - R f_c) + (m_c - m)(a - g e3)                                      [N, world]

and the geometric law with ``F = -K_p e_p - K_v e_v - m_c g e3 + m_c p_ddot_d - f_hat`` gives, with
``R f_a = F``, ``m_c (a - p_ddot_d) = -K_p e_p - K_v e_v``: the nominal closed loop of the controller's own
model, whatever the plant's mass and the external force (zero steady-state error). An observer on another
mass ``m_e`` (the scenario's ``estimator.mass``) would leave ``e_p,z = (m_e - m_c) g / k_p,z`` (ex3: 29 mm),
which is why the compensating observer takes the controller's model and not the ``estimator`` section's
(the estimator node, ``wrench_estimate``, keeps that one). The torque is the same argument with ``I_c``:
``tau_hat -> tau_ext + (I_c - I) w_dot + w x (I_c - I) w`` (body, ``Q^-T tau_e``), zero attitude error at rest.

**Contact.** On a surface the observer sees the reaction as an external force (standing on the ground,
``f_hat = -(m_c g e3 + R f_c)``, i.e. up); cancelling it would drive the thrust down. The rule: the vehicle
is in contact when its feet are within ``CONTACT_TOLERANCE`` of the ground
(``p_z >= ground.height - contact_height - CONTACT_TOLERANCE``) or its top within it of an enabled ceiling
(``p_z <= ceiling.height + top_height + CONTACT_TOLERANCE``). In contact the law gets no compensation and the
observer is restarted (its estimate is zero), so after take-off the compensation grows from zero with the
filter's own dynamics instead of jumping, and a touch-down switches it off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsr_control.controllers.common import Compensation
from fsr_estimation.core.observer import MomentumObserver
from fsr_sim.model.so3 import Mat3, euler_zyx_from_rotation_rows, mat_t_vec3, mat_vec3
from fsr_sim.model.vehicle import Vehicle

COMPENSATION_MODES = ("none", "estimate")
CONTACT_TOLERANCE = 0.002  # m: feet (or top) this close to a surface count as touching it
PERIOD_TOLERANCE = 0.01  # relative: a stamp step further than this from the control period is a gap
ZERO = (0.0, 0.0, 0.0)
# Largest c0 * T accepted with compensation (the observer alone takes c0 T < 2). Measured with the report's gains,
# in-process: c0 in 1..100 and r in 1..5 never diverge (scripts/sweep_compensation.py, c0 T <= 0.1), ex3 flies
# at c0 T = 0.5 and 0.7 (r = 1..5) and diverges at c0 T = 1.0 (r = 1 and 5) and 1.9: half of that, refused above.
MAX_C0_PERIOD = 0.5


@dataclass(frozen=True)
class Surfaces:
    """Where the vehicle touches something, for the contact rule (world NED down-coordinates [m]).

    ``ground_rest_z``: the centre's ``z`` with the feet on the ground (``ground.height - contact_height``),
    None without a ground; ``ceiling_rest_z``: with the top at the ceiling (``ceiling.height +
    top_height``), None without a ceiling.
    """

    ground_rest_z: float | None = None
    ceiling_rest_z: float | None = None

    def in_contact(self, z: float, tolerance: float = CONTACT_TOLERANCE) -> bool:
        """True if the centre's down-coordinate ``z`` [m] puts the vehicle within ``tolerance`` of a surface."""
        if self.ground_rest_z is not None and z >= self.ground_rest_z - tolerance:
            return True
        return self.ceiling_rest_z is not None and z <= self.ceiling_rest_z + tolerance

    def contact_mask(self, z: np.ndarray, tolerance: float = CONTACT_TOLERANCE) -> np.ndarray:
        """:meth:`in_contact` for an array of ``z`` [m] (the analysis counts gated steps with it)."""
        z = np.asarray(z, dtype=float)
        mask = np.zeros(z.shape, dtype=bool)
        if self.ground_rest_z is not None:
            mask |= z >= self.ground_rest_z - tolerance
        if self.ceiling_rest_z is not None:
            mask |= z <= self.ceiling_rest_z + tolerance
        return mask


@dataclass(frozen=True)
class CompensationConfig:
    """``controller.compensation: estimate`` with what its observer needs.

    c0 [rad/s], r: the filter (scenario ``estimator`` section); control_period [s]: the observer's sample
    time (``physics_dt * physics_substeps``); surfaces: the contact rule's geometry.
    """

    c0: float
    r: int
    control_period: float
    surfaces: Surfaces = Surfaces()


@dataclass
class CompensationReport:
    """What the compensation did in a flight: steps with an estimate cancelled, steps gated by contact,
    estimates that were late (0: the observer is in the controller's process) and observer restarts
    after a stamp gap."""

    compensated_steps: int = 0
    contact_steps: int = 0
    late_estimates: int = 0
    gaps: int = 0

    def as_dict(self) -> dict[str, int | str]:
        return {"mode": "estimate", "observer": "controller", "compensated_steps": self.compensated_steps,
                "contact_steps": self.contact_steps, "late_estimates": self.late_estimates, "gaps": self.gaps}


class WrenchCompensator:
    """The controller's own momentum observer and the contact gate (module docstring).

    Per step: :meth:`estimate` before the law (the estimate of the previous stamp, or None when gated),
    :meth:`record` after allocation (state and commanded wrench of this stamp).

    Parameters
    ----------
    config : CompensationConfig
        Filter, sample time, surfaces.
    vehicle : Vehicle
        The controller's nominal model: mass [kg], inertia [kg m^2] (the observer's model).
    """

    def __init__(self, config: CompensationConfig, vehicle: Vehicle) -> None:
        self.config = config
        self.observer = MomentumObserver(vehicle.mass, vehicle.inertia, config.c0, config.r, config.control_period)
        self.report = CompensationReport()
        self._ready = False  # the observer holds an estimate of the previous stamp
        self._history: list[tuple[float, float, float]] = []  # the last (up to 3) force estimates, newest last
        self._smooth = config.r >= 2
        self._rate_inverse: Mat3 = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
        self._last_stamp: float | None = None
        self._contact = False

    def estimate(self, stamp_s: float, position: np.ndarray) -> Compensation | None:
        """``(f_hat world NED [N], tau_hat body FRD [N m], f_hat_dot [N/s], f_hat_ddot [N/s^2])`` of the
        previous stamp for the state at ``stamp_s`` [s], or None (in contact, first step, after a gap): the
        law then runs uncompensated. The rates are the backward differences of the last estimates (zero until
        there are two, three). ``f_hat_ddot`` only for ``r >= 2``: with ``r = 1`` the estimate's rate jumps
        with every step of its input (``c0`` times the step: the disturbance switching on, a lift-off), so its
        second difference is an impulse of ``c0 * step / T``, which through ``w_dot_d`` kicked the attitude
        (ex3 with ``c0 = 100``, ``r = 1`` diverged with it); ``r = 1`` uses zero."""
        previous, self._last_stamp = self._last_stamp, stamp_s
        period = self.config.control_period
        if previous is not None and abs(stamp_s - previous - period) > PERIOD_TOLERANCE * period:
            self.report.gaps += 1
            self._ready = False
        self._contact = self.config.surfaces.in_contact(float(position[2]))
        if self._contact:
            self.report.contact_steps += 1
            self._ready = False
        if not self._ready:
            self.observer.reset()
            self._history.clear()
            return None
        self.report.compensated_steps += 1
        fx, fy, fz, ex, ey, ez = self.observer.estimate_values  # [f_e (world); tau_e (eta coordinates)]
        history = self._history
        history.append((fx, fy, fz))
        if len(history) > 3:
            del history[0]
        rate, acceleration = ZERO, ZERO
        if len(history) >= 2:
            (ax, ay, az), (bx, by, bz) = history[-2], history[-1]
            rate = ((bx - ax) / period, (by - ay) / period, (bz - az) / period)
        if len(history) == 3 and self._smooth:  # r >= 2: the estimate's rate is continuous
            (cx, cy, cz), (ax, ay, az), (bx, by, bz) = history
            scale = 1.0 / (period * period)
            acceleration = ((bx - 2.0 * ax + cx) * scale, (by - 2.0 * ay + cy) * scale, (bz - 2.0 * az + cz) * scale)
        tx, ty, tz = mat_t_vec3(self._rate_inverse, (ex, ey, ez))  # Q^-T tau_e (body)
        return (fx, fy, fz), (tx, ty, tz), rate, acceleration

    def record(self, rotation: np.ndarray, velocity_world: np.ndarray, angular_velocity_body: np.ndarray,
               force_body: np.ndarray, torque_body: np.ndarray) -> None:
        """Feed the observer the state of this stamp and the body wrench commanded for it [N, N m]."""
        phi, theta, psi = euler_zyx_from_rotation_rows(rotation.tolist())
        inverse = inverse_euler_rate_rows(phi, theta)
        self._rate_inverse = inverse  # Q^-1 of this sample: the estimate's torque in the body frame next step
        eta_dot = mat_vec3(inverse, angular_velocity_body.tolist())
        self.observer.update(velocity_world, (phi, theta, psi), eta_dot, force_body, torque_body)
        self._ready = True

    @property
    def in_contact(self) -> bool:
        """Whether the last state was in contact with a surface (compensation gated off)."""
        return self._contact


def inverse_euler_rate_rows(phi: float, theta: float) -> Mat3:
    """Rows of ``Q(eta)^-1`` (``eta_dot = Q^-1 omega_body``, ZYX, :func:`fsr_sim.model.so3.euler_rate_rows`):
    ``[[1, s_phi t_theta, c_phi t_theta], [0, c_phi, -s_phi], [0, s_phi / c_theta, c_phi / c_theta]]``, singular
    at pitch = +-90 deg (ZeroDivisionError)."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth = math.cos(theta)
    tth = math.sin(theta) / cth
    return ((1.0, sph * tth, cph * tth), (0.0, cph, -sph), (0.0, sph / cth, cph / cth))


def surfaces_for(vehicle: Vehicle, ground_height: float | None, ceiling_height: float | None) -> Surfaces:
    """The contact geometry of ``vehicle`` between a ground and a ceiling (NED heights [m], None: absent)."""
    return Surfaces(
        None if ground_height is None else ground_height - vehicle.contact_height,
        None if ceiling_height is None else ceiling_height + vehicle.top_height,
    )

