"""Disturbance rejection: the controller cancels the external wrench its own momentum observer estimates.

``controller.compensation: estimate`` (default ``none``) gives the flight controller a
:class:`WrenchCompensator`. It runs a :class:`fsr_estimation.estimator.observer.MomentumObserver` *inside the
controller*, on the controller's nominal model (mass ``m_c``, inertia ``I_c``: the scenario's vehicle), fed
with the controller's own input (``odom``) and its own output (the body wrench commanded after allocation,
what ``wrench_cmd`` carries), with the scenario's ``estimator.c0`` and ``estimator.r``. With
``estimator.input: measured`` it takes, instead of its output, the wrench the rotors' measured speeds and tilts
(``rotor_state`` of the same stamp) produce through the nominal allocation: a motor lag then no longer enters the
estimate as a disturbance (docs/estimation.md, *Compensation under rotor lag*).

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
``f_hat = -(m_c g e3 + R f_c)``, i.e. up); cancelling it would drive the thrust down. The rule
(:func:`fsr_sim.core.surfaces.in_contact`, the one contact rule of fsr): the vehicle is in contact when its
feet are within ``CONTACT_TOLERANCE`` of the ground (``p_z >= ground.height - contact_height -
CONTACT_TOLERANCE``) or its top within it of an enabled ceiling (``p_z <= ceiling.height + top_height +
CONTACT_TOLERANCE``). In contact the law gets no compensation and the observer is restarted (its estimate is
zero), so after take-off the compensation grows from zero with the filter's own dynamics instead of jumping,
and a touch-down switches it off.

The per-step code is the compiled core's (:mod:`fsr_control.core.compensation`); :class:`WrenchCompensator` is
its Python shell.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsr_control.core import compensation as core
from fsr_estimation.core.observer_step import ObserverState
from fsr_estimation.estimator.observer import MomentumObserver
from fsr_sim.core.so3 import matrix_rows
from fsr_sim.core.surfaces import CONTACT_TOLERANCE, Surfaces
from fsr_sim.model.vehicle import Vehicle

COMPENSATION_MODES = ("none", "estimate")
PERIOD_TOLERANCE = core.PERIOD_TOLERANCE
__all__ = ["CONTACT_TOLERANCE", "COMPENSATION_MODES", "CompensationConfig", "CompensationReport", "WrenchCompensator"]
# Largest c0 * T accepted with compensation (the observer alone takes c0 T < 2). Measured with the report's gains,
# in-process: c0 in 1..100 and r in 1..5 never diverge (fsr-sweep grids of docs/estimation.md, c0 T <= 0.1), ex3 flies
# at c0 T = 0.5 and 0.7 (r = 1..5) and diverges at c0 T = 1.0 (r = 1 and 5) and 1.9: half of that, refused above.
MAX_C0_PERIOD = 0.5


@dataclass(frozen=True)
class CompensationConfig:
    """``controller.compensation: estimate`` with what its observer needs.

    c0 [rad/s], r: the filter (scenario ``estimator`` section); control_period [s]: the observer's sample
    time (``physics_dt * physics_substeps``); surfaces: the contact rule's geometry (the environment around the
    nominal vehicle, :func:`fsr_sim.model.environment.pack_surfaces`); measured: the observer takes the rotors'
    measured speeds and tilts (``rotor_state``, ``estimator.input: measured``) through the nominal allocation
    instead of the commanded wrench (False: the command, also where the rotors do not lag); rates: the
    estimate's differences are handed to the law with it (the geometric law's ``feedforward: measured`` turns
    ``R_d`` with them; False: zero, ``R_d``'s rates the reference's alone: the estimate holds what the command
    itself causes - a rotor lag, the aerodynamics of the rotors' speeds - and its rates in ``R_d`` close a loop
    through the attitude that loses control under sensor noise).
    """

    c0: float
    r: int
    control_period: float
    surfaces: Surfaces
    measured: bool = False
    rates: bool = True


class CompensationReport:
    """What the compensation did in a flight (a view of the core's memory): steps with an estimate cancelled,
    steps gated by contact, estimates that were late (0: the observer is in the controller's process) and
    observer restarts after a stamp gap."""

    def __init__(self, memory: np.ndarray) -> None:
        self.memory = memory  # the core's COMPENSATION_MEMORY record

    @property
    def compensated_steps(self) -> int:
        return int(self.memory[0].compensated_steps)

    @property
    def contact_steps(self) -> int:
        return int(self.memory[0].contact_steps)

    @property
    def gaps(self) -> int:
        return int(self.memory[0].gaps)

    late_estimates = 0  # the observer is in the controller's process

    def as_dict(self) -> dict[str, int | str]:
        return {"mode": "estimate", "observer": "controller", "compensated_steps": self.compensated_steps,
                "contact_steps": self.contact_steps, "late_estimates": self.late_estimates, "gaps": self.gaps}


def pack_compensation(config: CompensationConfig | None, vehicle: Vehicle) -> tuple[core.CompensationParams,
                                                                                    core.CompensationState]:
    """The core's compensation parameters and a fresh state (``config`` None: disabled, a dormant observer)."""
    observer = MomentumObserver(vehicle.mass, vehicle.inertia, 1.0 if config is None else config.c0,
                                1 if config is None else config.r, 1.0 if config is None else config.control_period)
    surfaces = config.surfaces if config is not None else None
    if surfaces is None:
        from fsr_sim.model.environment import Environment, pack_surfaces

        surfaces = pack_surfaces(Environment(), vehicle)
    params = core.CompensationParams(config is not None, observer.params, observer.sample_time,
                                     config is not None and config.r >= 2, surfaces,
                                     config is not None and config.measured, config is None or config.rates)
    state = core.CompensationState(observer.state, np.zeros((3, 3)), np.eye(3), core.new_compensation_memory())
    return params, state


class WrenchCompensator:
    """The controller's own momentum observer and the contact gate (module docstring), on the compiled core.

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
        self.params, self.state = pack_compensation(config, vehicle)
        self.observer = _ObserverView(self.state.observer)
        self.report = CompensationReport(self.state.memory)

    def estimate(self, stamp_s: float, position: np.ndarray) -> tuple | None:
        """``(f_hat world NED [N], tau_hat body FRD [N m], f_hat_dot [N/s], f_hat_ddot [N/s^2])`` of the previous
        stamp for the state at ``stamp_s`` [s], or None (in contact, first step, after a gap): the law then runs
        uncompensated."""
        compensation = core.compensation_estimate(self.params, self.state, float(stamp_s), float(position[2]))
        return tuple(compensation[1:]) if compensation.active else None

    def record(self, rotation: np.ndarray, velocity_world: np.ndarray, angular_velocity_body: np.ndarray,
               force_body: np.ndarray, torque_body: np.ndarray) -> None:
        """Feed the observer the state of this stamp and the body wrench commanded for it [N, N m]."""
        vector = [tuple(float(v) for v in np.asarray(x, dtype=float).reshape(3))
                  for x in (velocity_world, angular_velocity_body, force_body, torque_body)]
        core.compensation_record(self.params, self.state, matrix_rows(np.ascontiguousarray(rotation, dtype=float)),
                                 *vector)

    @property
    def in_contact(self) -> bool:
        """Whether the last state was in contact with a surface (compensation gated off)."""
        return bool(self.state.memory[0].contact)


class _ObserverView:
    """The compensation's observer, read-only (its latest estimate)."""

    def __init__(self, state: ObserverState) -> None:
        self.state = state

    @property
    def estimate(self) -> np.ndarray:
        """The latest ``w_hat`` (a new array), shape (6,)."""
        return self.state.estimate.copy()
