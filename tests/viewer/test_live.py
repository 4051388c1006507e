"""Watching a flight live (fsr-fly --live): Foxglove's own WebSocket client (@foxglove/ws-protocol, pinned in
package-lock.json like the decoders; live_client.cjs) connects to the server during the flight, decodes what it
receives with @foxglove/rosmsg2-serialization, and sees what the recording holds. Every server binds 127.0.0.1 on a
free port (--live 0: the port taken is printed); every process started here is stopped by its own handle, and
every wait has a timeout."""

from __future__ import annotations

import base64
import json
import os
import queue
import re
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from fsr_bringup.visualization.foxglove import layout
from fsr_sim.contract import (
    BODY_FRAME,
    EXIT_CONFIG_ERROR,
    MAP_FRAME,
    MARKERS,
    ODOM,
    ROTOR_STATE,
    SIM_STATUS,
    TF,
    TF_STATIC,
    WORLD_FRAME,
)
from fsr_sim.recording.reader import open_recording

BIN = Path(sys.executable).parent
URL = re.compile(r"live: .*?(ws://\S+)")
FLY_TIMEOUT = 240.0  # s for a flight of a few seconds, start-up included, on a loaded machine


class Flight:
    """``fsr-fly`` running in the background, its output read line by line."""

    def __init__(self, tmp_path: Path, name: str, *args: str) -> None:
        self.out = tmp_path / f"{name}.mcap"
        self.process = subprocess.Popen(
            [str(BIN / "fsr-fly"), *args, "--out", str(self.out), "--no-analysis", "--quiet"],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env={**os.environ, "MPLBACKEND": "Agg"})
        self.lines: list[str] = []
        self.queue: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for line in self.process.stdout:
            self.queue.put(line.rstrip("\n"))
        self.queue.put(None)

    def wait_for(self, pattern: re.Pattern, timeout: float = 120.0) -> re.Match:
        """The first output line matching ``pattern`` (the flight fails the test if it ends first)."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                line = self.queue.get(timeout=max(deadline - time.monotonic(), 0.01))
            except queue.Empty:
                pytest.fail(f"no line matching {pattern.pattern} within {timeout} s:\n" + "\n".join(self.lines))
            if line is None:
                pytest.fail(f"fsr-fly ended before a line matching {pattern.pattern}:\n" + "\n".join(self.lines))
            self.lines.append(line)
            found = pattern.search(line)
            if found:
                return found

    def finish(self, timeout: float = FLY_TIMEOUT) -> str:
        """Wait for the end of the flight; its whole output."""
        self.process.wait(timeout=timeout)
        while (line := self.queue.get(timeout=10)) is not None:
            self.lines.append(line)
        assert self.process.returncode == 0, "\n".join(self.lines)
        return "\n".join(self.lines)

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait(timeout=30)


class Watcher:
    """live_client.cjs (Foxglove's WebSocket client and decoders) watching ``url`` in the background."""

    def __init__(self, decoders: Path, url: str, *args: str, timeout: float = FLY_TIMEOUT) -> None:
        self.process = subprocess.Popen(["node", str(decoders / "live_client.cjs"), url, "--timeout", str(timeout),
                                         *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    def seen(self, timeout: float = 60.0) -> dict:
        """What it saw (it ends when the server closes the connection at the end of the flight)."""
        stdout, stderr = self.process.communicate(timeout=timeout)
        assert self.process.returncode == 0, stderr
        return json.loads(stdout)

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.communicate(timeout=30)


def stamp_ns(message: dict) -> int:
    stamp = message["header"]["stamp"]
    return int(stamp["sec"]) * 1_000_000_000 + int(stamp["nanosec"])


def layout_topics() -> set[str]:
    """The topics the shipped layout plots (``/odom.pose...`` -> ``/odom``)."""
    paths = re.findall(r'"value": "(/[a-z_]+)[.\[]', json.dumps(layout()))
    return set(paths)


@pytest.mark.graph
@pytest.mark.parametrize("mode", ["graph", "in-process"])
def test_foxglove_watches_the_flight_live(tmp_path, decoders, mode):
    """During the flight a client subscribed at once sees every /odom and, in /tf, the pose of each (to 1e-12) with
    the same bytes as the recording; a client that subscribes after 1 s gets /tf_static and the last markers at
    once; a third subscribes to everything and stops reading, and the flight and its recording are complete."""
    extra = ["--in-process"] if mode == "in-process" else []
    flight = Flight(tmp_path, mode, "ex5_voliro", "--duration", "3", "--live", "0", *extra)
    watchers = []
    try:
        url = flight.wait_for(URL).group(1)
        odom, markers = "/" + ODOM.name, "/" + MARKERS.name
        watchers = [
            Watcher(decoders, url, "--subscribe", f"{odom},{TF.name},{markers},/{SIM_STATUS.name}", "--raw", odom),
            Watcher(decoders, url, "--subscribe", odom, "--late", f"{TF_STATIC.name},{markers}", "--late-after", "1.0"),
            Watcher(decoders, url, "--subscribe", ",".join(["/" + name for name in ("odom", "reference", "markers")]),
                    "--stop-reading"),
        ]
        flight.finish()
        prompt, late = watchers[0].seen(), watchers[1].seen()
    finally:
        for watcher in watchers:
            watcher.stop()
        flight.stop()

    recording = open_recording(flight.out)
    advertised = {channel["topic"]: channel for channel in prompt["advertised"]}
    assert set(recording.topics) <= set(advertised), "every recorded topic is served"
    lag = "/" + ROTOR_STATE.name  # published with actuator dynamics only
    absent = set() if lag in {"/" + t.lstrip("/") for t in recording.topics} else {lag}
    assert layout_topics() - absent <= set(advertised), "the layout's topics are all served (rotor_state: with lag)"
    for topic, type_name in recording.topics.items():
        assert (advertised[topic]["schemaName"], advertised[topic]["encoding"],
                advertised[topic]["schemaEncoding"]) == (type_name, "cdr", "ros2msg")

    # The prompt client: every odom from its subscription on (the recording's bytes), its pose in /tf (to 1e-12),
    # most of them before the flight ended.
    recorded = dict(recording.raw(odom))
    assert len(recorded) == 3001
    seen_odom = prompt["messages"][odom]
    steps = [stamp_ns(entry["message"]) // 1_000_000 for entry in seen_odom]
    assert steps == list(range(steps[0], 3001)) and len(steps) > 1000, "nothing dropped for a client that reads"
    for entry in seen_odom:
        assert base64.b64decode(entry["raw"]) == recorded[stamp_ns(entry["message"])]
    bodies = {stamp_ns(t): t["transform"] for entry in prompt["messages"][TF.name]
              for t in entry["message"]["transforms"] if t["child_frame_id"] == BODY_FRAME}
    both = [entry for entry in seen_odom if stamp_ns(entry["message"]) >= min(bodies)]  # once both subscribed
    assert len(both) > 1000
    for entry in both:
        pose = entry["message"]["pose"]["pose"]
        transform = bodies[stamp_ns(entry["message"])]
        got = [transform["translation"][a] for a in "xyz"] + [transform["rotation"][a] for a in "xyzw"]
        want = [pose["position"][a] for a in "xyz"] + [pose["orientation"][a] for a in "xyzw"]
        assert np.max(np.abs(np.subtract(got, want))) <= 1e-12
    assert prompt["finalArrival"] is not None
    running = [entry for entry in seen_odom if entry["arrival"] < prompt["finalArrival"]]
    assert len(running) >= len(seen_odom) / 2, "watched while the flight ran, not after it"
    drawn = prompt["messages"][markers]
    assert len(drawn) >= (3001 - steps[0]) // 20
    arms = next(m for m in drawn[-1]["message"]["markers"] if m["ns"] == "arms")
    assert arms["header"]["frame_id"] == WORLD_FRAME

    # The late client: /tf_static, published once at t = 0, as soon as it subscribes (after t = 1 s), and markers.
    (static,) = late["messages"][TF_STATIC.name]
    pairs = {(t["header"]["frame_id"], t["child_frame_id"]) for t in static["message"]["transforms"]}
    assert (MAP_FRAME, WORLD_FRAME) in pairs
    assert late["messages"][markers]

    # The client that stopped reading: nothing missing from the flight or its recording.
    status = json.loads(recording.messages("/" + SIM_STATUS.name)[-1][1].data)
    assert (status["state"], status["steps"]) == ("finished", 3000)
    assert recording.count(odom) == recording.count("/reference") == 3001


@pytest.mark.slow
def test_a_late_subscriber_gets_the_latched_topics_and_the_last_markers_at_once(decoders):
    """Written before anyone subscribed: /tf_static (two vehicles), two sim_status and three markers; a client that
    subscribes then gets both /tf_static, both statuses and the last markers only, stamped with the latest time
    served (no jump back in time for Foxglove), and nothing else."""
    from fsr_bringup.live.endpoint import LiveEndpoint
    from fsr_bringup.live.server import LiveServer
    from fsr_sim.ros import cdr_pack

    said: list[str] = []
    live = LiveServer(LiveEndpoint("127.0.0.1", 0), say=said.append)
    statuses = [cdr_pack.string(json.dumps({"state": state})) for state in ("running", "finished")]
    with live:
        for topic, type_name in ((TF_STATIC.name, TF_STATIC.type), ("/" + SIM_STATUS.name, SIM_STATUS.type),
                                 ("/" + MARKERS.name, MARKERS.type), ("/" + ODOM.name, ODOM.type)):
            live.add_topic(topic, type_name)
        static = [empty_tf(stamp) for stamp in (0, 1)]
        drawn = [empty_markers() for _ in range(3)]
        live.write_records([(TF_STATIC.name, static[0], 0, 0), ("/" + SIM_STATUS.name, statuses[0], 0, 0)])
        live.write_records([(TF_STATIC.name, static[1], 0, 0)] + [("/" + MARKERS.name, data, t, t)
                                                                   for t, data in zip((0, 20, 40), drawn, strict=True)])
        live.write_records([("/" + SIM_STATUS.name, statuses[1], 50, 50)])
        live.start()
        topics = ",".join((TF_STATIC.name, "/" + SIM_STATUS.name, "/" + MARKERS.name, "/" + ODOM.name))
        watcher = Watcher(decoders, live.endpoint.url, "--subscribe", topics, "--timeout", "3")
        try:
            seen = watcher.seen()
        finally:
            watcher.stop()
    messages = seen["messages"]
    assert [stamp_ns(entry["message"]["transforms"][0]) for entry in messages[TF_STATIC.name]] == [0, 1]
    assert [json.loads(entry["message"]["data"])["state"] for entry in messages["/" + SIM_STATUS.name]] == \
        ["running", "finished"]
    assert len(messages["/" + MARKERS.name]) == 1
    assert "/" + ODOM.name not in messages
    assert {int(entry["logTime"]) for entries in messages.values() for entry in entries} == {50}
    assert any("serving on ws://127.0.0.1:" in line for line in said)


def empty_tf(stamp_ns_: int) -> bytes:
    """The root vehicle's /tf_static message (no scenario: map -> world_ned, base_link_frd -> base_link), stamped
    ``stamp_ns_`` (CDR)."""
    from fsr_bringup.visualization.frames import static_frames

    layout_, values = static_frames(None, "/", moving_rotors=False)
    return layout_.pack_rows(np.array([stamp_ns_]), values[None, :])[0].tobytes()


def empty_markers() -> bytes:
    """A MarkerArray with one marker (CDR)."""
    from rclpy.serialization import serialize_message
    from visualization_msgs.msg import Marker, MarkerArray

    return serialize_message(MarkerArray(markers=[Marker(ns="arms")]))


@pytest.mark.slow
def test_a_client_that_stops_reading_changes_neither_the_flight_nor_its_recording(tmp_path, decoders):
    """In one process, at five times real time: a client subscribed to everything that stops reading is told once
    that it cannot keep up; the recording is the one a flight without --live writes, byte for byte."""
    args = ["ex4_geometric", "--in-process", "--duration", "10", "--set", "lockstep.real_time_factor=5"]
    flight = Flight(tmp_path, "live", *args, "--live", "0")
    watcher = None
    try:
        url = flight.wait_for(URL).group(1)
        topics = [t for t in ("/tf_static", "/tf", "/markers", *("/" + name for name in recorded_topic_names()))]
        watcher = Watcher(decoders, url, "--subscribe", ",".join(topics), "--stop-reading")
        output = flight.finish()
    finally:
        if watcher is not None:
            watcher.stop()
        flight.stop()
    alone = Flight(tmp_path, "alone", *args)
    try:
        alone.finish()
    finally:
        alone.stop()
    assert output.count("cannot keep up") == 1, output
    assert "simulated 10.000 s" in output
    assert flight.out.read_bytes() == alone.out.read_bytes()


def recorded_topic_names() -> list[str]:
    from fsr_sim.contract import recorded_topics

    return sorted(recorded_topics())


@pytest.mark.alone  # the pace measured on the wall clock (+-5 %)
@pytest.mark.slow
def test_in_process_live_flight_runs_at_the_real_time_factor(tmp_path, decoders):
    """A 5 s flight at lockstep.real_time_factor 1 takes 5 s +- 5 %, measured where a viewer sees it: the arrival
    times of the odometry at Foxglove's client against their stamps. The first and the last arrival span the flight
    from the client's subscription on, so start-up does not count (a loaded machine may take a second or two to
    start the client: at least half of the flight is still measured); the pacing waits for the wall clock after each
    20 ms chunk, and flying a chunk takes about a millisecond, so even a machine several times slower keeps the
    schedule (a stall over 1 s restarts it and would fail the test)."""
    flight = Flight(tmp_path, "paced", "ex4_geometric", "--in-process", "--duration", "5", "--live", "0")
    watcher = None
    try:
        url = flight.wait_for(URL).group(1)
        watcher = Watcher(decoders, url, "--subscribe", "/" + ODOM.name)
        output = flight.finish()
        seen = watcher.seen()
    finally:
        if watcher is not None:
            watcher.stop()
        flight.stop()
    odom = seen["messages"]["/" + ODOM.name]
    stamps = np.array([stamp_ns(entry["message"]) for entry in odom]) * 1e-9
    arrivals = np.array([entry["arrival"] for entry in odom]) * 1e-3
    assert stamps[0] < 2.5 and stamp_ns(odom[-1]["message"]) == 5_000_000_000
    ratio = (arrivals[-1] - arrivals[0]) / (stamps[-1] - stamps[0])
    assert 0.95 <= ratio <= 1.05, f"{stamps[-1] - stamps[0]:.3f} s of flight in {arrivals[-1] - arrivals[0]:.3f} s"
    wall = float(re.search(r"simulated 5\.000 s in ([0-9.]+) s wall", output).group(1))
    assert 4.75 <= wall <= 5.25, output


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
@pytest.mark.parametrize("command", ["in-process", "graph", "fsr-record"])
def test_a_bad_or_busy_port_is_one_line_exit_2_and_nothing_is_flown(tmp_path, command):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        out = tmp_path / "run" / "flight.mcap"
        if command == "fsr-record":
            argv = [str(BIN / "fsr-record"), "--out", str(out), "--live", str(port)]
        else:
            argv = [str(BIN / "fsr-fly"), "ex4_geometric", "--out", str(out), "--live", str(port),
                    *(["--in-process"] if command == "in-process" else [])]
        run = subprocess.run(argv, capture_output=True, text=True, timeout=120)
    assert run.returncode == EXIT_CONFIG_ERROR
    assert run.stdout == "" and run.stderr.count("\n") == 1, run.stderr
    assert f"127.0.0.1:{port}" in run.stderr and "in use" in run.stderr
    assert not (tmp_path / "run").exists()
    if command == "in-process":
        bad = subprocess.run([str(BIN / "fsr-fly"), "ex4_geometric", "--out", str(out), "--in-process", "--live",
                              "70000"], capture_output=True, text=True, timeout=120)
        assert bad.returncode == EXIT_CONFIG_ERROR and bad.stderr.count("\n") == 1 and "70000" in bad.stderr
        assert not (tmp_path / "run").exists()
