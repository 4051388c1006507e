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
    qx, qy, qz, qw = x[6], x[7], x[8], x[9]
    if qw < 0.0:
        qx, qy, qz, qw = -qx, -qy, -qz, -qw
    rotation = rotation_rows_from_quaternion(qx, qy, qz, qw)
    vbx, vby, vbz = mat_t_vec3(rotation, (x[3], x[4], x[5]))
    out[0], out[1], out[2] = x[0], x[1], x[2]
    out[3], out[4], out[5], out[6] = qx, qy, qz, qw
    out[7], out[8], out[9] = vbx, vby, vbz
    out[10], out[11], out[12] = x[10], x[11], x[12]
    force_world, torque_body = external
    fx, fy, fz = mat_t_vec3(rotation, force_world)
    out[13], out[14], out[15] = fx, fy, fz
    out[16], out[17], out[18] = torque_body
    for i in range(ODOM_SIZE):  # the true odom, kept whatever the sensor stage makes of out[:ODOM_SIZE]
        out[TRUE_ODOM + i] = out[i]


@jit
def read_odometry(row) -> tuple:  # noqa: ANN001
    """(position world [m], rows of ``R``, velocity world [m/s], angular velocity body [rad/s]) of a published
    ``odom`` (the first 13 numbers of ``row``)."""
    rotation = rotation_rows_from_quaternion(row[3], row[4], row[5], row[6])
    velocity_world = mat_vec3(rotation, (row[7], row[8], row[9]))
    return (row[0], row[1], row[2]), rotation, velocity_world, (row[10], row[11], row[12])
