"""Reusable graph-test harness: a leased ROS domain, node processes, and an rclpy test node.

Graph tests start real node processes (console scripts) in a ROS domain of their own, taken with
:func:`fsr_bringup.runner.domains.acquire_domain` from ``TEST_RANGE``, with discovery kept on localhost
and the shipped Fast DDS profile (fast discovery). The fixtures in ``harness/fixtures.py`` wrap this
module (``ros_graph`` gives a :class:`GraphHarness`, ``scenario_file`` binds :func:`scenario_file` to the
test's ``tmp_path``)::

    @pytest.mark.graph
    def test_something(ros_graph, scenario_file):
        path = scenario_file(duration=0.2)
        sim = ros_graph.start("simulator", [executable("simulator"), "--ros-args", "-p", f"scenario:={path}"])
        cmd = ros_graph.publisher("rotor_cmd", JointState)
        flight = ros_graph.run_controller(sim, lambda odom: rotor_command(stamp_ns(odom), speeds), cmd)
        assert flight.exit_code == 0 and flight.final_status["state"] == "finished"

Only processes started through :meth:`GraphHarness.start` are ever signalled or killed.
"""

from __future__ import annotations

import copy
import os
import signal
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain
from fsr_bringup.runner.processes import _die_with_parent
from fsr_sim.contract import ODOM, SIM_STATUS, SimStatus
from fsr_sim.ros.runtime import configure_environment

# A small scenario to start from: the exercise-4 quadrotor hovering 10 m up, no ground, 0.5 s.
BASE_SCENARIO: dict[str, Any] = {
    "name": "graph_test",
    "vehicle": "quadrotor_ex4",
    "duration": 0.5,
    "actuation": "rotors",
    "initial_state": {"position": [0.0, 0.0, -10.0]},
    "environment": {"ground": {"enabled": False}},
    "lockstep": {"timeout": 2.0},
}


def merged(base: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """``base`` deep-merged with ``overrides``: mappings merge key by key, a ``None`` value deletes the key."""
    result = copy.deepcopy(base)
    for key, value in overrides.items():
        if value is None:
            result.pop(key, None)
        elif isinstance(value, dict) and isinstance(result.get(key), dict):
            result[key] = merged(result[key], value)
        else:
            result[key] = copy.deepcopy(value)
    return result


def scenario_file(
    tmp_path: Path, base: dict[str, Any] | None = None, filename: str = "scenario.yaml", **overrides: Any
) -> Path:
    """Write ``base`` (default :data:`BASE_SCENARIO`) deep-merged with ``overrides`` to ``tmp_path/filename``.

    Example: ``scenario_file(tmp_path, duration=0.2, lockstep={"failsafe": "cut"})``.
    """
    data = merged(BASE_SCENARIO if base is None else base, overrides)
    path = Path(tmp_path) / filename
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def stamp_ns(msg: Any) -> int:
    """A message's ``header.stamp`` in integer nanoseconds."""
    return int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)


@dataclass
class Inbox:
    """Messages received on one subscription, in arrival order."""

    topic: str
    messages: list[Any] = field(default_factory=list)
    subscription: Any = None

    def __len__(self) -> int:
        return len(self.messages)


@dataclass
class SimulatorTranscript:
    """What :meth:`GraphHarness.run_controller` saw: every odom (in order), the statuses, the exit code."""

    odoms: list[Any]
    statuses: list[SimStatus | None]  # None: a message that is not a status
    exit_code: int | None
    log: str

    @property
    def final_status(self) -> SimStatus | None:
        finals = [s for s in self.statuses if s is not None and s.final]
        return finals[-1] if finals else None

    def odom_stamps_ns(self) -> list[int]:
        """Stamps of every odom received, in arrival order (the simulator sends each state once)."""
        return [stamp_ns(msg) for msg in self.odoms]


class GraphHarness:
    """One leased domain, the processes a test started, and a test node (own rclpy Context) in that domain."""

    def __init__(self, log_dir: Path) -> None:
        configure_environment()  # the test process's own participant: localhost discovery, fast profile
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from rclpy.signals import SignalHandlerOptions

        self.log_dir = Path(log_dir)
        self.lease = acquire_domain(TEST_RANGE)
        self.domain_id = self.lease.domain_id
        self.env = dict(os.environ)
        self.env.update(
            ROS_DOMAIN_ID=str(self.domain_id),
            ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
            PYTHONUNBUFFERED="1",
            RCUTILS_COLORIZED_OUTPUT="0",
        )
        self.env.pop("ROS_LOCALHOST_ONLY", None)
        self.processes: list[subprocess.Popen] = []
        self._log_files: list[Any] = []
        self.context = Context()
        rclpy.init(context=self.context, domain_id=self.domain_id, signal_handler_options=SignalHandlerOptions.NO)
        self.node = Node("graph_test", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    # ----- processes --------------------------------------------------------------------------------
    def start(self, name: str, argv: list[str], env: dict[str, str] | None = None) -> subprocess.Popen:
        """Start ``argv`` in the test domain; output (stdout+stderr) goes to ``<tmp_path>/<name>.log``.

        The process gets its own session and ``PR_SET_PDEATHSIG`` (dies with the test process); it is
        killed at teardown if still running. The returned Popen has ``name`` and ``log_path`` attributes.
        """
        log_path = self.log_dir / f"{name}.log"
        log_file = open(log_path, "w", encoding="utf-8")  # closed at teardown
        self._log_files.append(log_file)
        process = subprocess.Popen(
            argv,
            env={**self.env, **(env or {})},
            stdin=subprocess.DEVNULL,
            stdout=log_file,
            stderr=subprocess.STDOUT,
            start_new_session=True,
            preexec_fn=_die_with_parent,
        )
        process.name = name
        process.log_path = log_path
        self.processes.append(process)
        return process

    @staticmethod
    def log(process: subprocess.Popen) -> str:
        """Everything the process printed so far."""
        return Path(process.log_path).read_text(encoding="utf-8", errors="replace")

    def wait_exit(self, process: subprocess.Popen, timeout: float = 10.0) -> int:
        """Exit code of ``process`` (spinning the test node meanwhile); AssertionError with its log on timeout."""
        deadline = time.monotonic() + timeout
        while process.poll() is None:
            if time.monotonic() > deadline:
                raise AssertionError(f"{process.name} still running after {timeout} s; log:\n{self.log(process)}")
            self.executor.spin_once(timeout_sec=0.02)
        return process.returncode

    # ----- test node ---------------------------------------------------------------------------------
    def publisher(self, topic: str, msg_type: type, qos: Any = None) -> Any:
        """A publisher of the test node (default QoS: the project's STREAM_QOS)."""
        return self.node.create_publisher(msg_type, topic, qos if qos is not None else _stream_qos())

    def subscribe(
        self, topic: str, msg_type: type, qos: Any = None, callback: Callable[[Any], None] | None = None
    ) -> Inbox:
        """Keep every message of ``topic`` in an :class:`Inbox` (and call ``callback`` on each)."""
        inbox = Inbox(topic)

        def receive(msg: Any) -> None:
            inbox.messages.append(msg)
            if callback is not None:
                callback(msg)

        inbox.subscription = self.node.create_subscription(
            msg_type, topic, receive, qos if qos is not None else _stream_qos()
        )
        return inbox

    def spin_until(self, predicate: Callable[[], bool], timeout: float) -> bool:
        """Spin the test node until ``predicate()`` is true (True) or ``timeout`` s pass (False)."""
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                return False
            self.executor.spin_once(timeout_sec=0.01)
        return True

    def spin_for(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=max(0.0, min(0.01, deadline - time.monotonic())))

    def collect(
        self,
        topic: str,
        msg_type: type,
        count: int | None = None,
        until: Callable[[list[Any]], bool] | None = None,
        timeout: float = 5.0,
        qos: Any = None,
    ) -> list[Any]:
        """Subscribe, gather messages until ``count`` arrived or ``until(messages)`` holds or ``timeout``.

        Returns what arrived (maybe fewer than ``count`` on timeout: the caller asserts). A volatile topic
        only delivers what is published after the subscription matched; latched topics replay.
        """
        inbox = self.subscribe(topic, msg_type, qos)
        try:

            def satisfied() -> bool:
                if count is not None and len(inbox) >= count:
                    return True
                return until is not None and until(inbox.messages)

            self.spin_until(satisfied, timeout)
            return list(inbox.messages)
        finally:
            self.node.destroy_subscription(inbox.subscription)

    def wait_for_subscribers(self, publisher: Any, count: int = 1, timeout: float = 10.0) -> bool:
        """Poll until ``publisher`` has ``count`` matched subscriptions (discovery is asynchronous)."""
        return self.spin_until(lambda: publisher.get_subscription_count() >= count, timeout)

    def wait_for_publishers(self, topic: str, count: int = 1, timeout: float = 10.0) -> bool:
        """Poll until ``topic`` (resolved in the test node's namespace) has ``count`` publishers."""
        return self.spin_until(lambda: self.node.count_publishers(topic) >= count, timeout)

    def run_controller(
        self,
        process: subprocess.Popen,
        answer: Callable[[Any], Any],
        command_publisher: Any,
        odom_topic: str = ODOM.name,
        status_topic: str = SIM_STATUS.name,
        timeout: float = 20.0,
    ) -> SimulatorTranscript:
        """Act as the lockstep controller of a simulator process until it exits.

        For every ``odom`` received, ``answer(odom)`` returns a command message, a list of them (published
        in order) or None (no answer). The odom subscription and the command publisher must exist when
        the simulator starts its handshake (create ``command_publisher`` before calling this; the odom
        subscription is created here at once). Returns every odom and status seen and the exit code.
        """
        from fsr_sim.ros.message_schema import message_class
        from fsr_sim.ros.qos import qos_of

        def respond(odom: Any) -> None:
            reply = answer(odom)
            if reply is None:
                return
            for msg in reply if isinstance(reply, (list, tuple)) else (reply,):
                command_publisher.publish(msg)

        odoms = self.subscribe(odom_topic, message_class(ODOM.type), callback=respond)
        statuses = self.subscribe(status_topic, message_class(SIM_STATUS.type), qos_of(SIM_STATUS))
        try:
            deadline = time.monotonic() + timeout
            while process.poll() is None and time.monotonic() < deadline:
                self.executor.spin_once(timeout_sec=0.01)
            if process.poll() is None:
                raise AssertionError(f"{process.name} still running after {timeout} s; log:\n{self.log(process)}")
            self._drain(lambda: len(odoms) + len(statuses))
            return SimulatorTranscript(
                odoms=list(odoms.messages),
                statuses=[SimStatus.from_json(m.data) for m in statuses.messages],
                exit_code=process.returncode,
                log=self.log(process),
            )
        finally:
            self.node.destroy_subscription(odoms.subscription)
            self.node.destroy_subscription(statuses.subscription)

    def _drain(self, size: Callable[[], int], quiet: float = 0.2, limit: float = 3.0) -> None:
        """Spin until nothing new arrived for ``quiet`` s (messages already delivered to our reader)."""
        end = time.monotonic() + limit
        last, last_change = size(), time.monotonic()
        while time.monotonic() < end and time.monotonic() - last_change < quiet:
            self.executor.spin_once(timeout_sec=0.01)
            if size() != last:
                last, last_change = size(), time.monotonic()

    # ----- teardown ---------------------------------------------------------------------------------
    def stop_processes(self, timeout: float = 3.0) -> None:
        """SIGTERM every still-running process this harness started, then SIGKILL after ``timeout``."""
        running = [p for p in self.processes if p.poll() is None]
        for process in running:
            _signal(process, signal.SIGTERM)
        deadline = time.monotonic() + timeout
        for process in running:
            try:
                process.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                _signal(process, signal.SIGKILL)
                process.wait(2.0)

    def close(self) -> None:
        """Stop the started processes, destroy the test node, shut its context down, free the domain."""
        import rclpy

        try:
            self.stop_processes()
        finally:
            for log_file in self._log_files:
                log_file.close()
            try:
                self.executor.shutdown(timeout_sec=1.0)
                self.node.destroy_node()
            finally:
                rclpy.try_shutdown(context=self.context)
                self.lease.release()


def wait_for_text(path: Path, text: str, timeout: float = 60.0) -> None:
    """Wait until the log file ``path`` (written by another process) contains ``text``; AssertionError after
    ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if path.is_file() and text in path.read_text(errors="replace"):
            return
        time.sleep(0.05)  # polling a file another process writes
    raise AssertionError(f"'{text}' not in {path} after {timeout} s")


def wait_for_recorded(path: Path, topic: str, count: int, timeout: float = 90.0) -> int:
    """Wait until the recording being written (flushed every 0.5 s) holds ``count`` messages of ``topic``;
    the count reached, or AssertionError after ``timeout`` s."""
    from fsr_sim.recording.reader import RecordingError, open_recording

    deadline = time.monotonic() + timeout
    recorded = 0
    while time.monotonic() < deadline:
        try:
            recorded = open_recording(path).count(topic)
        except RecordingError:  # not created yet, or the topic's channel not written yet
            recorded = 0
        if recorded >= count:
            return recorded
        time.sleep(0.1)  # polling a file another process writes
    raise AssertionError(f"{path}: {recorded} of {count} '{topic}' messages after {timeout} s")


def _signal(process: subprocess.Popen, signum: int) -> None:
    try:
        process.send_signal(signum)
    except ProcessLookupError:
        pass


def _stream_qos() -> Any:
    from fsr_sim.ros.qos import STREAM_QOS

    return STREAM_QOS
