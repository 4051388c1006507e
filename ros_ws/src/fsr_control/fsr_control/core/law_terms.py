"""What the control laws of the compiled core share: the state and the measurements they fly on, the
compensation they are handed, their PD terms and how their matrices are held.

A law's (3, 3) matrices (its nominal inertia, its gains) are one (k, 3, 3) float64 array of its parameters,
``matrices[INERTIA]`` the inertia first: a law's parameters hold one array however many gains it has (each
array of the packed parameters costs the controller's tick time, placeholder or not: measured 0.04 us a tick).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from fsr_sim.core.jit import jit
from fsr_sim.core.so3 import Mat3, Vec3


class VehicleState(NamedTuple):
    """The vehicle's state a law is handed (``odom``'s)."""

    position: Vec3  # world NED [m]
    rotation: Mat3  # R: rows, body FRD -> world
    velocity_world: Vec3  # world NED [m/s]
    angular_velocity: Vec3  # body FRD [rad/s]


class Measured(NamedTuple):
    """What the vehicle measures of the same stamp as the state, read only by a law or an observer configured to
    use it (otherwise it may hold anything)."""

    imu: np.ndarray  # (6,) the IMU's angular velocity [rad/s] and specific force [m/s^2], body FRD
    speeds: np.ndarray  # (n,) the rotors' speeds [rad/s] (rotor_state)
    tilts: np.ndarray  # (n,) and tilts [rad]


class Compensation(NamedTuple):
    """The estimated external wrench a law cancels: force [N] world NED, torque [N m] body FRD, and the force's
    first and second time differences [N/s, N/s^2] (world); ``active`` False: the law as written."""

    active: bool
    force: Vec3
    torque: Vec3
    force_rate: Vec3
    force_acceleration: Vec3


NO_COMPENSATION = Compensation(False, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
INERTIA = 0  # every law's matrices[INERTIA]: its nominal inertia [kg m^2]


@jit
def matrix_at(matrices, index: int) -> Mat3:  # noqa: ANN001 - a float64 array of shape (k, 3, 3)
    """The rows of ``matrices[index]`` as a :data:`Mat3`."""
    return ((matrices[index, 0, 0], matrices[index, 0, 1], matrices[index, 0, 2]),
            (matrices[index, 1, 0], matrices[index, 1, 1], matrices[index, 1, 2]),
            (matrices[index, 2, 0], matrices[index, 2, 1], matrices[index, 2, 2]))


@jit
def linear_feedback(k_a: Mat3, e_a: Vec3, k_b: Mat3, e_b: Vec3, scale: float, feedforward: Vec3) -> Vec3:
    """``-K_a e_a - K_b e_b + scale * feedforward`` (the PD terms of the laws)."""
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
