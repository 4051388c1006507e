"""Rigid-body dynamics of a multirotor in NED, integrated with RK4 on the unit quaternion (SPEC §3.1).

    m p_ddot      = m g e3 + F_world                 (F_world = R f_b + f_ext, world NED [N])
    I_b omega_dot = -omega x I_b omega + tau_body     (body FRD [N m])
    q_dot         = 1/2 q (x) [omega; 0]              (R_dot = R S(omega))

The state is a flat array of 13 numbers: position world [m] (0:3), velocity world [m/s] (3:6),
quaternion ``[x, y, z, w]`` body -> world (6:10), angular velocity body [rad/s] (10:13). After each step
the quaternion is renormalised (projection onto SO(3)).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from fsr_sim.model.frames import GRAVITY
from fsr_sim.model.so3 import (
    Mat3,
    Vec3,
    quaternion_from_rotation,
    rotation_from_quaternion,
    rotation_rows_from_quaternion,
)

POSITION = slice(0, 3)
VELOCITY = slice(3, 6)
QUATERNION = slice(6, 10)
ANGULAR_VELOCITY = slice(10, 13)
STATE_SIZE = 13

# (t, position, rotation) -> (force world excluding gravity [N], torque body [N m])
WrenchFunction = Callable[[float, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
# The same on Python floats (the plant's fast path): (t, position (3 floats), rows of R) -> (f_x, f_y, f_z,
# tau_x, tau_y, tau_z), force world excluding gravity [N], torque body [N m].
FloatWrenchFunction = Callable[[float, Vec3, Mat3], tuple[float, float, float, float, float, float]]


def float_wrench(wrench: WrenchFunction) -> FloatWrenchFunction:
    """Adapt an array :data:`WrenchFunction` to the float signature used by :meth:`RigidBody.step_floats`."""

    def adapted(t: float, position: Vec3, rotation: Mat3) -> tuple[float, float, float, float, float, float]:
        force_world, torque_body = wrench(t, np.array(position), np.array(rotation))
        return (*np.asarray(force_world, dtype=float).tolist(), *np.asarray(torque_body, dtype=float).tolist())

    return adapted


class RigidBodyState:
    """One state as named parts (copies): ``position`` [m] and ``velocity`` [m/s] world NED, ``quaternion``
    ``[x, y, z, w]`` and ``rotation`` ``R`` (body FRD -> world NED), ``angular_velocity`` [rad/s] body FRD;
    ``vector`` is the flat 13-number state."""

    __slots__ = ("vector",)

    def __init__(self, vector: np.ndarray) -> None:
        self.vector = vector

    @property
    def position(self) -> np.ndarray:
        return self.vector[POSITION].copy()

    @property
    def velocity(self) -> np.ndarray:
        return self.vector[VELOCITY].copy()

    @property
    def quaternion(self) -> np.ndarray:
        return self.vector[QUATERNION].copy()

    @property
    def rotation(self) -> np.ndarray:
        return rotation_from_quaternion(self.vector[QUATERNION])

    @property
    def angular_velocity(self) -> np.ndarray:
        return self.vector[ANGULAR_VELOCITY].copy()

    def __repr__(self) -> str:
        return (f"RigidBodyState(position={self.position.tolist()}, velocity={self.velocity.tolist()}, "
                f"quaternion={self.quaternion.tolist()}, angular_velocity={self.angular_velocity.tolist()})")


def pack_state(
    position: np.ndarray, rotation: np.ndarray, velocity: np.ndarray, angular_velocity: np.ndarray
) -> np.ndarray:
    state = np.empty(STATE_SIZE)
    state[POSITION] = position
    state[VELOCITY] = velocity
    state[QUATERNION] = quaternion_from_rotation(rotation)
    state[ANGULAR_VELOCITY] = angular_velocity
    return state


class RigidBody:
    """Mass [kg] and inertia [kg m^2] of the true plant, and an RK4 step for a state-dependent wrench."""

    def __init__(self, mass: float, inertia: np.ndarray) -> None:
        self.mass = float(mass)
        self.inertia = np.array(inertia, dtype=float)
        self.inertia_inv = np.linalg.inv(self.inertia)
        self._inertia_rows = self.inertia.tolist()
        self._inertia_inv_rows = self.inertia_inv.tolist()

    def derivative(self, t: float, state: np.ndarray, wrench: WrenchFunction) -> np.ndarray:
        """``x_dot`` for the state ``x`` at time ``t`` [s]."""
        return np.array(self.derivative_floats(t, state.tolist(), float_wrench(wrench)))

    def derivative_floats(self, t: float, state: list[float], wrench: FloatWrenchFunction) -> tuple[float, ...]:
        """``x_dot`` (13 floats) for the state ``x`` (13 floats) at time ``t`` [s].

        Written on Python floats: for 3-vectors this is several times faster than numpy calls.
        """
        x, y, z, vx, vy, vz, qx, qy, qz, qw, wx, wy, wz = state
        rotation = rotation_rows_from_quaternion(qx, qy, qz, qw)
        fx, fy, fz, tx, ty, tz = wrench(t, (x, y, z), rotation)
        inv_m = 1.0 / self.mass
        (i00, i01, i02), (i10, i11, i12), (i20, i21, i22) = self._inertia_rows
        hx = i00 * wx + i01 * wy + i02 * wz  # I omega
        hy = i10 * wx + i11 * wy + i12 * wz
        hz = i20 * wx + i21 * wy + i22 * wz
        mx = tx - (wy * hz - wz * hy)  # tau - omega x I omega
        my = ty - (wz * hx - wx * hz)
        mz = tz - (wx * hy - wy * hx)
        (j00, j01, j02), (j10, j11, j12), (j20, j21, j22) = self._inertia_inv_rows
        return (
            vx, vy, vz,
            fx * inv_m, fy * inv_m, GRAVITY + fz * inv_m,
            0.5 * (qw * wx + qy * wz - qz * wy),
            0.5 * (qw * wy + qz * wx - qx * wz),
            0.5 * (qw * wz + qx * wy - qy * wx),
            -0.5 * (qx * wx + qy * wy + qz * wz),
            j00 * mx + j01 * my + j02 * mz,
            j10 * mx + j11 * my + j12 * mz,
            j20 * mx + j21 * my + j22 * mz,
        )

    def step(self, t: float, state: np.ndarray, dt: float, wrench: WrenchFunction) -> np.ndarray:
        """One classical RK4 step of length ``dt`` [s]; returns the new state (quaternion renormalised)."""
        return self.step_floats(t, state, dt, float_wrench(wrench))

    def step_floats(self, t: float, state: np.ndarray, dt: float, wrench: FloatWrenchFunction) -> np.ndarray:
        """:meth:`step` with a :data:`FloatWrenchFunction` (the arithmetic is the same, on Python floats)."""
        derivative = self.derivative_floats
        s = state.tolist()
        h = 0.5 * dt
        k1 = derivative(t, s, wrench)
        k2 = derivative(t + h, [x + h * k for x, k in zip(s, k1, strict=True)], wrench)
        k3 = derivative(t + h, [x + h * k for x, k in zip(s, k2, strict=True)], wrench)
        k4 = derivative(t + dt, [x + dt * k for x, k in zip(s, k3, strict=True)], wrench)
        c = dt / 6.0
        new = [x + c * (a + 2.0 * b + 2.0 * d + e) for x, a, b, d, e in zip(s, k1, k2, k3, k4, strict=True)]
        qx, qy, qz, qw = new[6:10]
        norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        if qw < 0.0:
            norm = -norm  # keep w >= 0 (same rotation), so published quaternions do not flip sign
        new[6:10] = (qx / norm, qy / norm, qz / norm, qw / norm)
        return np.array(new)
