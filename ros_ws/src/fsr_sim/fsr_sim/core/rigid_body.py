"""Rigid-body dynamics of a multirotor in NED (compiled core).

    m p_ddot      = m g e3 + F_world                 (F_world = R f_b + f_ext, world NED [N])
    I_b omega_dot = -omega x I_b omega + tau_body     (body FRD [N m])
    q_dot         = 1/2 q (x) [omega; 0]              (R_dot = R S(omega))

The state is a float64 array of 13 numbers, laid out by the index constants below: position world [m],
velocity world [m/s], quaternion ``[x, y, z, w]`` body -> world, angular velocity body [rad/s]. After each
RK4 step the quaternion is renormalised with ``w >= 0`` (projection onto SO(3); the same rotation as ``-q``,
so published quaternions do not flip sign).
"""

from __future__ import annotations

import math

from fsr_sim.core.jit import jit, jit_inline
from fsr_sim.core.so3 import Mat3, Vec3, rotation_rows_from_quaternion

GRAVITY = 9.81  # m/s^2, along +z (down) of the NED world frame

POSITION_X, POSITION_Y, POSITION_Z = 0, 1, 2
VELOCITY_X, VELOCITY_Y, VELOCITY_Z = 3, 4, 5
QUATERNION_X, QUATERNION_Y, QUATERNION_Z, QUATERNION_W = 6, 7, 8, 9
ANGULAR_VELOCITY_X, ANGULAR_VELOCITY_Y, ANGULAR_VELOCITY_Z = 10, 11, 12
STATE_SIZE = 13


@jit_inline
def state_position(state) -> Vec3:  # noqa: ANN001
    """Position world NED [m] of a state (13,)."""
    return state[POSITION_X], state[POSITION_Y], state[POSITION_Z]


@jit_inline
def state_velocity(state) -> Vec3:  # noqa: ANN001
    """Velocity world NED [m/s] of a state (13,)."""
    return state[VELOCITY_X], state[VELOCITY_Y], state[VELOCITY_Z]


@jit_inline
def state_quaternion(state) -> tuple[float, float, float, float]:  # noqa: ANN001
    """The quaternion ``[x, y, z, w]`` body -> world of a state (13,)."""
    return state[QUATERNION_X], state[QUATERNION_Y], state[QUATERNION_Z], state[QUATERNION_W]


@jit_inline
def state_angular_velocity(state) -> Vec3:  # noqa: ANN001
    """Angular velocity body FRD [rad/s] of a state (13,)."""
    return state[ANGULAR_VELOCITY_X], state[ANGULAR_VELOCITY_Y], state[ANGULAR_VELOCITY_Z]


@jit
def rigid_body_rates(state, mass: float, inertia, inertia_inv, force_world: tuple, torque_body: tuple,  # noqa: ANN001
                     out) -> None:  # noqa: ANN001
    """``x_dot`` of ``state`` (13,) into ``out`` (13,): mass [kg], inertia and its inverse (3, 3) [kg m^2],
    force world excluding gravity [N] and torque body [N m] (3-tuples)."""
    qx, qy, qz, qw = state_quaternion(state)
    wx, wy, wz = state_angular_velocity(state)
    fx, fy, fz = force_world
    tx, ty, tz = torque_body
    inv_m = 1.0 / mass
    hx = inertia[0, 0] * wx + inertia[0, 1] * wy + inertia[0, 2] * wz  # I omega
    hy = inertia[1, 0] * wx + inertia[1, 1] * wy + inertia[1, 2] * wz
    hz = inertia[2, 0] * wx + inertia[2, 1] * wy + inertia[2, 2] * wz
    mx = tx - (wy * hz - wz * hy)  # tau - omega x I omega
    my = ty - (wz * hx - wx * hz)
    mz = tz - (wx * hy - wy * hx)
    out[POSITION_X], out[POSITION_Y], out[POSITION_Z] = state_velocity(state)
    out[VELOCITY_X], out[VELOCITY_Y], out[VELOCITY_Z] = fx * inv_m, fy * inv_m, GRAVITY + fz * inv_m
    out[QUATERNION_X] = 0.5 * (qw * wx + qy * wz - qz * wy)
    out[QUATERNION_Y] = 0.5 * (qw * wy + qz * wx - qx * wz)
    out[QUATERNION_Z] = 0.5 * (qw * wz + qx * wy - qy * wx)
    out[QUATERNION_W] = -0.5 * (qx * wx + qy * wy + qz * wz)
    out[ANGULAR_VELOCITY_X] = inertia_inv[0, 0] * mx + inertia_inv[0, 1] * my + inertia_inv[0, 2] * mz
    out[ANGULAR_VELOCITY_Y] = inertia_inv[1, 0] * mx + inertia_inv[1, 1] * my + inertia_inv[1, 2] * mz
    out[ANGULAR_VELOCITY_Z] = inertia_inv[2, 0] * mx + inertia_inv[2, 1] * my + inertia_inv[2, 2] * mz


@jit
def stage_state(state, rates, h: float, out) -> None:  # noqa: ANN001
    """``out = state + h rates`` (an RK4 stage)."""
    for i in range(STATE_SIZE):
        out[i] = state[i] + h * rates[i]


@jit
def rk4_combine(state, k1, k2, k3, k4, dt: float) -> None:  # noqa: ANN001
    """``state += dt/6 (k1 + 2 k2 + 2 k3 + k4)`` in place, then the quaternion renormalised with ``w >= 0``."""
    c = dt / 6.0
    for i in range(STATE_SIZE):
        state[i] = state[i] + c * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    qx, qy, qz, qw = state_quaternion(state)
    norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    if qw < 0.0:
        norm = -norm
    state[QUATERNION_X], state[QUATERNION_Y] = qx / norm, qy / norm
    state[QUATERNION_Z], state[QUATERNION_W] = qz / norm, qw / norm


@jit
def state_rotation(state) -> Mat3:  # noqa: ANN001
    """Rows of ``R`` (body -> world) of a state's quaternion."""
    qx, qy, qz, qw = state_quaternion(state)
    return rotation_rows_from_quaternion(qx, qy, qz, qw)
