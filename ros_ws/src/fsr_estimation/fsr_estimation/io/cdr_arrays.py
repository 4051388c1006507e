"""Vectorised reading of stamped messages whose body is only float64 fields (Odometry, WrenchStamped).

Decoding 30 000 Odometry messages one by one takes seconds; when every payload of a topic has the same
layout (same length and the same frame ids, the normal case for a recording) the whole topic is one
``(N, length)`` byte array and the fields are fixed byte offsets. Layout, per the OMG CDR rules that
ROS 2 uses (little-endian, alignment relative to the end of the 4-byte encapsulation header):
``stamp.sec`` int32, ``stamp.nanosec`` uint32, ``frame_id`` (uint32 length incl. NUL + bytes), [padding to
4] ``child_frame_id`` (Odometry only), then the float64 fields aligned to 8. Anything else returns None
and the caller falls back to the generic decoder.
"""

from __future__ import annotations

import numpy as np

_ENCAPSULATION = 4
_CDR_LE = (0, 1)


def _align(offset: int, size: int) -> int:
    return (offset + size - 1) // size * size


def stamped_doubles(payloads: list[bytes], string_count: int, double_count: int
                    ) -> tuple[np.ndarray, np.ndarray] | None:
    """(stamps [ns] (N,), float64 fields (N, double_count)) of uniform CDR payloads, or None.

    string_count: strings after the stamp (1 for WrenchStamped's ``frame_id``, 2 for Odometry's
    ``frame_id`` and ``child_frame_id``); double_count: the float64 fields that follow (6 for a wrench,
    85 for an Odometry).
    """
    if not payloads:
        return None
    length = len(payloads[0])
    if length < _ENCAPSULATION + 8 or any(len(p) != length for p in payloads):
        return None
    first = payloads[0]
    if tuple(first[:2]) != _CDR_LE:
        return None
    offset = 8  # body offset after the stamp
    strings = []  # byte ranges (length prefix and text) that must be equal in every message
    for _ in range(string_count):
        offset = _align(offset, 4)
        if _ENCAPSULATION + offset + 4 > length:
            return None
        size = int.from_bytes(first[_ENCAPSULATION + offset:_ENCAPSULATION + offset + 4], "little")
        strings.append(slice(_ENCAPSULATION + offset, _ENCAPSULATION + offset + 4 + size))
        offset += 4 + size
    offset = _align(offset, 8)
    if _ENCAPSULATION + offset + 8 * double_count != length:
        return None
    table = np.frombuffer(b"".join(payloads), dtype=np.uint8).reshape(len(payloads), length)
    # Same encapsulation and the same strings (frame ids) in every message: then the offsets hold for all.
    # (Padding bytes are not compared: writers may leave them uninitialised.)
    if not np.all(table[:, :2] == table[0, :2]):
        return None
    if not all(np.all(table[:, span] == table[0, span]) for span in strings):
        return None
    sec = np.ascontiguousarray(table[:, 4:8]).view("<i4")[:, 0].astype(np.int64)
    nanosec = np.ascontiguousarray(table[:, 8:12]).view("<u4")[:, 0].astype(np.int64)
    values = np.ascontiguousarray(table[:, _ENCAPSULATION + offset:]).view("<f8").astype(float)
    return sec * 1_000_000_000 + nanosec, values
