"""The state as the simulator publishes it (``nav_msgs/Odometry`` values) and as the nodes read it back.

One definition of the arithmetic on both sides of ``odom``, shared by the simulator node, the controller
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

from fsr_sim.model.so3 import Vec3, rotation_from_quaternion

Quaternion = tuple[float, float, float, float]


def odometry_values(state_vector: np.ndarray) -> tuple[Vec3, Quaternion, Vec3, Vec3]:
    """(position world [m], quaternion ``[x, y, z, w]`` with ``w >= 0``, velocity body [m/s], angular velocity
    body [rad/s]) of a plant state vector (shape (13,), :mod:`fsr_sim.model.rigid_body` layout)."""
    x, y, z, _, _, _, qx, qy, qz, qw, wx, wy, wz = state_vector.tolist()
    if qw < 0.0:
        qx, qy, qz, qw = -qx, -qy, -qz, -qw
    rotation = rotation_from_quaternion((qx, qy, qz, qw))
    vbx, vby, vbz = (rotation.T @ state_vector[3:6]).tolist()
    return (x, y, z), (qx, qy, qz, qw), (vbx, vby, vbz), (wx, wy, wz)


def state_from_odometry_values(
    position: Vec3, quaternion: Quaternion, velocity_body: Vec3, angular_velocity_body: Vec3
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(position world [m], ``R`` body -> world, velocity world [m/s], angular velocity body [rad/s]) from the
    published values (shapes (3,), (3, 3), (3,), (3,))."""
    rotation = rotation_from_quaternion(quaternion)
    velocity_world = rotation @ np.array(velocity_body, dtype=float)
    return np.array(position, dtype=float), rotation, velocity_world, np.array(angular_velocity_body, dtype=float)


def odometry_values_ok(pose: tuple[float, ...], twist: tuple[float, ...]) -> bool:
    """Whether read-back values can be used: ``pose`` (x y z qx qy qz qw) and ``twist`` (linear xyz, angular
    xyz) all finite and the quaternion non-zero (``|q|^2 > 1e-12``)."""
    _, _, _, qx, qy, qz, qw = pose
    return all(map(math.isfinite, pose + twist)) and (qx * qx + qy * qy + qz * qz + qw * qw) > 1e-12
