"""Message <-> numpy conversions shared by every node (frames as in docs/model.md §4).

* ``nav_msgs/Odometry``: pose in ``world_ned`` (position [m], orientation body FRD -> world NED),
  twist in ``base_link_frd`` (linear velocity and angular velocity in body axes, the ROS convention).
* ``geometry_msgs/WrenchStamped``: force [N] and torque [N m] in ``frame_id``.
* ``sensor_msgs/JointState`` rotor commands: ``rotor_i`` with velocity [rad/s], ``tilt_i`` with
  position [rad].

Stamps are integer nanoseconds of simulated time so that the lockstep can match them exactly.
"""

from __future__ import annotations

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState

from fsr_sim.contract import BODY_FRAME, ODOM, ROTOR_CMD, joint_names, rotor_joint, tilt_joint
from fsr_sim.core.odometry import read_odometry
from fsr_sim.core.so3 import Mat3, Vec3
from fsr_sim.model.odometry import odometry_values_ok, state_from_odometry_values
from fsr_sim.model.so3 import quaternion_from_rotation
from fsr_sim.ros import cdr_read


def time_from_ns(stamp_ns: int) -> Time:
    return Time(sec=int(stamp_ns // 1_000_000_000), nanosec=int(stamp_ns % 1_000_000_000))


def odometry_from_state(
    stamp_ns: int,
    position: np.ndarray,
    rotation: np.ndarray,
    velocity_world: np.ndarray,
    angular_velocity_body: np.ndarray,
    msg: Odometry | None = None,
) -> Odometry:
    """Fill an Odometry (reused if given): twist.linear is ``R^T v_world`` (body axes)."""
    msg = Odometry() if msg is None else msg
    msg.header.stamp = time_from_ns(stamp_ns)
    msg.header.frame_id = ODOM.frame
    msg.child_frame_id = ODOM.child_frame
    pose = msg.pose.pose
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in position)
    q = quaternion_from_rotation(rotation)
    pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = (float(v) for v in q)
    velocity_body = rotation.T @ velocity_world
    twist = msg.twist.twist
    twist.linear.x, twist.linear.y, twist.linear.z = (float(v) for v in velocity_body)
    twist.angular.x, twist.angular.y, twist.angular.z = (float(v) for v in angular_velocity_body)
    return msg


def state_from_odometry(msg: Odometry) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(position world [m], R body->world, velocity world [m/s], angular velocity body [rad/s]): the
    arithmetic of :func:`fsr_sim.model.odometry.state_from_odometry_values`."""
    p = msg.pose.pose.position
    o = msg.pose.pose.orientation
    lin = msg.twist.twist.linear
    ang = msg.twist.twist.angular
    return state_from_odometry_values((p.x, p.y, p.z), (o.x, o.y, o.z, o.w), (lin.x, lin.y, lin.z),
                                      (ang.x, ang.y, ang.z))


def odometry_state_from_bytes(data: bytes) -> tuple[int, Vec3, Mat3, Vec3, Vec3]:
    """The state of an ``odom`` payload (CDR bytes of a ``raw=True`` subscription) as the compiled core takes it:
    (stamp [ns], position world [m], rows of ``R`` body -> world, velocity world [m/s], angular velocity body
    [rad/s]), by :func:`fsr_sim.core.odometry.read_odometry`. ValueError, naming the problem, for bytes that
    cannot be read or values :func:`fsr_sim.model.odometry.odometry_values_ok` refuses (NaN/inf, a zero
    quaternion)."""
    try:
        stamp_ns, pose, twist = cdr_read.odometry(data)
    except ValueError as error:
        raise ValueError(f"cannot be read: {error}") from error
    if not odometry_values_ok(pose, twist):
        raise ValueError(f"odom at {stamp_ns} ns holds NaN/inf or a zero quaternion")
    return stamp_ns, *read_odometry(pose + twist)


def state_from_odometry_bytes(data: bytes) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`odometry_state_from_bytes` as arrays (position (3,), ``R`` (3, 3), velocity (3,), angular velocity
    (3,)): what :func:`state_from_odometry` gives for the message."""
    stamp_ns, *state = odometry_state_from_bytes(data)
    return stamp_ns, *(np.array(part) for part in state)


def wrench_stamped(
    stamp_ns: int, force: np.ndarray, torque: np.ndarray, frame_id: str = BODY_FRAME
) -> WrenchStamped:
    msg = WrenchStamped()
    msg.header.stamp = time_from_ns(stamp_ns)
    msg.header.frame_id = frame_id
    msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = (float(v) for v in force)
    msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = (float(v) for v in torque)
    return msg


def wrench_from_msg(msg: WrenchStamped) -> tuple[np.ndarray, np.ndarray]:
    f, t = msg.wrench.force, msg.wrench.torque
    return np.array((f.x, f.y, f.z)), np.array((t.x, t.y, t.z))


def rotor_command(stamp_ns: int, speeds: np.ndarray, tilts: np.ndarray | None = None) -> JointState:
    """JointState with ``rotor_i`` (velocity, rad/s) and, for tilting vehicles, ``tilt_i`` (position, rad)."""
    msg = JointState()
    msg.header.stamp = time_from_ns(stamp_ns)
    msg.header.frame_id = ROTOR_CMD.frame
    n = len(speeds)
    velocities = [float(v) for v in speeds]
    positions = [0.0] * n
    if tilts is not None:
        velocities += [0.0] * n
        positions += [float(v) for v in tilts]
    msg.name = joint_names(n, tilting=tilts is not None)
    msg.velocity = velocities
    msg.position = positions
    return msg


def rotor_command_arrays(msg: JointState, rotor_count: int) -> tuple[np.ndarray, np.ndarray | None]:
    """(speeds [rad/s], tilts [rad] or None) from a rotor JointState; ValueError naming what is wrong."""
    index = {name: i for i, name in enumerate(msg.name)}
    speeds = _joint_values(msg, index, [rotor_joint(i) for i in range(rotor_count)], "velocity")
    tilts = None
    if tilt_joint(0) in index:
        tilts = _joint_values(msg, index, [tilt_joint(i) for i in range(rotor_count)], "position")
    return finite_rotor_command(speeds, tilts)


def finite_rotor_command(speeds: np.ndarray, tilts: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None]:
    """``(speeds, tilts)`` as they are; ValueError if any value is NaN or inf."""
    if not np.isfinite(speeds).all() or (tilts is not None and not np.isfinite(tilts).all()):
        raise ValueError(f"{ROTOR_CMD.name} holds NaN or inf")
    return speeds, tilts


def _joint_values(msg: JointState, index: dict[str, int], joints: list[str], field: str) -> np.ndarray:
    """The ``field`` (velocity or position) of each of ``joints``, by ``index`` (name -> place in ``msg``)."""
    values = getattr(msg, field)
    out = np.empty(len(joints))
    for i, joint in enumerate(joints):
        j = index.get(joint)
        if j is None or j >= len(values):
            raise ValueError(f"{ROTOR_CMD.name} has no {field} for '{joint}' (names: {list(msg.name)})")
        out[i] = values[j]
    return out
