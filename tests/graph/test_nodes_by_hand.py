"""Nodes started by hand (docs/architecture.md, "Starting one node on its own"): they end by themselves with the flight,
and every node exits within 2 s of SIGINT/SIGTERM whatever it is doing.

Each test leases its own ROS domain (``ros_graph``), keeps discovery on localhost, waits on events (log
lines, exits) with timeouts, and signals or kills only the processes it started.
"""

from __future__ import annotations

import random
import signal
import subprocess
import time

import numpy as np
import pytest

from fsr_bringup.runner.processes import executable
from fsr_sim.recording.reader import open_recording

pytestmark = pytest.mark.graph

SIGNAL_BUDGET_S = 2.0  # every node exits within this long of SIGINT/SIGTERM
STARTED_LINES = {  # a log line each node prints once it is built (before any peer is discovered)
    "simulator": "waiting for",
    "controller": "controller for",
    "estimator": "estimator: c0",
    "recorder": "recording ",
}


def by_hand_commands(scenario: str, *, duration: float | None = None, wait_for: int = 3,
                     keep_running: bool = False, out: str = "manual.mcap") -> dict[str, list[str]]:
    """docs/architecture.md's four by-hand lines (recorder first, simulator last), optionally shortened/kept alive."""
    keep = ["-p", "exit_on_finish:=false"] if keep_running else []
    simulator = [executable("simulator"), "--ros-args", "-p", f"scenario:={scenario}",
                 "-p", f"wait_for_subscribers:={wait_for}"]
    if duration is not None:
        simulator += ["-p", f"duration:={duration}"]
    return {
        "recorder": [executable("fsr-record"), "--out", out, "--scenario", scenario,
                     *(["--keep-running"] if keep_running else [])],
        "estimator": [executable("estimator"), "--ros-args", "-p", f"scenario:={scenario}", "-p", "c0:=5.0",
                      "-p", "r:=2", *keep],
        "controller": [executable("controller"), "--ros-args", "-p", f"scenario:={scenario}", *keep],
        "simulator": simulator,
    }


def wait_for_line(ros_graph, process: subprocess.Popen, text: str, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while text not in ros_graph.log(process):
        if process.poll() is not None:
            raise AssertionError(f"{process.name} exited ({process.returncode}) before '{text}':\n"
                                 f"{ros_graph.log(process)}")
        if time.monotonic() > deadline:
            raise AssertionError(f"{process.name}: no '{text}' within {timeout} s:\n{ros_graph.log(process)}")
        time.sleep(0.01)


def unique_stamps(recording, topic: str) -> np.ndarray:
    return np.unique([t for t, _ in recording.raw(topic)])


def test_by_hand_nodes_end_with_the_flight_and_the_recording_is_complete(ros_graph, tmp_path):
    out = tmp_path / "manual.mcap"
    steps = 400
    processes = {
        name: ros_graph.start(name, argv)
        for name, argv in by_hand_commands("ex4_geometric", duration=steps * 1e-3, out=str(out)).items()
    }
    for name in ("recorder", "estimator", "controller", "simulator"):  # nothing sends them a signal
        assert ros_graph.wait_exit(processes[name], timeout=60.0) == 0, ros_graph.log(processes[name])
    assert "flight ended (/sim_status finished): exiting" in ros_graph.log(processes["controller"])
    assert "closing the recording" in ros_graph.log(processes["recorder"])
    recording = open_recording(out)
    assert not recording.truncated
    expected = np.arange(steps + 1) * 1_000_000  # t_0 .. t_N [ns]
    for topic in ("/odom", "/wrench_truth", "/wrench_cmd", "/reference", "/wrench_estimate"):
        np.testing.assert_array_equal(unique_stamps(recording, topic), expected, err_msg=topic)
    assert recording.count("/mass_estimate") == steps + 1
    statuses = [msg.data for _, msg in recording.messages("/sim_status")]
    assert '"state": "finished"' in statuses[-1]
    assert "ex4_geometric" in recording.scenario_yaml  # --scenario took the built-in name


def test_fleet_recorder_ends_only_when_every_vehicle_has_ended(ros_graph, tmp_path):
    out = tmp_path / "fleet.mcap"
    steps = {"/uav1": 150, "/uav2": 600}
    recorder = ros_graph.start("recorder", [executable("fsr-record"), "--out", str(out), "--scenario",
                                            "ex4_geometric", "--namespace", "/uav1", "--namespace", "/uav2"])
    started = [recorder]
    for ns, count in steps.items():
        ros_args = ["--ros-args", "-p", "scenario:=ex4_geometric", "-r", f"__ns:={ns}"]
        started.append(ros_graph.start(f"{ns[1:]}_controller", [executable("controller"), *ros_args]))
        started.append(ros_graph.start(f"{ns[1:]}_simulator", [
            executable("simulator"), *ros_args, "-p", "wait_for_subscribers:=2", "-p", f"duration:={count * 1e-3}",
            *(["-p", "publish_clock:=false"] if ns != "/uav1" else []),
        ]))
    for process in started:
        assert ros_graph.wait_exit(process, timeout=60.0) == 0, ros_graph.log(process)
    log = ros_graph.log(recorder)
    assert "flight ended (/uav1/sim_status finished, /uav2/sim_status finished)" in log
    recording = open_recording(out)
    assert not recording.truncated
    for ns, count in steps.items():
        np.testing.assert_array_equal(unique_stamps(recording, f"{ns}/odom"), np.arange(count + 1) * 1_000_000)
        np.testing.assert_array_equal(unique_stamps(recording, f"{ns}/wrench_cmd"), np.arange(count + 1) * 1_000_000)


# ----- bounded shutdown ---------------------------------------------------------------------------------------
# 12 rounds of the four nodes: each signalled once per round (the simulator not after the end: it has exited)
# -> 10 signals for the simulator, 12 for each other node.
SCHEDULE = ("starting", "waiting_for_peers", "mid_flight", "after_the_end", "starting", "mid_flight",
            "waiting_for_peers", "mid_flight", "starting", "after_the_end", "waiting_for_peers", "mid_flight")


def send(process: subprocess.Popen, signum: int, sent: dict[str, float]) -> None:
    """Signal ``process`` if it still runs; note when (``sent[name]``)."""
    if process.poll() is None:
        process.send_signal(signum)
        sent[process.name] = time.monotonic()


def exit_times(processes: list[subprocess.Popen], sent: dict[str, float], timeout: float = 10.0) -> dict[str, float]:
    """Seconds from each signalled process's signal to its exit (inf if it did not exit within ``timeout``)."""
    exited: dict[str, float] = {}
    deadline = time.monotonic() + timeout
    while len(exited) < len(sent) and time.monotonic() < deadline:
        for process in processes:
            if process.name in sent and process.name not in exited and process.poll() is not None:
                exited[process.name] = time.monotonic() - sent[process.name]
        time.sleep(0.005)
    return {name: exited.get(name, float("inf")) for name in sent}


@pytest.mark.alone  # each exit timed against a 2 s budget on the wall clock
def test_every_node_exits_within_2s_of_a_signal_in_any_phase(ros_graph, tmp_path):
    rng = random.Random(20261201)
    results: list[tuple[str, str, str, float, subprocess.Popen]] = []
    for index, phase in enumerate(SCHEDULE):
        signum = signal.SIGINT if rng.random() < 0.5 else signal.SIGTERM
        commands = by_hand_commands(
            "ex4_geometric",
            duration=0.3 if phase == "after_the_end" else 60.0,
            wait_for=99 if phase == "waiting_for_peers" else 3,  # 99: the handshake never completes
            keep_running=True,  # helpers wait for the signal even after the end of the flight
            out=str(tmp_path / f"round{index}.mcap"),
        )
        order = list(commands)
        rng.shuffle(order)
        times: dict[str, float] = {}  # process name -> seconds from its signal to its exit
        processes: dict[str, subprocess.Popen] = {}
        if phase == "starting":
            for name in order:  # one at a time: signalled right after it is built (no peer yet), plus 0-300 ms
                processes[name] = ros_graph.start(f"r{index}_{name}", commands[name])
                wait_for_line(ros_graph, processes[name], STARTED_LINES[name])
                time.sleep(rng.uniform(0.0, 0.3))
                sent: dict[str, float] = {}
                send(processes[name], signum, sent)
                times.update(exit_times([processes[name]], sent))
        else:
            processes = {name: ros_graph.start(f"r{index}_{name}", argv) for name, argv in commands.items()}
            for name, line in STARTED_LINES.items():
                wait_for_line(ros_graph, processes[name], line)
            if phase == "waiting_for_peers":  # every node built; the simulator waits for 99 subscribers
                ros_graph.spin_for(0.3)
            elif phase == "mid_flight":
                wait_for_line(ros_graph, processes["simulator"], "answered the initial state: stepping")
            else:
                assert ros_graph.wait_exit(processes["simulator"], timeout=60.0) == 0
            time.sleep(rng.uniform(0.0, 0.3))
            sent = {}
            for name in order:
                send(processes[name], signum, sent)
            times = exit_times(list(processes.values()), sent)
        for name, seconds in times.items():
            node = name.split("_", 1)[1]
            results.append((node, phase, signum.name, seconds, processes[node]))
        ros_graph.stop_processes()  # normally nothing is left; SIGKILLs only this round's processes
    report = "\n".join(f"{name:10s} {phase:18s} {sig:7s} {seconds:.3f} s exit {process.returncode}"
                       for name, phase, sig, seconds, process in results)
    print(f"\n{len(results)} signals, slowest exit {max(r[3] for r in results):.3f} s\n{report}")
    counts = {name: sum(r[0] == name for r in results) for name in STARTED_LINES}
    assert min(counts.values()) >= 10, counts
    assert all(r[3] <= SIGNAL_BUDGET_S for r in results), f"exit slower than {SIGNAL_BUDGET_S} s:\n{report}"
    assert all(r[4].returncode == 0 for r in results), f"non-zero exit after a signal:\n{report}"


@pytest.mark.parametrize("node", ["controller", "estimator"])
def test_exit_on_finish_must_be_a_bool(ros_graph, node):
    process = ros_graph.start(node, [executable(node), "--ros-args", "-p", "scenario:=ex4_geometric",
                                     "-p", "exit_on_finish:=maybe"])
    assert ros_graph.wait_exit(process, timeout=30.0) == 2
    assert f"{node}: parameter 'exit_on_finish': must be true or false, got 'maybe'" in ros_graph.log(process)
