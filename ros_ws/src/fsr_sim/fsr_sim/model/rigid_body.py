"""The rigid-body state as named parts, for Python code (the dynamics are :mod:`fsr_sim.core.rigid_body`).

    m p_ddot      = m g e3 + F_world                 (F_world = R f_b + f_ext, world NED [N])
    I_b omega_dot = -omega x I_b omega + tau_body     (body FRD [N m])
    q_dot         = 1/2 q (x) [omega; 0]              (R_dot = R S(omega))

The state is a flat array of 13 numbers: position world [m] (0:3), velocity world [m/s] (3:6),
quaternion ``[x, y, z, w]`` body -> world (6:10), angular velocity body [rad/s] (10:13) (the layout of
:mod:`fsr_sim.core.rigid_body`, whose index constants these slices are made of).
"""

from __future__ import annotations

import numpy as np

from fsr_sim.core import rigid_body as core
from fsr_sim.model.so3 import quaternion_from_rotation, rotation_from_quaternion

POSITION = slice(core.POSITION_X, core.POSITION_Z + 1)
VELOCITY = slice(core.VELOCITY_X, core.VELOCITY_Z + 1)
QUATERNION = slice(core.QUATERNION_X, core.QUATERNION_W + 1)
ANGULAR_VELOCITY = slice(core.ANGULAR_VELOCITY_X, core.ANGULAR_VELOCITY_Z + 1)
STATE_SIZE = core.STATE_SIZE


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
    """The 13-number state of named parts (``rotation`` (3, 3) body -> world, stored as its quaternion)."""
    state = np.empty(STATE_SIZE)
    state[POSITION] = position
    state[VELOCITY] = velocity
    state[QUATERNION] = quaternion_from_rotation(rotation)
    state[ANGULAR_VELOCITY] = angular_velocity
    return state
