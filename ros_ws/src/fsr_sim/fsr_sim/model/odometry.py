"""The state as the simulator publishes it (``nav_msgs/Odometry`` values) and as the nodes read it back.

One definition of the arithmetic on both sides of ``odom`` (the compiled core's :mod:`fsr_sim.core.odometry`,
called here from Python), shared by the simulator node, the controller
and estimator nodes (on the values :mod:`fsr_sim.ros.cdr_read` takes from the bytes; message objects through
:mod:`fsr_sim.ros.conversions`) and the in-process loop, so that a flight in one process and the node graph
see bit-identical numbers; :func:`odometry_values_ok` is the one check the nodes apply before using them:

* published: position world NED [m]; orientation the unit quaternion ``[x, y, z, w]`` body -> world with the
  sign fixed to ``w >= 0`` (the same rotation as ``-q``; consecutive messages stay comparable); twist in the
  body frame (ROS convention): linear ``R^T v_world`` [m/s], angular ``omega_b`` [rad/s];
* read back: ``R`` from that quaternion and ``v_world = R v_body``.
"""

from __future__ import annotations

import math

import numpy as np

from fsr_sim.core import odometry as core
from fsr_sim.core.so3 import Vec3

Quaternion = tuple[float, float, float, float]
NO_EXTERNAL_WRENCH = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


def published_row(state_vector: np.ndarray, external: tuple | None = None) -> np.ndarray:
    """A published row of :mod:`fsr_sim.core.odometry`: ``odom`` then ``wrench_truth`` numbers (no IMU: zero),
    for a state (13,) and the true external wrench (force world [N], torque body [N m]; None: zero)."""
    row = np.zeros(core.PUBLISHED_SIZE)
    if external is None:
        external = NO_EXTERNAL_WRENCH
    else:
        external = tuple(tuple(float(v) for v in part) for part in external)
    core.publish_state(np.ascontiguousarray(state_vector, dtype=float), external, row)
    return row


def odometry_values(state_vector: np.ndarray) -> tuple[Vec3, Quaternion, Vec3, Vec3]:
    """(position world [m], quaternion ``[x, y, z, w]`` with ``w >= 0``, velocity body [m/s], angular velocity
    body [rad/s]) of a plant state vector (shape (13,), :mod:`fsr_sim.model.rigid_body` layout)."""
    x, y, z, qx, qy, qz, qw, vx, vy, vz, wx, wy, wz = published_row(state_vector)[:core.ODOM_SIZE].tolist()
    return (x, y, z), (qx, qy, qz, qw), (vx, vy, vz), (wx, wy, wz)


def state_from_odometry_values(
    position: Vec3, quaternion: Quaternion, velocity_body: Vec3, angular_velocity_body: Vec3
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(position world [m], ``R`` body -> world, velocity world [m/s], angular velocity body [rad/s]) from the
    published values (shapes (3,), (3, 3), (3,), (3,))."""
    row = np.array((*position, *quaternion, *velocity_body, *angular_velocity_body), dtype=float)
    return state_from_odometry_row(row)


def state_from_odometry_row(row: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`state_from_odometry_values` of the first 13 numbers of a published row."""
    position, rotation, velocity_world, angular_velocity = core.read_odometry(row)
    return np.array(position), np.array(rotation), np.array(velocity_world), np.array(angular_velocity)


def odometry_values_ok(pose: tuple[float, ...], twist: tuple[float, ...]) -> bool:
    """Whether read-back values can be used: ``pose`` (x y z qx qy qz qw) and ``twist`` (linear xyz, angular
    xyz) all finite and the quaternion non-zero (``|q|^2 > 1e-12``)."""
    _, _, _, qx, qy, qz, qw = pose
    return all(map(math.isfinite, pose + twist)) and (qx * qx + qy * qy + qz * qz + qw * qw) > 1e-12
