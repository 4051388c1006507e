"""Writing standard ROS 2 MCAP recordings (what ``ros2 bag record -s mcap`` produces).

Profile ``ros2``, one schema per message type with encoding ``ros2msg`` and the full message definition
(:func:`fsr_sim.ros.message_schema.message_definition`), message encoding ``cdr``, zstd-compressed chunks
and a summary section. Chunks are kept small (256 KiB by default) and :meth:`RecordingWriter.flush` can
be called periodically, so that a process killed with SIGKILL leaves a file whose complete chunks can
still be read (:func:`fsr_sim.recording.reader.open_recording` reports it as truncated). A finished chunk is
compressed and written on a writer thread while the caller fills the next one (:class:`_ChunkWriter`: the
compression is about half of what recording an in-process step costs); :meth:`RecordingWriter.flush` and
:meth:`RecordingWriter.close` wait for it, so a flight stopped by Ctrl-C or SIGTERM still closes a whole file.

Raw CDR bytes (from a ``raw=True`` subscription) are written as they are; :meth:`write_message`
serialises an rclpy message instance first.
"""

from __future__ import annotations

import queue
import struct
import threading
import zlib
from collections.abc import Sequence
from pathlib import Path
from typing import IO, Any

import numpy as np
import zstandard
from mcap.data_stream import RecordBuilder
from mcap.records import ChunkIndex
from mcap.writer import CompressionType, IndexType, Writer

from fsr_sim.ros.message_schema import type_definition

DEFAULT_CHUNK_SIZE = 256 * 1024
_MESSAGE_OPCODE = 0x05
_MESSAGE_HEAD = struct.Struct("<BQHIQQ")  # opcode, record length, channel, sequence, log time, publish time
_MESSAGE_FIELDS = 2 + 4 + 8 + 8
_CHUNK_OPCODE = 0x06
_ZSTD = b"zstd"
# opcode, record length, message start and end time, uncompressed size and CRC, compression, compressed size
_CHUNK_HEAD = struct.Struct(f"<BQQQQII{len(_ZSTD)}sQ")
_CHUNK_FIELDS = _CHUNK_HEAD.size - 9  # the record's length without its data
MCAP_ZSTD_LEVEL = 3  # what mcap's own writer uses (zstandard's default)
# The fast path's level: on a flight's chunks the same ratio as 3 (6.91 vs 6.93) at 1.9 instead of 2.6 us of CPU
# per in-process step; any level reads back alike (Foxglove, rosbags, mcap)
ZSTD_LEVEL = 1
_MESSAGE_HEAD_DTYPE = np.dtype([("opcode", "u1"), ("length", "<u8"), ("channel", "<u2"), ("sequence", "<u4"),
                                ("log_time", "<u8"), ("publish_time", "<u8")])  # packed: _MESSAGE_HEAD's bytes


class RecordingWriter:
    """An MCAP file being written; use as a context manager or call :meth:`close`."""

    def __init__(
        self,
        path: str | Path,
        metadata: dict[str, dict[str, str]] | None = None,
        chunk_size: int = DEFAULT_CHUNK_SIZE,
        fast_path: bool = True,
        background: bool = True,
        zstd_level: int = ZSTD_LEVEL,
    ) -> None:
        """``fast_path``: write records straight into the open chunk where the installed mcap allows it, and
        finish the chunks with :class:`_ChunkWriter` (the same records; False writes through mcap's own API, as
        with any other version). ``background``: compress and write the finished chunks on a writer thread while
        the caller goes on (fast path only; the file is the same, byte for byte). ``zstd_level``: the fast path's
        compression level (mcap's API path compresses at :data:`MCAP_ZSTD_LEVEL`; with that level the fast path
        writes its file byte for byte)."""
        self.path = Path(path)
        try:
            self._file: IO[bytes] | None = open(self.path, "wb")  # noqa: SIM115 - closed in close()
        except OSError as exc:
            raise OSError(f"cannot write recording '{self.path}': {exc.strerror or exc}") from exc
        self._writer = Writer(self._file, chunk_size=chunk_size, compression=CompressionType.ZSTD)
        self._writer.start(profile="ros2", library="fsr")
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._sequence: dict[str, int] = {}
        self.message_counts: dict[str, int] = {}
        for name, data in (metadata or {}).items():
            self._writer.add_metadata(name, dict(data))
        self._fast = _FastMessages.attach(self._writer, background, zstd_level) if fast_path else None

    @property
    def fast_path(self) -> bool:
        """Whether records go straight into the open chunk (the pinned mcap) or through mcap's API."""
        return self._fast is not None

    def add_topic(self, topic: str, type_name: str) -> None:
        """Register ``topic`` (absolute name) with its type (``nav_msgs/msg/Odometry``); idempotent."""
        if topic in self._channels:
            return
        schema_id = self._schemas.get(type_name)
        if schema_id is None:
            definition = type_definition(type_name)
            schema_id = self._writer.register_schema(
                name=type_name, encoding="ros2msg", data=definition.encode("utf-8")
            )
            self._schemas[type_name] = schema_id
        self._channels[topic] = self._writer.register_channel(
            topic=topic, message_encoding="cdr", schema_id=schema_id, metadata={"offered_qos_profiles": ""}
        )
        self._sequence[topic] = 0
        self.message_counts[topic] = 0

    def write(self, topic: str, data: bytes, log_time_ns: int, publish_time_ns: int | None = None) -> None:
        """Append one CDR-encoded message of a registered topic."""
        channel_id = self._channels.get(topic)
        if channel_id is None:
            raise KeyError(f"topic '{topic}' was not registered with add_topic()")
        sequence = self._sequence[topic]
        self._sequence[topic] = sequence + 1
        self.message_counts[topic] += 1
        self._writer.add_message(
            channel_id=channel_id,
            log_time=int(log_time_ns),
            data=data,
            publish_time=int(log_time_ns if publish_time_ns is None else publish_time_ns),
            sequence=sequence,
        )

    def write_batch(self, messages: Sequence[tuple[str, bytes]], log_time_ns: int) -> None:
        """Append CDR messages of registered topics that share ``log_time_ns`` (publish time = log time)."""
        log_time = int(log_time_ns)
        self.write_records([(topic, data, log_time, log_time) for topic, data in messages])

    def write_records(self, records: Sequence[tuple[str, bytes, int, int]]) -> None:
        """Append ``(topic, CDR bytes, log_time_ns, publish_time_ns)`` records of registered topics, in order.

        The file is the one :meth:`write` would produce message by message (tested byte for byte); with the
        pinned ``mcap`` writer the records go straight into its current chunk (~2 us per message instead of
        ~15 us through ``Writer.add_message``)."""
        fast = self._fast
        if fast is None:
            for topic, data, log_time, publish_time in records:
                self.write(topic, data, log_time, publish_time)
            return
        channels, sequences, counts = self._channels, self._sequence, self.message_counts
        batch = []
        for topic, data, log_time, publish_time in records:
            channel_id = channels.get(topic)
            if channel_id is None:
                raise KeyError(f"topic '{topic}' was not registered with add_topic()")
            sequence = sequences[topic]
            sequences[topic] = sequence + 1
            counts[topic] += 1
            batch.append((channel_id, sequence, data, int(log_time), int(publish_time)))
        fast.add(batch)

    def write_block(self, stamps_ns: np.ndarray, messages: Sequence[tuple[str, np.ndarray | None, np.ndarray]]
                    ) -> None:
        """Append a block of steps at once (an in-process flight's log, a thousand steps at a time).

        ``messages`` holds one entry per topic: ``(topic, steps, payloads)`` with ``steps`` the indices into
        ``stamps_ns`` [ns] of the steps that have a message on it (increasing; None: every step) and
        ``payloads`` their CDR bytes as uint8 rows (count, size) (:meth:`fsr_sim.ros.cdr_pack.StampedDoubles.
        pack_rows`). The file is the one :meth:`write_batch` would produce step by step, each step's messages in
        the order of ``messages`` with log time = publish time = its stamp (tested byte for byte): the record
        headers, their order and the chunk boundaries are computed with numpy for the whole block.
        """
        stamps = np.asarray(stamps_ns, dtype=np.int64)
        entries = []
        for topic, steps, payloads in messages:
            if topic not in self._channels:
                raise KeyError(f"topic '{topic}' was not registered with add_topic()")
            steps = np.arange(len(stamps)) if steps is None else np.asarray(steps, dtype=np.int64)
            if len(steps) != len(payloads):
                raise ValueError(f"topic '{topic}': {len(steps)} steps but {len(payloads)} payloads")
            if len(steps):
                entries.append((topic, steps, np.asarray(payloads, dtype=np.uint8)))
        if self._fast is None:
            order = sorted((int(step), place, row) for place, (_, steps, _) in enumerate(entries)
                           for row, step in enumerate(steps.tolist()))
            for step, place, row in order:
                topic, _, payloads = entries[place]
                self.write(topic, payloads[row].tobytes(), int(stamps[step]))
            return
        if not entries:
            return
        dense = [len(steps) == len(stamps) for _, steps, _ in entries]
        if dense[0] and dense == sorted(dense, reverse=True):  # the every-step topics first: no sort
            self._fast.add_block(*self._dense_first(stamps, entries, dense.count(True)))
            return
        records, step_keys, place_keys, channels = [], [], [], []  # sparse topics before every-step ones
        for place, (topic, steps, payloads) in enumerate(entries):
            record = np.empty((len(steps), _MESSAGE_HEAD.size + payloads.shape[1]), dtype=np.uint8)
            self._head(topic, stamps[steps], payloads, record[:, :_MESSAGE_HEAD.size])
            record[:, _MESSAGE_HEAD.size:] = payloads
            records.append(record)
            step_keys.append(steps)
            place_keys.append(np.full(len(steps), place))
            channels.append(np.full(len(steps), self._channels[topic], dtype=np.int64))
        sizes = np.concatenate([np.full(len(r), r.shape[1], dtype=np.int64) for r in records])
        order = np.lexsort((np.concatenate(place_keys), np.concatenate(step_keys)))  # step, then topic order
        self._sequence_in_order(records, channels, order)
        ends = np.cumsum(sizes[order])
        self._fast.add_block(self._interleaved(records, order, sizes, ends), ends, np.concatenate(channels)[order],
                             stamps[np.concatenate(step_keys)][order])

    def _head(self, topic: str, stamps: np.ndarray, payloads: np.ndarray, out: np.ndarray) -> None:
        """Write the message record headers of ``payloads`` (rows) on ``topic`` stamped ``stamps`` into ``out``
        (uint8 (count, head size)) and count them."""
        count = len(payloads)
        head = np.empty(count, _MESSAGE_HEAD_DTYPE)
        head["opcode"] = _MESSAGE_OPCODE
        head["length"] = _MESSAGE_FIELDS + payloads.shape[1]
        head["channel"] = self._channels[topic]
        head["sequence"] = self._sequence[topic] + np.arange(count)
        head["log_time"] = head["publish_time"] = stamps
        out[:] = head.view(np.uint8).reshape(count, -1)
        self._sequence[topic] += count
        self.message_counts[topic] += count

    def _dense_first(self, stamps: np.ndarray, entries: list[tuple[str, np.ndarray, np.ndarray]], dense: int
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``add_block``'s arguments for a block whose first ``dense`` entries have a message in every step (a
        flight's topics) and the others in some (markers, rotor frames on ``/tf``), in :meth:`write_block`'s
        order (step, then entry). The every-step records of a step are one row of a (steps, width) matrix, filled
        in place; the records go to the block in one copy: the runs of rows between two sparse records, and
        these. Each record's place is computed, not sorted: step ``k``'s every-step record ``i`` comes after
        ``k`` rows and the sparse records of earlier steps; the ``j``-th sparse record (by step, then entry) of
        step ``k`` after ``k + 1`` rows and ``j`` sparse records."""
        steps = len(stamps)
        head_size = _MESSAGE_HEAD.size
        widths = [head_size + payloads.shape[1] for _, _, payloads in entries]
        rows = np.empty((steps, sum(widths[:dense])), dtype=np.uint8)
        records, channels, step_keys = [], [], []
        column = 0
        for place, (topic, entry_steps, payloads) in enumerate(entries):
            if place < dense:
                record = rows[:, column:column + widths[place]]
                column += widths[place]
            else:
                record = np.empty((len(payloads), widths[place]), dtype=np.uint8)
            self._head(topic, stamps[entry_steps], payloads, record[:, :head_size])
            record[:, head_size:] = payloads
            records.append(record)
            channels.append(np.full(len(payloads), self._channels[topic], dtype=np.int64))
            step_keys.append(entry_steps)
        sparse_steps = np.concatenate(step_keys[dense:]) if len(entries) > dense else np.zeros(0, dtype=np.int64)
        sparse_places = np.concatenate([np.full(len(entry_steps), place) for place, entry_steps
                                        in enumerate(step_keys) if place >= dense] or [np.zeros(0, dtype=np.int64)])
        sparse_rank = np.empty(len(sparse_steps), dtype=np.int64)
        sparse_rank[np.lexsort((sparse_places, sparse_steps))] = np.arange(len(sparse_steps))
        earlier = np.searchsorted(np.sort(sparse_steps), np.arange(steps), side="left")  # sparse before step k
        places = [np.arange(steps) * dense + place + earlier for place in range(dense)]
        if len(sparse_steps):
            places.append((sparse_steps + 1) * dense + sparse_rank)
        order = np.empty(steps * dense + len(sparse_steps), dtype=np.int64)
        order[np.concatenate(places)] = np.arange(len(order))  # record (entry-major) -> its place in the block
        self._sequence_in_order(records, channels, order)
        sizes = np.concatenate([np.full(len(record), record.shape[1], dtype=np.int64) for record in records])
        ends = np.cumsum(sizes[order])
        if not len(sparse_steps):
            block = rows.reshape(-1)
        else:
            block = np.empty(int(ends[-1]), dtype=np.uint8)
            at = done = 0
            for index in np.argsort(sparse_rank).tolist():  # the sparse records in block order
                step, place = int(sparse_steps[index]), int(sparse_places[index])
                if step >= done:
                    run = rows[done:step + 1].reshape(-1)
                    block[at:at + len(run)] = run
                    at, done = at + len(run), step + 1
                row = records[place][index - int(np.searchsorted(sparse_places, place))]  # its row in its entry
                block[at:at + len(row)] = row
                at += len(row)
            block[at:] = rows[done:].reshape(-1)
        return (block, ends, np.concatenate(channels)[order], stamps[np.concatenate(step_keys)][order])

    @staticmethod
    def _interleaved(records: list[np.ndarray], order: np.ndarray, sizes: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """The records of a block back to back in ``order`` (step, then entry): each record scattered to its place
        (blocks whose every-step entries come first take :meth:`_dense_first`)."""
        starts = np.empty_like(sizes)
        starts[order] = ends - sizes[order]  # each record's place in the block
        block = np.empty(int(ends[-1]), dtype=np.uint8)
        first = 0
        for rows in records:
            count, size = rows.shape
            block[starts[first:first + count, None] + np.arange(size)] = rows
            first += count
        return block

    @staticmethod
    def _sequence_in_order(records: list[np.ndarray], channels: list[np.ndarray], order: np.ndarray) -> None:
        """Renumber the records of a topic given by several entries (messages of two sizes on one topic) in
        their written ``order``, as :meth:`write` would number them."""
        entry_channels = [int(c[0]) for c in channels]
        shared = {c for c in entry_channels if entry_channels.count(c) > 1}
        if not shared:
            return
        entry = np.concatenate([np.full(len(r), place) for place, r in enumerate(records)])
        row = np.concatenate([np.arange(len(r)) for r in records])
        for channel in shared:
            places = [place for place, c in enumerate(entry_channels) if c == channel]
            first = min(int(records[place][0, 11:15].view("<u4")[0]) for place in places)
            mine = order[np.isin(entry[order], places)]  # this topic's records, in written order
            sequence = (first + np.arange(len(mine))).astype("<u4")
            for place in places:
                taken = entry[mine] == place
                records[place][row[mine][taken], 11:15] = sequence[taken].view(np.uint8).reshape(-1, 4)

    def write_message(self, topic: str, msg: Any, log_time_ns: int) -> None:
        """Serialise an rclpy message instance and append it (registering the topic if new)."""
        from rclpy.serialization import serialize_message

        if topic not in self._channels:
            cls = type(msg)
            self.add_topic(topic, f"{cls.__module__.split('.')[0]}/msg/{cls.__name__}")
        self.write(topic, serialize_message(msg), log_time_ns)

    def flush(self) -> None:
        """Close the current chunk and push it to the file (it survives a SIGKILL from now on)."""
        if self._file is not None:
            if self._fast is not None:
                self._fast.chunks.finish_chunk()
                self._fast.chunks.wait()
            self._writer.flush()

    def close(self) -> None:
        """Write the summary and the footer and close the file; safe to call twice."""
        if self._file is None:
            return
        interrupted: KeyboardInterrupt | None = None
        try:
            if self._fast is not None:
                self._fast.chunks.finish_chunk()
                try:
                    self._fast.chunks.close()  # every chunk in the file before the summary that indexes them
                except KeyboardInterrupt as interrupt:  # raised once the file is whole
                    interrupted = interrupt
            self._writer.finish()
            if interrupted is not None:
                raise interrupted
        finally:
            if self._fast is not None:
                self._fast.chunks.close()
            self._file.close()
            self._file = None

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()


class _FastMessages:
    """Appends message records to an ``mcap.writer.Writer``'s open chunk exactly as ``add_message`` does
    (same record bytes, chunk message index, chunk and file statistics), without a ``Message`` object and
    four small writes per message. Used only with the writer internals it was written against."""

    def __init__(self, writer: Writer, background: bool, zstd_level: int) -> None:
        self.writer = writer
        self.builder = writer._Writer__chunk_builder  # noqa: SLF001 - see attach()
        self.statistics = writer._Writer__statistics  # noqa: SLF001
        self.maybe_finalize = writer._Writer__maybe_finalize_chunk  # noqa: SLF001
        self.chunk_size = writer._Writer__chunk_size  # noqa: SLF001
        self.chunks = _ChunkWriter(self.builder, self.statistics, writer._Writer__stream,  # noqa: SLF001
                                   writer._Writer__chunk_indices, background, zstd_level)  # noqa: SLF001

    @classmethod
    def attach(cls, writer: Writer, background: bool = True, zstd_level: int = ZSTD_LEVEL) -> _FastMessages | None:
        """The fast path for ``writer``, or None if its internals are not the expected ones (any other
        ``mcap`` version: :meth:`RecordingWriter.write_batch` then calls ``add_message``). Its chunks are
        finished by a :class:`_ChunkWriter` (mcap's ``__finalize_chunk`` replaced on this writer)."""
        try:
            builder = writer._Writer__chunk_builder  # noqa: SLF001
            ok = (builder is not None and hasattr(builder, "message_indices") and hasattr(builder, "num_messages")
                  and hasattr(builder.record_writer, "_buffer")
                  and hasattr(writer._Writer__statistics, "channel_message_counts")  # noqa: SLF001
                  and writer._Writer__compression == CompressionType.ZSTD  # noqa: SLF001
                  and writer._Writer__enable_crcs and not writer._Writer__enable_data_crcs  # noqa: SLF001
                  and writer._Writer__index_types & IndexType.MESSAGE  # noqa: SLF001
                  and callable(getattr(writer, "_Writer__finalize_chunk", None)))
            fast = cls(writer, background, zstd_level) if ok else None
        except AttributeError:
            return None
        if fast is not None:  # mcap's own calls (add_message's, flush's, finish's) finish chunks this way too
            writer._Writer__finalize_chunk = fast.chunks.finish_chunk  # noqa: SLF001
        return fast

    def add(self, batch: list[tuple[int, int, bytes, int, int]]) -> None:
        """Append (channel id, sequence, data, log time, publish time) records."""
        statistics, builder, chunk_size = self.statistics, self.builder, self.chunk_size
        channel_counts = statistics.channel_message_counts
        indices = builder.message_indices
        buffer = builder.record_writer._buffer  # noqa: SLF001
        pack = _MESSAGE_HEAD.pack
        for channel_id, sequence, data, log_time, publish_time in batch:
            if statistics.message_count == 0:
                statistics.message_start_time = statistics.message_end_time = log_time
            elif log_time < statistics.message_start_time:
                statistics.message_start_time = log_time
            elif log_time > statistics.message_end_time:
                statistics.message_end_time = log_time
            statistics.message_count += 1
            channel_counts[channel_id] += 1
            if builder.num_messages == 0:
                builder.message_start_time = builder.message_end_time = log_time
            elif log_time < builder.message_start_time:
                builder.message_start_time = log_time
            elif log_time > builder.message_end_time:
                builder.message_end_time = log_time
            index = indices.get(channel_id)
            if not index:
                index = indices[channel_id] = _message_index_class()(channel_id=channel_id, records=[])
            index.records.append((log_time, buffer.tell()))
            builder.num_messages += 1
            buffer.write(pack(_MESSAGE_OPCODE, _MESSAGE_FIELDS + len(data), channel_id, sequence, log_time,
                              publish_time))
            buffer.write(data)
            if buffer.tell() > chunk_size:  # what add_message does after each message
                self.maybe_finalize()
                buffer = builder.record_writer._buffer  # noqa: SLF001 - a new one after the chunk

    def add_block(self, block: np.ndarray, ends: np.ndarray, channels: np.ndarray, log_times: np.ndarray) -> None:
        """Append whole message records: ``block`` (uint8) holds them back to back, ``ends`` (int) the end of
        each in ``block``, ``channels`` and ``log_times`` (int) theirs. Same chunks, message indices and
        statistics as :meth:`add` record by record: a chunk is closed right after the record that takes its
        buffer past the chunk size."""
        statistics, builder, chunk_size = self.statistics, self.builder, self.chunk_size
        start = 0  # index of the next record
        while start < len(ends):
            base = int(ends[start - 1]) if start else 0  # its position in the block
            buffer = builder.record_writer._buffer  # noqa: SLF001 - a new one after each chunk
            position = buffer.tell()
            # The first record (from start on) whose end passes the chunk size closes the chunk.
            stop = int(np.searchsorted(ends[start:], chunk_size - position + base, side="right")) + start + 1
            stop = min(stop, len(ends))
            offsets = position + np.concatenate(([base], ends[start:stop - 1])) - base
            times = log_times[start:stop]
            piece_channels = channels[start:stop]
            low, high = int(times.min()), int(times.max())
            _cover_times(statistics, statistics.message_count == 0, low, high)
            _cover_times(builder, builder.num_messages == 0, low, high)
            count = stop - start
            statistics.message_count += count
            builder.num_messages += count
            present, first, slots = np.unique(piece_channels, return_index=True, return_inverse=True)
            by_channel = np.argsort(slots, kind="stable")  # the records grouped by channel, each in written order
            entries = np.column_stack((times, offsets))[by_channel]
            counts = np.bincount(slots, minlength=len(present))
            ends_of = np.cumsum(counts).tolist()
            counts = counts.tolist()
            for slot in np.argsort(first).tolist():  # channels in order of appearance, as add() meets them
                channel_id = int(present[slot])
                statistics.channel_message_counts[channel_id] += counts[slot]
                index = builder.message_indices.get(channel_id)
                if not index:
                    index = builder.message_indices[channel_id] = _message_index_class()(channel_id=channel_id,
                                                                                          records=[])
                index.records.append(entries[ends_of[slot] - counts[slot]:ends_of[slot]])  # a block of entries
            buffer.write(block[base:int(ends[stop - 1])].data)
            self.maybe_finalize()
            start = stop


class _ChunkWriter:
    """Finishes the chunks of an ``mcap.writer.Writer`` as its ``__finalize_chunk`` does - the same records (byte
    for byte at mcap's level, :data:`MCAP_ZSTD_LEVEL`): the chunk (zstd at ``zstd_level``, CRC-32 of the
    uncompressed records), its message indexes and its chunk index for the summary - on a writer thread
    (``background``) or in the caller's.

    On the thread, the compression (about half of a recorded in-process step) runs while the flight goes on;
    the caller hands over the finished chunk's records and indexes and goes on filling the next one. Until
    :meth:`wait` returns, only the thread writes to the file (chunks in the order they were finished)."""

    def __init__(self, builder: Any, statistics: Any, stream: IO[bytes], chunk_indices: list[Any],
                 background: bool, zstd_level: int) -> None:
        self.builder = builder
        self.statistics = statistics
        self.stream = stream
        self.chunk_indices = chunk_indices
        self.background = background
        self.compressor = zstandard.ZstdCompressor(level=zstd_level)  # used by one thread only
        self._jobs: queue.SimpleQueue[tuple[bytes, int, int, list[Any]] | None] = queue.SimpleQueue()
        self._pending = 0  # chunks handed over and not yet written
        self._done = threading.Condition()
        self._thread: threading.Thread | None = None
        self._error: BaseException | None = None

    def finish_chunk(self) -> None:
        """Close the open chunk (if it holds a message) and write it, or hand it to the writer thread."""
        builder = self.builder
        if builder.num_messages == 0:
            return
        self.statistics.chunk_count += 1
        job = (builder.end(), builder.message_start_time, builder.message_end_time,
               list(builder.message_indices.values()))
        builder.reset()
        if not self.background:
            self._write(*job)
            return
        self._raise_error()
        if self._thread is None:
            self._thread = threading.Thread(target=self._work, name="mcap-chunks", daemon=True)
            self._thread.start()
        with self._done:
            self._pending += 1
        self._jobs.put(job)  # never blocks (unbounded): a Ctrl-C cannot lose a chunk here

    def wait(self) -> None:
        """Return once every chunk handed over is in the file; re-raise the writer thread's error. A Ctrl-C
        (KeyboardInterrupt) meanwhile is raised after the wait, so that the file keeps every chunk."""
        interrupted: KeyboardInterrupt | None = None
        while True:
            try:
                with self._done:
                    while self._pending and self._error is None:
                        self._done.wait()
                break
            except KeyboardInterrupt as interrupt:
                interrupted = interrupt
        self._raise_error()
        if interrupted is not None:
            raise interrupted

    def close(self) -> None:
        """Wait for the chunks handed over, then end the writer thread; safe to call twice."""
        thread, self._thread = self._thread, None
        if thread is None:
            return
        try:
            self.wait()
        finally:
            self._jobs.put(None)
            thread.join()

    def _raise_error(self) -> None:
        if self._error is not None:
            error, self._error = self._error, None
            name = getattr(self.stream, "name", "the recording")
            raise OSError(f"cannot write recording '{name}': {getattr(error, 'strerror', None) or error}") from error

    def _work(self) -> None:
        while (job := self._jobs.get()) is not None:
            try:
                if self._error is None:
                    self._write(*job)
            except BaseException as error:  # noqa: BLE001 - handed to the caller by wait()
                self._error = error
            with self._done:
                self._pending -= 1
                self._done.notify_all()

    def _write(self, data: bytes, start: int, end: int, indices: list[Any]) -> None:
        """Write one chunk record (``data``: its uncompressed records), its message indexes, and note its
        chunk index."""
        compressed = self.compressor.compress(data)
        stream = self.stream
        chunk_start = stream.tell()
        stream.write(_CHUNK_HEAD.pack(_CHUNK_OPCODE, _CHUNK_FIELDS + len(compressed), start, end, len(data),
                                      zlib.crc32(data), len(_ZSTD), _ZSTD, len(compressed)))
        stream.write(compressed)
        index_start = stream.tell()
        records = RecordBuilder()
        offsets = {}
        for index in indices:
            offsets[index.channel_id] = index_start + records.count
            index.write(records)
        length = records.count
        stream.write(records.end())
        self.chunk_indices.append(ChunkIndex(
            message_start_time=start, message_end_time=end, chunk_start_offset=chunk_start,
            chunk_length=index_start - chunk_start, message_index_offsets=offsets, message_index_length=length,
            compression=_ZSTD.decode(), compressed_size=len(compressed), uncompressed_size=len(data)))


def _cover_times(record: Any, empty: bool, low: int, high: int) -> None:
    """Widen ``record``'s ``message_start_time``/``message_end_time`` (file statistics, a chunk) to take log
    times ``low..high`` [ns]; set them when it holds no message yet. :meth:`_FastMessages.add` does the same
    per message inline (the recorder node's hot path)."""
    if empty:
        record.message_start_time, record.message_end_time = low, high
    else:
        record.message_start_time = min(record.message_start_time, low)
        record.message_end_time = max(record.message_end_time, high)


def _message_index_class() -> type:
    """``mcap.records.MessageIndex`` whose ``write`` packs all its entries at once (the same bytes)."""
    global _MESSAGE_INDEX
    if _MESSAGE_INDEX is None:
        from mcap.records import MessageIndex

        class PackedMessageIndex(MessageIndex):
            """``records``: (log time, offset) pairs (one message) or (k, 2) arrays of them (a block)."""

            def write(self, stream: Any) -> None:
                entries = np.concatenate([np.asarray(entry, dtype="<u8").reshape(-1) for entry in self.records])
                stream.start_record(_MESSAGE_INDEX_OPCODE)
                stream.write(struct.pack("<HI", self.channel_id, 8 * len(entries)))
                stream.write(entries.tobytes())
                stream.finish_record()

        _MESSAGE_INDEX = PackedMessageIndex
    return _MESSAGE_INDEX


_MESSAGE_INDEX: type | None = None
_MESSAGE_INDEX_OPCODE = 0x07
