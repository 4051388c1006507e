"""Incremental nonlinear dynamic inversion per step (compiled core): thrust along ``-z_b`` and a body torque, for
fixed rotors, from the vehicle's own measurements.

Its equations are in :mod:`fsr_control.controllers.indi` (the Python shell); its parameters are
:class:`IndiParams`, its memory the geometric law's ``MEMORY_SIZE`` entries (the geometric law runs on it)
followed by the filter's states laid out below.

Every signal the increment uses passes through the same second-order low-pass (``IndiParams.filter``: the
exact discretisation ``x <- Phi x + Gamma u`` of ``y_ddot = w_n^2 (u - y) - 2 zeta w_n y_dot``, ``x = (y,
y_dot)``), so that they are synchronous: the IMU's angular velocity (its filtered derivative is the angular
acceleration), the IMU's specific force, and the rotors' force and torque (their measured speeds through the
nominal allocation, or without ``rotor_state`` the wrench commanded at the previous step). The increment is
then the external wrench the filtered signals imply, handed to the geometric law with reference feed-forward as
its compensation (:func:`fsr_control.core.geometric_law.geometric_law`); the rates of ``R_d`` are the
reference's alone (its jerk and snap): nothing measured is differentiated into them.

The attitude loop damps with the gyro (the IMU's angular velocity, not ``odom``'s). Where ``odom`` is a
measurement (``IndiParams.predict``: noisy, late or slower than the control rate), the law flies on its own
estimate of the pose and velocity at the current step (:func:`_estimate`): the IMU integrated (strapdown) from
step to step, corrected at each new ``odom`` sample towards it by the share ``IndiParams.correction`` of the
difference to the estimate of the step that sample measured (``IndiParams.delay`` steps back), so that the
sample's delay and hold are bridged by the IMU and its noise is averaged.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_control.core import geometric_law as geometric
from fsr_control.core.geometric_law import GeometricParams
from fsr_control.core.law_terms import INERTIA, Compensation, matrix_at
from fsr_control.core.reference import ReferenceSample
from fsr_sim.core.jit import jit_inline
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.core.rotors import measured_rotor_wrench
from fsr_sim.core.so3 import Mat3, Vec3, cross3, mat_t_mat3, mat_vec3

MATRICES = geometric.MATRICES  # the geometric law's: inertia, K_p, K_v, K_i, K_R, K_W
FILTER_SIZE = 6  # IndiParams.filter: Phi (2 x 2, row by row), then Gamma (2)


class IndiParams(NamedTuple):
    mass: float  # nominal mass [kg]
    matrices: np.ndarray  # (6, 3, 3): MATRICES, matrices[INERTIA] the inertia
    integral: bool  # the integral term is on (k_i != 0)
    integral_limit: float  # [N] bound on |K_i int e_p| (anti-windup)
    filter: np.ndarray  # (FILTER_SIZE,): the low-pass's Phi and Gamma at the control period
    allocation: np.ndarray  # (6, n) nominal wrench per signed squared rotor speed [N, N m per (rad/s)^2]
    c_f: float  # thrust coefficient [N s^2]
    rotor_state: bool  # the rotors' speeds are measured (rotor_state); False: the previous command's wrench
    period: float  # [s] the control period (the estimate's integration step)
    predict: bool  # odom is a measurement: fly on the IMU-propagated estimate (_estimate); False: odom as it is
    delay: int  # steps odom's samples are late by (<= HISTORY - 1)
    correction: float  # in (0, 1]: the share of the difference to a new odom sample the estimate takes

    @classmethod
    def unused(cls) -> IndiParams:
        """Placeholder parameters, for a controller that flies another law."""
        return cls(0.0, np.zeros((len(MATRICES), 3, 3)), False, 0.0, np.zeros(FILTER_SIZE), np.zeros((6, 0)), 0.0,
                   False, 0.0, False, 0, 0.0)


# memory after the geometric law's: whether the filter holds a sample, whether a command was recorded, the
# previous step's commanded wrench (force, torque: 6), then per filtered signal (angular velocity, specific force,
# rotor force, rotor torque) its 3 values and their 3 rates
HAS_FILTER, HAS_COMMAND = geometric.MEMORY_SIZE, geometric.MEMORY_SIZE + 1
COMMAND = geometric.MEMORY_SIZE + 2
FILTERS = COMMAND + 6
ANGULAR_VELOCITY, SPECIFIC_FORCE, ROTOR_FORCE, ROTOR_TORQUE = range(4)
FILTER_STATES = 6  # per signal: 3 values, then 3 rates
# the estimate (IndiParams.predict): whether it is started, the step count, the last odom sample (position,
# velocity world, R row by row: POSE_SIZE), the previous step's IMU sample, then the estimate of each of the last
# HISTORY steps (the step k at slot k % HISTORY, the current one last written)
POSE_SIZE = 15
HISTORY = 64  # steps of estimates kept: the longest odometry delay bridged is HISTORY - 1 steps
HAS_ESTIMATE = FILTERS + 4 * FILTER_STATES
ESTIMATE_STEP = HAS_ESTIMATE + 1
LAST_SAMPLE = ESTIMATE_STEP + 1
PREVIOUS_IMU = LAST_SAMPLE + POSE_SIZE
ESTIMATES = PREVIOUS_IMU + 6
MEMORY_SIZE = ESTIMATES + HISTORY * POSE_SIZE


@jit_inline
def _filtered(params: IndiParams, memory, signal: int, value: Vec3, first: bool) -> tuple:  # noqa: ANN001
    """Step the low-pass of ``signal`` with the sample ``value`` (``first``: start at rest on it); returns its
    (value, rate)."""
    at = FILTERS + FILTER_STATES * signal
    f = params.filter
    for i in range(3):
        if first:
            memory[at + i], memory[at + 3 + i] = value[i], 0.0
        else:
            y, y_dot = memory[at + i], memory[at + 3 + i]
            memory[at + i] = f[0] * y + f[1] * y_dot + f[4] * value[i]
            memory[at + 3 + i] = f[2] * y + f[3] * y_dot + f[5] * value[i]
    return ((memory[at], memory[at + 1], memory[at + 2]), (memory[at + 3], memory[at + 4], memory[at + 5]))


@jit_inline
def _exp_rows(x: float, y: float, z: float) -> Mat3:
    """``Exp([x, y, z])``: the rotation by the rotation vector (Rodrigues)."""
    angle = math.sqrt(x * x + y * y + z * z)
    if angle < 1e-9:
        a, b = 1.0, 0.5
    else:
        a, b = math.sin(angle) / angle, (1.0 - math.cos(angle)) / (angle * angle)
    return ((1.0 - b * (y * y + z * z), -a * z + b * x * y, a * y + b * x * z),
            (a * z + b * x * y, 1.0 - b * (x * x + z * z), -a * x + b * y * z),
            (-a * y + b * x * z, a * x + b * y * z, 1.0 - b * (x * x + y * y)))


@jit_inline
def _mat_mat3(a: Mat3, b: Mat3) -> Mat3:
    return ((a[0][0] * b[0][0] + a[0][1] * b[1][0] + a[0][2] * b[2][0],
             a[0][0] * b[0][1] + a[0][1] * b[1][1] + a[0][2] * b[2][1],
             a[0][0] * b[0][2] + a[0][1] * b[1][2] + a[0][2] * b[2][2]),
            (a[1][0] * b[0][0] + a[1][1] * b[1][0] + a[1][2] * b[2][0],
             a[1][0] * b[0][1] + a[1][1] * b[1][1] + a[1][2] * b[2][1],
             a[1][0] * b[0][2] + a[1][1] * b[1][2] + a[1][2] * b[2][2]),
            (a[2][0] * b[0][0] + a[2][1] * b[1][0] + a[2][2] * b[2][0],
             a[2][0] * b[0][1] + a[2][1] * b[1][1] + a[2][2] * b[2][1],
             a[2][0] * b[0][2] + a[2][1] * b[1][2] + a[2][2] * b[2][2]))


@jit_inline
def _put_pose(memory, at: int, position: Vec3, velocity: Vec3, rotation: Mat3) -> None:  # noqa: ANN001
    for i in range(3):
        memory[at + i], memory[at + 3 + i] = position[i], velocity[i]
        for j in range(3):
            memory[at + 6 + 3 * i + j] = rotation[i][j]


@jit_inline
def _pose(memory, at: int) -> tuple:  # noqa: ANN001
    """``(position, velocity, R rows)`` stored from ``at``."""
    r = at + 6
    return ((memory[at], memory[at + 1], memory[at + 2]), (memory[at + 3], memory[at + 4], memory[at + 5]),
            ((memory[r], memory[r + 1], memory[r + 2]), (memory[r + 3], memory[r + 4], memory[r + 5]),
             (memory[r + 6], memory[r + 7], memory[r + 8])))


@jit_inline
def _estimate(params: IndiParams, memory, position: Vec3, rotation: Mat3, velocity_world: Vec3,  # noqa: ANN001
              imu) -> tuple:  # noqa: ANN001
    """``(position, R rows, velocity world)`` of the vehicle at this step (module docstring), from ``odom``'s
    sample (held, ``params.delay`` steps late) and the IMU (``imu``: angular velocity [rad/s], specific force
    [m/s^2], body FRD, of this step).

    Propagation over the period ``T`` (trapezoidal, the previous and this IMU sample ``(w', s')``, ``(w, s)``):
    ``R <- R Exp((w' + w) T / 2)``, ``v <- v + (R' s' + R s) T / 2 + g e3 T``, ``p <- p + (v' + v) T / 2``.
    A new sample (any number differs from the last one) measures the step ``k - delay``: with the estimate
    ``(p_k', v_k', R_k')`` kept for that step, the correction ``c = correction`` moves the estimate of that step
    and of every later one by ``c (p_o - p_k')``, ``c (v_o - v_k')`` and ``R <- Exp(c theta) R`` with
    ``Exp(theta) = R_o R_k'^T`` (small angles: ``theta`` the vee of the skew part)."""
    gyro = (imu[0], imu[1], imu[2])
    specific_force = (imu[3], imu[4], imu[5])
    if memory[HAS_ESTIMATE] == 0.0:
        memory[HAS_ESTIMATE], memory[ESTIMATE_STEP] = 1.0, 0.0
        _put_pose(memory, LAST_SAMPLE, position, velocity_world, rotation)
        _put_pose(memory, ESTIMATES, position, velocity_world, rotation)
        for i in range(6):
            memory[PREVIOUS_IMU + i] = imu[i]
        return position, rotation, velocity_world
    step = int(memory[ESTIMATE_STEP])
    p, v, r = _pose(memory, ESTIMATES + POSE_SIZE * (step % HISTORY))
    dt = params.period
    gyro_p = (memory[PREVIOUS_IMU], memory[PREVIOUS_IMU + 1], memory[PREVIOUS_IMU + 2])
    force_p = (memory[PREVIOUS_IMU + 3], memory[PREVIOUS_IMU + 4], memory[PREVIOUS_IMU + 5])
    r_new = _mat_mat3(r, _exp_rows(0.5 * dt * (gyro_p[0] + gyro[0]), 0.5 * dt * (gyro_p[1] + gyro[1]),
                                   0.5 * dt * (gyro_p[2] + gyro[2])))
    a_p, a_n = mat_vec3(r, force_p), mat_vec3(r_new, specific_force)
    v_new = (v[0] + 0.5 * dt * (a_p[0] + a_n[0]), v[1] + 0.5 * dt * (a_p[1] + a_n[1]),
             v[2] + 0.5 * dt * (a_p[2] + a_n[2]) + GRAVITY * dt)
    p_new = (p[0] + 0.5 * dt * (v[0] + v_new[0]), p[1] + 0.5 * dt * (v[1] + v_new[1]),
             p[2] + 0.5 * dt * (v[2] + v_new[2]))
    step += 1
    memory[ESTIMATE_STEP] = float(step)
    _put_pose(memory, ESTIMATES + POSE_SIZE * (step % HISTORY), p_new, v_new, r_new)
    for i in range(6):
        memory[PREVIOUS_IMU + i] = imu[i]
    last_p, last_v, last_r = _pose(memory, LAST_SAMPLE)
    new = False
    for i in range(3):
        if position[i] != last_p[i] or velocity_world[i] != last_v[i]:
            new = True
        for j in range(3):
            if rotation[i][j] != last_r[i][j]:
                new = True
    if new:
        _put_pose(memory, LAST_SAMPLE, position, velocity_world, rotation)
        back = min(params.delay, step, HISTORY - 1)
        p_k, v_k, r_k = _pose(memory, ESTIMATES + POSE_SIZE * ((step - back) % HISTORY))
        c = params.correction
        dp = (c * (position[0] - p_k[0]), c * (position[1] - p_k[1]), c * (position[2] - p_k[2]))
        dv = (c * (velocity_world[0] - v_k[0]), c * (velocity_world[1] - v_k[1]),
              c * (velocity_world[2] - v_k[2]))
        e = mat_t_mat3(r_k, rotation)  # R_k'^T R_o; R_o R_k'^T = R_k' e R_k'^T: the world-frame angle
        body = (0.5 * (e[2][1] - e[1][2]), 0.5 * (e[0][2] - e[2][0]), 0.5 * (e[1][0] - e[0][1]))
        world = mat_vec3(r_k, body)
        turn = _exp_rows(c * world[0], c * world[1], c * world[2])
        for k in range(step - back, step + 1):
            at = ESTIMATES + POSE_SIZE * (k % HISTORY)
            pk, vk, rk = _pose(memory, at)
            _put_pose(memory, at, (pk[0] + dp[0], pk[1] + dp[1], pk[2] + dp[2]),
                      (vk[0] + dv[0], vk[1] + dv[1], vk[2] + dv[2]), _mat_mat3(turn, rk))
    p_now, v_now, r_now = _pose(memory, ESTIMATES + POSE_SIZE * (step % HISTORY))
    return p_now, r_now, v_now


@jit_inline
def indi_law(params: IndiParams, memory, t: float, reference: ReferenceSample, position: Vec3,  # noqa: ANN001
             rotation: Mat3, velocity_world: Vec3, angular_velocity: Vec3, imu, speeds, tilts) -> tuple:  # noqa: ANN001
    """``(status, [0, 0, -u_T], tau_b, R_d)`` of INDI (:mod:`fsr_control.controllers.indi`): ``imu`` (6,) the
    IMU's angular velocity [rad/s] and specific force [m/s^2] (body FRD), ``speeds``, ``tilts`` (n,) the rotors'
    (``rotor_state``)."""
    if params.predict:
        position, rotation, velocity_world = _estimate(params, memory, position, rotation, velocity_world, imu)
    m = params.mass
    inertia = matrix_at(params.matrices, INERTIA)
    gyro = (imu[0], imu[1], imu[2])
    specific_force = (imu[3], imu[4], imu[5])
    first = memory[HAS_FILTER] == 0.0
    if params.rotor_state:
        force_r, torque_r = measured_rotor_wrench(params.allocation, params.c_f, False, speeds, tilts)
    elif memory[HAS_COMMAND] != 0.0:
        c = COMMAND
        force_r = (memory[c], memory[c + 1], memory[c + 2])
        torque_r = (memory[c + 3], memory[c + 4], memory[c + 5])
    else:  # no command yet: the rotors are taken to hold the vehicle as measured (no external wrench)
        force_r = (m * specific_force[0], m * specific_force[1], m * specific_force[2])
        torque_r = cross3(gyro, mat_vec3(inertia, gyro))
    omega_f, omega_dot_f = _filtered(params, memory, ANGULAR_VELOCITY, gyro, first)
    force_f = _filtered(params, memory, SPECIFIC_FORCE, specific_force, first)[0]
    rotor_force_f = _filtered(params, memory, ROTOR_FORCE, force_r, first)[0]
    rotor_torque_f = _filtered(params, memory, ROTOR_TORQUE, torque_r, first)[0]
    memory[HAS_FILTER] = 1.0
    # m s = f_rotors + f_ext (body) and I w_dot + w x I w = tau_rotors + tau_ext, on the filtered signals
    external_body = (m * force_f[0] - rotor_force_f[0], m * force_f[1] - rotor_force_f[1],
                     m * force_f[2] - rotor_force_f[2])
    inertia_rate = mat_vec3(inertia, omega_dot_f)
    gyroscopic = cross3(omega_f, mat_vec3(inertia, omega_f))
    external_torque = (inertia_rate[0] + gyroscopic[0] - rotor_torque_f[0],
                       inertia_rate[1] + gyroscopic[1] - rotor_torque_f[1],
                       inertia_rate[2] + gyroscopic[2] - rotor_torque_f[2])
    zero = (0.0, 0.0, 0.0)
    # R_d's rates from the reference alone: the increment's rate is not fed forward (a rate of the measured
    # force turns R_d with every rotor-speed change the aerodynamics feel, a loop that tumbles the vehicle)
    increment = Compensation(True, mat_vec3(rotation, external_body), external_torque, zero, zero)
    own = GeometricParams(m, params.matrices, params.integral, params.integral_limit, True, 0.0)
    return geometric.geometric_law(own, memory, t, reference, position, rotation, velocity_world, gyro, increment)


@jit_inline
def indi_allocated(params: IndiParams, memory, force: Vec3, torque: Vec3, shortfall) -> None:  # noqa: ANN001
    """After the allocation: keep the wrench the command produces (``force``, ``torque``, body [N, N m]) for the
    next step's increment (without ``rotor_state``), and hold the integral as the geometric law does."""
    c = COMMAND
    memory[c], memory[c + 1], memory[c + 2] = force
    memory[c + 3], memory[c + 4], memory[c + 5] = torque
    memory[HAS_COMMAND] = 1.0
    geometric.geometric_allocated(GeometricParams(params.mass, params.matrices, params.integral,
                                                  params.integral_limit, True, 0.0), memory, shortfall)
