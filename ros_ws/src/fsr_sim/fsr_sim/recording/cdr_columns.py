"""Vectorised decoding of whole topics of CDR messages into numpy columns (no per-message Python objects).

Decoding a 30 s, 1 kHz recording message by message (``mcap_ros2`` or ``rclpy``) costs 50-100 us per
Odometry, several seconds per run. Messages of one topic almost always share one byte layout (same frame
ids, same joint names, same sequence lengths), so the layout is worked out once from one message and every
numeric field is then a strided column of the ``(n_messages, n_bytes)`` byte matrix.

CDR (XCDR1, as ROS 2 writes it): a 4-byte encapsulation header (``00 01`` = little endian), then the
fields in declaration order, each primitive aligned to its size (at most 8) counted from the end of that
header; strings and sequences are a ``uint32`` count followed by the elements (strings include their NUL).

A layout is fully determined by the string lengths and sequence counts met while walking a message, so
the messages that share the first message's length, counts and string bytes share its layout exactly;
the others are split off and walked in turn. Field paths are dotted (``pose.pose.position.x``,
``points.0.transforms.0.translation.x``); a numeric sequence or array is one path with a 2-D column.

Used by every whole-log reader (``fsr_bringup.analysis.load``, ``fsr_estimation.io.flight_log``); needs
the ROS message definitions (``rosidl_parser`` and the message packages), not a running ROS graph.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache, cached_property
from typing import Any

import numpy as np
from rosidl_parser.definition import (
    AbstractGenericString,
    AbstractSequence,
    AbstractWString,
    Array,
    BasicType,
    NamespacedType,
)

from fsr_sim.ros.message_schema import message_class

HEADER_BYTES = 4  # CDR encapsulation header
MAX_LAYOUTS = 32  # beyond this many distinct layouts a topic is decoded message by message

_DTYPES = {
    "boolean": "u1", "octet": "u1", "char": "u1", "uint8": "u1", "int8": "i1",
    "uint16": "<u2", "int16": "<i2", "uint32": "<u4", "int32": "<i4", "uint64": "<u8", "int64": "<i8",
    "float": "<f4", "double": "<f8", "wchar": "<u2",
}


class LayoutError(ValueError):
    """A message that the vectorised decoder does not handle (big endian, wide strings, cut short)."""


@dataclass
class Layout:
    """Where every field of one message sits: numeric columns, strings, and the bytes that fix the layout."""

    size: int
    numbers: dict[str, tuple[int, str, int | None]] = field(default_factory=dict)  # path -> (offset, dtype, count)
    strings: dict[str, str] = field(default_factory=dict)  # path -> value
    key_spans: list[tuple[int, int]] = field(default_factory=list)  # (offset, length) of counts and string bytes

    @cached_property
    def key_columns(self) -> np.ndarray:
        """The byte positions of the key spans (int64 (k,)): what a message must share with this one to share its
        layout."""
        return np.concatenate([np.arange(offset, offset + size) for offset, size in self.key_spans] or [[]]
                              ).astype(np.int64)


@cache
def _members(cls: type) -> tuple[tuple[str, Any], ...]:
    return tuple(zip(cls.get_fields_and_field_types().keys(), cls.SLOT_TYPES, strict=True))


class _Walker:
    """Walks one message's bytes along its type definition, filling a :class:`Layout`."""

    def __init__(self, data: bytes) -> None:
        if len(data) < HEADER_BYTES or data[1] != 1:
            raise LayoutError("not little-endian CDR")
        self.data = data
        self.pos = HEADER_BYTES
        self.layout = Layout(size=len(data), key_spans=[(0, HEADER_BYTES)])

    def align(self, size: int) -> None:
        size = min(size, 8)
        self.pos += (-(self.pos - HEADER_BYTES)) % size

    def count(self) -> int:
        self.align(4)
        if self.pos + 4 > len(self.data):
            raise LayoutError("message cut short")
        value = int.from_bytes(self.data[self.pos : self.pos + 4], "little")
        self.layout.key_spans.append((self.pos, 4))
        self.pos += 4
        return value

    def string(self, path: str) -> None:
        length = self.count()
        end = self.pos + length
        if end > len(self.data):
            raise LayoutError("string runs past the end of the message")
        raw = self.data[self.pos : end]
        self.layout.key_spans.append((self.pos, length))
        self.layout.strings[path] = raw.rstrip(b"\0").decode("utf-8", errors="replace")
        self.pos = end

    def numbers(self, path: str, typename: str, count: int | None) -> None:
        dtype = _DTYPES[typename]
        size = np.dtype(dtype).itemsize
        if count == 0:  # an empty sequence has no element padding (it may end the message)
            self.layout.numbers[path] = (self.pos, dtype, 0)
            return
        self.align(size)
        self.layout.numbers[path] = (self.pos, dtype, count)
        self.pos += size * (1 if count is None else count)
        if self.pos > len(self.data):
            raise LayoutError("message cut short")

    def member(self, path: str, slot: Any) -> None:
        if isinstance(slot, BasicType):
            self.numbers(path, slot.typename, None)
        elif isinstance(slot, AbstractWString):
            raise LayoutError("wide strings are not supported")
        elif isinstance(slot, AbstractGenericString):
            self.string(path)
        elif isinstance(slot, NamespacedType):
            self.struct(path, message_class("/".join([*slot.namespaces, slot.name])))
        elif isinstance(slot, Array | AbstractSequence):
            count = slot.size if isinstance(slot, Array) else self.count()
            item = slot.value_type
            if isinstance(item, BasicType):
                self.numbers(path, item.typename, count)
            else:
                for i in range(count):
                    self.member(f"{path}.{i}", item)
        else:
            raise LayoutError(f"unsupported field type {type(slot).__name__}")

    def struct(self, prefix: str, cls: type) -> None:
        for name, slot in _members(cls):
            self.member(f"{prefix}.{name}" if prefix else name, slot)


def message_layout(data: bytes, cls: type) -> Layout:
    """The layout of one CDR message of class ``cls`` (an rclpy message class)."""
    walker = _Walker(data)
    walker.struct("", cls)
    return walker.layout


_LAYOUTS: dict[tuple[type, int], list[tuple[Layout, bytes]]] = {}  # (class, size) -> layouts and their key bytes
_LAYOUTS_KEPT = 256


def _layout_of(message: np.ndarray, cls: type) -> Layout:
    """:func:`message_layout` of ``message`` (uint8 row), from the layouts already walked where one fits: a
    layout is fixed by the bytes of its key spans (counts, string bytes), so a message of the same size with
    the same bytes there has it exactly (a block of an in-process recording: one walk per topic and flight)."""
    known = _LAYOUTS.setdefault((cls, len(message)), [])
    for layout, key in known:
        if message[layout.key_columns].tobytes() == key:
            return layout
    layout = message_layout(message.tobytes(), cls)
    if sum(len(layouts) for layouts in _LAYOUTS.values()) >= _LAYOUTS_KEPT:
        _LAYOUTS.clear()
        known = _LAYOUTS.setdefault((cls, len(message)), [])
    known.append((layout, message[layout.key_columns].tobytes()))
    return layout


@dataclass
class Columns:
    """Decoded fields of ``n`` messages: numeric columns (NaN where a message lacks the field) and strings."""

    n: int
    numbers: dict[str, np.ndarray]
    strings: dict[str, np.ndarray]  # object arrays of str (None where absent)

    def get(self, path: str) -> np.ndarray:
        if path not in self.numbers:
            raise KeyError(f"no field '{path}' (fields: {', '.join(sorted(self.numbers)[:20])} ...)")
        return self.numbers[path]


def decode_columns(payloads: list[bytes] | np.ndarray, type_name: str, fields: tuple[str, ...] | None = None
                   ) -> Columns:
    """Decode every message of one topic into columns; raises :class:`LayoutError` if it cannot.

    payloads: CDR bytes of ``n`` messages of ``type_name`` (``nav_msgs/msg/Odometry``), or a uint8 array (n, size)
    of messages of one length (an in-process block). Returns
    ``numbers[path]`` of shape (n,) for scalars and (n, k) for arrays/sequences (float64; integers that
    fit exactly, e.g. stamps, are kept as int64), and ``strings[path]`` of shape (n,). ``fields``: only the
    numeric paths that start with one of these (``("pose.pose.position.",)``; None: all).
    """
    cls = message_class(type_name)
    n = len(payloads)
    groups: list[tuple[np.ndarray, Layout, np.ndarray]] = []  # (message indices, layout, byte matrix rows)
    if isinstance(payloads, np.ndarray):  # rows of one length (uint8, (n, size)): already the byte matrix
        lengths = np.full(n, payloads.shape[1] if n else 0, dtype=np.int64)
    else:
        lengths = np.fromiter((len(p) for p in payloads), dtype=np.int64, count=n)
    for length in np.unique(lengths):
        index = np.flatnonzero(lengths == length)
        if isinstance(payloads, np.ndarray):
            matrix = np.ascontiguousarray(payloads, dtype=np.uint8)
        else:
            matrix = np.frombuffer(b"".join(payloads[i] for i in index), dtype=np.uint8).reshape(len(index), length)
        remaining = np.arange(len(index))
        while remaining.size:
            if len(groups) >= MAX_LAYOUTS:
                raise LayoutError(f"more than {MAX_LAYOUTS} message layouts on one topic")
            first = matrix[remaining[0]]
            layout = _layout_of(first, cls)
            keys = layout.key_columns
            rows = matrix[:, keys] if remaining.size == len(matrix) else matrix[np.ix_(remaining, keys)]
            same = np.all(rows == first[keys], axis=1)
            groups.append((index[remaining[same]], layout, matrix[remaining[same]]))
            remaining = remaining[~same]
    return _assemble(n, groups, fields)


def _assemble(n: int, groups: list[tuple[np.ndarray, Layout, np.ndarray]], fields: tuple[str, ...] | None = None
              ) -> Columns:
    widths: dict[str, int | None] = {}
    kinds: dict[str, str] = {}
    for _, layout, _ in groups:
        for path, (_, dtype, count) in layout.numbers.items():
            if fields is not None and not path.startswith(fields):
                continue
            widths[path] = count if widths.get(path) is None else max(widths[path], count or 0)
            kinds.setdefault(path, dtype)
    integer_ok = len(groups) == 1  # a missing value in some group forces NaN (float)
    numbers: dict[str, np.ndarray] = {}
    for path, width in widths.items():
        is_int = integer_ok and np.dtype(kinds[path]).kind in "iub"
        shape = (n,) if width is None else (n, width)
        out = np.zeros(shape, dtype=np.int64) if is_int else np.full(shape, np.nan)
        for rows, layout, matrix in groups:
            if path not in layout.numbers:
                continue
            offset, dtype, count = layout.numbers[path]
            size = np.dtype(dtype).itemsize * (1 if count is None else count)
            values = np.ascontiguousarray(matrix[:, offset : offset + size]).view(dtype)
            if count is None:
                out[rows] = values[:, 0]
            else:
                out[rows, :count] = values
        numbers[path] = out
    strings: dict[str, np.ndarray] = {}
    for rows, layout, _ in groups:
        for path, value in layout.strings.items():
            column = strings.setdefault(path, np.full(n, None, dtype=object))
            column[rows] = value
    return Columns(n, numbers, strings)


NS_PER_S = 1_000_000_000


def _merged(parts: list[Columns]) -> Columns:
    """One :class:`Columns` of messages decoded one by one (rows in the order of ``parts``)."""
    n = len(parts)
    numbers: dict[str, np.ndarray] = {}
    strings: dict[str, np.ndarray] = {}
    for path in dict.fromkeys(p for part in parts for p in part.numbers):
        width = max((part.numbers[path].shape[1] if part.numbers[path].ndim == 2 else 0) for part in parts
                    if path in part.numbers)
        out = np.full((n, width) if width else (n,), np.nan)
        for row, part in enumerate(parts):
            if path in part.numbers:
                value = part.numbers[path][0]
                if width:
                    out[row, : np.size(value)] = value
                else:
                    out[row] = value
        numbers[path] = out
    for path in dict.fromkeys(p for part in parts for p in part.strings):
        strings[path] = np.array([part.strings[path][0] if path in part.strings else None for part in parts],
                                 dtype=object)
    return Columns(n, numbers, strings)


def stamped_columns(recording: Any, topic: str) -> tuple[np.ndarray, Columns]:
    """The one whole-topic decoder of a :class:`fsr_sim.recording.reader.Recording`: (stamps [ns] (n,) int64,
    columns), rows sorted by stamp (stable).

    The stamp is the header stamp where the type has a header, the log time otherwise. A topic whose
    messages have more layouts than :data:`MAX_LAYOUTS` is decoded message by message (same columns,
    slower); :class:`LayoutError` only for payloads that do not match their type at all.
    """
    raw = recording.raw(topic)
    type_name = recording.topics[recording.resolve(topic)]
    payloads = [data for _, data in raw]
    try:
        columns = decode_columns(payloads, type_name)
    except LayoutError:
        columns = _merged([decode_columns([data], type_name) for data in payloads])
    if "header.stamp.sec" in columns.numbers:
        stamp = columns.numbers["header.stamp.sec"].astype(np.int64) * NS_PER_S
        stamp += columns.numbers["header.stamp.nanosec"].astype(np.int64)
    else:
        stamp = np.fromiter((t for t, _ in raw), dtype=np.int64, count=len(raw))
    order = np.argsort(stamp, kind="stable")
    columns.numbers = {key: value[order] for key, value in columns.numbers.items()}
    columns.strings = {key: value[order] for key, value in columns.strings.items()}
    return stamp[order], columns
