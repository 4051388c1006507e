"""The geometric law per step (compiled core): thrust along ``-z_b`` and a body torque, for fixed rotors.

Its equations, the two feed-forwards of its desired rates and the integral term are in
:mod:`fsr_control.controllers.geometric` (the Python shell); its parameters are :class:`GeometricParams`, its
memory the ``MEMORY_SIZE`` entries laid out below.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_control.core import imu_bridge
from fsr_control.core.flatness import attitude_from_thrust_vector
from fsr_control.core.imu_bridge import BridgeParams, bridged_state
from fsr_control.core.law_terms import INERTIA, Compensation, linear_feedback, matrix_at
from fsr_control.core.reference import ReferenceSample
from fsr_sim.core.jit import jit_inline
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.core.rotors import SHORTFALL_TOLERANCE
from fsr_sim.core.so3 import Mat3, Vec3, attitude_error3, cross3, dot3, mat_t_mat3, mat_vec3

# GeometricParams.matrices: the nominal inertia [kg m^2], K_p [N/m], K_v [N s/m], K_i [N/(m s)] on the
# integral of the position error, K_R [N m/rad], K_w [N m s/rad]
MATRICES = ("inertia", "k_p", "k_v", "k_i", "k_r", "k_w")
K_P, K_V, K_I, K_R, K_W = range(1, len(MATRICES))


class GeometricParams(NamedTuple):
    mass: float  # nominal mass [kg]
    matrices: np.ndarray  # (6, 3, 3): MATRICES, matrices[INERTIA] the inertia
    integral: bool  # the integral term is on (k_i != 0)
    integral_limit: float  # [N] bound on |K_i int e_p| (anti-windup)
    reference_feedforward: bool  # w_d, w_dot_d from the reference (True) or the measured acceleration (False)
    acceleration_cutoff: float  # [Hz] of the first-order low-pass on the measured acceleration and on the
    # compensated estimate's rates (0: none)
    gyro: bool  # the attitude loop takes the IMU's angular velocity (the gyro) instead of odom's
    bridge: BridgeParams  # enabled: fly on the IMU-bridged estimate of the pose and velocity (imu_bridge)

    @classmethod
    def unused(cls) -> GeometricParams:
        """Placeholder parameters, for a controller that flies another law."""
        return cls(0.0, np.zeros((len(MATRICES), 3, 3)), False, 0.0, False, 0.0, False, BridgeParams.unused())


# memory entries: the previous sample, its filtered measured acceleration and the filtered rates of the
# compensated estimate (vectors: 3 entries), the position error's integral [m s], whether the last command
# fell short on the axes the position loop acts through (thrust, roll and pitch torque), then the IMU bridge's
HAS_PREVIOUS, PREVIOUS_TIME, PREVIOUS_VELOCITY, FILTERED_ACCELERATION = 0, 1, 2, 5
HAS_FILTERED_RATES, FILTERED_FORCE_RATE, FILTERED_FORCE_ACCELERATION = 8, 9, 12
INTEGRAL, INTEGRAL_HOLD = 15, 18
BRIDGE = 19
MEMORY_SIZE = BRIDGE + imu_bridge.MEMORY_SIZE


@jit_inline
def _measured_acceleration(memory, t: float, velocity_world: Vec3, thrust: float, mass: float,  # noqa: ANN001
                           z_b: Vec3, cutoff: float) -> Vec3:
    """Acceleration [m/s^2] from consecutive velocities (includes unmodelled forces); the model's
    ``g e3 - u_T z_b / m`` at the first step or when time does not advance. With a ``cutoff`` [Hz] > 0, through
    a first-order low-pass ``a_f <- a_f + (1 - exp(-2 pi f_c dt)) (a - a_f)`` (from the model's value at the
    first step): a difference of measured velocities amplifies their noise by ``1 / dt``."""
    has_previous, previous_time = memory[HAS_PREVIOUS] != 0.0, memory[PREVIOUS_TIME]
    vx, vy, vz = memory[PREVIOUS_VELOCITY], memory[PREVIOUS_VELOCITY + 1], memory[PREVIOUS_VELOCITY + 2]
    memory[HAS_PREVIOUS], memory[PREVIOUS_TIME] = 1.0, t
    memory[PREVIOUS_VELOCITY], memory[PREVIOUS_VELOCITY + 1], memory[PREVIOUS_VELOCITY + 2] = velocity_world
    if has_previous and t > previous_time:
        dt = t - previous_time
        raw = ((velocity_world[0] - vx) / dt, (velocity_world[1] - vy) / dt, (velocity_world[2] - vz) / dt)
        if cutoff <= 0.0:
            return raw
        gain = 1.0 - math.exp(-2.0 * math.pi * cutoff * dt)
        f = FILTERED_ACCELERATION
        memory[f] += gain * (raw[0] - memory[f])
        memory[f + 1] += gain * (raw[1] - memory[f + 1])
        memory[f + 2] += gain * (raw[2] - memory[f + 2])
        return memory[f], memory[f + 1], memory[f + 2]
    scale = thrust / mass
    model = (-scale * z_b[0], -scale * z_b[1], GRAVITY - scale * z_b[2])
    memory[FILTERED_ACCELERATION], memory[FILTERED_ACCELERATION + 1], memory[FILTERED_ACCELERATION + 2] = model
    return model


@jit_inline
def _low_pass3(memory, at: int, value: Vec3, gain: float, first: bool) -> Vec3:  # noqa: ANN001
    """``y <- y + gain (value - y)`` on the 3 entries of ``memory`` from ``at`` (``first``: ``y = value``)."""
    for i in range(3):
        if first:
            memory[at + i] = value[i]
        else:
            memory[at + i] += gain * (value[i] - memory[at + i])
    return memory[at], memory[at + 1], memory[at + 2]


@jit_inline
def _filtered_rates(memory, t: float, compensation: Compensation, cutoff: float) -> tuple:  # noqa: ANN001
    """The compensated estimate's rate and second rate [N/s, N/s^2] through the measured acceleration's low-pass
    (cutoff [Hz] > 0; from their first values after the compensation (re)starts): they are backward differences
    of the estimate, which amplify its noise by ``1 / T`` and ``1 / T^2``. Call before the previous sample's
    time is updated (it reads it)."""
    if cutoff <= 0.0 or not compensation.active:
        memory[HAS_FILTERED_RATES] = 0.0
        return compensation.force_rate, compensation.force_acceleration
    first = memory[HAS_FILTERED_RATES] == 0.0 or memory[HAS_PREVIOUS] == 0.0 or not t > memory[PREVIOUS_TIME]
    gain = 0.0 if first else 1.0 - math.exp(-2.0 * math.pi * cutoff * (t - memory[PREVIOUS_TIME]))
    memory[HAS_FILTERED_RATES] = 1.0
    return (_low_pass3(memory, FILTERED_FORCE_RATE, compensation.force_rate, gain, first),
            _low_pass3(memory, FILTERED_FORCE_ACCELERATION, compensation.force_acceleration, gain, first))


@jit_inline
def _integral_force(params: GeometricParams, memory, t: float, e_p: Vec3) -> Vec3:  # noqa: ANN001
    """``K_i int e_p dt`` [N] (world): the position error integrated over the time since the previous sample,
    unless the last command fell short (:func:`geometric_allocated`), then the integral scaled back so that
    ``|K_i int e_p| <= integral_limit``. Call before the previous sample's time is updated (it reads it)."""
    if memory[HAS_PREVIOUS] != 0.0 and t > memory[PREVIOUS_TIME] and memory[INTEGRAL_HOLD] == 0.0:
        dt = t - memory[PREVIOUS_TIME]
        memory[INTEGRAL] += e_p[0] * dt
        memory[INTEGRAL + 1] += e_p[1] * dt
        memory[INTEGRAL + 2] += e_p[2] * dt
    force = mat_vec3(matrix_at(params.matrices, K_I), (memory[INTEGRAL], memory[INTEGRAL + 1], memory[INTEGRAL + 2]))
    size = math.sqrt(dot3(force, force))
    if size > params.integral_limit:
        scale = params.integral_limit / size
        memory[INTEGRAL] *= scale
        memory[INTEGRAL + 1] *= scale
        memory[INTEGRAL + 2] *= scale
        return force[0] * scale, force[1] * scale, force[2] * scale
    return force


@jit_inline
def geometric_law(params: GeometricParams, memory, t: float, reference: ReferenceSample, position: Vec3,  # noqa: ANN001
                  rotation: Mat3, velocity_world: Vec3, angular_velocity: Vec3, compensation: Compensation) -> tuple:
    """``(status, [0, 0, -u_T], tau_b, R_d)`` of the geometric law (:mod:`fsr_control.controllers.geometric`)."""
    m = params.mass
    k_p, k_v = matrix_at(params.matrices, K_P), matrix_at(params.matrices, K_V)
    inertia = matrix_at(params.matrices, INERTIA)
    e_p = (position[0] - reference.position[0], position[1] - reference.position[1],
           position[2] - reference.position[2])
    e_v = (velocity_world[0] - reference.velocity[0], velocity_world[1] - reference.velocity[1],
           velocity_world[2] - reference.velocity[2])
    a = linear_feedback(k_p, e_p, k_v, e_v, m, reference.acceleration)
    if params.integral:
        force_i = _integral_force(params, memory, t, e_p)
        a = (a[0] - force_i[0], a[1] - force_i[1], a[2] - force_i[2])
    a = (a[0], a[1], a[2] - m * GRAVITY)  # - m g e3
    if compensation.active:
        f_hat = compensation.force
        a = (a[0] - f_hat[0], a[1] - f_hat[1], a[2] - f_hat[2])  # - f_hat (world)
    r = rotation
    z_b = (r[0][2], r[1][2], r[2][2])
    thrust = -dot3(a, z_b)
    w = angular_velocity
    f_dot, f_ddot = _filtered_rates(memory, t, compensation, params.acceleration_cutoff)
    if params.reference_feedforward:  # R_d's rates from the reference alone: m p_dddot_d, m p_ddddot_d
        memory[HAS_PREVIOUS], memory[PREVIOUS_TIME] = 1.0, t
        jerk_d, snap_d = reference.jerk, reference.snap
        a_dot = (m * jerk_d[0], m * jerk_d[1], m * jerk_d[2])
        a_ddot = (m * snap_d[0], m * snap_d[1], m * snap_d[2])
        if compensation.active:
            a_dot = (a_dot[0] - f_dot[0], a_dot[1] - f_dot[1], a_dot[2] - f_dot[2])
            a_ddot = (a_ddot[0] - f_ddot[0], a_ddot[1] - f_ddot[1], a_ddot[2] - f_ddot[2])
    else:  # differentiate a with the measured acceleration and the model's jerk of this thrust
        z_b_dot = mat_vec3(r, (w[1], -w[0], 0.0))  # R S(w) e3
        acceleration = _measured_acceleration(memory, t, velocity_world, thrust, m, z_b, params.acceleration_cutoff)
        acc_d, jerk_d = reference.acceleration, reference.jerk
        e_a = (acceleration[0] - acc_d[0], acceleration[1] - acc_d[1], acceleration[2] - acc_d[2])
        a_dot = linear_feedback(k_p, e_v, k_v, e_a, m, jerk_d)
        if params.integral:  # d/dt of -K_i int e_p
            k_i_e = mat_vec3(matrix_at(params.matrices, K_I), e_p)
            a_dot = (a_dot[0] - k_i_e[0], a_dot[1] - k_i_e[1], a_dot[2] - k_i_e[2])
        if compensation.active:  # the estimate changes too: R_d turns with it (w_d, w_dot_d)
            a_dot = (a_dot[0] - f_dot[0], a_dot[1] - f_dot[1], a_dot[2] - f_dot[2])
        thrust_dot = -dot3(a_dot, z_b) - dot3(a, z_b_dot)
        e_j = (-(thrust_dot * z_b[0] + thrust * z_b_dot[0]) / m - jerk_d[0],
               -(thrust_dot * z_b[1] + thrust * z_b_dot[1]) / m - jerk_d[1],
               -(thrust_dot * z_b[2] + thrust * z_b_dot[2]) / m - jerk_d[2])
        a_ddot = linear_feedback(k_p, e_a, k_v, e_j, m, reference.snap)
        if params.integral:
            k_i_e = mat_vec3(matrix_at(params.matrices, K_I), e_v)
            a_ddot = (a_ddot[0] - k_i_e[0], a_ddot[1] - k_i_e[1], a_ddot[2] - k_i_e[2])
        if compensation.active:
            a_ddot = (a_ddot[0] - f_ddot[0], a_ddot[1] - f_ddot[1], a_ddot[2] - f_ddot[2])
    status, rotation_desired, omega_d, omega_dot_d = attitude_from_thrust_vector(
        (-a[0], -a[1], -a[2]), (-a_dot[0], -a_dot[1], -a_dot[2]), (-a_ddot[0], -a_ddot[1], -a_ddot[2]),
        reference.yaw, reference.yaw_rate, reference.yaw_acceleration,
    )
    relative = mat_t_mat3(r, rotation_desired)  # R_b^T R_d
    omega_d_body = mat_vec3(relative, omega_d)
    e_w = (w[0] - omega_d_body[0], w[1] - omega_d_body[1], w[2] - omega_d_body[2])
    gyro = cross3(w, mat_vec3(inertia, w))
    turn = cross3(w, omega_d_body)
    turn_d = mat_vec3(relative, omega_dot_d)
    feedforward = mat_vec3(inertia, (turn[0] - turn_d[0], turn[1] - turn_d[1], turn[2] - turn_d[2]))
    e_r = attitude_error3(r, rotation_desired)
    k_r, k_w = matrix_at(params.matrices, K_R), matrix_at(params.matrices, K_W)
    feedback = linear_feedback(k_r, e_r, k_w, e_w, 0.0, (0.0, 0.0, 0.0))
    torque = (feedback[0] + gyro[0] - feedforward[0], feedback[1] + gyro[1] - feedforward[1],
              feedback[2] + gyro[2] - feedforward[2])
    if compensation.active:
        tau_hat = compensation.torque
        torque = (torque[0] - tau_hat[0], torque[1] - tau_hat[1], torque[2] - tau_hat[2])
    return status, (0.0, 0.0, -thrust), torque, rotation_desired


@jit_inline
def flown_state(params: GeometricParams, memory, position: Vec3, rotation: Mat3, velocity_world: Vec3,  # noqa: ANN001
                angular_velocity: Vec3, imu) -> tuple:  # noqa: ANN001
    """``(position, R rows, velocity world, angular velocity body)`` the law flies on: ``odom``'s, or where the
    law takes the IMU (``imu`` (6,): angular velocity [rad/s], specific force [m/s^2], body FRD) its gyro's rate
    and, where ``odom`` is a measurement, the IMU-bridged estimate of this step
    (:func:`fsr_control.core.imu_bridge.bridged_state`)."""
    if params.bridge.enabled:
        position, rotation, velocity_world = bridged_state(params.bridge, memory, BRIDGE, position, rotation,
                                                           velocity_world, imu)
    if params.gyro:
        angular_velocity = (imu[0], imu[1], imu[2])
    return position, rotation, velocity_world, angular_velocity


@jit_inline
def geometric_allocated(params: GeometricParams, memory, shortfall) -> None:  # noqa: ANN001
    """After the allocation: hold the integral at the next step while this command fell short (``shortfall``:
    demanded minus produced body wrench, 6 entries) on thrust or roll/pitch torque, the axes the position loop
    acts through (conditional integration; yaw giving way does not hold it)."""
    if params.integral:
        short = False
        for i in range(5):
            if abs(shortfall[i]) > SHORTFALL_TOLERANCE:
                short = True
        memory[INTEGRAL_HOLD] = 1.0 if short else 0.0
