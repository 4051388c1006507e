"""One object that turns a state into an actuator command: planner + control law + allocation.

``FlightController.command(t, p, R, v_world, w_body)`` runs the compiled core's tick
(:func:`fsr_control.core.controller.controller_tick`: the reference at ``t`` [s] (and ahead, for a law that
reads a horizon), the configured law -- geometric, Voliro or another of the catalog, each returning a body
wrench -- on the nominal vehicle model, with
``controller.compensation: estimate`` cancelling the wrench its own observer estimated at the previous stamp
(:mod:`fsr_control.compensation`), and the allocation to rotor speeds and tilts, or the wrench passed
through in wrench actuation). The controller node and the in-process loop run exactly this tick, once per
lockstep step; :meth:`FlightController.command_row` is its allocation-free form (the output row of
:mod:`fsr_control.core.controller`), :meth:`FlightController.command` the same as Python objects.

Frames: position world NED [m], ``R`` body FRD -> world, velocity world [m/s], angular velocity body
[rad/s]. Outputs: body wrench [N, N m], rotor speeds [rad/s], tilt angles [rad].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsr_control.allocation import make_actuation
from fsr_control.compensation import WrenchCompensator, pack_compensation
from fsr_control.config.controller_config import ControllerConfig
from fsr_control.controllers.catalog import LAWS
from fsr_control.controllers.common import CompiledLaw, WrenchCommand
from fsr_control.core import controller as core
from fsr_control.core import laws
from fsr_control.core.aerodynamic_feedforward import AeroFeedforward, new_aero_memory
from fsr_control.core.flatness import ATTITUDE_ERRORS, ATTITUDE_OK
from fsr_control.core.reference import CHANNELS, DERIVATIVES, HORIZON_WIDTH
from fsr_control.planning.feasibility import LegAdjustment
from fsr_control.planning.trajectory import Reference, Trajectory
from fsr_sim.core.so3 import Mat3, Vec3, matrix_rows
from fsr_sim.model.plant import pack_aerodynamics
from fsr_sim.model.rotors import SaturationReport, rotor_axes, rotor_columns
from fsr_sim.model.so3 import vector3
from fsr_sim.model.vehicle import Vehicle

ROLL_PITCH_TOLERANCE = 1e-4  # rad: a goal for a fixed-rotor vehicle must be level (yaw only)


def make_control_law(config: ControllerConfig, vehicle: Vehicle) -> CompiledLaw:
    """The law ``config.type`` names (:data:`fsr_control.controllers.catalog.LAWS`) on the nominal ``vehicle``."""
    law = LAWS[config.type]
    params = laws.law_params(law.kind, law.pack(vehicle, config), law.horizon_steps, law.horizon_dt)
    return CompiledLaw(params)


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

    @classmethod
    def from_row(cls, stamp: float, row: np.ndarray, rotors: bool, tilting: bool) -> ControlOutput:
        """The output of one core tick (its row, :mod:`fsr_control.core.controller`)."""
        def part(at: int, size: int = 3) -> np.ndarray:
            return row[at:at + size].copy()

        n = (len(row) - core.ROTOR_SPEEDS) // 2
        reference = Reference(
            stamp, part(core.REFERENCE_POSITION), part(core.REFERENCE_VELOCITY), part(core.REFERENCE_ACCELERATION),
            part(core.REFERENCE_JERK), part(core.REFERENCE_SNAP), part(core.REFERENCE_ROTATION, 9).reshape(3, 3),
            part(core.REFERENCE_ANGULAR_VELOCITY), part(core.REFERENCE_ANGULAR_ACCELERATION),
            float(row[core.REFERENCE_YAW]), float(row[core.REFERENCE_YAW_RATE]),
            float(row[core.REFERENCE_YAW_ACCELERATION]))
        desired = WrenchCommand(part(core.DESIRED_FORCE), part(core.DESIRED_TORQUE),
                                part(core.COMMANDED_ROTATION, 9).reshape(3, 3))
        return cls(stamp, part(core.FORCE), part(core.TORQUE), part(core.ROTOR_SPEEDS, n) if rotors else None,
                   part(core.ROTOR_SPEEDS + n, n) if tilting else None, reference, bool(row[core.SATURATED]),
                   desired, part(core.SHORTFALL, 6))

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


def pack_aerodynamic_feedforward(vehicle: Vehicle, actuation: str, mode: str) -> AeroFeedforward:
    """The core's :class:`~fsr_control.core.aerodynamic_feedforward.AeroFeedforward` for
    ``controller.aerodynamics`` ``mode`` (``model`` | ``none``): the nominal vehicle's aerodynamics as the plant
    packs them (:func:`fsr_sim.model.plant.pack_aerodynamics`); off for ``none`` or a model without any."""
    aerodynamics = pack_aerodynamics(vehicle, actuation)
    enabled = mode == "model" and (aerodynamics.parasitic or aerodynamics.rotor)
    return AeroFeedforward(enabled, aerodynamics, rotor_columns(vehicle, rotor_axes(vehicle)), float(vehicle.mass),
                           vehicle.rotor_count * float(vehicle.c_f))


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
        if vehicle.fully_actuated and actuation != "rotors":
            raise ValueError("a fully actuated vehicle needs 'actuation: rotors' (its wrench is allocated to them)")
        objective = config.secondary_objective
        self.actuator = make_actuation(vehicle, actuation, config.allocation, config.air_mode, objective.type,
                                       objective.exponent, objective.iterations)
        self.compensator = (WrenchCompensator(config.compensation, vehicle)
                            if config.compensation is not None else None)
        compensation = ((self.compensator.params, self.compensator.state) if self.compensator is not None
                        else pack_compensation(None, vehicle))
        self.rotors = actuation == "rotors"
        self.tilting = self.rotors and vehicle.has_servos
        self.output = np.zeros(core.output_size(vehicle.rotor_count))  # the last tick's output row
        self.state = core.ControllerState(self.law.memory, self.actuator.state, compensation[1],
                                          np.zeros((DERIVATIVES, CHANNELS)),
                                          np.zeros((self.law.params.horizon_steps, HORIZON_WIDTH)),
                                          new_aero_memory(vehicle.rotor_count))
        self._law_and_allocation = (self.law.params, self.actuator.params, compensation[0],
                                    pack_aerodynamic_feedforward(vehicle, actuation, config.aerodynamics))
        self.params: core.ControllerParams | None = None  # packed with the trajectory's table
        self.trajectory: Trajectory | None = None
        self._pending_goal: tuple[np.ndarray, np.ndarray, float] | None = None
        self.last_stamp = start_time
        self._imu, self._rotors = np.zeros(6), np.zeros(vehicle.rotor_count)  # when not measured
        law_type = LAWS[config.type]
        self.needs_imu = law_type.needs_imu or config.use_imu  # the law reads the IMU (imu)
        measured_input = config.compensation is not None and config.compensation.measured
        # the law or the compensation's observer reads the rotors' measured speeds (rotor_state), where published
        self.needs_rotor_state = config.rotor_state and (law_type.needs_rotor_state or measured_input)
        if start_position is not None and start_rotation is not None:
            self._plan(start_position, start_rotation, start_time)

    @property
    def saturation(self) -> SaturationReport:
        """Rotor-speed saturation so far (count, first time, worst rotor)."""
        return self.actuator.saturation

    @property
    def tilt_saturation(self) -> SaturationReport:
        return self.actuator.tilt_saturation

    @property
    def plan_adjustments(self) -> list[LegAdjustment]:
        """The infeasible legs and goals so far and what the planner did with each (empty: none)."""
        return [] if self.trajectory is None else self.trajectory.adjustments

    def compensation_summary(self) -> dict[str, int | str]:
        """``{"mode": "none"}``, or what the compensation did (:class:`fsr_control.compensation.CompensationReport`)."""
        return {"mode": "none"} if self.compensator is None else self.compensator.report.as_dict()

    def _plan(self, position: np.ndarray, rotation: np.ndarray, time: float) -> None:
        self.trajectory = self.config.trajectory(self.vehicle, self.actuation, position, rotation, time)
        if self._pending_goal is not None:
            goal_position, goal_rotation, duration = self._pending_goal
            self._pending_goal = None
            self.trajectory.replan(goal_position, goal_rotation, time, duration)
        self._pack()

    def _pack(self) -> None:
        """(Re)pack the core's parameters with the trajectory's current table."""
        self.params = core.ControllerParams(self.trajectory.table(), *self._law_and_allocation)

    def reference(self, stamp_s: float) -> Reference:
        """The desired state at ``stamp_s`` [s] (the trajectory must exist)."""
        return self.trajectory.evaluate(stamp_s)

    def command_row(self, stamp_s: float, position: Vec3, rotation: Mat3, velocity_world: Vec3,
                    angular_velocity_body: Vec3, imu: np.ndarray | None = None, speeds: np.ndarray | None = None,
                    tilts: np.ndarray | None = None) -> np.ndarray:
        """The core tick for the state at ``stamp_s`` [s] (position, velocity world and angular velocity body as
        3-tuples of floats, ``R`` as its rows): its output row (:attr:`output`, reused at every call). ``imu``
        (6,): the IMU's angular velocity [rad/s] and specific force [m/s^2] of the same stamp; ``speeds``,
        ``tilts`` (n,): the rotors' measured state (``rotor_state``); float arrays, read only by a law or an
        observer that uses them (:attr:`needs_imu`, :attr:`needs_rotor_state`; None: zeros).

        Raises ValueError when no attitude can be commanded (the reference is in the row then, nothing else)."""
        if self.trajectory is None:
            self._plan(np.array(position), np.array(rotation), stamp_s)
        self.last_stamp = stamp_s
        measured = laws.Measured(self._imu if imu is None else imu, self._rotors if speeds is None else speeds,
                                 self._rotors if tilts is None else tilts)
        status = core.controller_tick(self.params, self.state, stamp_s,
                                      laws.VehicleState(position, rotation, velocity_world, angular_velocity_body),
                                      measured, self.output)
        if status != ATTITUDE_OK:
            raise ValueError(ATTITUDE_ERRORS[status])
        return self.output

    def command(
        self,
        stamp_s: float,
        position: np.ndarray,
        rotation: np.ndarray,
        velocity_world: np.ndarray,
        angular_velocity_body: np.ndarray,
        imu: np.ndarray | None = None,
        speeds: np.ndarray | None = None,
        tilts: np.ndarray | None = None,
    ) -> ControlOutput:
        """Command for the state at ``stamp_s`` [s] (arrays: position (3,), ``R`` (3, 3), velocities (3,); ``imu``
        (6,), ``speeds`` and ``tilts`` (n,) the measurements of :meth:`command_row`)."""
        def array(values: np.ndarray | None) -> np.ndarray | None:
            return None if values is None else np.ascontiguousarray(values, dtype=float)

        row = self.command_row(float(stamp_s), vector3(position), matrix_rows(np.ascontiguousarray(rotation, float)),
                               vector3(velocity_world), vector3(angular_velocity_body), array(imu), array(speeds),
                               array(tilts))
        return ControlOutput.from_row(float(stamp_s), row, self.rotors, self.tilting)

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
        if not self.vehicle.fully_actuated:
            # Only yaw is commandable: the body z axis of a level goal is the world's down axis.
            tilt = math.acos(max(-1.0, min(1.0, float(rotation[2, 2]))))
            if tilt > ROLL_PITCH_TOLERANCE:
                raise ValueError(
                    f"goal attitude is tilted by {math.degrees(tilt):.3f} deg; '{self.vehicle.name}' is not fully "
                    "actuated: it accepts only yaw goals (roll = pitch = 0)"
                )
        duration = self.config.goal_duration if duration is None else float(duration)
        if not duration > 0.0:
            raise ValueError(f"goal duration must be > 0 s, got {duration}")
        now = self.last_stamp if now is None else float(now)
        if self.trajectory is None:
            self._pending_goal = (position, rotation, duration)
            return
        self.trajectory.replan(position, rotation, now, duration)
        self._pack()
