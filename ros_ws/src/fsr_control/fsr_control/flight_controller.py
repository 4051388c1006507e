"""One object that turns a state into an actuator command: planner + control law + allocation.

``FlightController.command(t, p, R, v_world, w_body)`` evaluates the reference at ``t`` [s], runs the
configured law (:class:`fsr_control.controllers.common.ControlLaw`: geometric or Voliro, both returning a
body wrench) on the nominal vehicle model (with ``controller.compensation: estimate``, cancelling the wrench its
own observer estimated at the previous stamp, :mod:`fsr_control.compensation`), and allocates the wrench to
rotor speeds (and tilts) or passes it through in wrench actuation. The controller node and the in-process loop
both call exactly this, once per lockstep step (1 kHz), so it does no allocation beyond small arrays.

Frames: position world NED [m], ``R`` body FRD -> world, velocity world [m/s], angular velocity body
[rad/s]. Outputs: body wrench [N, N m], rotor speeds [rad/s], tilt angles [rad].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsr_control.allocation import FixedRotorActuation, TiltingActuation, WrenchActuation
from fsr_control.compensation import WrenchCompensator
from fsr_control.config.controller_config import ControllerConfig
from fsr_control.controllers.common import ControlLaw, WrenchCommand
from fsr_control.controllers.geometric import GeometricController
from fsr_control.controllers.voliro import VoliroController
from fsr_control.planning.trajectory import Reference, Trajectory
from fsr_sim.model.allocation import SaturationReport
from fsr_sim.model.vehicle import Vehicle

ROLL_PITCH_TOLERANCE = 1e-4  # rad: a goal for a fixed-rotor vehicle must be level (yaw only)


def make_control_law(config: ControllerConfig, vehicle: Vehicle) -> ControlLaw:
    """The law ``config.type`` names (``geometric`` or ``voliro``) on the nominal ``vehicle``."""
    if config.type == "voliro":
        return VoliroController(vehicle, config.gains, config.angular_feedforward)
    return GeometricController(vehicle, config.gains)


def seconds_from_ns(stamp_ns: int) -> float:
    """Sim time [s] of an integer-nanosecond stamp: the one conversion the node and the in-process loop
    share, so both evaluate the reference at bit-identical times."""
    return stamp_ns * 1e-9


@dataclass
class ControlOutput:
    """The command for the state stamped ``stamp`` [s] (see :class:`fsr_control.allocation.Actuated`)."""

    stamp: float
    force_body: np.ndarray
    torque_body: np.ndarray
    rotor_speeds: np.ndarray | None
    tilt_angles: np.ndarray | None
    reference: Reference
    saturated: bool
    desired: WrenchCommand  # the law's wrench before allocation, and the attitude it commands
    shortfall: np.ndarray | None = None  # (6,) demanded - produced body wrench [N, N m] (wrench_shortfall)

    @property
    def thrust(self) -> float:
        """``u_T = -f_z`` [N] (thrust along ``-z_b``)."""
        return -float(self.force_body[2])

    @property
    def rotation_cmd(self) -> np.ndarray:
        """The commanded attitude ``R_c`` (body FRD -> world NED): the geometric law's ``R_d``, or the reference."""
        return self.desired.rotation_commanded

    @property
    def force_desired(self) -> np.ndarray:
        """Body force the law asked for, before allocation [N]."""
        return self.desired.force_body

    @property
    def torque_desired(self) -> np.ndarray:
        """Body torque the law asked for, before allocation [N m]."""
        return self.desired.torque_body


class FlightController:
    """Planner + control law + allocation for one vehicle (nominal model ``vehicle``).

    ``actuation``: ``rotors`` or ``wrench``. The trajectory starts at ``start_position`` / ``start_rotation``
    (the scenario's initial state) or, if they are not given, at the first state passed to :meth:`command`.
    """

    def __init__(
        self,
        config: ControllerConfig,
        vehicle: Vehicle,
        actuation: str,
        start_position: np.ndarray | None = None,
        start_rotation: np.ndarray | None = None,
        start_time: float = 0.0,
    ) -> None:
        if actuation not in ("rotors", "wrench"):
            raise ValueError(f"actuation must be 'rotors' or 'wrench', got '{actuation}'")
        self.config = config
        self.vehicle = vehicle
        self.actuation = actuation
        self.law = make_control_law(config, vehicle)
        if vehicle.is_tilting and actuation != "rotors":
            raise ValueError("a tilting-rotor vehicle needs 'actuation: rotors' (its wrench is 6-D)")
        if actuation == "wrench":
            self.actuator = WrenchActuation()
        elif vehicle.is_tilting:
            objective = config.secondary_objective
            self.actuator = TiltingActuation.with_objective(
                vehicle, objective.type, objective.exponent, objective.iterations, config.allocation
            )
        else:
            self.actuator = FixedRotorActuation(vehicle, config.allocation, config.air_mode)
        self.compensator = (WrenchCompensator(config.compensation, vehicle)
                            if config.compensation is not None else None)
        self.trajectory: Trajectory | None = None
        self._pending_goal: tuple[np.ndarray, np.ndarray, float] | None = None
        self.last_stamp = start_time
        if start_position is not None and start_rotation is not None:
            self._plan(start_position, start_rotation, start_time)

    @property
    def saturation(self) -> SaturationReport:
        """Rotor-speed saturation so far (count, first time, worst rotor)."""
        return self.actuator.saturation

    @property
    def tilt_saturation(self) -> SaturationReport:
        return self.actuator.tilt_saturation

    def compensation_summary(self) -> dict[str, int | str]:
        """``{"mode": "none"}``, or what the compensation did (:class:`fsr_control.compensation.CompensationReport`)."""
        return {"mode": "none"} if self.compensator is None else self.compensator.report.as_dict()

    def _plan(self, position: np.ndarray, rotation: np.ndarray, time: float) -> None:
        self.trajectory = Trajectory(
            self.config.waypoints, position, rotation, full_attitude=self.vehicle.is_tilting, start_time=time
        )
        if self._pending_goal is not None:
            goal_position, goal_rotation, duration = self._pending_goal
            self._pending_goal = None
            self.trajectory.replan(goal_position, goal_rotation, time, duration)

    def reference(self, stamp_s: float) -> Reference:
        """The desired state at ``stamp_s`` [s] (the trajectory must exist)."""
        return self.trajectory.evaluate(stamp_s)

    def command(
        self,
        stamp_s: float,
        position: np.ndarray,
        rotation: np.ndarray,
        velocity_world: np.ndarray,
        angular_velocity_body: np.ndarray,
    ) -> ControlOutput:
        """Command for the state at ``stamp_s`` [s]."""
        if self.trajectory is None:
            self._plan(position, rotation, stamp_s)
        self.last_stamp = stamp_s
        reference = self.trajectory.evaluate(stamp_s)
        compensator = self.compensator
        if compensator is None:
            desired = self.law.compute(reference, position, rotation, velocity_world, angular_velocity_body)
            actuated = self.actuator.allocate(stamp_s, desired.force_body, desired.torque_body)
        else:  # cancel the estimate of t_(k-1); then feed the observer this state and this command
            estimate = compensator.estimate(stamp_s, position)
            desired = self.law.compute(reference, position, rotation, velocity_world, angular_velocity_body,
                                       estimate)
            actuated = self.actuator.allocate(stamp_s, desired.force_body, desired.torque_body)
            compensator.record(rotation, velocity_world, angular_velocity_body, actuated.force_body,
                               actuated.torque_body)
        return ControlOutput(
            stamp_s, actuated.force_body, actuated.torque_body, actuated.rotor_speeds, actuated.tilt_angles,
            reference, actuated.saturated, desired, actuated.shortfall,
        )

    def set_goal(
        self,
        position: np.ndarray,
        rotation: np.ndarray,
        now: float | None = None,
        duration: float | None = None,
    ) -> None:
        """Fly to a new pose from the current reference (at ``now``, default: the last command's stamp).

        position: world NED [m]; rotation: body -> world (for a fixed-rotor vehicle only its yaw is used and
        roll/pitch must be 0); duration [s]: default the scenario's ``trajectory.goal_duration``.
        Raises ValueError for non-finite values, a non-level goal for fixed rotors, or duration <= 0.
        """
        position = np.asarray(position, dtype=float)
        rotation = np.asarray(rotation, dtype=float)
        if position.shape != (3,) or rotation.shape != (3, 3):
            raise ValueError(f"goal needs position (3,) and rotation (3, 3), got {position.shape}, {rotation.shape}")
        if not (np.all(np.isfinite(position)) and np.all(np.isfinite(rotation))):
            raise ValueError("goal holds NaN or inf")
        if not self.vehicle.is_tilting:
            # Only yaw is commandable: the body z axis of a level goal is the world's down axis.
            tilt = math.acos(max(-1.0, min(1.0, float(rotation[2, 2]))))
            if tilt > ROLL_PITCH_TOLERANCE:
                raise ValueError(
                    f"goal attitude is tilted by {math.degrees(tilt):.3f} deg; the fixed-rotor vehicle "
                    f"'{self.vehicle.name}' accepts only yaw goals (roll = pitch = 0)"
                )
        duration = self.config.goal_duration if duration is None else float(duration)
        if not duration > 0.0:
            raise ValueError(f"goal duration must be > 0 s, got {duration}")
        now = self.last_stamp if now is None else float(now)
        if self.trajectory is None:
            self._pending_goal = (position, rotation, duration)
            return
        self.trajectory.replan(position, rotation, now, duration)
