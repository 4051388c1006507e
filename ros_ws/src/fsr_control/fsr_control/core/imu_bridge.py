"""The vehicle's pose and velocity at the current step from a late, held ``odom`` and the IMU (compiled core):
what a law flies on where ``odom`` is a measurement (noisy, late or slower than the control rate).

The IMU is integrated (strapdown) from step to step and, at each new ``odom`` sample, the estimate is moved
towards it by the share :attr:`BridgeParams.correction` of the difference to the estimate of the step that sample
measured (:attr:`BridgeParams.delay` steps back): the sample's delay and hold are bridged by the IMU and its
noise is averaged. Used by the geometric law of ``controller.profile: flight`` when the vehicle has an IMU
(:mod:`fsr_control.core.geometric_law`) and by INDI (:mod:`fsr_control.core.indi_law`).

Memory (the :data:`BRIDGE_MEMORY` record, ``LawMemory.bridge``): whether the estimate is started, the step
count, the last ``odom`` sample (a pose: position, velocity world, ``R`` row by row, :data:`POSE_SIZE` numbers),
the previous step's IMU sample, then the estimate of each of the last :data:`HISTORY` steps (the step ``k`` at
row ``k % HISTORY``, the current one last written).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_sim.core.jit import jit_inline
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.core.so3 import Mat3, Vec3, mat_t_mat3, mat_vec3

POSE_SIZE = 15
HISTORY = 64  # steps of estimates kept: the longest odometry delay bridged is HISTORY - 1 steps
BRIDGE_MEMORY = np.dtype([
    ("has_estimate", np.bool_),
    ("estimate_step", np.int64),  # the step of the current estimate (0: the first sample's)
    ("last_sample", np.float64, (POSE_SIZE,)),  # odom's last sample
    ("previous_imu", np.float64, (6,)),  # the previous step's IMU sample
    ("estimates", np.float64, (HISTORY, POSE_SIZE)),  # the estimates of the last HISTORY steps
], align=True)
"""The bridge's memory (module docstring)."""


class BridgeParams(NamedTuple):
    enabled: bool  # odom is a measurement: fly on the estimate; False: odom as it is
    period: float  # [s] the control period (the integration step)
    delay: int  # steps odom's samples are late by (<= HISTORY - 1)
    correction: float  # in (0, 1]: the share of the difference to a new odom sample the estimate takes

    @classmethod
    def unused(cls) -> BridgeParams:
        """Parameters of a law that flies on ``odom`` as it is."""
        return cls(False, 0.0, 0, 0.0)


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
def _put_pose(pose, position: Vec3, velocity: Vec3, rotation: Mat3) -> None:  # noqa: ANN001
    """A pose into ``pose`` (POSE_SIZE,): position, velocity, ``R`` row by row."""
    for i in range(3):
        pose[i], pose[3 + i] = position[i], velocity[i]
        for j in range(3):
            pose[6 + 3 * i + j] = rotation[i][j]


@jit_inline
def _pose(pose) -> tuple:  # noqa: ANN001
    """``(position, velocity, R rows)`` of ``pose`` (POSE_SIZE,)."""
    return ((pose[0], pose[1], pose[2]), (pose[3], pose[4], pose[5]),
            ((pose[6], pose[7], pose[8]), (pose[9], pose[10], pose[11]), (pose[12], pose[13], pose[14])))


@jit_inline
def bridged_state(params: BridgeParams, memory, position: Vec3, rotation: Mat3,  # noqa: ANN001
                  velocity_world: Vec3, imu) -> tuple:  # noqa: ANN001
    """``(position, R rows, velocity world)`` of the vehicle at this step (module docstring), from ``odom``'s
    sample (held, ``params.delay`` steps late) and the IMU (``imu``: angular velocity [rad/s], specific force
    [m/s^2], body FRD, of this step); ``memory`` the estimate's :data:`BRIDGE_MEMORY` record.

    Propagation over the period ``T`` (trapezoidal, the previous and this IMU sample ``(w', s')``, ``(w, s)``):
    ``R <- R Exp((w' + w) T / 2)``, ``v <- v + (R' s' + R s) T / 2 + g e3 T``, ``p <- p + (v' + v) T / 2``.
    A new sample (any number differs from the last one) measures the step ``k - delay``: with the estimate
    ``(p_k', v_k', R_k')`` kept for that step, the correction ``c = correction`` moves the estimate of that step
    and of every later one by ``c (p_o - p_k')``, ``c (v_o - v_k')`` and ``R <- Exp(c theta) R`` with
    ``Exp(theta) = R_o R_k'^T`` (small angles: ``theta`` the vee of the skew part)."""
    gyro = (imu[0], imu[1], imu[2])
    specific_force = (imu[3], imu[4], imu[5])
    estimates, last_sample, previous_imu = memory.estimates, memory.last_sample, memory.previous_imu
    if not memory.has_estimate:
        memory.has_estimate, memory.estimate_step = True, 0
        _put_pose(last_sample, position, velocity_world, rotation)
        _put_pose(estimates[0], position, velocity_world, rotation)
        for i in range(6):
            previous_imu[i] = imu[i]
        return position, rotation, velocity_world
    step = int(memory.estimate_step)
    p, v, r = _pose(estimates[step % HISTORY])
    dt = params.period
    gyro_p = (previous_imu[0], previous_imu[1], previous_imu[2])
    force_p = (previous_imu[3], previous_imu[4], previous_imu[5])
    r_new = _mat_mat3(r, _exp_rows(0.5 * dt * (gyro_p[0] + gyro[0]), 0.5 * dt * (gyro_p[1] + gyro[1]),
                                   0.5 * dt * (gyro_p[2] + gyro[2])))
    a_p, a_n = mat_vec3(r, force_p), mat_vec3(r_new, specific_force)
    v_new = (v[0] + 0.5 * dt * (a_p[0] + a_n[0]), v[1] + 0.5 * dt * (a_p[1] + a_n[1]),
             v[2] + 0.5 * dt * (a_p[2] + a_n[2]) + GRAVITY * dt)
    p_new = (p[0] + 0.5 * dt * (v[0] + v_new[0]), p[1] + 0.5 * dt * (v[1] + v_new[1]),
             p[2] + 0.5 * dt * (v[2] + v_new[2]))
    step += 1
    memory.estimate_step = step
    _put_pose(estimates[step % HISTORY], p_new, v_new, r_new)
    for i in range(6):
        previous_imu[i] = imu[i]
    last_p, last_v, last_r = _pose(last_sample)
    new = False
    for i in range(3):
        if position[i] != last_p[i] or velocity_world[i] != last_v[i]:
            new = True
        for j in range(3):
            if rotation[i][j] != last_r[i][j]:
                new = True
    if new:
        _put_pose(last_sample, position, velocity_world, rotation)
        back = min(params.delay, step, HISTORY - 1)
        p_k, v_k, r_k = _pose(estimates[(step - back) % HISTORY])
        c = params.correction
        dp = (c * (position[0] - p_k[0]), c * (position[1] - p_k[1]), c * (position[2] - p_k[2]))
        dv = (c * (velocity_world[0] - v_k[0]), c * (velocity_world[1] - v_k[1]),
              c * (velocity_world[2] - v_k[2]))
        e = mat_t_mat3(r_k, rotation)  # R_k'^T R_o; R_o R_k'^T = R_k' e R_k'^T: the world-frame angle
        body = (0.5 * (e[2][1] - e[1][2]), 0.5 * (e[0][2] - e[2][0]), 0.5 * (e[1][0] - e[0][1]))
        world = mat_vec3(r_k, body)
        turn = _exp_rows(c * world[0], c * world[1], c * world[2])
        for k in range(step - back, step + 1):
            slot = estimates[k % HISTORY]
            pk, vk, rk = _pose(slot)
            _put_pose(slot, (pk[0] + dp[0], pk[1] + dp[1], pk[2] + dp[2]),
                      (vk[0] + dv[0], vk[1] + dv[1], vk[2] + dv[2]), _mat_mat3(turn, rk))
    p_now, v_now, r_now = _pose(estimates[step % HISTORY])
    return p_now, r_now, v_now
