"""Packed-template CDR encoders for the messages fsr publishes at every step (no rclpy, no message objects).

Every per-step message of a flight has a fixed byte layout: its frame ids, joint names and sequence lengths
never change, only the stamp and the numbers do. A :class:`Template` lays the message out once (XCDR1 little
endian, as ROS 2 writes it: the 4-byte encapsulation header ``00 01 00 00``, then the fields in declaration
order, each primitive aligned to its size counted from the end of that header, strings and sequences a
``uint32`` count first, strings with their NUL) and every message is then two ``struct.pack_into`` calls
and one copy: ~1 us instead of building a message object and serialising it with rclpy (20-50 us).

The bytes are what rclpy's ``serialize_message`` writes for the same message, except that every alignment
padding byte is zero (rclpy leaves padding uninitialised, and appends 4 such bytes after a ``JointState``
whose trailing ``effort`` sequence is empty; the payload over DDS stops at the end of the data, as here).
The nodes publish these bytes (``Publisher.publish(bytes)``) and the in-process recording writes them, so
the graph and an in-process flight record the same payloads (tested field by field against rclpy, and the
padding checked to be zero).

Stamps are integer nanoseconds of simulated time (``sec = stamp // 1e9``, ``nanosec = stamp % 1e9``).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

import numpy as np

ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR_LE, options 0
NS_PER_S = 1_000_000_000
_STAMP = struct.Struct("<iI")
_UINT32 = struct.Struct("<I")


class Template:
    """Lays out one CDR message field by field; the offsets returned mark where the numbers go."""

    def __init__(self) -> None:
        self.buffer = bytearray(ENCAPSULATION)

    @property
    def offset(self) -> int:
        return len(self.buffer)

    def align(self, size: int) -> None:
        """Zero padding up to a multiple of ``size`` bytes (counted from the end of the encapsulation header)."""
        self.buffer += bytes((-(len(self.buffer) - len(ENCAPSULATION))) % size)

    def uint32(self, value: int) -> None:
        self.align(4)
        self.buffer += _UINT32.pack(value)

    def int32(self, value: int) -> None:
        self.align(4)
        self.buffer += struct.pack("<i", value)

    def boolean(self, value: bool) -> None:
        self.buffer += bytes((1 if value else 0,))

    def zeros(self, alignment: int, size: int) -> int:
        """``size`` zero bytes aligned to ``alignment`` (a field filled in at each message): their offset."""
        self.align(alignment)
        offset = self.offset
        self.buffer += bytes(size)
        return offset

    def floats(self, count: int) -> int:
        """``count`` float32 (e.g. a ``std_msgs/ColorRGBA``): the offset of the first."""
        return self.zeros(4, 4 * count)

    def string(self, text: str) -> None:
        data = text.encode("utf-8")
        self.uint32(len(data) + 1)
        self.buffer += data + b"\x00"

    def strings(self, texts: Sequence[str]) -> None:
        self.uint32(len(texts))
        for text in texts:
            self.string(text)

    def stamp(self) -> int:
        """``builtin_interfaces/Time`` (int32 sec, uint32 nanosec): its offset."""
        return self.zeros(4, 8)

    def header(self, frame_id: str) -> int:
        """``std_msgs/Header``: the stamp's offset."""
        offset = self.stamp()
        self.string(frame_id)
        return offset

    def doubles(self, count: int) -> int:
        """``count`` float64 (a fixed array, or a nested message of doubles): the offset of the first."""
        return self.zeros(8, 8 * count)

    def double_sequence(self, count: int) -> int:
        """``float64[]`` of ``count`` elements: the offset of the first element."""
        self.uint32(count)
        return self.doubles(count) if count else self.offset


class StampedDoubles:
    """A message that is a ``Header`` (fixed ``frame_id``) or a bare stamp, then doubles at fixed places.

    ``runs`` are (offset, count) of the runs of doubles in field order; :meth:`pack` takes all the doubles in
    that order. Runs separated only by zero bytes (padding, zero covariances) are packed by one struct
    (``x`` pad bytes are written as zeros).
    """

    def __init__(self, template: Template, stamp_offset: int | None, runs: list[tuple[int, int]]) -> None:
        self.template = bytes(template.buffer)
        self.size = len(self.template)
        self.stamp_offset = stamp_offset
        self.value_count = sum(count for _, count in runs)
        self.runs = list(runs)
        segments: list[tuple[int, str, int]] = []  # (offset, format, value count)
        end = -1
        for offset, count in runs:
            if segments and not any(self.template[end:offset]):
                first, fmt, values = segments[-1]
                segments[-1] = (first, f"{fmt}{offset - end}x{count}d", values + count)
            else:
                segments.append((offset, f"{count}d", count))
            end = offset + 8 * count
        self._segments = [(offset, struct.Struct("<" + fmt), count) for offset, fmt, count in segments]
        self._single = self._segments[0] if len(self._segments) == 1 else None

    def pack(self, stamp_ns: int, values: Sequence[float]) -> bytes:
        """The message stamped ``stamp_ns`` [ns] holding ``values`` (floats, in field order)."""
        buffer = bytearray(self.template)
        if self.stamp_offset is not None:
            _STAMP.pack_into(buffer, self.stamp_offset, *divmod(stamp_ns, NS_PER_S))
        single = self._single
        if single is not None:
            single[1].pack_into(buffer, single[0], *values)
        else:
            start = 0
            for offset, packer, count in self._segments:
                packer.pack_into(buffer, offset, *values[start:start + count])
                start += count
        return bytes(buffer)

    def pack_rows(self, stamps_ns: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Many messages at once (a whole block of a log): row ``k`` of the result (uint8, shape (N, size)) is
        ``pack(stamps_ns[k], values[k])`` byte for byte. ``stamps_ns`` (N,) int [ns]; ``values`` (N,
        value_count) float, in field order (the template's padding and constant fields are copied as they are).
        """
        stamps = np.asarray(stamps_ns, dtype=np.int64)
        values = np.asarray(values, dtype="<f8").reshape(len(stamps), self.value_count)
        rows = np.tile(np.frombuffer(self.template, dtype=np.uint8), (len(stamps), 1))
        if self.stamp_offset is not None:
            seconds, nanoseconds = np.divmod(stamps, NS_PER_S)
            stamp = np.empty((len(stamps), 2), dtype="<u4")
            stamp[:, 0] = seconds.astype("<i4").view("<u4")
            stamp[:, 1] = nanoseconds
            rows[:, self.stamp_offset:self.stamp_offset + 8] = stamp.view(np.uint8)
        start = 0
        for offset, count in self.runs:
            rows[:, offset:offset + 8 * count] = np.ascontiguousarray(values[:, start:start + count]).view(np.uint8)
            start += count
        return rows


class StampedNumbers:
    """A message of fixed layout with several stamps (one per nested ``Header``, all the same) and runs of float64
    and float32 at fixed places: ``tf2_msgs/TFMessage``, ``visualization_msgs/MarkerArray``. Only
    :meth:`pack_rows` (many messages at once, as :meth:`StampedDoubles.pack_rows`).

    ``runs``: (offset, count, dtype ``"<f8"`` or ``"<f4"``) in value order."""

    def __init__(self, template: Template, stamp_offsets: Sequence[int], runs: Sequence[tuple[int, int, str]]) -> None:
        self.template = bytes(template.buffer)
        self.size = len(self.template)
        self.stamp_offsets = tuple(stamp_offsets)
        self.runs = tuple(runs)
        self.value_count = sum(count for _, count, _ in runs)

    def pack_rows(self, stamps_ns: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Row ``k`` (uint8, shape (N, size)): the message stamped ``stamps_ns[k]`` [ns] holding ``values[k]``
        (N, value_count) in run order (float32 runs rounded to float32)."""
        stamps = np.asarray(stamps_ns, dtype=np.int64)
        values = np.asarray(values, dtype=np.float64).reshape(len(stamps), self.value_count)
        rows = np.tile(np.frombuffer(self.template, dtype=np.uint8), (len(stamps), 1))
        seconds, nanoseconds = np.divmod(stamps, NS_PER_S)
        stamp = np.empty((len(stamps), 2), dtype="<u4")
        stamp[:, 0] = seconds.astype("<i4").view("<u4")
        stamp[:, 1] = nanoseconds
        stamp_bytes = stamp.view(np.uint8)
        for offset in self.stamp_offsets:
            rows[:, offset:offset + 8] = stamp_bytes
        start = 0
        for offset, count, dtype in self.runs:
            size = np.dtype(dtype).itemsize
            rows[:, offset:offset + size * count] = values[:, start:start + count].astype(dtype).view(np.uint8)
            start += count
        return rows


def odometry(frame_id: str, child_frame_id: str) -> StampedDoubles:
    """``nav_msgs/Odometry``: values = position (3), orientation x y z w (4), twist linear (3), angular (3);
    both covariances zero."""
    t = Template()
    stamp = t.header(frame_id)
    t.string(child_frame_id)
    pose = t.doubles(7)
    t.doubles(36)
    twist = t.doubles(6)
    t.doubles(36)
    return StampedDoubles(t, stamp, [(pose, 7), (twist, 6)])


def wrench_stamped(frame_id: str) -> StampedDoubles:
    """``geometry_msgs/WrenchStamped``: values = force (3), torque (3)."""
    t = Template()
    stamp = t.header(frame_id)
    return StampedDoubles(t, stamp, [(t.doubles(6), 6)])


def quaternion_stamped(frame_id: str) -> StampedDoubles:
    """``geometry_msgs/QuaternionStamped``: values = x, y, z, w."""
    t = Template()
    stamp = t.header(frame_id)
    return StampedDoubles(t, stamp, [(t.doubles(4), 4)])


def float64() -> StampedDoubles:
    """``std_msgs/Float64`` (no stamp: ``pack(0, (value,))``)."""
    t = Template()
    return StampedDoubles(t, None, [(t.doubles(1), 1)])


def clock() -> StampedDoubles:
    """``rosgraph_msgs/Clock`` (only the stamp: ``pack(stamp_ns, ())``)."""
    t = Template()
    stamp = t.stamp()
    return StampedDoubles(t, stamp, [])


def joint_state(frame_id: str, names: Sequence[str], positions: int, velocities: int, efforts: int = 0
                ) -> StampedDoubles:
    """``sensor_msgs/JointState`` with these names and sequence lengths: values = positions, velocities,
    efforts."""
    t = Template()
    stamp = t.header(frame_id)
    t.strings(names)
    runs = []
    for count in (positions, velocities, efforts):
        offset = t.double_sequence(count)
        if count:
            runs.append((offset, count))
    return StampedDoubles(t, stamp, runs)


def imu(frame_id: str, angular_velocity_variance: Sequence[float], linear_acceleration_variance: Sequence[float]
        ) -> StampedDoubles:
    """``sensor_msgs/Imu`` without an orientation (the identity quaternion, ``orientation_covariance[0] = -1``:
    not provided) and diagonal covariances of the angular velocity [(rad/s)^2] and linear acceleration
    [(m/s^2)^2] per axis (fixed for a flight): values = angular velocity (3), linear acceleration (3)."""
    t = Template()
    stamp = t.header(frame_id)
    orientation = t.doubles(4)
    covariance = t.doubles(9)
    angular = t.doubles(3)
    angular_covariance = t.doubles(9)
    linear = t.doubles(3)
    linear_covariance = t.doubles(9)
    struct.pack_into("<d", t.buffer, orientation + 24, 1.0)
    struct.pack_into("<d", t.buffer, covariance, -1.0)
    for i in range(3):
        struct.pack_into("<d", t.buffer, angular_covariance + 32 * i, float(angular_velocity_variance[i]))
        struct.pack_into("<d", t.buffer, linear_covariance + 32 * i, float(linear_acceleration_variance[i]))
    return StampedDoubles(t, stamp, [(angular, 3), (linear, 3)])


def trajectory_point(frame_id: str, joint_name: str) -> StampedDoubles:
    """``trajectory_msgs/MultiDOFJointTrajectory`` with one joint and one point (``time_from_start`` 0):
    values = translation (3), rotation x y z w (4), velocity linear (3), angular (3), acceleration linear (3),
    angular (3)."""
    t = Template()
    stamp = t.header(frame_id)
    t.strings([joint_name])
    t.uint32(1)  # points
    t.uint32(1)  # transforms
    transform = t.doubles(7)
    t.uint32(1)  # velocities
    velocity = t.doubles(6)
    t.uint32(1)  # accelerations
    acceleration = t.doubles(6)
    t.stamp()  # time_from_start (builtin_interfaces/Duration: int32 sec, uint32 nanosec), zero
    return StampedDoubles(t, stamp, [(transform, 7), (velocity, 6), (acceleration, 6)])


def string(text: str) -> bytes:
    """``std_msgs/String``."""
    t = Template()
    t.string(text)
    return bytes(t.buffer)
