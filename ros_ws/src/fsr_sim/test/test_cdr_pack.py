"""The packed CDR encoders against rclpy's own ``serialize_message``, byte for byte.

For every message type fsr packs and a set of value patterns (zeros, negatives, tiny/huge, NaN/inf, stamps
with and without a seconds part, frames and names of every length modulo 4): every data byte (counts,
strings, numbers, as the CDR walker of :mod:`fsr_sim.recording.cdr_columns` finds them) equals rclpy's,
every padding byte is zero, the message ends where its data ends, and rclpy reads it back equal.
"""

from __future__ import annotations

import math

import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import QuaternionStamped, Transform, Twist, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu, JointState
from std_msgs.msg import Float64, String
from trajectory_msgs.msg import MultiDOFJointTrajectory, MultiDOFJointTrajectoryPoint

from fsr_sim.recording.cdr_columns import message_layout
from fsr_sim.ros import cdr_pack

STAMPS = [0, 1, 999_999_999, 1_000_000_000, 12_345_678_901, 2**31 * 1_000_000_000 - 1]
VALUE_PATTERNS = [
    lambda i: 0.0,
    lambda i: -1.5 * (i + 1),
    lambda i: 1e-300 * (i + 1),
    lambda i: 1e300 / (i + 1),
    lambda i: (-0.0, math.pi, math.inf, -math.inf, 1 / 3)[i % 5],
]
FRAMES = ["", "a", "ab", "abc", "world_ned", "base_link_frd", "world_ned_x"]


def _time(stamp_ns: int) -> Time:
    return Time(sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000)


def _covered(data: bytes, cls: type) -> tuple[set[int], int]:
    """Byte positions holding data (encapsulation, counts, strings, numbers) and where the data ends."""
    layout = message_layout(data, cls)
    covered: set[int] = set()
    for offset, length in layout.key_spans:
        covered.update(range(offset, offset + length))
    for offset, dtype, count in layout.numbers.values():
        size = int(dtype[-1]) * (1 if count is None else count)
        covered.update(range(offset, offset + size))
    return covered, max(covered) + 1


def check_bytes(ours: bytes, msg: object) -> None:
    cls = type(msg)
    reference = serialize_message(msg)
    covered, end = _covered(ours, cls)
    assert len(ours) == end, "the message must end where its data ends"
    reference_covered, _ = _covered(reference, cls)
    assert covered == reference_covered
    assert all(ours[i] == reference[i] for i in covered)
    assert all(ours[i] == 0 for i in range(len(ours)) if i not in covered), "padding must be zero"
    assert len(reference) >= end  # rclpy appends uninitialised bytes after an empty trailing sequence
    assert deserialize_message(ours, cls) == msg or _nan_equal(deserialize_message(ours, cls), msg)


def _nan_equal(a: object, b: object) -> bool:
    return serialize_message(a)[:16] == serialize_message(b)[:16] and repr(a) == repr(b)


def _values(pattern: int, count: int) -> list[float]:
    return [float(VALUE_PATTERNS[pattern](i)) for i in range(count)]


@pytest.mark.parametrize("pattern", range(len(VALUE_PATTERNS)))
@pytest.mark.parametrize("frame", FRAMES)
def test_odometry_wrench_quaternion(pattern: int, frame: str) -> None:
    for stamp in STAMPS:
        v = _values(pattern, 13)
        msg = Odometry()
        msg.header.stamp, msg.header.frame_id, msg.child_frame_id = _time(stamp), frame, frame[::-1] + "c"
        p, o = msg.pose.pose.position, msg.pose.pose.orientation
        p.x, p.y, p.z, o.x, o.y, o.z, o.w = v[:7]
        t = msg.twist.twist
        t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z = v[7:]
        check_bytes(cdr_pack.odometry(frame, frame[::-1] + "c").pack(stamp, v), msg)

        w = WrenchStamped()
        w.header.stamp, w.header.frame_id = _time(stamp), frame
        f, q = w.wrench.force, w.wrench.torque
        f.x, f.y, f.z, q.x, q.y, q.z = v[:6]
        check_bytes(cdr_pack.wrench_stamped(frame).pack(stamp, v[:6]), w)

        a = QuaternionStamped()
        a.header.stamp, a.header.frame_id = _time(stamp), frame
        a.quaternion.x, a.quaternion.y, a.quaternion.z, a.quaternion.w = v[:4]
        check_bytes(cdr_pack.quaternion_stamped(frame).pack(stamp, v[:4]), a)


@pytest.mark.parametrize("pattern", range(len(VALUE_PATTERNS)))
@pytest.mark.parametrize("frame", FRAMES)
def test_trajectory_point(pattern: int, frame: str) -> None:
    for stamp in STAMPS:
        v = _values(pattern, 19)
        msg = MultiDOFJointTrajectory()
        msg.header.stamp, msg.header.frame_id = _time(stamp), frame
        msg.joint_names = [frame + "_joint"]
        transform = Transform()
        tr, ro = transform.translation, transform.rotation
        tr.x, tr.y, tr.z, ro.x, ro.y, ro.z, ro.w = v[:7]
        velocity, acceleration = Twist(), Twist()
        for twist, part in ((velocity, v[7:13]), (acceleration, v[13:19])):
            twist.linear.x, twist.linear.y, twist.linear.z, twist.angular.x, twist.angular.y, twist.angular.z = part
        msg.points = [MultiDOFJointTrajectoryPoint(transforms=[transform], velocities=[velocity],
                                                   accelerations=[acceleration])]
        check_bytes(cdr_pack.trajectory_point(frame, frame + "_joint").pack(stamp, v), msg)


@pytest.mark.parametrize("pattern", range(len(VALUE_PATTERNS)))
@pytest.mark.parametrize("frame", FRAMES)
def test_imu(pattern: int, frame: str) -> None:
    """No orientation (identity, ``orientation_covariance[0] = -1``), diagonal covariances (zero: ideal)."""
    for variances in ((0.0, 0.0, 0.0, 0.0, 0.0, 0.0), (6e-5, 7e-5, 8e-5, 3e-3, 2e-3, 1.5)):
        for stamp in STAMPS:
            v = _values(pattern, 6)
            msg = Imu()
            msg.header.stamp, msg.header.frame_id = _time(stamp), frame
            msg.orientation.w, msg.orientation_covariance[0] = 1.0, -1.0
            w, a = msg.angular_velocity, msg.linear_acceleration
            w.x, w.y, w.z, a.x, a.y, a.z = v
            for i in range(3):
                msg.angular_velocity_covariance[4 * i] = variances[i]
                msg.linear_acceleration_covariance[4 * i] = variances[3 + i]
            check_bytes(cdr_pack.imu(frame, variances[:3], variances[3:]).pack(stamp, v), msg)


@pytest.mark.parametrize("rotors", [1, 4, 6, 8])
@pytest.mark.parametrize("tilting", [False, True])
@pytest.mark.parametrize("pattern", range(len(VALUE_PATTERNS)))
def test_joint_state(rotors: int, tilting: bool, pattern: int) -> None:
    names = [f"rotor_{i + 1}" for i in range(rotors)] + ([f"tilt_{i + 1}" for i in range(rotors)] if tilting else [])
    count = len(names)
    for stamp in STAMPS:
        positions, velocities = _values(pattern, count), _values((pattern + 1) % len(VALUE_PATTERNS), count)
        msg = JointState(name=names, position=positions, velocity=velocities)
        msg.header.stamp, msg.header.frame_id = _time(stamp), "base_link_frd"
        packer = cdr_pack.joint_state("base_link_frd", names, count, count)
        check_bytes(packer.pack(stamp, positions + velocities), msg)
    empty = JointState(name=names, velocity=velocities)
    check_bytes(cdr_pack.joint_state("", names, 0, count).pack(0, velocities), empty)


@pytest.mark.parametrize("pattern", range(len(VALUE_PATTERNS)))
def test_float64_clock_string(pattern: int) -> None:
    for value in _values(pattern, 5):
        check_bytes(cdr_pack.float64().pack(0, (value,)), Float64(data=value))
    for stamp in STAMPS:
        check_bytes(cdr_pack.clock().pack(stamp, ()), Clock(clock=_time(stamp)))
    for text in ["", "a", '{"state": "running"}', "é" * 7, "x" * 101]:
        check_bytes(cdr_pack.string(text), String(data=text))


@pytest.mark.parametrize("frame", FRAMES)
def test_readers_match_rclpy(frame: str) -> None:
    """cdr_read gives the doubles and stamp of rclpy's own serialisation (padding uninitialised) bit for bit."""
    from fsr_sim.ros import cdr_read

    for stamp in STAMPS:
        for pattern in range(len(VALUE_PATTERNS)):
            v = _values(pattern, 13)
            msg = Odometry()
            msg.header.stamp, msg.header.frame_id, msg.child_frame_id = _time(stamp), frame, frame + "xy"
            p, o = msg.pose.pose.position, msg.pose.pose.orientation
            p.x, p.y, p.z, o.x, o.y, o.z, o.w = v[:7]
            t = msg.twist.twist
            t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z = v[7:]
            msg.pose.covariance[0] = 7.0
            got_stamp, pose, twist = cdr_read.odometry(serialize_message(msg))
            assert got_stamp == stamp
            assert repr(pose + twist) == repr(tuple(v))
            w = WrenchStamped()
            w.header.stamp, w.header.frame_id = _time(stamp), frame
            w.wrench.force.x, w.wrench.force.y, w.wrench.force.z = v[:3]
            w.wrench.torque.x, w.wrench.torque.y, w.wrench.torque.z = v[3:6]
            assert cdr_read.wrench_stamped(serialize_message(w)) == (stamp, tuple(v[:6])) or repr(
                cdr_read.wrench_stamped(serialize_message(w))) == repr((stamp, tuple(v[:6])))
            imu = Imu()
            imu.header.stamp, imu.header.frame_id = _time(stamp), frame
            imu.orientation.x, imu.orientation_covariance[8], imu.angular_velocity_covariance[4] = v[6:9]
            imu.linear_acceleration_covariance[0] = v[9]
            g, a = imu.angular_velocity, imu.linear_acceleration
            g.x, g.y, g.z, a.x, a.y, a.z = v[:6]
            got_stamp, values = cdr_read.imu(serialize_message(imu))
            assert got_stamp == stamp and repr(values) == repr(tuple(v[:6]))
    with pytest.raises(ValueError):
        cdr_read.imu(serialize_message(Imu())[:100])
    with pytest.raises(ValueError):
        cdr_read.odometry(serialize_message(Odometry())[:40])
    with pytest.raises(ValueError):
        cdr_read.wrench_stamped(b"\x01\x00\x00\x00" + bytes(60))


@pytest.mark.parametrize("frame", FRAMES)
@pytest.mark.parametrize("joints", [["base_link_frd"], ["a", "bc", "def"], []])
def test_the_reference_and_attitude_cmd_readers_match_rclpy(frame: str, joints: list[str]) -> None:
    """The reference pose and the commanded attitude (what the simulator checks a loss of control against), read from
    rclpy's serialisation whatever the joint names' lengths, bit for bit."""
    from fsr_sim.ros import cdr_read

    for stamp in STAMPS:
        v = _values(1, 7)
        msg = MultiDOFJointTrajectory()
        msg.header.stamp, msg.header.frame_id = _time(stamp), frame
        msg.joint_names = joints
        transform = Transform()
        tr, ro = transform.translation, transform.rotation
        tr.x, tr.y, tr.z, ro.x, ro.y, ro.z, ro.w = v
        msg.points = [MultiDOFJointTrajectoryPoint(transforms=[transform])]
        assert repr(cdr_read.reference_pose(serialize_message(msg))) == repr((stamp, tuple(v)))
    with pytest.raises(ValueError):
        cdr_read.reference_pose(serialize_message(MultiDOFJointTrajectory()))
    attitude = QuaternionStamped()
    attitude.header.stamp, attitude.header.frame_id = _time(STAMPS[-1]), frame
    q = attitude.quaternion
    q.x, q.y, q.z, q.w = _values(2, 4)
    assert repr(cdr_read.quaternion_stamped(serialize_message(attitude))) == repr((STAMPS[-1], tuple(_values(2, 4))))


@pytest.mark.parametrize("names", [["rotor_1", "rotor_2", "rotor_3", "rotor_4"],
                                   [f"rotor_{i + 1}" for i in range(8)] + [f"tilt_{i + 1}" for i in range(8)],
                                   ["rotor_10", "a", "bc"]])
def test_joint_state_reader(names: list[str]) -> None:
    from fsr_sim.ros import cdr_read

    reader = cdr_read.JointStateReader(names)
    n = len(names)
    for pattern in range(len(VALUE_PATTERNS)):
        positions, velocities = _values(pattern, n), _values((pattern + 2) % len(VALUE_PATTERNS), n)
        packed = cdr_pack.joint_state("base_link_frd", names, n, n).pack(123_456_789_012, positions + velocities)
        assert repr(reader.read(packed)) == repr((123_456_789_012, tuple(positions), tuple(velocities)))
        msg = JointState(name=names, velocity=velocities)
        msg.header.frame_id = "xyz"
        got = reader.read(cdr_pack.joint_state("xyz", names, 0, n).pack(0, velocities))
        assert repr(got) == repr((0, (), tuple(velocities)))
    assert reader.read(cdr_pack.joint_state("", names[::-1] + ["x"], 0, 0).pack(0, ())) is None


@pytest.mark.parametrize("packer", [
    cdr_pack.odometry("world_ned", "base_link_frd"), cdr_pack.wrench_stamped("ab"), cdr_pack.quaternion_stamped(""),
    cdr_pack.float64(), cdr_pack.clock(), cdr_pack.trajectory_point("world_ned", "base_link_frd"),
    cdr_pack.joint_state("base_link_frd", ["rotor_1", "rotor_2", "tilt_1", "tilt_2"], 4, 4),
    cdr_pack.joint_state("a", ["rotor_1"], 0, 1), cdr_pack.imu("base_link_frd", (1e-4, 2e-4, 3e-4), (0.0, 0.0, 0.0))],
    ids=lambda packer: f"{packer.value_count}_values_{packer.size}_bytes")
def test_pack_rows_is_pack_for_each_row(packer: cdr_pack.StampedDoubles) -> None:
    """A block packed at once (the in-process recording) holds, row by row, the bytes of ``pack``."""
    import numpy as np

    stamps = np.array(STAMPS * len(VALUE_PATTERNS), dtype=np.int64)
    values = np.array([_values(pattern, packer.value_count) for pattern in range(len(VALUE_PATTERNS))
                       for _ in STAMPS]).reshape(len(stamps), packer.value_count)
    rows = packer.pack_rows(stamps, values)
    assert rows.dtype == np.uint8 and rows.shape == (len(stamps), packer.size)
    for k, stamp in enumerate(stamps.tolist()):
        assert rows[k].tobytes() == packer.pack(stamp, values[k].tolist())
