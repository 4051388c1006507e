"""Controller messages <-> numpy: the rclpy objects of what the controller publishes (the node publishes the
same values as packed CDR, :class:`fsr_control.nodes.packets.ControllerPackets`, tested equal), and goals.

* ``reference`` (trajectory_msgs/MultiDOFJointTrajectory, frame ``world_ned``, one joint ``base_link_frd``,
  one point): ``transforms[0]`` the desired pose (translation world NED [m], rotation ``R_d`` body -> world),
  ``velocities[0]`` linear velocity world [m/s] and angular velocity ``R_d omega_d`` world [rad/s],
  ``accelerations[0]`` linear acceleration world [m/s^2] and ``R_d omega_dot_d`` world [rad/s^2].
* ``attitude_cmd`` (geometry_msgs/QuaternionStamped, frame ``world_ned``): the commanded attitude ``R_c``
  (body FRD -> world NED, ``[x, y, z, w]`` with ``w >= 0``) that the attitude loop tracks: the geometric
  controller's ``R_d`` built from the thrust vector, the Voliro controller's reference attitude.
* ``wrench_desired`` (geometry_msgs/WrenchStamped, ``base_link_frd``): the body wrench the control law asked
  for, before allocation and rotor clamping (``wrench_cmd`` is the wrench after them).
* ``goal`` (geometry_msgs/PoseStamped, world NED): position and orientation of the new target;
  ``header.frame_id`` must be ``world_ned`` (or empty, taken as ``world_ned``): no transforms are looked up,
  so a goal in any other frame is refused rather than silently read as NED.
* Stamps: the controller's outputs carry the stamp of the ``odom`` they answer (integer ns of sim time).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from geometry_msgs.msg import PoseStamped, QuaternionStamped, Transform, Twist
from trajectory_msgs.msg import MultiDOFJointTrajectory, MultiDOFJointTrajectoryPoint

from fsr_control.flight_controller import ControlOutput
from fsr_control.planning.trajectory import Reference
from fsr_sim.contract import (
    ATTITUDE_CMD,
    GOAL,
    REFERENCE,
    ROTOR_CMD,
    WRENCH_CMD,
    WRENCH_DESIRED,
    WRENCH_SHORTFALL,
)
from fsr_sim.model.so3 import quaternion_from_rotation, rotation_from_quaternion
from fsr_sim.ros.conversions import rotor_command, time_from_ns, wrench_stamped


def reference_message(stamp_ns: int, reference: Reference) -> MultiDOFJointTrajectory:
    """The one-point trajectory message of a :class:`Reference` (see the module docstring)."""
    msg = MultiDOFJointTrajectory()
    msg.header.stamp = time_from_ns(stamp_ns)
    msg.header.frame_id = REFERENCE.frame
    msg.joint_names = [REFERENCE.child_frame]
    transform = Transform()
    transform.translation.x, transform.translation.y, transform.translation.z = reference.position.tolist()
    q = quaternion_from_rotation(reference.rotation).tolist()
    transform.rotation.x, transform.rotation.y, transform.rotation.z, transform.rotation.w = q
    velocity = Twist()
    velocity.linear.x, velocity.linear.y, velocity.linear.z = reference.velocity.tolist()
    velocity.angular.x, velocity.angular.y, velocity.angular.z = (
        reference.rotation @ reference.angular_velocity
    ).tolist()
    acceleration = Twist()
    acceleration.linear.x, acceleration.linear.y, acceleration.linear.z = reference.acceleration.tolist()
    acceleration.angular.x, acceleration.angular.y, acceleration.angular.z = (
        reference.rotation @ reference.angular_acceleration
    ).tolist()
    point = MultiDOFJointTrajectoryPoint(transforms=[transform], velocities=[velocity], accelerations=[acceleration])
    msg.points = [point]
    return msg


def controller_messages(stamp_ns: int, output: ControlOutput, rotors: bool) -> list[tuple[str, Any]]:
    """(topic, message) of everything the controller publishes for the state stamped ``stamp_ns``: ``rotor_cmd``
    (rotor actuation only), ``wrench_cmd``, ``wrench_shortfall`` (demanded minus produced wrench),
    ``reference``, ``attitude_cmd``, ``wrench_desired``. The node publishes these; a recording of an in-process
    flight writes them."""
    messages: list[tuple[str, Any]] = []
    if rotors:
        messages.append((ROTOR_CMD.name, rotor_command(stamp_ns, output.rotor_speeds, output.tilt_angles)))
    messages.append((WRENCH_CMD.name, wrench_stamped(stamp_ns, output.force_body, output.torque_body)))
    if output.shortfall is not None:
        messages.append((WRENCH_SHORTFALL.name, wrench_stamped(stamp_ns, output.shortfall[:3], output.shortfall[3:])))
    messages.append((REFERENCE.name, reference_message(stamp_ns, output.reference)))
    messages.append((ATTITUDE_CMD.name, attitude_command_message(stamp_ns, output.rotation_cmd)))
    messages.append((WRENCH_DESIRED.name, wrench_stamped(stamp_ns, output.force_desired, output.torque_desired)))
    return messages


def attitude_command_message(stamp_ns: int, rotation: np.ndarray) -> QuaternionStamped:
    """``attitude_cmd``: the commanded attitude ``R_c`` (body FRD -> world NED) as a unit quaternion, ``w >= 0``."""
    msg = QuaternionStamped()
    msg.header.stamp = time_from_ns(stamp_ns)
    msg.header.frame_id = ATTITUDE_CMD.frame
    x, y, z, w = quaternion_from_rotation(np.asarray(rotation, dtype=float)).tolist()
    if w < 0.0:
        x, y, z, w = -x, -y, -z, -w
    msg.quaternion.x, msg.quaternion.y, msg.quaternion.z, msg.quaternion.w = x, y, z, w
    return msg


def goal_from_message(msg: PoseStamped) -> tuple[np.ndarray, np.ndarray]:
    """(position world NED [m], rotation body -> world) of a goal.

    Raises
    ------
    ValueError
        If ``header.frame_id`` is neither ``world_ned`` nor empty (the message names the frame), or the pose
        holds NaN/inf, or the orientation is a zero quaternion.
    """
    frame = msg.header.frame_id
    if frame not in ("", GOAL.frame):
        raise ValueError(f"{GOAL.name} frame_id is {frame!r}, expected {GOAL.frame!r} (or empty); no transform is "
                         "applied")
    p, o = msg.pose.position, msg.pose.orientation
    values = (p.x, p.y, p.z, o.x, o.y, o.z, o.w)
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"{GOAL.name} holds NaN or inf")
    if o.x * o.x + o.y * o.y + o.z * o.z + o.w * o.w < 1e-12:
        raise ValueError(f"{GOAL.name} orientation is a zero quaternion")
    return np.array((p.x, p.y, p.z)), rotation_from_quaternion((o.x, o.y, o.z, o.w))
