"""The controller's per-step tick (compiled core): reference (and its horizon) -> (compensation, or the model's
aerodynamics along the reference) -> law -> allocation.

:func:`controller_tick` is what the controller node, :class:`fsr_control.flight_controller.FlightController`
and the in-process loop run for the state stamped ``t``. It writes one output row (:func:`output_size`
float64) laid out by the index constants below, in the order of the messages the controller publishes
(``wrench_cmd``, ``wrench_shortfall``, ``reference``, ``attitude_cmd``, ``wrench_desired``: each a contiguous
slice holding its numbers in field order), then what only the Python API and the recording's analysis need,
then the rotor speeds and tilts.

Frames: position world NED [m], ``R`` body FRD -> world, velocity world [m/s], angular velocity body [rad/s].
Besides the state (``odom``'s, a :class:`~fsr_control.core.law_terms.VehicleState`) the tick is handed what the
vehicle measures of the same stamp (a :class:`~fsr_control.core.law_terms.Measured`): ``imu`` (6,), the IMU's
angular velocity [rad/s] and specific force [m/s^2] (body FRD, ``imu``'s numbers), and the rotors' ``speeds``
[rad/s] and ``tilts`` [rad] (n,) (``rotor_state``'s). Only a law or an observer configured to use them reads them
(:data:`fsr_control.controllers.catalog.LAWS`' ``needs_imu`` and ``needs_rotor_state``, ``estimator.input:
measured``); otherwise they may hold anything (the node passes zeros when it is not subscribed).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from fsr_control.core.aerodynamic_feedforward import AeroFeedforward, AeroMemory, aerodynamic_feedforward
from fsr_control.core.allocation import TILTING, AllocationParams, AllocationState, allocate
from fsr_control.core.compensation import (
    CompensationParams,
    CompensationState,
    compensation_estimate,
    compensation_record,
)
from fsr_control.core.flatness import ATTITUDE_OK
from fsr_control.core.laws import (
    NO_COMPENSATION,
    LawMemory,
    LawParams,
    Measured,
    VehicleState,
    control_law,
    law_allocated,
)
from fsr_control.core.reference import TrajectoryTable, sample_horizon, sample_reference
from fsr_sim.core.jit import jit
from fsr_sim.core.rotors import measured_rotor_wrench
from fsr_sim.core.so3 import Mat3, mat_vec3, put3, put_rows3, quaternion_from_rotation_rows

# The output row. wrench_cmd: the body wrench the allocated command produces (body FRD, N and N m).
FORCE, TORQUE = 0, 3
SHORTFALL = 6  # wrench_shortfall: demanded minus produced body wrench (6)
# reference (trajectory_msgs/MultiDOFJointTrajectory point): position, orientation (x y z w), linear velocity,
# angular velocity R_d omega_d (world), linear acceleration, angular acceleration R_d omega_dot_d (world)
REFERENCE_POSITION, REFERENCE_QUATERNION, REFERENCE_VELOCITY = 12, 15, 19
REFERENCE_ANGULAR_VELOCITY_WORLD, REFERENCE_ACCELERATION, REFERENCE_ANGULAR_ACCELERATION_WORLD = 22, 25, 28
REFERENCE_MESSAGE_SIZE = 19
COMMANDED_QUATERNION = 31  # attitude_cmd: the commanded attitude R_c (x y z w)
DESIRED_FORCE, DESIRED_TORQUE = 35, 38  # wrench_desired: the law's wrench before allocation
REFERENCE_JERK, REFERENCE_SNAP = 41, 44
REFERENCE_ROTATION = 47  # R_d, 9 entries row by row
REFERENCE_ANGULAR_VELOCITY, REFERENCE_ANGULAR_ACCELERATION = 56, 59  # omega_d, omega_dot_d (desired body)
REFERENCE_YAW, REFERENCE_YAW_RATE, REFERENCE_YAW_ACCELERATION = 62, 63, 64
COMMANDED_ROTATION = 65  # R_c, 9 entries row by row
SATURATED = 74
ROTOR_SPEEDS = 75  # n entries [rad/s], then n tilts [rad]


def output_size(rotor_count: int) -> int:
    """Length of the output row for ``rotor_count`` rotors."""
    return ROTOR_SPEEDS + 2 * rotor_count


class ControllerParams(NamedTuple):
    trajectory: TrajectoryTable
    law: LawParams
    allocation: AllocationParams
    compensation: CompensationParams
    aerodynamics: AeroFeedforward  # controller.aerodynamics: model (fsr_control.core.aerodynamic_feedforward)


class ControllerState(NamedTuple):
    law: LawMemory  # the laws' memory (fsr_control.core.laws)
    allocation: AllocationState
    compensation: CompensationState
    reference: np.ndarray  # (5, 4) scratch: the active segment's channel derivatives
    horizon: np.ndarray  # (law.horizon_steps, HORIZON_WIDTH): the reference ahead (fsr_control.core.reference)
    aerodynamics: AeroMemory  # the aerodynamic feed-forward's (fsr_control.core.aerodynamic_feedforward)


@jit
def _put_quaternion(out, at: int, rows: Mat3) -> None:  # noqa: ANN001
    out[at], out[at + 1], out[at + 2], out[at + 3] = quaternion_from_rotation_rows(rows)


@jit
def controller_tick(params: ControllerParams, state: ControllerState, t: float, vehicle: VehicleState,
                    measured: Measured, out) -> int:  # noqa: ANN001
    """The command for the ``vehicle``'s state at ``t`` [s] into ``out`` (module docstring), with what it
    ``measured`` of the same stamp (the IMU's sample and the rotors' speeds and tilts). Returns the law's status
    (``ATTITUDE_OK``, or why no attitude could be commanded: ``out`` then holds only the reference)."""
    reference = sample_reference(params.trajectory, t, state.reference)
    rotation_d = reference.rotation
    put3(out, REFERENCE_POSITION, reference.position)
    _put_quaternion(out, REFERENCE_QUATERNION, rotation_d)
    put3(out, REFERENCE_VELOCITY, reference.velocity)
    put3(out, REFERENCE_ANGULAR_VELOCITY_WORLD, mat_vec3(rotation_d, reference.angular_velocity))
    put3(out, REFERENCE_ACCELERATION, reference.acceleration)
    put3(out, REFERENCE_ANGULAR_ACCELERATION_WORLD, mat_vec3(rotation_d, reference.angular_acceleration))
    put3(out, REFERENCE_JERK, reference.jerk)
    put3(out, REFERENCE_SNAP, reference.snap)
    put_rows3(out, REFERENCE_ROTATION, rotation_d)
    put3(out, REFERENCE_ANGULAR_VELOCITY, reference.angular_velocity)
    put3(out, REFERENCE_ANGULAR_ACCELERATION, reference.angular_acceleration)
    out[REFERENCE_YAW], out[REFERENCE_YAW_RATE] = reference.yaw, reference.yaw_rate
    out[REFERENCE_YAW_ACCELERATION] = reference.yaw_acceleration
    compensation = NO_COMPENSATION
    if params.compensation.enabled:  # cancel the estimate of t_(k-1), then feed the observer this step
        compensation = compensation_estimate(params.compensation, state.compensation, t, vehicle.position[2])
    elif params.aerodynamics.enabled:  # the estimate holds the aerodynamics too: one or the other
        compensation = aerodynamic_feedforward(params.aerodynamics, state.aerodynamics, t, reference)
    if params.law.horizon_steps > 0:
        sample_horizon(params.trajectory, t, params.law.horizon_dt, state.reference, state.horizon)
    status, force_d, torque_d, rotation_c = control_law(params.law, state.law, state.horizon, t, reference, vehicle,
                                                        compensation, measured)
    if status != ATTITUDE_OK:
        return status
    put3(out, DESIRED_FORCE, force_d)
    put3(out, DESIRED_TORQUE, torque_d)
    put_rows3(out, COMMANDED_ROTATION, rotation_c)
    _put_quaternion(out, COMMANDED_QUATERNION, rotation_c)
    n = (out.shape[0] - ROTOR_SPEEDS) // 2
    actuated = allocate(params.allocation, state.allocation, t, force_d, torque_d, out[ROTOR_SPEEDS:ROTOR_SPEEDS + n],
                        out[ROTOR_SPEEDS + n:], out[SHORTFALL:SHORTFALL + 6])
    put3(out, FORCE, actuated.force)
    put3(out, TORQUE, actuated.torque)
    out[SATURATED] = 1.0 if actuated.saturated else 0.0
    law_allocated(params.law, state.law, actuated.force, actuated.torque, out[SHORTFALL:SHORTFALL + 6])
    if params.compensation.enabled:
        force_a, torque_a = actuated.force, actuated.torque  # the commanded wrench, or (input measured) the rotors'
        if params.compensation.measured:
            allocation = params.allocation
            force_a, torque_a = measured_rotor_wrench(allocation.allocation, allocation.c_f,
                                                      allocation.mode == TILTING, measured.speeds, measured.tilts)
        compensation_record(params.compensation, state.compensation, vehicle.rotation, vehicle.velocity_world,
                            vehicle.angular_velocity, force_a, torque_a)
    return ATTITUDE_OK
