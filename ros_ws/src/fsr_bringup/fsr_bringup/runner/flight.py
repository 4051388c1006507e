"""One graph flight: validate the scenario, start simulator/controller/estimator/recorder, supervise, stop.

Order: the recorder first (so it is subscribed before anything is published), then the estimator and the
controller, the simulator last; the simulator's lockstep handshake waits for all of them. The flight
ends when the simulator exits (end of the scenario, divergence, or a failure). Then the nodes get SIGINT
in waves, with SIGTERM/SIGKILL fallbacks: the simulators (on Ctrl-C they are still running: they publish
``sim_status`` stopped with the last step), then the controllers and estimators (they answer every state up
to that step), the recorder last (it drains until it holds every message up to that step, then closes the
file). Nodes that already ended by themselves (``exit_on_finish``: code 0 once ``sim_status`` is final)
are fine.

A node that dies (non-zero exit) during the flight is reported by name; the flight goes on (the simulator applies the
scenario's failsafe when the controller is gone) and the run's exit code is non-zero.

``fsr-fly`` has no DDS participant of its own: the flight's progress, each ``sim_status`` and the node list
come from its watcher process (``runner/watcher_node.py``, which says why), stopped with the simulators.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from fsr_bringup.live.endpoint import LiveEndpoint
from fsr_bringup.runner.domains import DomainLease
from fsr_bringup.runner.processes import NodeProcess, ProcessGroup, describe_exit, executable
from fsr_sim.contract import (
    CLOCK,
    DIVERGED,
    EXIT_DIVERGED,
    EXIT_FAILURE,
    EXIT_INTERRUPTED,
    EXIT_OK,
    FINISHED,
    STOPPED,
    SimStatus,
    recorded_topics,
)
from fsr_sim.ros.recorder_match import RECORDED_TOPICS
from fsr_sim.ros.runtime import TEARDOWN_HUNG_SIGNAL, configure_environment

EXIT_NODE_FAILED = EXIT_FAILURE
TEARDOWN_HUNG = -TEARDOWN_HUNG_SIGNAL  # returncode of a node that its watchdog ended after its work was done
MISSING_REPORT_AFTER = 3.0  # s: first warning naming the nodes not discovered yet (--nodes)
MISSING_REPORT_EVERY = 5.0  # s: then again this often until the flight starts
PLAIN_PROGRESS_EVERY_S = 10.0  # s of wall time between progress lines when stdout is not a terminal
END_BY_THEMSELVES_S = 3.0  # s after a normal end for the nodes to end on their own before they are signalled


@dataclass
class FlightResult:
    exit_code: int
    failures: list[str] = field(default_factory=list)
    wall_time: float = 0.0
    sim_time: float = 0.0
    interrupted: bool = False
    stepping_rate: float = float("nan")  # simulated s per wall s while the simulator stepped (start-up excluded)
    notes: list[str] = field(default_factory=list)  # warnings that do not fail the run

    @property
    def real_time_factor(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else float("nan")


class Console:
    """Prefixed node output (hidden by ``quiet``) and the flight's progress: a line rewritten in place on a
    terminal, else (a CI log, a pipe) a plain line every :data:`PLAIN_PROGRESS_EVERY_S` of wall time."""

    def __init__(self, quiet: bool = False, prog: str = "fsr-fly") -> None:
        self.quiet = quiet
        self.prog = prog
        self.tty = sys.stdout.isatty()
        self.lock = threading.Lock()
        self.progress_line = ""
        self.last_plain = time.monotonic()

    def echo(self, name: str, line: str) -> None:
        if not self.quiet:
            self._above_progress(sys.stdout, f"[{name}] {line}\n")

    def notice(self, text: str) -> None:
        """A line of fsr-fly's own on stderr, shown even with ``--quiet`` (e.g. nodes not discovered yet)."""
        self._above_progress(sys.stderr, f"{self.prog}: {text}\n")

    def _above_progress(self, stream: TextIO, text: str) -> None:
        """``text`` on ``stream``; on a terminal the progress line is cleared first and written again after it."""
        with self.lock:
            shown = self.tty and self.progress_line
            if shown:
                sys.stdout.write("\r\033[K")
                sys.stdout.flush()
            stream.write(text)
            stream.flush()
            if shown:
                sys.stdout.write(self.progress_line)
                sys.stdout.flush()

    def progress(self, text: str) -> None:
        with self.lock:
            if not self.tty:
                now = time.monotonic()
                if now - self.last_plain >= PLAIN_PROGRESS_EVERY_S:
                    self.last_plain = now
                    sys.stdout.write(f"{self.prog}: {text}\n")
                    sys.stdout.flush()
                return
            self.progress_line = text
            sys.stdout.write("\r\033[K" + text)
            sys.stdout.flush()

    def flight_progress(self, sim_time: float, duration: float, wall: float) -> None:
        """Simulated time [s] out of ``duration`` after ``wall`` seconds, and their ratio."""
        rtf = sim_time / wall if wall > 0 else 0.0
        self.progress(f"t = {sim_time:7.3f} / {duration:.3f} s   real-time factor {rtf:5.2f}")

    def count_progress(self, what: str, done: int, total: int, wall: float) -> None:
        """``done`` of ``total`` ``what`` (flights, frames) after ``wall`` seconds: the rate and the time left."""
        rate = done / wall if wall > 0 else 0.0
        eta = (total - done) / rate if rate > 0 else float("nan")
        self.progress(f"{done} / {total} {what}   {rate:6.1f} {what}/s   ETA {eta:5.1f} s")

    def end_progress(self) -> None:
        if self.tty and self.progress_line:
            with self.lock:
                sys.stdout.write("\r\033[K")
                sys.stdout.flush()
                self.progress_line = ""


@dataclass(frozen=True)
class Failure:
    """How a command's long run (:func:`long_run`) ends on an exception of ``errors``: exit ``code`` and
    ``<prog>: message(error)`` on stderr, after the run's clean-up where ``clean_up``."""

    errors: type[BaseException] | tuple[type[BaseException], ...]
    code: int
    message: Callable[[Any], str] = str
    clean_up: bool = True


@dataclass
class RunOutcome:
    exit_code: int | None = None  # the code the command returns after a failure; None: the run went through


@contextlib.contextmanager
def long_run(console: Console, failures: tuple[Failure, ...],
             clean_up: Callable[[], None] = lambda: None) -> Iterator[RunOutcome]:
    """A command's long run, the progress line of ``console`` ended however it ends. SIGTERM raises
    KeyboardInterrupt inside it, as Ctrl-C does (the command then stops the same way). An exception of one of
    ``failures`` (the first that matches) ends the run as that failure says, setting the outcome's ``exit_code``;
    any other propagates."""
    def terminate(signum: int, _frame: object) -> None:
        raise KeyboardInterrupt(signal.Signals(signum).name)

    outcome = RunOutcome()
    previous = signal.signal(signal.SIGTERM, terminate)
    try:
        try:
            yield outcome
        finally:
            signal.signal(signal.SIGTERM, previous)
            console.end_progress()
    except BaseException as error:
        failure = next((failure for failure in failures if isinstance(error, failure.errors)), None)
        if failure is None:
            raise
        if failure.clean_up:
            clean_up()
        print(f"{console.prog}: {failure.message(error)}", file=sys.stderr)
        outcome.exit_code = failure.code


@dataclass(frozen=True)
class VehicleLaunch:
    """How to start one vehicle's nodes: its namespace ('' for a single vehicle) and its validated scenario file."""

    namespace: str
    scenario_path: Path
    with_estimator: bool

    def process_name(self, node: str) -> str:
        return f"{self.namespace.strip('/')}/{node}" if self.namespace else node


def node_commands(
    members: list[VehicleLaunch], recording: Path, scenario_path: Path, startup_timeout: float | None = None,
    record_topics: frozenset[str] | None = None, live: LiveEndpoint | None = None,
) -> list[tuple[str, list[str]]]:
    """(name, argv) of each node of the graph, in start order: recorder, then per vehicle the estimator,
    the controller and the simulator (whose lockstep handshake waits for the others, local or remote).
    ``record_topics``: the recorder keeps only these (:func:`fsr_sim.contract.recording_selection`); ``live``:
    the recorder serves what it records there."""
    recorder = [executable("fsr-record"), "--out", str(recording), "--scenario", str(scenario_path)]
    if record_topics is not None:
        recorder += ["--only", ",".join(sorted(record_topics))]
    if live is not None:
        recorder += ["--live", str(live.port), "--live-host", live.host]
    for member in members:
        if member.namespace:
            recorder += ["--namespace", member.namespace]
    commands = [("recorder", recorder)]
    # every node waits for the recorder's reader on each recorded topic it publishes (fsr_sim.ros.recorder_match)
    recorded = record_topics if record_topics is not None else frozenset({*recorded_topics(), CLOCK.name})
    for index, member in enumerate(members):
        ros_args = ["--ros-args", "-p", f"scenario:={member.scenario_path}",
                    "-p", f"{RECORDED_TOPICS.name}:={','.join(sorted(recorded))}"]
        if member.namespace:
            ros_args += ["-r", f"__ns:={member.namespace}"]
        if member.with_estimator:
            commands.append((member.process_name("estimator"), [executable("estimator"), *ros_args]))
        commands.append((member.process_name("controller"), [executable("controller"), *ros_args]))
        odom_subscribers = 3 if member.with_estimator else 2  # controller, recorder (+ estimator)
        simulator = [executable("simulator"), *ros_args, "-p", f"wait_for_subscribers:={odom_subscribers}"]
        if index > 0:
            simulator += ["-p", "publish_clock:=false"]  # one /clock for the whole run
        if startup_timeout is not None:
            simulator += ["-p", f"startup_timeout:={float(startup_timeout)!r}"]
        commands.append((member.process_name("simulator"), simulator))
    return commands


def child_environment(domain: DomainLease, localhost_only: bool) -> dict[str, str]:
    configure_environment()
    env = dict(os.environ)
    env["ROS_DOMAIN_ID"] = str(domain.domain_id)
    if localhost_only:
        env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        env.pop("ROS_LOCALHOST_ONLY", None)
    else:
        env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "SUBNET"
    env["PYTHONUNBUFFERED"] = "1"
    env["RCUTILS_COLORIZED_OUTPUT"] = "0"
    env.setdefault("RCUTILS_CONSOLE_OUTPUT_FORMAT", "[{severity}] {message}")
    return env


def fly_graph(
    members: list[VehicleLaunch],
    recording: Path,
    scenario_path: Path,
    log_dir: Path,
    domain: DomainLease,
    duration: float,
    console: Console,
    localhost_only: bool = True,
    nodes: set[str] | None = None,
    startup_timeout: float | None = None,
    record_topics: frozenset[str] | None = None,
    live: LiveEndpoint | None = None,
) -> FlightResult:
    """Run the graph until every simulator has ended; stop everything; report failures by node name.

    ``nodes``: the process names this host starts (``None``: all of them); the others run on other hosts
    of the same domain (``runner/remote.py``). Without a local simulator the flight ends when every
    vehicle's ``sim_status`` reports a final state.
    """
    from fsr_bringup.runner.remote import expected_node_paths
    from fsr_bringup.runner.watcher import WATCHER_PROCESS, FlightWatcher, watcher_command

    log_dir.mkdir(parents=True, exist_ok=True)
    env = child_environment(domain, localhost_only)
    group = ProcessGroup(env, log_dir, console.echo)
    interrupted: list[str] = []

    def on_signal(signum: int, _frame: object) -> None:
        interrupted.append(signal.Signals(signum).name)

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    commands = node_commands(members, recording, scenario_path, startup_timeout, record_topics, live)
    all_names = [name for name, _command in commands]
    local = set(all_names) if nodes is None else set(nodes)
    simulators = {m.process_name("simulator"): m.namespace for m in members if m.process_name("simulator") in local}
    expected = expected_node_paths([name for name in all_names if name not in local])  # on other hosts
    namespaces = [m.namespace for m in members]
    watcher = FlightWatcher(namespaces)
    start = time.monotonic()
    failures: list[str] = []
    notes: list[str] = []
    remote_end: dict[str, SimStatus] | None = None
    try:
        for name, command in commands:
            if name in local:
                group.start(name, command)
        group.start(WATCHER_PROCESS, watcher_command(namespaces), events=watcher.feed)
        reported: set[str] = set()
        last_progress = 0.0
        next_missing_report = start + MISSING_REPORT_AFTER
        while not interrupted:
            watcher.wait(0.05)
            for node in group.nodes:
                code = node.returncode
                if code is None or node.name in reported or node.name in simulators:
                    continue
                reported.add(node.name)
                if code == 0 and node.name != WATCHER_PROCESS:
                    continue  # ended by itself at the end of the flight (exit_on_finish), or stopped on purpose
                if code == TEARDOWN_HUNG:
                    notes.append(teardown_hung_note(node))  # it had ended by itself, its work done
                    continue
                failures.append(f"{node.name} died during the flight ({describe_exit(code)})")
                console.echo("fsr-fly", f"ERROR: {failures[-1]}; see {node.log_path}")
            if simulators and all(group.get(name).returncode is not None for name in simulators):
                break
            if not simulators:
                remote_end = watcher.final_statuses()
                if remote_end is not None or WATCHER_PROCESS in reported:
                    break  # without the watcher this host would never learn that the flight ended
            now = time.monotonic()
            if nodes is not None and now >= next_missing_report and not watcher.started():
                next_missing_report = now + MISSING_REPORT_EVERY
                missing = watcher.missing(expected)
                if missing:
                    console.notice(f"WARNING: after {now - start:.0f} s, nodes of other hosts not discovered yet "
                                   f"in domain {domain.domain_id}: {', '.join(missing)}")
            if now - last_progress > 0.25:
                last_progress = now
                console.flight_progress(watcher.sim_time, duration, now - start)
    finally:
        console.end_progress()
        if not interrupted and simulators and not failures:
            # A normal end: the other nodes see the final sim_status and end by themselves once they have
            # answered and recorded everything (a signal now would read like an interruption in their logs).
            group.wait_for_exit([n.name for n in group.nodes if n.name not in (*simulators, WATCHER_PROCESS)],
                                END_BY_THEMSELVES_S)
        # The watcher goes with the first wave: it is not needed any more, and if its DDS teardown hangs
        # (watcher_node.py) the wave's SIGTERM/SIGKILL ends it while nothing waits for its exit code.
        group.stop_all(first=(*simulators, WATCHER_PROCESS))
        sim_time = watcher.sim_time
        stepping_rate = watcher.stepping_rate
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    wall_time = time.monotonic() - start
    if interrupted:
        return FlightResult(EXIT_INTERRUPTED, failures, wall_time, sim_time, interrupted=True,
                            stepping_rate=stepping_rate, notes=notes)
    recorder = group.get("recorder")
    if recorder is not None and "recorder" not in reported and recorder.returncode not in (0, None):
        if recorder.returncode == TEARDOWN_HUNG:
            notes.append(teardown_hung_note(recorder))  # the file was closed before the teardown
        else:
            failures.append(f"recorder failed while closing the file ({describe_exit(recorder.returncode)})")
    exit_code = EXIT_NODE_FAILED if failures else EXIT_OK
    for namespace, status in (remote_end or {}).items():  # the simulators ran on another host
        where = f"{namespace}/simulator" if namespace else "simulator"
        sim_time = max(sim_time, float(status.sim_time))
        if status.state == DIVERGED:
            failures.append(f"{where} (remote): the flight diverged: {status.reason}")
            exit_code = EXIT_DIVERGED
        elif status.state == STOPPED:
            failures.append(f"{where} (remote) stopped: {status.reason}")
            exit_code = exit_code if exit_code == EXIT_DIVERGED else EXIT_NODE_FAILED
    for name, namespace in simulators.items():
        code = group.get(name).returncode
        state = watcher.state(namespace)
        if code == TEARDOWN_HUNG and state in (FINISHED, DIVERGED):  # its final status was published
            notes.append(teardown_hung_note(group.get(name)))
            code = EXIT_DIVERGED if state == DIVERGED else EXIT_OK
        if code == EXIT_DIVERGED:
            failures.append(f"{name}: the flight diverged (see {group.get(name).log_path} for the reason)")
            exit_code = EXIT_DIVERGED
        elif code not in (0, None):
            failures.insert(0, f"{name} failed ({describe_exit(code)}); see {group.get(name).log_path}")
            exit_code = exit_code if exit_code == EXIT_DIVERGED else EXIT_NODE_FAILED
    return FlightResult(exit_code, failures, wall_time, sim_time, stepping_rate=stepping_rate, notes=notes)


def teardown_hung_note(node: NodeProcess) -> str:
    return (f"{node.name}: its rcl/DDS teardown hung after its work was done (a Fast DDS deadlock, see "
            f"fsr_bringup/runner/watcher_node.py) and its watchdog ended it; see {node.log_path}")
