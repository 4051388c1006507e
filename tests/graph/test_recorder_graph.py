"""fsr-record as a real process in its own ROS domain: completeness, decoding, signals, crashes, bad paths."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import deserialize_message

from fsr_bringup.cli.analyze_cli import main as analyze_main
from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain
from fsr_sim.recording.reader import RecordingError, open_recording
from fsr_sim.ros.conversions import odometry_from_state, wrench_stamped
from fsr_sim.ros.qos import STREAM_QOS
from fsr_sim.ros.runtime import configure_environment

RECORD = str(Path(sys.executable).parent / "fsr-record")
N = 3000
DISCOVERY_TIMEOUT = 10.0


def odom_message(k: int) -> Odometry:
    angle = 0.001 * k
    rotation = np.array([[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0], [0, 0, 1]])
    return odometry_from_state(
        k * 1_000_000, np.array([k, -0.5 * k, -1.0]), rotation, np.array([0.1, 0.2, k * 1e-3]), np.array([0, 0, 0.3])
    )


def wrench_message(k: int) -> WrenchStamped:
    return wrench_stamped(k * 1_000_000, np.array([k, 1.0, 2.0]), np.array([0.0, -k, 0.5]))


class Graph:
    """A leased ROS domain, the recorder process in it and a publishing node in this process."""

    def __init__(self, tmp_path: Path) -> None:
        configure_environment()
        import rclpy
        from rclpy.context import Context

        self.lease = acquire_domain(TEST_RANGE)
        self.env = dict(os.environ, ROS_DOMAIN_ID=str(self.lease.domain_id),
                        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
        self.context = Context()
        rclpy.init(context=self.context, domain_id=self.lease.domain_id)
        self.node = rclpy.create_node("recorder_test_publisher", context=self.context)
        self.odom = self.node.create_publisher(Odometry, "odom", STREAM_QOS)
        self.wrench = self.node.create_publisher(WrenchStamped, "wrench_truth", STREAM_QOS)
        self.out = tmp_path / "run.mcap"
        self.process: subprocess.Popen | None = None

    def start_recorder(self, *extra: str) -> None:
        self.process = subprocess.Popen(
            [RECORD, "--out", str(self.out), *extra], env=self.env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True,
        )
        deadline = time.monotonic() + DISCOVERY_TIMEOUT
        while self.odom.get_subscription_count() < 1 or self.wrench.get_subscription_count() < 1:
            assert self.process.poll() is None, f"recorder exited early: {self.process.communicate()}"
            assert time.monotonic() < deadline, "recorder did not subscribe"
            time.sleep(0.01)

    def publish(self, count: int, start: int = 0, stop: threading.Event | None = None) -> None:
        for k in range(start, start + count):
            if stop is not None and stop.is_set():
                return
            self.odom.publish(odom_message(k))
            self.wrench.publish(wrench_message(k))

    def all_acked(self) -> None:
        from rclpy.duration import Duration

        for pub in (self.odom, self.wrench):
            assert pub.wait_for_all_acked(Duration(seconds=10)), "recorder did not acknowledge every message"

    def stop(self, signum: int, timeout: float = 10.0) -> tuple[int, str, str]:
        assert self.process is not None
        self.process.send_signal(signum)
        out, err = self.process.communicate(timeout=timeout)
        return self.process.returncode, out, err

    def close(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        self.node.destroy_node()
        self.context.try_shutdown()
        self.lease.release()


@pytest.fixture
def graph(tmp_path: Path):
    g = Graph(tmp_path)
    yield g
    g.close()


def wait_until_on_disk(path: Path, count: int, timeout: float = 30.0) -> None:
    """Poll the file being written until its complete chunks hold ``count`` odom messages."""
    deadline = time.monotonic() + timeout
    on_disk = 0
    while time.monotonic() < deadline:
        try:
            on_disk = open_recording(path).count("odom")
        except RecordingError:
            on_disk = 0
        if on_disk >= count:
            return
        time.sleep(0.05)  # polling a file another process writes
    raise AssertionError(f"{path}: {on_disk} of {count} odom messages on disk after {timeout} s")


def assert_prefix(path: Path, count: int) -> None:
    """The file holds exactly messages 0..count-1 of both topics, decoded equal to what was sent."""
    recording = open_recording(path)
    assert recording.count("odom") == count and recording.count("wrench_truth") == count
    for topic, cls, make in (("odom", Odometry, odom_message), ("wrench_truth", WrenchStamped, wrench_message)):
        for k, (log_time, data) in enumerate(recording.raw(topic)):
            assert log_time == k * 1_000_000  # header stamp, simulated time
            assert deserialize_message(data, cls) == make(k)


@pytest.mark.graph
def test_records_every_message_readable_by_standard_tools(graph: Graph, tmp_path: Path) -> None:
    scenario = tmp_path / "scenario.yaml"
    scenario.write_text("name: recorded\nvehicle: quadrotor_ex4\nduration: 1.0\n")
    graph.start_recorder("--scenario", str(scenario))
    graph.publish(N)
    graph.all_acked()
    code, out, err = graph.stop(signal.SIGINT)
    assert code == 0, err
    assert f"/odom: {N}" in out and f"/wrench_truth: {N}" in out
    recording = open_recording(graph.out)
    assert not recording.truncated
    assert recording.topics["/odom"] == "nav_msgs/msg/Odometry"
    assert recording.scenario_yaml == scenario.read_text()
    assert_prefix(graph.out, N)

    from mcap_ros2.reader import read_ros2_messages

    seen = {"/odom": 0, "/wrench_truth": 0}
    for item in read_ros2_messages(str(graph.out), topics=list(seen)):
        k = seen[item.channel.topic]
        if item.channel.topic == "/odom":
            assert item.ros_msg.pose.pose.position.x == k and item.ros_msg.header.stamp.nanosec == k * 1_000_000 % 10**9
        else:
            assert item.ros_msg.wrench.torque.y == -k
        seen[item.channel.topic] += 1
    assert seen == {"/odom": N, "/wrench_truth": N}

    from rosbags.highlevel import AnyReader

    with AnyReader([graph.out]) as reader:
        connections = [c for c in reader.connections if c.topic == "/odom"]
        xs = [reader.deserialize(raw, c.msgtype).pose.pose.position.x for c, _, raw in reader.messages(connections)]
    assert xs == list(range(N))


BATCH = 1000  # messages per topic between acknowledgements: the publisher's lead stays far below its depth


@pytest.mark.graph
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_signal_mid_stream_closes_a_valid_file_without_losing_received_messages(graph: Graph, signum: int) -> None:
    graph.start_recorder()
    halt, first_batch_received = threading.Event(), threading.Event()
    errors: list[str] = []

    def stream() -> None:
        """Batches of BATCH messages per topic, each acknowledged by the recorder before the next one (a
        reliable KEEP_LAST writer more than its depth ahead of a reader would drop samples: DDS history,
        not the recorder, would then be under test), until halted."""
        from rclpy.duration import Duration

        k = 0
        while not halt.is_set():
            graph.publish(BATCH, k, halt)
            k += BATCH
            for pub in (graph.odom, graph.wrench):
                if not pub.wait_for_all_acked(Duration(seconds=10)) and not halt.is_set():
                    errors.append(f"batch ending at {k} not acknowledged within 10 s")
                    return
            first_batch_received.set()

    publisher = threading.Thread(target=stream)
    publisher.start()
    try:
        assert first_batch_received.wait(30.0), errors or "the recorder acknowledged no batch within 30 s"
        code, out, err = graph.stop(signum)  # mid-stream: the publisher goes on until halted
    finally:
        halt.set()
        publisher.join(30.0)
    assert not publisher.is_alive() and not errors, errors
    assert code == 0, err
    recording = open_recording(graph.out)
    assert not recording.truncated
    odom_count = recording.count("odom")
    assert odom_count >= BATCH  # at least the acknowledged batch
    assert f"/odom: {odom_count}" in out  # everything taken was written
    # Received messages form a gap-free prefix of what was sent, decoded equal to it.
    for topic, cls, make in (("odom", Odometry, odom_message), ("wrench_truth", WrenchStamped, wrench_message)):
        for k, (_, data) in enumerate(recording.raw(topic)):
            assert deserialize_message(data, cls) == make(k)


@pytest.mark.graph
def test_sigkill_leaves_a_file_readable_up_to_the_last_chunk(graph: Graph, tmp_path: Path, capsys) -> None:
    graph.start_recorder()
    graph.publish(N)
    graph.all_acked()
    wait_until_on_disk(graph.out, N)  # the recorder completes its chunk while idle (every FLUSH_PERIOD)
    code, _, _ = graph.stop(signal.SIGKILL)
    assert code == -signal.SIGKILL
    recording = open_recording(graph.out)
    assert recording.truncated
    assert_prefix(graph.out, N)
    assert analyze_main([str(graph.out), "--out", str(tmp_path / "analysis"), "--no-figures"]) == 0
    captured = capsys.readouterr()
    assert "TRUNCATED" in captured.err
    assert "truncated" in captured.out


@pytest.mark.parametrize(
    ("out", "reason"),
    [("/dev/full", "No space left on device"), ("/nonexistent-fsr-dir/run.mcap", "No such file or directory")],
)
def test_unwritable_output_is_one_line_error_exit_1(out: str, reason: str) -> None:
    result = subprocess.run([RECORD, "--out", out], capture_output=True, text=True, timeout=30)
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and out in lines[0] and reason in lines[0]


def test_bad_topic_argument_exit_2() -> None:
    result = subprocess.run([RECORD, "--out", "/tmp/unused.mcap", "--topic", "x:no_pkg/msg/Nope"],
                            capture_output=True, text=True, timeout=30)
    assert result.returncode == 2
    assert "no_pkg" in result.stderr


@pytest.mark.graph
def test_namespaces_and_latched_status_published_before_the_recorder(graph: Graph) -> None:
    from std_msgs.msg import String

    from fsr_bringup.analysis.load import load_flight
    from fsr_sim.ros.qos import LATCHED_QOS

    status = graph.node.create_publisher(String, "/uav1/sim_status", LATCHED_QOS)
    status.publish(String(data='{"state": "running", "reason": "", "sim_time": 0.25, "steps": 250}'))
    pubs = {ns: graph.node.create_publisher(Odometry, f"{ns}/odom", STREAM_QOS) for ns in ("/uav1", "/uav2")}
    graph.odom, graph.wrench = pubs["/uav1"], pubs["/uav2"]  # start_recorder waits for both to match
    graph.start_recorder("--namespace", "/uav1", "--namespace", "uav2")
    for k in range(200):
        for pub in pubs.values():
            pub.publish(odom_message(k))
    graph.all_acked()
    code, out, err = graph.stop(signal.SIGTERM)
    assert code == 0, err
    recording = open_recording(graph.out)
    assert recording.count("/uav1/odom") == recording.count("/uav2/odom") == 200
    assert not recording.has("/odom")
    assert recording.raw("/uav1/sim_status")[0][0] == 250_000_000  # log time = its sim_time
    flight = load_flight(recording)
    assert flight.namespace == "/uav1" and any("several vehicles" in note for note in flight.notes)
    assert flight.sim_status[0].state == "running"
