"""The control laws per step (compiled core): geometric (fixed rotors) and Voliro (fully actuated).

:func:`control_law` is the interface the controller's tick calls: the law ``params.kind`` names, given the
reference at ``t``, the reference over the law's horizon (``params.horizon_steps`` rows at ``t + dt, ...,
t + N dt``, ``dt = params.horizon_dt``, laid out as in :mod:`fsr_control.core.reference`; no rows for a law
that does not look ahead), the state and the compensation. A new law is its function (in a core file of
its own), a branch in :func:`control_law` and an entry in :data:`fsr_control.controllers.catalog.LAWS`
(``docs/extending.md``).

Each law takes the reference, the state (position and velocity world NED [m, m/s], ``R`` rows body FRD -> world,
angular velocity body [rad/s]) and, with ``controller.compensation: estimate``, the estimated external wrench
to cancel (:class:`Compensation`), and return ``(status, force_body, torque_body, R_c)``: the body wrench
[N, N m] to produce and the attitude the law steers to. Their equations and the reasons behind them are in
:mod:`fsr_control.controllers.geometric` and :mod:`fsr_control.controllers.voliro` (the Python shells).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_control.core.flatness import ATTITUDE_OK, attitude_from_thrust_vector
from fsr_control.core.reference import ReferenceSample
from fsr_sim.core.jit import jit, jit_inline
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.core.so3 import (
    Mat3,
    Vec3,
    attitude_error3,
    cross3,
    dot3,
    mat_t_mat3,
    mat_t_vec3,
    mat_vec3,
    matrix_rows,
)

# LawState.memory entries: the geometric law's previous sample, its filtered measured acceleration and the
# filtered rates of the compensated estimate (vectors: 3 entries)
HAS_PREVIOUS, PREVIOUS_TIME, PREVIOUS_VELOCITY, FILTERED_ACCELERATION = 0, 1, 2, 5
HAS_FILTERED_RATES, FILTERED_FORCE_RATE, FILTERED_FORCE_ACCELERATION = 8, 9, 12
MEMORY_SIZE = 15


# LawParams.kind
GEOMETRIC, VOLIRO = 0, 1


class LawParams(NamedTuple):
    kind: int  # which law (GEOMETRIC, VOLIRO, ...)
    mass: float  # nominal mass [kg]
    inertia: np.ndarray  # (3, 3) nominal inertia [kg m^2]
    k_p: np.ndarray  # (3, 3)
    k_v: np.ndarray  # (3, 3): K_v (geometric) or K_d (Voliro)
    k_r: np.ndarray  # (3, 3)
    k_w: np.ndarray  # (3, 3)
    report_feedforward: bool  # Voliro: the report's angular feed-forward
    horizon_steps: int  # reference samples ahead the law reads (0: none)
    horizon_dt: float  # their spacing [s]
    acceleration_cutoff: float  # [Hz] of the first-order low-pass on the measured acceleration and on the
    # compensated estimate's rates (0: none)


class Compensation(NamedTuple):
    """The estimated external wrench a law cancels: force [N] world NED, torque [N m] body FRD, and the force's
    first and second time differences [N/s, N/s^2] (world); ``active`` False: the law as written."""

    active: bool
    force: Vec3
    torque: Vec3
    force_rate: Vec3
    force_acceleration: Vec3


NO_COMPENSATION = Compensation(False, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


@jit
def linear_feedback(k_a: Mat3, e_a: Vec3, k_b: Mat3, e_b: Vec3, scale: float, feedforward: Vec3) -> Vec3:
    """``-K_a e_a - K_b e_b + scale * feedforward`` (the PD terms of both laws)."""
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = k_a
    (b00, b01, b02), (b10, b11, b12), (b20, b21, b22) = k_b
    x, y, z = e_a
    u, v, w = e_b
    fx, fy, fz = feedforward
    return (
        -(a00 * x + a01 * y + a02 * z) - (b00 * u + b01 * v + b02 * w) + scale * fx,
        -(a10 * x + a11 * y + a12 * z) - (b10 * u + b11 * v + b12 * w) + scale * fy,
        -(a20 * x + a21 * y + a22 * z) - (b20 * u + b21 * v + b22 * w) + scale * fz,
    )


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
    of the estimate, which amplify its noise by ``1 / T`` and ``1 / T^2``. Call before the measured acceleration
    (it reads the previous sample's time)."""
    if cutoff <= 0.0 or not compensation.active:
        memory[HAS_FILTERED_RATES] = 0.0
        return compensation.force_rate, compensation.force_acceleration
    first = memory[HAS_FILTERED_RATES] == 0.0 or memory[HAS_PREVIOUS] == 0.0 or not t > memory[PREVIOUS_TIME]
    gain = 0.0 if first else 1.0 - math.exp(-2.0 * math.pi * cutoff * (t - memory[PREVIOUS_TIME]))
    memory[HAS_FILTERED_RATES] = 1.0
    return (_low_pass3(memory, FILTERED_FORCE_RATE, compensation.force_rate, gain, first),
            _low_pass3(memory, FILTERED_FORCE_ACCELERATION, compensation.force_acceleration, gain, first))


@jit_inline
def geometric_law(params: LawParams, memory, t: float, reference: ReferenceSample, position: Vec3,  # noqa: ANN001
                  rotation: Mat3, velocity_world: Vec3, angular_velocity: Vec3, compensation: Compensation) -> tuple:
    """``(status, [0, 0, -u_T], tau_b, R_d)`` of the geometric law (:mod:`fsr_control.controllers.geometric`)."""
    m = params.mass
    k_p, k_v = matrix_rows(params.k_p), matrix_rows(params.k_v)
    inertia = matrix_rows(params.inertia)
    e_p = (position[0] - reference.position[0], position[1] - reference.position[1],
           position[2] - reference.position[2])
    e_v = (velocity_world[0] - reference.velocity[0], velocity_world[1] - reference.velocity[1],
           velocity_world[2] - reference.velocity[2])
    a = linear_feedback(k_p, e_p, k_v, e_v, m, reference.acceleration)
    a = (a[0], a[1], a[2] - m * GRAVITY)  # - m g e3
    if compensation.active:
        f_hat = compensation.force
        a = (a[0] - f_hat[0], a[1] - f_hat[1], a[2] - f_hat[2])  # - f_hat (world)
    r = rotation
    z_b = (r[0][2], r[1][2], r[2][2])
    thrust = -dot3(a, z_b)
    # R_d and its rates: differentiate a with the measured acceleration and the model's jerk of this thrust.
    w = angular_velocity
    z_b_dot = mat_vec3(r, (w[1], -w[0], 0.0))  # R S(w) e3
    f_dot, f_ddot = _filtered_rates(memory, t, compensation, params.acceleration_cutoff)
    acceleration = _measured_acceleration(memory, t, velocity_world, thrust, m, z_b, params.acceleration_cutoff)
    acc_d, jerk_d = reference.acceleration, reference.jerk
    e_a = (acceleration[0] - acc_d[0], acceleration[1] - acc_d[1], acceleration[2] - acc_d[2])
    a_dot = linear_feedback(k_p, e_v, k_v, e_a, m, jerk_d)
    if compensation.active:  # the estimate changes too: R_d turns with it (w_d, w_dot_d)
        a_dot = (a_dot[0] - f_dot[0], a_dot[1] - f_dot[1], a_dot[2] - f_dot[2])
    thrust_dot = -dot3(a_dot, z_b) - dot3(a, z_b_dot)
    e_j = (-(thrust_dot * z_b[0] + thrust * z_b_dot[0]) / m - jerk_d[0],
           -(thrust_dot * z_b[1] + thrust * z_b_dot[1]) / m - jerk_d[1],
           -(thrust_dot * z_b[2] + thrust * z_b_dot[2]) / m - jerk_d[2])
    a_ddot = linear_feedback(k_p, e_a, k_v, e_j, m, reference.snap)
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
    feedback = linear_feedback(matrix_rows(params.k_r), e_r, matrix_rows(params.k_w), e_w, 0.0, (0.0, 0.0, 0.0))
    torque = (feedback[0] + gyro[0] - feedforward[0], feedback[1] + gyro[1] - feedforward[1],
              feedback[2] + gyro[2] - feedforward[2])
    if compensation.active:
        tau_hat = compensation.torque
        torque = (torque[0] - tau_hat[0], torque[1] - tau_hat[1], torque[2] - tau_hat[2])
    return status, (0.0, 0.0, -thrust), torque, rotation_desired


@jit_inline
def voliro_law(params: LawParams, reference: ReferenceSample, position: Vec3, rotation: Mat3,
               velocity_world: Vec3, angular_velocity: Vec3, compensation: Compensation) -> tuple:
    """``(status, f_b, tau_b, R_d)`` of the Voliro law (:mod:`fsr_control.controllers.voliro`): the body wrench
    ``[R_b^T m (v - g e3); I_b w + w_b x I_b w_b]`` (minus the compensated wrench)."""
    e_p = (position[0] - reference.position[0], position[1] - reference.position[1],
           position[2] - reference.position[2])
    e_v = (velocity_world[0] - reference.velocity[0], velocity_world[1] - reference.velocity[1],
           velocity_world[2] - reference.velocity[2])
    v = linear_feedback(matrix_rows(params.k_p), e_p, matrix_rows(params.k_v), e_v, 1.0, reference.acceleration)
    r = rotation
    rotation_desired = reference.rotation
    relative = mat_t_mat3(r, rotation_desired)  # R_b^T R_d
    w_b = angular_velocity
    omega_d_body = mat_vec3(relative, reference.angular_velocity)
    omega_dot_d_body = mat_vec3(relative, reference.angular_acceleration)
    e_r = attitude_error3(r, rotation_desired)
    e_w = (w_b[0] - omega_d_body[0], w_b[1] - omega_d_body[1], w_b[2] - omega_d_body[2])
    feedback = linear_feedback(matrix_rows(params.k_r), e_r, matrix_rows(params.k_w), e_w, 0.0, (0.0, 0.0, 0.0))
    turn = cross3(w_b, omega_d_body)
    inertia = matrix_rows(params.inertia)
    if params.report_feedforward:
        ff = mat_vec3(inertia, (turn[0] + omega_dot_d_body[0], turn[1] + omega_dot_d_body[1],
                                turn[2] + omega_dot_d_body[2]))
        w = (feedback[0] + ff[0], feedback[1] + ff[1], feedback[2] + ff[2])
    else:
        w = (feedback[0] - turn[0] + omega_dot_d_body[0], feedback[1] - turn[1] + omega_dot_d_body[1],
             feedback[2] - turn[2] + omega_dot_d_body[2])
    m = params.mass
    inertia_w = mat_vec3(inertia, w)
    gyro = cross3(w_b, mat_vec3(inertia, w_b))
    if compensation.active:
        fx, fy, fz = compensation.force
        tx, ty, tz = compensation.torque
        force = mat_t_vec3(r, (m * v[0] - fx, m * v[1] - fy, m * (v[2] - GRAVITY) - fz))
        torque = (inertia_w[0] + gyro[0] - tx, inertia_w[1] + gyro[1] - ty, inertia_w[2] + gyro[2] - tz)
        return ATTITUDE_OK, force, torque, rotation_desired
    force_body = mat_t_vec3(r, (v[0], v[1], v[2] - GRAVITY))
    return (ATTITUDE_OK, (m * force_body[0], m * force_body[1], m * force_body[2]),
            (inertia_w[0] + gyro[0], inertia_w[1] + gyro[1], inertia_w[2] + gyro[2]), rotation_desired)


@jit_inline
def control_law(params: LawParams, memory, horizon, t: float, reference: ReferenceSample,  # noqa: ANN001
                position: Vec3, rotation: Mat3, velocity_world: Vec3, angular_velocity: Vec3,
                compensation: Compensation) -> tuple:
    """``(status, force_body, torque_body, R_c)`` of the law ``params.kind`` (module docstring): ``memory`` the
    law's own (``MEMORY_SIZE``), ``horizon`` the reference ahead (``params.horizon_steps`` rows)."""
    if params.kind == VOLIRO:
        return voliro_law(params, reference, position, rotation, velocity_world, angular_velocity, compensation)
    # a new law: its branch here, e.g. ``if params.kind == MY_LAW: return my_law(params, horizon, ...)``
    return geometric_law(params, memory, t, reference, position, rotation, velocity_world, angular_velocity,
                         compensation)
