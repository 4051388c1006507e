"""Serving a flight live over the Foxglove WebSocket protocol, with the Foxglove SDK's server (``foxglove-sdk``).

:class:`LiveServer` takes what a recording is given - topics with their types, then CDR messages with their log
times - so it serves exactly what the recording holds: every topic the recorder writes (those of
:mod:`fsr_sim.contract`, ``/tf``, ``/tf_static`` and ``markers`` included, under every vehicle namespace), the
same CDR bytes, advertised as ``cdr`` with their ROS 2 message definitions (``ros2msg`` schemas: the texts of
the MCAP's schemas, :func:`fsr_sim.ros.message_schema.type_definition`) and stamped with their log times (the
simulated time; never earlier than a message already served: the graph's messages arrive slightly out of
order across topics, and Foxglove takes a time going back for a seek). Foxglove decodes them as it decodes the
recording, so the layout ``docs/foxglove/fsr.json`` works on a live connection unchanged. :class:`Tee` hands a
recording's writes to both the file and the server.

A client that subscribes late gets at once what a ROS subscriber of a latched topic would get: the messages
so far of every topic the contract declares latched (``/tf_static``: one message per vehicle; ``sim_status``),
and the last ``markers`` (the vehicle as last drawn). Nothing waits for a client: each one has its own queue of
``BACKLOG`` messages in the SDK, and a client that cannot keep up (or has stopped reading) loses the oldest of
its queue, which is reported once per client; the flight, the recording and the other clients go on unchanged.
Messages are only serialised for channels that have a subscriber.
"""

from __future__ import annotations

import logging
import sys
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from fsr_bringup.live.endpoint import LiveEndpoint
from fsr_sim.contract import MARKERS, topic_named

BACKLOG = 4096  # messages queued per client before its oldest are dropped (~0.3 s of every topic at 1 kHz)
LATCHED_DEPTH = 64  # messages of a latched topic kept for late subscribers (/tf_static: one per vehicle)
MARKERS_HELD = 1  # markers kept for late subscribers: the last one (the vehicle as last drawn)
STOP_WAIT_S = 1.0  # s the server's stop may take before the flight's command goes on without it


class LiveServerError(RuntimeError):
    """The server cannot bind its address (the message names it and the reason)."""


def _held_depth(topic: str) -> int:
    """How many of a topic's latest messages a late subscriber gets at once (0: none)."""
    contract = topic_named(topic)
    if contract is None:
        return 0
    if contract.qos == "LATCHED":
        return LATCHED_DEPTH
    return MARKERS_HELD if contract.name == MARKERS.name else 0


class LiveServer:
    """A Foxglove WebSocket server fed like a recording writer (module docstring).

    Its topics are added first, then :meth:`start` binds the port and accepts clients, which are advertised every
    topic as they connect: a topic added while clients are connected is advertised to them before the SDK's
    server (0.30) knows it has, and a client that subscribes at once may be told the channel is unknown, so the
    runners start the server once every topic of the flight is there. ``stop()`` ends it (also as a context
    manager)."""

    def __init__(self, endpoint: LiveEndpoint, name: str = "fsr", say: Callable[[str], None] | None = None
                 ) -> None:
        """Serve on ``endpoint`` once started; ``say`` prints a line for the user (the address served, clients
        connecting and leaving, a client dropping messages)."""
        import foxglove

        self.endpoint = endpoint
        self.name = name
        self.say = say or _stderr
        self._events = _ClientEvents(self.say)
        self.context = foxglove.Context()
        self.server: Any = None
        self.channels: dict[str, Any] = {}  # topic -> foxglove.Channel
        self.held: dict[str, tuple[bytes, ...]] = {}  # topic -> the CDR messages a late subscriber gets at once
        self.depth: dict[str, int] = {}  # topic -> how many of its latest messages are held
        self.time_ns = 0  # the latest log time served [ns]

    def start(self) -> None:
        """Bind the port and accept clients (:class:`LiveServerError` naming the address if it cannot); idempotent."""
        if self.server is not None:
            return
        import foxglove

        self._events.install()
        try:
            self.server = foxglove.start_server(name=self.name, host=self.endpoint.host, port=self.endpoint.port,
                                                context=self.context, server_listener=_Replay(self),
                                                message_backlog_size=BACKLOG)
        except RuntimeError as error:
            self._events.uninstall()
            reason = str(error).removeprefix("FoxgloveError: ")
            raise LiveServerError(f"cannot serve live on {self.endpoint.host}:{self.endpoint.port}: {reason}") from None
        self.endpoint = LiveEndpoint(self.endpoint.host, self.server.port)
        self.say(f"live: serving on {self.endpoint.url} (Foxglove: Open connection -> Foxglove WebSocket; layout "
                 "docs/foxglove/fsr.json)")

    # ----- fed like a RecordingWriter ---------------------------------------------------------------------------
    def add_topic(self, topic: str, type_name: str) -> None:
        """Advertise ``topic`` (absolute name) with its type's ROS 2 message definition; idempotent."""
        if topic in self.channels:
            return
        from foxglove import Channel, Schema

        from fsr_sim.ros.message_schema import type_definition

        schema = Schema(name=type_name, encoding="ros2msg", data=type_definition(type_name).encode("utf-8"))
        self.depth[topic] = _held_depth(topic)
        self.channels[topic] = Channel(topic, schema=schema, message_encoding="cdr", context=self.context)

    def write_records(self, records: Sequence[tuple[str, bytes, int, int]]) -> None:
        """Serve ``(topic, CDR bytes, log time [ns], publish time)`` records, in order."""
        for topic, data, log_time, _publish in records:
            self._serve(topic, bytes(data), int(log_time))

    def write_batch(self, messages: Sequence[tuple[str, bytes]], log_time_ns: int) -> None:
        """Serve CDR messages that share ``log_time_ns``."""
        for topic, data in messages:
            self._serve(topic, bytes(data), int(log_time_ns))

    def write_block(self, stamps_ns: np.ndarray, messages: Sequence[tuple[str, np.ndarray | None, np.ndarray]]
                    ) -> None:
        """Serve a block of steps (:meth:`fsr_sim.recording.writer.RecordingWriter.write_block`'s arguments) in the
        recording's order: step by step, each step's messages in the order of ``messages``. Only the messages of
        subscribed topics are taken out of the block, and the last ones of held topics."""
        stamps = np.maximum(np.asarray(stamps_ns, dtype=np.int64), self.time_ns)  # never back in time
        steps_of, places, rows_of = [], [], []
        for place, (topic, steps, rows) in enumerate(messages):
            depth = self.depth[topic]
            if depth and len(rows):
                self._hold(topic, [row.tobytes() for row in rows[-depth:]])
            if len(rows) and self.channels[topic].has_sinks():
                steps_of.append(np.arange(len(rows)) if steps is None else np.asarray(steps, dtype=np.int64))
                places.append(place)
                rows_of.append(rows)
        if steps_of:
            step = np.concatenate(steps_of)
            entry = np.concatenate([np.full(len(s), i) for i, s in enumerate(steps_of)])
            index = np.concatenate([np.arange(len(s)) for s in steps_of])
            order = np.lexsort((entry, step))  # by step, then in the order of ``messages``
            logs = [self.channels[messages[place][0]].base.log for place in places]
            for k, i, t in zip(entry[order].tolist(), index[order].tolist(), stamps[step[order]].tolist(), strict=True):
                logs[k](rows_of[k][i].tobytes(), t, None)
        if len(stamps):
            self.time_ns = max(self.time_ns, int(stamps[-1]))

    def flush(self) -> None:
        """Nothing to flush: messages leave as they are logged."""

    def close(self) -> None:
        """The flight's messages are all served; the server stays up until :meth:`stop` (its owner's call)."""

    def _serve(self, topic: str, data: bytes, log_time: int) -> None:
        """Log one message to its channel's subscribers, stamped ``log_time`` or, if that is earlier, the latest
        time served (Foxglove takes a message stamped before the previous one for a jump back in time, a seek,
        and drops what it holds); keep it for late subscribers if its topic is held."""
        if log_time < self.time_ns:
            log_time = self.time_ns
        self.time_ns = log_time
        if self.depth[topic]:
            self._hold(topic, [data])
        channel = self.channels[topic]
        if channel.has_sinks():
            channel.base.log(data, log_time, None)

    def _hold(self, topic: str, messages: list[bytes]) -> None:
        """Keep the latest messages of a held topic (a new tuple, swapped in whole: the server's thread reads it
        without a lock)."""
        kept = (*self.held.get(topic, ()), *messages)
        self.held[topic] = kept[max(len(kept) - self.depth[topic], 0):]

    # ----- late subscribers --------------------------------------------------------------------------------------
    def replay(self, topic: str) -> None:
        """Send the held messages of ``topic`` (a client has just subscribed to it), stamped with the latest time
        served, as a ROS subscriber of a latched topic receives them now. The channel's other subscribers get
        them again, which changes nothing: the same latched data, the same last markers."""
        channel = self.channels.get(topic)
        for data in self.held.get(topic, ()):
            channel.base.log(data, self.time_ns, None)

    # ----- life cycle --------------------------------------------------------------------------------------------
    def tee(self, writer: Any) -> Tee:
        """A writer that writes to ``writer`` (the recording) and serves the same here."""
        return Tee(writer, self)

    def stop(self) -> None:
        """Close every connection and free the port, within ``STOP_WAIT_S``; safe to call twice. The SDK's stop waits
        for every client's pending writes, forever for a client that stopped reading: it is left to a background
        thread, which the process's exit ends."""
        if self.server is None:
            return
        stopping = threading.Thread(target=self.server.stop, name="live-server-stop", daemon=True)
        stopping.start()
        stopping.join(STOP_WAIT_S)
        if stopping.is_alive():
            self.say("live: a client that does not read was cut off")
        self.server = None
        self._events.uninstall()

    def __enter__(self) -> LiveServer:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.stop()


class Tee:
    """A recording writer (:class:`fsr_sim.recording.writer.RecordingWriter`) whose every write is also served by
    a :class:`LiveServer`; the file gets exactly the calls it would get alone. Anything else (``path``,
    ``message_counts``, ``close``) is the writer's."""

    def __init__(self, writer: Any, live: LiveServer) -> None:
        self.writer = writer
        self.live = live

    def add_topic(self, topic: str, type_name: str) -> None:
        self.writer.add_topic(topic, type_name)
        self.live.add_topic(topic, type_name)

    def write_records(self, records: Sequence[tuple[str, bytes, int, int]]) -> None:
        self.writer.write_records(records)
        self.live.write_records(records)

    def write_batch(self, messages: Sequence[tuple[str, bytes]], log_time_ns: int) -> None:
        self.writer.write_batch(messages, log_time_ns)
        self.live.write_batch(messages, log_time_ns)

    def write_block(self, stamps_ns: np.ndarray, messages: Sequence[tuple[str, np.ndarray | None, np.ndarray]]
                    ) -> None:
        self.writer.write_block(stamps_ns, messages)
        self.live.write_block(stamps_ns, messages)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.writer, name)


class _Replay:
    """The server's listener: a late subscriber gets the held messages of the channel at once."""

    def __init__(self, live: LiveServer) -> None:
        self.live = live

    def on_subscribe(self, _client: Any, channel: Any) -> None:
        self.live.replay(channel.topic)

    def on_unsubscribe(self, _client: Any, _channel: Any) -> None:
        pass


class _ClientEvents(logging.Handler):
    """Turns the SDK's log records (it logs through Python's ``logging``, logger ``foxglove``) into one line per
    event for the user: a client connected, left, or cannot keep up (said once per client: the SDK drops the
    oldest of its queued messages). The SDK's other records at WARNING and above are passed on as they are,
    except the errors of a connection that a client dropped (a closed browser tab: a client leaving)."""

    LOGGER = "foxglove"
    CLIENT_GONE = ("Error receiving from client ", "Error sending message to client ")

    def __init__(self, say: Callable[[str], None]) -> None:
        super().__init__(logging.INFO)
        self.say = say
        self.slow: set[str] = set()
        self.logger = logging.getLogger(self.LOGGER)
        self.previous: tuple[int, bool] | None = None

    def install(self) -> None:
        self.previous = (self.logger.level, self.logger.propagate)
        self.logger.setLevel(logging.INFO)
        self.logger.propagate = False
        self.logger.addHandler(self)

    def uninstall(self) -> None:
        self.logger.removeHandler(self)
        if self.previous is not None:
            self.logger.level, self.logger.propagate = self.previous

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = record.getMessage()
        except Exception:  # noqa: BLE001 - a log record must never break the flight
            return
        if text.startswith("Registered client "):
            self.say(f"live: client {text.removeprefix('Registered client ')} connected")
        elif text.startswith("Unregistered client "):
            self.say(f"live: client {text.removeprefix('Unregistered client ')} left")
        elif text.startswith("outbox for client ") and text.endswith(" full"):
            client = text.removeprefix("outbox for client ").removesuffix(" full")
            if client not in self.slow:
                self.slow.add(client)
                self.say(f"live: client {client} cannot keep up: dropping its oldest messages (the flight and "
                         "the recording go on unchanged)")
        elif record.levelno >= logging.WARNING and not text.startswith(self.CLIENT_GONE):
            self.say(f"live: {record.levelname.lower()}: {text}")


def _stderr(text: str) -> None:
    print(f"{Path(sys.argv[0]).name or 'fsr'}: {text}", file=sys.stderr, flush=True)
