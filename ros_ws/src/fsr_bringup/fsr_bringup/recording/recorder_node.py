"""``fsr-record --out RUN.mcap``: record the fsr graph's topics to a standard ROS 2 MCAP file.

    fsr-record --out run.mcap --scenario ex4_geometric      # or --scenario my_flight.yaml
    fsr-record --out fleet.mcap --namespace /uav1 --namespace /uav2 --topic /status:std_msgs/msg/String
    fsr-record --out run.mcap --scenario ex4_geometric --live    # and watch it in Foxglove (ws://localhost:8765)

Subscribes up front (so nothing published after the simulator's handshake is missed), without
deserialising (``raw=True``), to ``/clock`` and, under each namespace (default: the node's own, so
``-r __ns:=/uav1`` works), to every topic :mod:`fsr_sim.contract` marks as recorded (``odom``, ``rotor_cmd``,
..., ``sim_status``), each with the contract's QoS and a deep queue. Messages are taken in batches from a
wait set (no executor callback per message: a 1 kHz lockstep graph publishes ~10 k messages/s) and written
in arrival order.

Times: ``log_time`` is the simulated time of the message: its header stamp (``/clock``: the clock value;
``sim_status``: its ``sim_time``); a per-step topic without a stamp that the contract pairs with a stamped one
(``mass_estimate`` with ``wrench_estimate``: :attr:`fsr_sim.contract.Topic.stamped_like`) gets the stamp of the
partner's message of the same state (the i-th of each, both in order from one publisher: held until the partner
arrives); other messages without a stamp get the latest simulated time the recorder has seen, i.e. their
sim-clock receive time (0 before the first). ``publish_time`` is the publisher's source timestamp (wall clock).

End: once every recorded ``sim_status`` (one per namespace) reported the end of the flight and the
producers have gone (or nothing arrived for a while), the recorder takes what is still queued, finishes
the file and exits 0 by itself (:mod:`fsr_sim.ros.flight_end`); ``--keep-running`` records until a signal.

Derived topics (:mod:`fsr_bringup.recording.derived`): ``/tf_static`` and ``/tf`` (from every ``odom``) and
``markers`` (the vehicle for a viewer, with ``--scenario``) are written as the messages they come from arrive;
``markers`` is also published over DDS, and so are ``/tf`` and ``/tf_static`` where ``tf2_msgs`` is installed
(:mod:`fsr_bringup.recording.tf_publishers`). The recorder draws them, not the simulator, because it holds every
topic of a step (the simulator has neither the estimate nor the reference of the state it publishes) and
because the simulator's per-step loop then pays nothing for them.

Live (``--live [PORT]``, ``--live-host``): everything written to the file is also served over the Foxglove
WebSocket protocol as it is written (:mod:`fsr_bringup.live.server`); a port that cannot be bound is one line and
exit 2 before anything is subscribed or written.

Files survive crashes: chunks are small and flushed every ``FLUSH_PERIOD`` s, so a SIGKILLed file is
readable up to its last complete chunk. SIGINT/SIGTERM: take what is still queued, write the summary,
exit 0. A path that cannot be written: one line naming it and the reason, exit 1, before subscribing.

Draining at shutdown: once a namespace's simulator has ended (final ``sim_status``: ``finished``,
``diverged`` or ``stopped``, whose ``sim_time`` is the stamp ``t_K`` of its last state), the recorder knows
what to expect: every per-step stamped stream of that namespace that has started
(:func:`fsr_sim.contract.stamped_streams`) up to ``t_K``. It keeps taking until
each has (in-order reliable streams: the last stamp reached means nothing before it is missing), at most
``DRAIN_STALL_S`` without a message or ``DRAIN_FINAL_MAX_S`` in all, and names a stream that falls short.
Without a final status (the flight still runs) it stops after ``DRAIN_QUIET_S`` without a message
(``DRAIN_MAX_S`` at most). ``fsr-fly`` stops the recorder last, after the simulator and after the
controller and estimator have answered every state (:mod:`fsr_sim.ros.flight_end`). After SIGINT/SIGTERM the
drain ends at the latest ``SIGNAL_DRAIN_S`` after the signal (a node exits within 2 s of a signal). Without
``--keep-running`` the recorder also ends by itself once every recorded ``sim_status`` is final and the
graph has gone quiet (:class:`fsr_sim.ros.flight_end.FlightEndRule`).
"""

from __future__ import annotations

import argparse
import struct
import sys
import time
from collections import deque
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fsr_bringup.live.endpoint import add_live_arguments, endpoint_of, reserve
from fsr_bringup.recording.derived import DERIVED_SOURCES, DerivedTopics
from fsr_bringup.recording.metadata import scenario_from_text
from fsr_bringup.recording.tf_publishers import TfPublishers
from fsr_sim.cli.arguments import ArgumentParser, argument_type
from fsr_sim.contract import (
    BY_NAME,
    CLOCK,
    MARKERS,
    SIM_STATUS,
    STAMP_TOLERANCE_NS,
    SimStatus,
    recorded_topics,
    recording_selection,
    resolve,
    stamped_streams,
    topic_named,
)
from fsr_sim.recording.reader import SCENARIO_METADATA
from fsr_sim.recording.writer import RecordingWriter
from fsr_sim.ros.runtime import (
    EXIT_CONFIG_ERROR,
    EXIT_FAILURE,
    EXIT_OK,
    configure_environment,
    run_node,
    signal_deadline,
)

STANDARD_TOPICS = recorded_topics()
CHUNK_SIZE = 64 * 1024  # bytes: ~70 ms of a 1 kHz graph per chunk
FLUSH_PERIOD = 0.5  # s of wall time between flushes: at most this much is lost to a SIGKILL
BATCH_GATHER_S = 0.01  # s between batches while messages flow (~100 steps of a 1 kHz graph per batch)
WAIT_TIMEOUT_NS = 100_000_000  # a signal is noticed within 0.1 s
DRAIN_QUIET_S = 0.2  # at shutdown, stop taking after this long without a message
DRAIN_MAX_S = 1.0
DRAIN_STALL_S = 2.0  # with a final sim_status: give up on a stream after this long without a message
DRAIN_FINAL_MAX_S = 15.0
DRAINED_TOPICS = stamped_streams()
SIGNAL_DRAIN_S = 0.8  # s after SIGINT/SIGTERM: stop taking then, whatever is still arriving
_STAMP = struct.Struct("<iI")

if TYPE_CHECKING:
    from fsr_bringup.live.server import LiveServer


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = ArgumentParser(prog="fsr-record", doc=__doc__, exit_codes={
        EXIT_OK: "the recording is complete", EXIT_FAILURE: "the file could not be written",
        EXIT_CONFIG_ERROR: "invalid argument, topic type or scenario (nothing was recorded)"})
    parser.add_argument("--out", required=True, type=Path, help="MCAP file to write (overwritten)")
    parser.add_argument(
        "--scenario", help="scenario stored in the file's metadata: a built-in name (e.g. ex4_geometric) or a YAML path"
    )
    parser.add_argument(
        "--keep-running", action="store_true",
        help="record until SIGINT/SIGTERM instead of ending with the flight (every sim_status final)",
    )
    parser.add_argument(
        "--namespace", action="append", default=[], metavar="NS",
        help="record the standard topics under NS (repeatable; default: the node's namespace)",
    )
    parser.add_argument(
        "--only", metavar="LIST", type=argument_type(recording_selection),
        help="record only these of the standard topics, comma-separated (e.g. odom,reference,clock); sim_status "
             "is always recorded (default: all)",
    )
    parser.add_argument(
        "--topic", action="append", default=[], metavar="NAME:TYPE",
        help="also record NAME (relative names go under each namespace) of TYPE pkg/msg/Type (repeatable)",
    )
    add_live_arguments(parser, "everything recorded")
    return parser.parse_args(argv)


def topic_list(namespaces: list[str], extra: list[str], only: frozenset[str] | None = None) -> list[tuple[str, str]]:
    """(topic name, type) to subscribe to; relative names are resolved by the node (its namespace). ``only``:
    the standard topics to keep (:func:`fsr_sim.contract.recording_selection`; None: all)."""
    prefixes = ["/" + ns.strip("/") + "/" if ns.strip("/") else "/" for ns in namespaces] or [""]
    standard = {name: type_name for name, type_name in STANDARD_TOPICS.items() if only is None or name in only}
    topics: dict[str, str] = {CLOCK.name: CLOCK.type} if only is None or CLOCK.name in only else {}
    extras: list[tuple[str, str]] = []
    for item in extra:
        name, sep, type_name = item.rpartition(":")
        if not sep or not name or not type_name:
            raise ValueError(f"--topic: expected NAME:TYPE (e.g. odom:nav_msgs/msg/Odometry), got '{item}'")
        extras.append((name, type_name))
    for prefix in prefixes:
        for name, type_name in [*standard.items(), *extras]:
            topics[name if name.startswith("/") else prefix + name] = type_name
    return list(topics.items())


def starts_with_stamp(msg_class: type) -> bool:
    """True when the message starts with a ``std_msgs/Header`` or a ``builtin_interfaces/Time``: its
    ``int32 sec, uint32 nanosec`` are then the first 8 bytes after the 4-byte CDR encapsulation header."""
    from rosidl_parser.definition import NamespacedType

    first = msg_class.SLOT_TYPES[0] if msg_class.SLOT_TYPES else None
    return isinstance(first, NamespacedType) and (tuple(first.namespaces), first.name) in (
        (("std_msgs", "msg"), "Header"), (("builtin_interfaces", "msg"), "Time"),
    )


def stamp_ns(data: bytes) -> int:
    """The leading ``sec, nanosec`` of a CDR message (either byte order)."""
    sec, nanosec = (_STAMP if data[1] == 1 else struct.Struct(">iI")).unpack_from(data, 4)
    return sec * 1_000_000_000 + nanosec


def status_time_ns(data: bytes) -> int | None:
    """``sim_time`` [ns] of a ``sim_status`` message (std_msgs/String CDR: uint32 length, then JSON text)."""
    text = status_text(data)
    status = None if text is None else SimStatus.from_json(text)
    return None if status is None else status.stamp_ns


def status_text(data: bytes) -> str | None:
    """The text of a std_msgs/String CDR message (uint32 length incl. the NUL, then the bytes)."""
    try:
        (length,) = struct.unpack_from("<I" if data[1] == 1 else ">I", data, 4)
        return data[8 : 8 + length].rstrip(b"\0").decode("utf-8")
    except (struct.error, IndexError, UnicodeDecodeError):
        return None


def final_status_ns(data: bytes) -> int | None:
    """``sim_time`` [ns] of a final (``finished`` / ``diverged`` / ``stopped``) ``sim_status``, else None."""
    from fsr_sim.ros.flight_end import final_stamp_ns

    text = status_text(data)
    return None if text is None else final_stamp_ns(text)


def make_recorder(writer: RecordingWriter, topics: list[tuple[str, str]], keep_running: bool = False,
                  scenario_yaml: str | None = None, only: frozenset[str] | None = None, live: LiveServer | None = None
                  ) -> type:
    """Build the node class lazily (rclpy is imported only after the environment is configured).
    ``scenario_yaml``: the recorded scenario (what the derived topics are drawn from, :mod:`fsr_bringup.recording.
    derived`); ``only``: the ``--only`` selection; ``live``: the server ``writer`` also writes to (a
    :class:`fsr_bringup.live.server.Tee`), told every topic before it is started."""
    from rclpy.node import Node
    from rclpy.qos import QoSProfile

    from fsr_sim.ros.flight_end import FlightEndRule
    from fsr_sim.ros.message_schema import message_class
    from fsr_sim.ros.qos import STREAM_DEPTH, STREAM_QOS, qos_of
    from fsr_sim.ros.wait_set import SubscriptionWaitSet

    def reader_qos(name: str, type_name: str) -> QoSProfile:
        """The contract's QoS of a topic (a ``--topic`` outside it: a stream's), with a deep queue whatever the
        publisher's depth (the recorder needs every sample); reliability and durability match the publisher's."""
        topic = topic_named(name)
        profile = qos_of(topic) if topic is not None and topic.type == type_name else STREAM_QOS
        return QoSProfile(reliability=profile.reliability, durability=profile.durability, history=profile.history,
                          depth=max(profile.depth, STREAM_DEPTH))

    def is_status(name: str, type_name: str) -> bool:
        return name.rsplit("/", 1)[-1] == SIM_STATUS.name and type_name == SIM_STATUS.type

    class Recorder(Node):
        """Subscriptions drained from one wait set into the MCAP writer."""

        def __init__(self) -> None:
            super().__init__("fsr_recorder", start_parameter_services=False)
            self.writer = writer
            self.exit_code = EXIT_OK
            self.failed = False
            self.sim_time_ns = 0
            self.last_flush = time.monotonic()
            self.unflushed = False
            self.entries: list[tuple[object, str, bool, bool]] = []  # (subscription, topic, stamped, status)
            self.last_stamp: dict[str, int] = {}  # topic -> newest stamp written [ns]
            self.final_ns: dict[str, int] = {}  # namespace -> stamp of its simulator's last state [ns]
            self.drained: dict[str, str] = {}  # topic -> namespace, for the streams awaited at shutdown
            for name, type_name in topics:
                cls = message_class(type_name)
                sub = self.create_subscription(cls, name, lambda *_: None, reader_qos(name, type_name), raw=True)
                topic = sub.topic_name
                writer.add_topic(topic, type_name)
                self.entries.append((sub, topic, starts_with_stamp(cls), is_status(name, type_name)))
                namespace, _, base = topic.rpartition("/")
                if base in DRAINED_TOPICS and type_name == BY_NAME[base].type:
                    self.drained[topic] = namespace
            subscribed = {topic for _sub, topic, _stamped, _status in self.entries}
            self.partner_of: dict[str, str] = {}  # unstamped topic -> the stamped topic whose stamps it takes
            for topic in subscribed:
                contract = topic_named(topic)
                partner = f"{topic.rpartition('/')[0]}/{contract.stamped_like}" if contract is not None and \
                    contract.stamped_like else None
                if partner in subscribed:
                    self.partner_of[topic] = partner
            self.partner_stamps: dict[str, deque[int]] = {p: deque() for p in self.partner_of.values()}
            self.unstamped: dict[str, deque[tuple[bytes, int]]] = {t: deque() for t in self.partner_of}
            self.wait_set = SubscriptionWaitSet(self, [entry[0] for entry in self.entries])
            status_topics = [topic for _sub, topic, _stamped, status in self.entries if status]
            self.flight_end = None if keep_running or not status_topics else FlightEndRule(status_topics)
            self.stop_flag: object = None  # set by run_node
            self.derived: dict[str, tuple[DerivedTopics, object]] = {}  # namespace -> (its topics, markers publisher)
            self.derive_failed: set[str] = set()
            self.derived_topics: dict[str, DerivedTopics] = {}  # namespace -> its derived topics (built once)
            self.frames = TfPublishers.create(self)  # /tf and /tf_static over DDS (None: no tf2_msgs here)
            if live is not None:  # every topic a client may see, before the server takes its first client
                for namespace in sorted({topic.rpartition("/")[0] for _sub, topic, *_ in self.entries
                                         if topic.rsplit("/", 1)[-1] in DERIVED_SOURCES}):
                    try:
                        for topic, type_name in self.derived_topics_of(namespace).topics().items():
                            live.add_topic(topic, type_name)
                    except Exception:  # noqa: BLE001 - said at the namespace's first message (derive)
                        continue
            self.get_logger().info(f"recording {len(self.entries)} topics to {writer.path}")

        def derived_topics_of(self, namespace: str) -> DerivedTopics:
            """The derived topics of a vehicle namespace (nothing written yet)."""
            found = self.derived_topics.get(namespace)
            if found is None:
                scenario, _ = scenario_from_text(scenario_yaml, namespace or "/", f"{writer.path} (--scenario)",
                                                 writer.path.parent)
                found = self.derived_topics[namespace] = DerivedTopics(scenario, namespace or "/", only)
            return found

        def derived_of(self, namespace: str) -> tuple[DerivedTopics, object]:
            """The derived topics of a vehicle namespace, set up (``/tf_static`` written) at its first message."""
            found = self.derived.get(namespace)
            if found is None:
                derived = self.derived_topics_of(namespace)
                for topic, type_name in derived.topics().items():
                    writer.add_topic(topic, type_name)
                publisher = None
                if derived.markers:
                    publisher = self.create_publisher(message_class(MARKERS.type),
                                                      resolve(MARKERS.name, namespace or "/"), qos_of(MARKERS))
                found = self.derived[namespace] = (derived, publisher)
                self.write_derived(derived.static(), None)
            return found

        def write_derived(self, messages: list[tuple[str, object, object]], publisher: object) -> None:
            """Write derived ``(topic, stamps, payload rows)`` (log time = publish time = stamp); publish the
            markers, and the frames where tf2_msgs is installed."""
            records = []
            for topic, stamps, rows in messages:
                for stamp, row in zip(stamps.tolist(), rows, strict=True):
                    data = row.tobytes()
                    records.append((topic, data, stamp, stamp))
                    if publisher is not None and topic.endswith("/" + MARKERS.name):
                        publisher.publish(data)
                    elif self.frames is not None:
                        self.frames.publish(topic, data)
            self.writer.write_records(records)

        def done(self) -> bool:
            if self.failed:
                return True
            if self.flight_end is None or not self.flight_end.ended(self.producers_gone):
                return False
            self.get_logger().info(f"flight ended ({self.flight_end.describe()}): closing the recording")
            return True

        def producers_gone(self) -> bool:
            """No node publishes on any recorded topic any more (everything it sent has been acknowledged)."""
            return all(sub.get_publisher_count() == 0 for sub, *_ in self.entries)

        def spin_once(self, _executor: object, stop: object) -> None:
            """Wait up to 0.1 s for messages, then take and write everything queued; after a batch, let the
            next one gather for ``BATCH_GATHER_S`` (the queues are deep: fewer, larger batches cost less CPU
            than a wake-up per message)."""
            if self.take(WAIT_TIMEOUT_NS) and not stop:
                time.sleep(BATCH_GATHER_S)

        def take(self, timeout_ns: int) -> int:
            batch: list[tuple[int, int, str, bytes, bool, bool]] = []
            for index, data, info in self.wait_set.take_ready(timeout_ns):
                _, topic, stamped, status = self.entries[index]
                batch.append((info["received_timestamp"], info["source_timestamp"], topic, data, stamped, status))
            if batch:
                batch.sort(key=lambda item: item[0])
                self.write(batch)
                if self.flight_end is not None:
                    self.flight_end.activity()
                    for _received, _source, topic, data, _stamped, status in batch:
                        text = status_text(data) if status else None
                        if text is not None:
                            self.flight_end.status(topic, text)
            self.maybe_flush()
            return len(batch)

        def write(self, batch: list[tuple[int, int, str, bytes, bool, bool]]) -> None:
            records = []
            try:
                for _received, source, topic, data, stamped, status in batch:
                    if stamped:
                        log_time = stamp_ns(data)
                        self.sim_time_ns = max(self.sim_time_ns, log_time)
                        if log_time > self.last_stamp.get(topic, -1):
                            self.last_stamp[topic] = log_time
                        if topic in self.partner_stamps:
                            self.partner_stamps[topic].append(log_time)
                    elif topic in self.unstamped:
                        self.unstamped[topic].append((data, source))
                        continue
                    elif status:
                        status_ns = status_time_ns(data)
                        log_time = self.sim_time_ns if status_ns is None else status_ns
                        final = final_status_ns(data)
                        if final is not None:
                            self.final_ns[topic.rpartition("/")[0]] = final
                    else:
                        log_time = self.sim_time_ns
                    records.append((topic, data, log_time, source))
                records += self.paired_records()
                self.writer.write_records(records)
                self.derive(records)
                self.unflushed = True
            except OSError as error:
                self.fail(error)

        def paired_records(self, unmatched: bool = False) -> list[tuple[str, bytes, int, int]]:
            """The held unstamped messages whose partner's stamp has come, at that stamp (``unmatched``: the rest
            too, at the latest simulated time: the file is being closed)."""
            records = []
            for topic, held in self.unstamped.items():
                stamps = self.partner_stamps[self.partner_of[topic]]
                while held and (stamps or unmatched):
                    data, source = held.popleft()
                    records.append((topic, data, stamps.popleft() if stamps else self.sim_time_ns, source))
            return records

        def derive(self, records: list[tuple[str, bytes, int, int]]) -> None:
            """Hand the batch's messages to their namespace's derived topics, one call per topic."""
            grouped: dict[str, tuple[list[int], list[bytes]]] = {}
            for topic, data, log_time, _source in records:
                if topic.rsplit("/", 1)[-1] in DERIVED_SOURCES:
                    stamps, payloads = grouped.setdefault(topic, ([], []))
                    stamps.append(log_time)
                    payloads.append(data)
            for topic, (stamps, payloads) in grouped.items():
                namespace, _, base = topic.rpartition("/")
                if namespace in self.derive_failed:
                    continue
                try:
                    derived, publisher = self.derived_of(namespace)
                    self.write_derived(derived.take(base, np.array(stamps, dtype=np.int64), payloads), publisher)
                except OSError:
                    raise
                except Exception as error:  # noqa: BLE001 - a viewer's topics must never cost the recording
                    self.derive_failed.add(namespace)
                    print(f"fsr-record: warning: no more /tf or markers for {namespace or '/'}: {error!r}",
                          file=sys.stderr, flush=True)

        def maybe_flush(self) -> None:
            """Complete the current chunk every FLUSH_PERIOD s (also when the graph has gone quiet)."""
            now = time.monotonic()
            if self.unflushed and not self.failed and now - self.last_flush >= FLUSH_PERIOD:
                try:
                    self.writer.flush()
                except OSError as error:
                    self.fail(error)
                self.last_flush = now
                self.unflushed = False

        def fail(self, error: OSError) -> None:
            if not self.failed:
                print(f"fsr-record: error: cannot write {self.writer.path}: {error.strerror or error}",
                      file=sys.stderr, flush=True)
            self.failed = True
            self.exit_code = EXIT_FAILURE

        def short_streams(self) -> list[str] | None:
            """Started streams whose newest stamp is before their simulator's last state; None when no
            simulator has ended (nothing known to wait for)."""
            if not self.final_ns:
                return None
            short = []
            for topic, namespace in self.drained.items():
                final, last = self.final_ns.get(namespace), self.last_stamp.get(topic)
                if final is not None and last is not None and last < final - STAMP_TOLERANCE_NS:
                    short.append(topic)
            return short

        def drain(self) -> None:
            """Take what is still queued (see the module docstring for when to stop)."""
            start = quiet_since = time.monotonic()
            end = signal_deadline(self.stop_flag, SIGNAL_DRAIN_S, DRAIN_FINAL_MAX_S)
            while not self.failed and time.monotonic() < end:
                if self.take(50_000_000):
                    quiet_since = time.monotonic()
                short = self.short_streams()
                now = time.monotonic()
                if short is None:
                    if now - quiet_since >= DRAIN_QUIET_S or now - start >= DRAIN_MAX_S:
                        return
                elif not short:
                    self.take(0)  # what came with the last stamped messages (mass_estimate, /clock)
                    return
                elif now - quiet_since >= DRAIN_STALL_S or now - start >= DRAIN_FINAL_MAX_S:
                    for topic in short:
                        final = self.final_ns[self.drained[topic]]
                        print(f"fsr-record: warning: {topic} ends at t = {self.last_stamp[topic] * 1e-9:.4f} s, "
                              f"before the simulator's last state t = {final * 1e-9:.4f} s", file=sys.stderr,
                              flush=True)
                    return

        def close(self) -> None:
            """Take what is still queued, then finish the file (summary and footer) and report counts."""
            if not self.failed:
                self.drain()
                try:
                    self.writer.write_records(self.paired_records(unmatched=True))
                except OSError as error:
                    self.fail(error)
            try:
                self.writer.close()
            except OSError as error:
                self.fail(error)
            counts = self.writer.message_counts
            total = sum(counts.values())
            lines = [f"  {topic}: {count}" for topic, count in sorted(counts.items())]
            state = "FAILED, file incomplete" if self.failed else "closed"
            print(f"fsr-record: {state}: wrote {total} messages to {self.writer.path}", *lines, sep="\n",
                  flush=True)

    return Recorder


def scenario_text(scenario: str) -> str:
    """YAML text kept in the metadata for ``--scenario``: an existing file as it is (a scenario or the
    runner's fleet file), else a built-in scenario name or path, loaded and dumped (merged, checked)."""
    from fsr_sim.config.scenario import load_scenario
    from fsr_sim.config.validation import ConfigError

    path = Path(scenario)
    if path.is_file():
        try:
            return path.read_text(encoding="utf-8")
        except OSError as error:
            raise ValueError(f"--scenario: cannot read {path}: {error.strerror or error}") from None
    try:
        return load_scenario(scenario).dump()
    except ConfigError as error:
        raise ValueError(f"--scenario: {error}") from None


def open_writer(out: Path, scenario: str | None) -> RecordingWriter:
    """Create the file and push its header to disk now, so that a bad path fails before subscribing;
    ``writer.scenario_yaml`` is the scenario's text kept in the metadata (None without ``scenario``)."""
    text = None if scenario is None else scenario_text(scenario)
    metadata = None if text is None else {SCENARIO_METADATA: {"yaml": text}}
    writer = RecordingWriter(out, metadata=metadata, chunk_size=CHUNK_SIZE)
    writer.scenario_yaml = text
    try:
        writer.flush()
    except OSError:
        try:
            writer.close()
        except OSError:
            pass
        raise
    return writer


def main(argv: list[str] | None = None) -> int:
    configure_environment()
    from rclpy.utilities import remove_ros_args

    argv = sys.argv if argv is None else argv
    args = parse_args(remove_ros_args(argv)[1:])
    from fsr_sim.ros.message_schema import message_class

    try:
        topics = topic_list(args.namespace, args.topic, args.only)
    except ValueError as error:
        print(f"fsr-record: error: {error}", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    for name, type_name in topics:
        try:
            message_class(type_name)
        except (ValueError, ImportError, AttributeError) as error:
            print(f"fsr-record: error: --topic {name}: unknown message type '{type_name}' ({error})", file=sys.stderr)
            return EXIT_CONFIG_ERROR
    live = None
    if endpoint_of(args) is not None:
        from fsr_bringup.live.server import LiveServer

        try:
            reserve(endpoint_of(args))  # a bad or busy port fails now, before anything is subscribed or written
        except ValueError as error:
            print(f"fsr-record: error: {error}", file=sys.stderr)
            return EXIT_CONFIG_ERROR
        live = LiveServer(endpoint_of(args), "fsr-record")
    try:
        writer = open_writer(args.out, args.scenario)
    except ValueError as error:
        print(f"fsr-record: error: {error}", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    except OSError as error:
        reason = error.strerror or str(error)
        message = str(error) if str(error).startswith("cannot write") else f"cannot write {args.out}: {reason}"
        print(f"fsr-record: error: {message}", file=sys.stderr)
        return EXIT_FAILURE
    nodes: list[object] = []

    def make_node(_args: list[str]) -> object:
        node = make_recorder(writer if live is None else live.tee(writer), topics, args.keep_running,
                             writer.scenario_yaml, args.only, live)()
        if live is not None:
            from fsr_bringup.live.server import LiveServerError

            try:
                live.start()
            except LiveServerError as error:  # the port was taken since it was checked: exit 2
                raise ValueError(str(error)) from None
        nodes.append(node)
        return node

    try:  # the node's exit_code is EXIT_FAILURE once writing failed
        code = run_node(make_node, argv)
    finally:
        if not nodes:  # the node was never built: still leave a valid (empty) file
            try:
                writer.close()
            except OSError:
                pass
    return code  # only reached when the node was never built: run_node ends the process otherwise


if __name__ == "__main__":
    sys.exit(main())
