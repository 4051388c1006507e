"""The geometric law per step (compiled core): thrust along ``-z_b`` and a body torque, for fixed rotors.

Its equations, the two feed-forwards of its desired rates and the integral term are in
:mod:`fsr_control.controllers.geometric` (the Python shell); its parameters are :class:`GeometricParams`, its
memory the :data:`GEOMETRIC_MEMORY` record (``LawMemory.geometric``) and, flying on the IMU, the IMU bridge's
(``LawMemory.bridge``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_control.core.flatness import attitude_from_thrust_vector
from fsr_control.core.imu_bridge import BridgeParams, bridged_state
from fsr_control.core.law_terms import INERTIA, Compensation, VehicleState, linear_feedback, matrix_at
from fsr_control.core.reference import ReferenceSample
from fsr_sim.core.jit import jit_inline
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.core.rotors import SHORTFALL_TOLERANCE
from fsr_sim.core.so3 import Vec3, attitude_error3, cross3, dot3, mat_t_mat3, mat_vec3

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


GEOMETRIC_MEMORY = np.dtype([
    ("has_previous", np.bool_),  # a previous sample was seen
    ("previous_time", np.float64),  # its time [s]
    ("previous_velocity", np.float64, (3,)),  # its velocity world [m/s]
    ("filtered_acceleration", np.float64, (3,)),  # the measured acceleration's low-pass [m/s^2]
    ("has_filtered_rates", np.bool_),  # the compensated estimate's rates are filtered from a first value
    ("filtered_force_rate", np.float64, (3,)),  # [N/s]
    ("filtered_force_acceleration", np.float64, (3,)),  # [N/s^2]
    ("integral", np.float64, (3,)),  # the position error's integral [m s]
    ("integral_hold", np.bool_),  # the last command fell short on thrust or roll/pitch torque
], align=True)
"""The geometric law's memory (``LawMemory.geometric[0]``), kept between steps."""


@jit_inline
def _measured_acceleration(memory, t: float, velocity_world: Vec3, thrust: float, mass: float,  # noqa: ANN001
                           z_b: Vec3, cutoff: float) -> Vec3:
    """Acceleration [m/s^2] from consecutive velocities (includes unmodelled forces); the model's
    ``g e3 - u_T z_b / m`` at the first step or when time does not advance. With a ``cutoff`` [Hz] > 0, through
    a first-order low-pass ``a_f <- a_f + (1 - exp(-2 pi f_c dt)) (a - a_f)`` (from the model's value at the
    first step): a difference of measured velocities amplifies their noise by ``1 / dt``."""
    has_previous, previous_time = memory.has_previous, memory.previous_time
    previous = memory.previous_velocity
    vx, vy, vz = previous[0], previous[1], previous[2]
    memory.has_previous, memory.previous_time = True, t
    previous[0], previous[1], previous[2] = velocity_world
    f = memory.filtered_acceleration
    if has_previous and t > previous_time:
        dt = t - previous_time
        raw = ((velocity_world[0] - vx) / dt, (velocity_world[1] - vy) / dt, (velocity_world[2] - vz) / dt)
        if cutoff <= 0.0:
            return raw
        gain = 1.0 - math.exp(-2.0 * math.pi * cutoff * dt)
        f[0] += gain * (raw[0] - f[0])
        f[1] += gain * (raw[1] - f[1])
        f[2] += gain * (raw[2] - f[2])
        return f[0], f[1], f[2]
    scale = thrust / mass
    model = (-scale * z_b[0], -scale * z_b[1], GRAVITY - scale * z_b[2])
    f[0], f[1], f[2] = model
    return model


@jit_inline
def _low_pass3(y, value: Vec3, gain: float, first: bool) -> Vec3:  # noqa: ANN001
    """``y <- y + gain (value - y)`` on the 3 entries of ``y`` (``first``: ``y = value``)."""
    for i in range(3):
        if first:
            y[i] = value[i]
        else:
            y[i] += gain * (value[i] - y[i])
    return y[0], y[1], y[2]


@jit_inline
def _filtered_rates(memory, t: float, compensation: Compensation, cutoff: float) -> tuple:  # noqa: ANN001
    """The compensated estimate's rate and second rate [N/s, N/s^2] through the measured acceleration's low-pass
    (cutoff [Hz] > 0; from their first values after the compensation (re)starts): they are backward differences
    of the estimate, which amplify its noise by ``1 / T`` and ``1 / T^2``. Call before the previous sample's
    time is updated (it reads it)."""
    if cutoff <= 0.0 or not compensation.active:
        memory.has_filtered_rates = False
        return compensation.force_rate, compensation.force_acceleration
    first = not memory.has_filtered_rates or not memory.has_previous or not t > memory.previous_time
    gain = 0.0 if first else 1.0 - math.exp(-2.0 * math.pi * cutoff * (t - memory.previous_time))
    memory.has_filtered_rates = True
    return (_low_pass3(memory.filtered_force_rate, compensation.force_rate, gain, first),
            _low_pass3(memory.filtered_force_acceleration, compensation.force_acceleration, gain, first))


@jit_inline
def _integral_force(params: GeometricParams, memory, t: float, e_p: Vec3) -> Vec3:  # noqa: ANN001
    """``K_i int e_p dt`` [N] (world): the position error integrated over the time since the previous sample,
    unless the last command fell short (:func:`geometric_allocated`), then the integral scaled back so that
    ``|K_i int e_p| <= integral_limit``. Call before the previous sample's time is updated (it reads it)."""
    integral = memory.integral
    if memory.has_previous and t > memory.previous_time and not memory.integral_hold:
        dt = t - memory.previous_time
        integral[0] += e_p[0] * dt
        integral[1] += e_p[1] * dt
        integral[2] += e_p[2] * dt
    force = mat_vec3(matrix_at(params.matrices, K_I), (integral[0], integral[1], integral[2]))
    size = math.sqrt(dot3(force, force))
    if size > params.integral_limit:
        scale = params.integral_limit / size
        integral[0] *= scale
        integral[1] *= scale
        integral[2] *= scale
        return force[0] * scale, force[1] * scale, force[2] * scale
    return force


@jit_inline
def geometric_law(params: GeometricParams, memory, t: float, reference: ReferenceSample,  # noqa: ANN001
                  state: VehicleState, compensation: Compensation) -> tuple:
    """``(status, [0, 0, -u_T], tau_b, R_d)`` of the geometric law (:mod:`fsr_control.controllers.geometric`);
    ``memory`` its :data:`GEOMETRIC_MEMORY` record."""
    position, rotation, velocity_world, angular_velocity = state
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
        memory.has_previous, memory.previous_time = True, t
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
def flown_state(params: GeometricParams, bridge_memory, state: VehicleState, imu) -> VehicleState:  # noqa: ANN001
    """The state the law flies on: ``odom``'s (``state``), or where the law takes the IMU (``imu`` (6,): angular
    velocity [rad/s], specific force [m/s^2], body FRD) its gyro's rate and, where ``odom`` is a measurement, the
    IMU-bridged estimate of this step (:func:`fsr_control.core.imu_bridge.bridged_state`, on its
    :data:`~fsr_control.core.imu_bridge.BRIDGE_MEMORY` record ``bridge_memory``)."""
    position, rotation, velocity_world, angular_velocity = state
    if params.bridge.enabled:
        position, rotation, velocity_world = bridged_state(params.bridge, bridge_memory, position, rotation,
                                                           velocity_world, imu)
    if params.gyro:
        angular_velocity = (imu[0], imu[1], imu[2])
    return VehicleState(position, rotation, velocity_world, angular_velocity)


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
        memory.integral_hold = short
