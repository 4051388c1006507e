"""The state as the simulator publishes it and as the nodes read it back (compiled core).

The published row holds the numbers of ``odom``, ``wrench_truth`` and ``imu`` in their messages' field order
(:data:`PUBLISHED_SIZE` float64), so the simulator node, the in-process loop and the recording all use the
same values:

* ``odom``: position world NED [m]; orientation the unit quaternion ``[x, y, z, w]`` body -> world with
  ``w >= 0``; twist in the body frame (ROS convention): linear ``R^T v_world`` [m/s], angular ``omega_b``
  [rad/s];
* ``wrench_truth``: the true external force in the body frame ``R^T f_ext,world`` [N] and torque [N m];
* ``imu`` (with an IMU, :mod:`fsr_sim.core.imu`; else left as it is): the measured angular velocity [rad/s]
  and specific force ``R^T (p_ddot - g e3)`` [m/s^2], body FRD, then the same two true (not published: the
  truth the logs compare the measurement with);
* ``odom_truth``: ``odom``'s numbers of the true state (:data:`TRUE_ODOM`, the first 13 before the sensor stage
  measures them): what the simulator publishes beside a measured ``odom`` (a sensor stage on), so that a
  recording holds the state the tracking errors are taken on.

Read back (:func:`read_odometry`): ``R`` from that quaternion and ``v_world = R v_body``.
"""

from __future__ import annotations

from fsr_sim.core.jit import jit
from fsr_sim.core.rigid_body import state_angular_velocity, state_position, state_quaternion, state_velocity
from fsr_sim.core.so3 import mat_t_vec3, mat_vec3, rotation_rows_from_quaternion

ODOM_POSITION, ODOM_QUATERNION, ODOM_VELOCITY, ODOM_ANGULAR_VELOCITY = 0, 3, 7, 10
ODOM_SIZE = 13
TRUTH_FORCE, TRUTH_TORQUE = 13, 16
WRENCH_TRUTH_END = 19
IMU_ANGULAR_VELOCITY, IMU_LINEAR_ACCELERATION = 19, 22  # imu as published (measured)
IMU_TRUE_ANGULAR_VELOCITY, IMU_TRUE_LINEAR_ACCELERATION = 25, 28  # the true values (not published)
IMU_END = 25
TRUE_ODOM = 31  # odom_truth: odom's 13 numbers of the true state
PUBLISHED_SIZE = 44


@jit
def publish_state(x, external: tuple, out) -> None:  # noqa: ANN001
    """The ``odom`` and ``wrench_truth`` numbers (the first 19 of the published row) of a plant state ``x`` (13,)
    with the true external wrench (force world [N], torque body [N m]); ``odom``'s also at :data:`TRUE_ODOM`."""
    qx, qy, qz, qw = state_quaternion(x)
    if qw < 0.0:
        qx, qy, qz, qw = -qx, -qy, -qz, -qw
    rotation = rotation_rows_from_quaternion(qx, qy, qz, qw)
    vbx, vby, vbz = mat_t_vec3(rotation, state_velocity(x))
    p, q, v, w = ODOM_POSITION, ODOM_QUATERNION, ODOM_VELOCITY, ODOM_ANGULAR_VELOCITY
    out[p], out[p + 1], out[p + 2] = state_position(x)
    out[q], out[q + 1], out[q + 2], out[q + 3] = qx, qy, qz, qw
    out[v], out[v + 1], out[v + 2] = vbx, vby, vbz
    out[w], out[w + 1], out[w + 2] = state_angular_velocity(x)
    force_world, torque_body = external
    fx, fy, fz = mat_t_vec3(rotation, force_world)
    out[TRUTH_FORCE], out[TRUTH_FORCE + 1], out[TRUTH_FORCE + 2] = fx, fy, fz
    out[TRUTH_TORQUE], out[TRUTH_TORQUE + 1], out[TRUTH_TORQUE + 2] = torque_body
    for i in range(ODOM_SIZE):  # the true odom, kept whatever the sensor stage makes of out[:ODOM_SIZE]
        out[TRUE_ODOM + i] = out[i]


@jit
def read_odometry(row) -> tuple:  # noqa: ANN001
    """(position world [m], rows of ``R``, velocity world [m/s], angular velocity body [rad/s]) of a published
    ``odom`` (the first 13 numbers of ``row``)."""
    p, q, v, w = ODOM_POSITION, ODOM_QUATERNION, ODOM_VELOCITY, ODOM_ANGULAR_VELOCITY
    rotation = rotation_rows_from_quaternion(row[q], row[q + 1], row[q + 2], row[q + 3])
    velocity_world = mat_vec3(rotation, (row[v], row[v + 1], row[v + 2]))
    return (row[p], row[p + 1], row[p + 2]), rotation, velocity_world, (row[w], row[w + 1], row[w + 2])
