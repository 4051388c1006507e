"""Reading the per-step messages fsr subscribes to straight from their CDR bytes (``raw=True`` subscriptions).

A node that answers every step does not need a message object: it needs the stamp and a few doubles.
These readers walk the only variable part of the layout (the header's ``frame_id``, and ``Odometry``'s
``child_frame_id``) and unpack the numbers with one ``struct`` call (~1 us instead of ~20-50 us for rclpy's
deserialisation into Python objects). Little-endian CDR only (what ROS 2 writes on x86_64); anything else
raises :class:`ValueError`, and so does a message that is cut short. The values are the message's doubles,
bit for bit (tested against rclpy's ``deserialize_message``).
"""

from __future__ import annotations

import struct

_HEADER = 4
_STAMP = struct.Struct("<iIi")  # sec, nanosec, frame_id length
_UINT32 = struct.Struct("<I")
_POSE = struct.Struct("<7d")
_SIX = struct.Struct("<6d")  # a twist, a wrench
_THREE = struct.Struct("<3d")  # a vector
_QUATERNION = struct.Struct("<4d")
_COVARIANCE_BYTES = 36 * 8
NS_PER_S = 1_000_000_000


def _check(data: bytes) -> None:
    if len(data) < _HEADER + 12 or data[1] != 1:
        raise ValueError("not a little-endian CDR message")


def _after_header(data: bytes) -> tuple[int, int]:
    """(stamp [ns], offset after the header's frame_id)."""
    sec, nanosec, length = _STAMP.unpack_from(data, _HEADER)
    return sec * NS_PER_S + nanosec, _HEADER + 12 + length


def _align(offset: int, size: int) -> int:
    return offset + (-(offset - _HEADER)) % size


def odometry(data: bytes) -> tuple[int, tuple[float, ...], tuple[float, ...]]:
    """``nav_msgs/Odometry``: (stamp [ns], pose (x y z qx qy qz qw), twist (linear xyz, angular xyz))."""
    _check(data)
    try:
        stamp, offset = _after_header(data)
        offset = _align(offset, 4)
        (length,) = _UINT32.unpack_from(data, offset)
        offset = _align(offset + 4 + length, 8)
        pose = _POSE.unpack_from(data, offset)
        twist = _SIX.unpack_from(data, offset + 56 + _COVARIANCE_BYTES)
    except struct.error as error:
        raise ValueError(f"Odometry message cut short: {error}") from None
    return stamp, pose, twist


def _header_and_doubles(data: bytes, layout: struct.Struct, type_name: str) -> tuple[int, tuple[float, ...]]:
    """(stamp [ns], the doubles of ``layout`` right after the header): a ``*Stamped`` message of one fixed-size
    body; ValueError naming ``type_name`` when the bytes end early."""
    _check(data)
    try:
        stamp, offset = _after_header(data)
        values = layout.unpack_from(data, _align(offset, 8))
    except struct.error as error:
        raise ValueError(f"{type_name} message cut short: {error}") from None
    return stamp, values


def wrench_stamped(data: bytes) -> tuple[int, tuple[float, ...]]:
    """``geometry_msgs/WrenchStamped``: (stamp [ns], (force xyz, torque xyz))."""
    return _header_and_doubles(data, _SIX, "WrenchStamped")


def imu(data: bytes) -> tuple[int, tuple[float, ...]]:
    """``sensor_msgs/Imu``: (stamp [ns], (angular velocity xyz, linear acceleration xyz))."""
    _check(data)
    try:
        stamp_ns, offset = _after_header(data)
        offset = _align(offset, 8) + 32 + 72  # orientation, its covariance
        angular = _THREE.unpack_from(data, offset)
        linear = _THREE.unpack_from(data, offset + 24 + 72)  # after the angular velocity's covariance
    except struct.error as error:
        raise ValueError(f"Imu message cut short: {error}") from None
    return stamp_ns, angular + linear


def quaternion_stamped(data: bytes) -> tuple[int, tuple[float, ...]]:
    """``geometry_msgs/QuaternionStamped``: (stamp [ns], (x, y, z, w))."""
    return _header_and_doubles(data, _QUATERNION, "QuaternionStamped")


def reference_pose(data: bytes) -> tuple[int, tuple[float, ...]]:
    """``trajectory_msgs/MultiDOFJointTrajectory``: (stamp [ns], its first point's first transform: translation
    x y z, rotation x y z w). ValueError for a message without a point or a transform."""
    _check(data)
    try:
        stamp_ns, offset = _after_header(data)
        offset = _align(offset, 4)
        (names,) = _UINT32.unpack_from(data, offset)
        offset += 4
        for _ in range(names):  # joint_names: each a uint32 length and its bytes, 4-aligned
            offset = _align(offset, 4)
            (length,) = _UINT32.unpack_from(data, offset)
            offset += 4 + length
        offset = _align(offset, 4)
        points, transforms = _UINT32.unpack_from(data, offset)[0], _UINT32.unpack_from(data, offset + 4)[0]
        if not points or not transforms:
            raise ValueError("MultiDOFJointTrajectory without a point or a transform")
        pose = _POSE.unpack_from(data, _align(offset + 8, 8))
    except struct.error as error:
        raise ValueError(f"MultiDOFJointTrajectory message cut short: {error}") from None
    return stamp_ns, pose


def stamp(data: bytes) -> int:
    """The leading ``Header`` stamp [ns] of a message (little-endian CDR)."""
    _check(data)
    return _after_header(data)[0]


class JointStateReader:
    """``sensor_msgs/JointState`` with a known list of names -> (stamp [ns], positions, velocities).

    :meth:`read` returns None when the message's names are not exactly ``names`` (in that order, with zero
    padding): the caller then decodes the message the general way."""

    def __init__(self, names: list[str]) -> None:
        block = bytearray(_UINT32.pack(len(names)))
        for name in names:
            block += bytes((-len(block)) % 4)
            data = name.encode("utf-8") + b"\x00"
            block += _UINT32.pack(len(data)) + data
        self.names_block = bytes(block)

    def read(self, data: bytes) -> tuple[int, tuple[float, ...], tuple[float, ...]] | None:
        _check(data)
        stamp_ns, offset = _after_header(data)
        offset = _align(offset, 4)
        end = offset + len(self.names_block)
        if data[offset:end] != self.names_block:
            return None
        try:
            positions, offset = _double_sequence(data, end)
            velocities, _ = _double_sequence(data, offset)
        except struct.error as error:
            raise ValueError(f"JointState message cut short: {error}") from None
        return stamp_ns, positions, velocities


def _double_sequence(data: bytes, offset: int) -> tuple[tuple[float, ...], int]:
    offset = _align(offset, 4)
    (count,) = _UINT32.unpack_from(data, offset)
    offset += 4
    if not count:
        return (), offset
    offset = _align(offset, 8)
    return struct.unpack_from(f"<{count}d", data, offset), offset + 8 * count
