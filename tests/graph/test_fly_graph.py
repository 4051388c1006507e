"""``fsr-fly`` end to end: the whole node graph as separate processes, faults, fleets and concurrent runs.

Every run takes its own ROS domain (fsr-fly leases one), records to ``tmp_path`` and is checked through
its recording. Durations are short so the suite stays fast; the physics is checked elsewhere.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fsr_bringup.analysis.run import analyze_recording
from fsr_sim.recording.reader import open_recording
from harness.graph import wait_for_recorded, wait_for_text

pytestmark = pytest.mark.graph

BIN = Path(sys.executable).parent
BUILT_IN = ("ex3_estimation", "ex4_geometric", "ex5_voliro", "octo_ground_effect", "ceiling_approach",
            "step_disturbance")


def env() -> dict[str, str]:
    return {**os.environ, "MPLBACKEND": "Agg", "PYTHONUNBUFFERED": "1"}


def fly(args: list[str], timeout: float = 180.0) -> subprocess.CompletedProcess:
    return subprocess.run([str(BIN / "fsr-fly"), "--quiet", *args], env=env(), capture_output=True, text=True,
                          timeout=timeout)


def start_fly(args: list[str]) -> subprocess.Popen:
    return subprocess.Popen([str(BIN / "fsr-fly"), *args], env=env(), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def children(pid: int) -> dict[int, str]:
    """{pid: command line} of the direct children of ``pid``."""
    found = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
            found[int(entry.name)] = cmdline
    return found


def node_pid(fly_pid: int, executable: str) -> int:
    for pid, cmdline in children(fly_pid).items():
        if f"/{executable} " in cmdline:
            return pid
    raise AssertionError(f"no {executable} child of fsr-fly {fly_pid}: {children(fly_pid)}")


def odom_positions(recording: Path, topic: str = "odom") -> np.ndarray:
    return np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z]
                     for _, m in open_recording(recording).messages(topic)])


def final_status(recording, namespace: str = "") -> dict:
    return json.loads(recording.messages(f"{namespace}/sim_status")[-1][1].data)


@pytest.mark.parametrize("scenario", BUILT_IN)
def test_every_built_in_scenario_flies_records_every_step_and_analyses(tmp_path, scenario):
    out = tmp_path / f"{scenario}.mcap"
    run = fly([scenario, "--duration", "0.5", "--out", str(out), "--no-analysis"])
    assert run.returncode == 0, run.stdout + run.stderr
    recording = open_recording(out)
    assert not recording.truncated
    steps = 500
    # Every simulator step is in the file: odom for t_0..t_N, a command and an estimate per answered state.
    assert recording.count("odom") == recording.count("wrench_truth") == steps + 1
    assert recording.count("wrench_cmd") == recording.count("wrench_shortfall") >= steps
    assert recording.count("wrench_estimate") >= steps
    assert recording.count("reference") >= steps
    assert final_status(recording)["state"] == "finished"
    analysis = subprocess.run([str(BIN / "fsr-analyze"), str(out), "--out", str(tmp_path / "analysis")],
                              env=env(), capture_output=True, text=True, timeout=120)
    assert analysis.returncode == 0, analysis.stderr
    metrics = json.loads((tmp_path / "analysis" / "metrics.json").read_text())
    assert metrics and list((tmp_path / "analysis").glob("*.png"))
    assert "cannot decode" not in json.dumps(metrics)  # every recorded topic decodes (rotor_cmd included)


def test_graph_and_in_process_runs_agree(tmp_path):
    for scenario, sets in (("ex4_geometric", []), ("ex5_voliro", ["--set", "sensors.preset=ideal"])):  # ex5: imu
        graph, local = tmp_path / f"{scenario}_graph.mcap", tmp_path / f"{scenario}_local.mcap"
        for out, extra in ((graph, []), (local, ["--in-process"])):
            run = fly([scenario, "--duration", "0.5", "--out", str(out), "--no-analysis", *sets, *extra])
            assert run.returncode == 0, run.stdout + run.stderr
        a, b = odom_positions(graph), odom_positions(local)
        assert a.shape == b.shape == (501, 3)
        assert np.max(np.abs(a - b)) < 1e-9
        # The same messages, byte for byte: what the nodes publish is what an in-process recording writes.
        g, loc = open_recording(graph), open_recording(local)
        per_step = sorted(t for t in set(g.topics) & set(loc.topics) if t not in ("/sim_status", "/clock"))
        assert len(per_step) >= 9, per_step  # rotor_cmd too in rotor actuation
        assert ("/imu" in per_step) == bool(sets)
        for topic in per_step:
            if topic == "/tf":  # in stamp order: the rotor frames come with the markers, after later odom in the graph
                assert sorted(g.raw(topic)) == sorted(loc.raw(topic)), topic
            else:  # at the same log times too: mass_estimate (no header) at its state's stamp
                assert list(g.raw(topic)) == list(loc.raw(topic)), topic
        # /clock (not in an in-process recording) is as deep as the streams: the recorder keeps every step.
        assert g.count("/clock") == 501
        # a normal end reads as one: every node ended by itself (the watcher, fsr-fly's own, is stopped)
        logs = {log.name: log.read_text() for log in (tmp_path / f"{scenario}_graph" / "logs").glob("*.log")}
        assert {"simulator.log", "controller.log", "estimator.log", "recorder.log"} <= set(logs), sorted(logs)
        assert not [name for name, text in logs.items() if "received SIG" in text], logs


def test_killed_controller_is_reported_and_the_recording_is_complete(tmp_path):
    out = tmp_path / "run.mcap"
    process = start_fly(["ex4_geometric", "--duration", "5", "--out", str(out), "--no-analysis",
                         "--set", "lockstep.timeout=0.2"])
    try:
        wait_for_recorded(out, "odom", 300)  # mid-flight, from the recording (the kill must precede the end)
        os.kill(node_pid(process.pid, "controller"), signal.SIGKILL)
        stdout, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode == 1, stdout + stderr
    assert "controller died during the flight (killed by SIGKILL)" in stderr
    recording = open_recording(out)
    assert not recording.truncated
    assert recording.count("odom") == 5001  # the simulator finished the flight on its failsafe
    assert final_status(recording)["state"] == "finished"
    assert 300 <= recording.count("wrench_cmd") < 5001  # answered until killed, not to the end


@pytest.mark.parametrize("victim", ["estimator", "recorder"])
def test_killed_estimator_or_recorder_is_reported_and_the_flight_goes_on(tmp_path, victim):
    out = tmp_path / "run.mcap"
    process = start_fly(["step_disturbance", "--duration", "5", "--out", str(out), "--no-analysis"])
    try:
        wait_for_recorded(out, "odom", 300)  # mid-flight, from the recording (the kill must precede the end)
        os.kill(node_pid(process.pid, "estimator" if victim == "estimator" else "fsr-record"), signal.SIGKILL)
        stdout, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode == 1, stdout + stderr
    assert f"{victim} died during the flight (killed by SIGKILL)" in stderr
    wait_for_text(tmp_path / "run" / "logs" / "simulator.log", "finished: reached the scenario duration")
    recording = open_recording(out)
    if victim == "estimator":
        assert not recording.truncated and recording.count("odom") == 5001
        assert recording.count("wrench_estimate") < 5001
    else:
        assert recording.truncated  # cut by SIGKILL: readable up to its last complete chunk
        assert recording.count("odom") > 0


def test_interrupted_run_records_every_message_up_to_the_last_step_and_says_interrupted(tmp_path):
    """After Ctrl-C the recording used to miss the last ~0.1 s of commands and ~1 s of estimates."""
    out = tmp_path / "run.mcap"
    process = start_fly(["ex4_geometric", "--set", "actuation=rotors", "--duration", "120", "--out", str(out)])
    try:
        wait_for_text(tmp_path / "run" / "logs" / "simulator.log", "stepping")
        nodes = {pid: cmdline for pid, cmdline in children(process.pid).items()
                 if "from multiprocessing." not in cmdline}  # the figures' fork server, started during the flight
        assert len(nodes) == 5, nodes  # the four nodes and fsr-fly's flight watcher
        assert sum("fsr_bringup.runner.watcher_node" in cmdline for cmdline in nodes.values()) == 1, nodes
        wait_for_recorded(out, "odom", 2000)  # ~2 s in, from the recorder's own flushed file
        process.send_signal(signal.SIGINT)
        stdout, stderr = process.communicate(timeout=180)
    finally:
        process.kill()
    assert process.returncode == 130, stdout + stderr
    assert not any(Path(f"/proc/{pid}").exists() for pid in nodes), "a node outlived fsr-fly"
    recording = open_recording(out)
    assert not recording.truncated
    status = final_status(recording)
    assert status["state"] == "stopped" and status["reason"] == "received SIGINT"
    steps = status["steps"]
    assert 2000 <= steps < 120_000
    expected = [k * 1_000_000 for k in range(steps + 1)]  # t_0 .. t_K, the last state the simulator published
    for topic in ("odom", "wrench_truth", "rotor_cmd", "wrench_cmd", "reference", "wrench_estimate"):
        stamps = [t for t, _ in recording.raw(topic)]
        assert sorted(set(stamps)) == expected, f"{topic}: {len(set(stamps))} of {steps + 1} stamps"
        assert all(t == 0 for t in stamps[len(expected):]) or len(stamps) == len(expected)  # repeats: t_0 only
    assert recording.count("mass_estimate") == recording.count("wrench_estimate")
    summary = (tmp_path / "run" / "summary.md").read_text()
    assert f"interrupted at t = {steps * 1e-3:.3f} s" in summary, summary
    assert f"fsr-fly: flight interrupted: simulated {steps * 1e-3:.3f} s" in stdout, stdout  # one stop time


def test_invalid_scenario_is_refused_before_any_process_starts(tmp_path):
    scenario = tmp_path / "typo.yaml"
    scenario.write_text("vehicle: quadrotor_ex4\nduration: 1.0\ncontroler: {type: geometric}\n")
    run = fly([str(scenario), "--out", str(tmp_path / "run.mcap")], timeout=60)
    assert run.returncode == 2
    assert "Traceback" not in run.stderr
    assert str(scenario) in run.stderr and "controler" in run.stderr
    assert not (tmp_path / "run").exists()
    for bad in (["ex4_geometric", "--set", "controller.gains.k_p=[1, 2]"],
                ["ex4_geometric", "--set", "estimator.c0=0"],
                ["ex5_voliro", "--set", "controller.type=geometric"],
                ["no_such_scenario"]):
        run = fly([*bad, "--out", str(tmp_path / "bad.mcap")], timeout=60)
        assert run.returncode == 2 and "Traceback" not in run.stderr and run.stderr.count("\n") == 1, run.stderr


def test_divergence_ends_the_flight_with_the_reason_and_a_recording(tmp_path):
    out = tmp_path / "crash.mcap"
    run = fly(["ex4_geometric", "--duration", "2", "--out", str(out), "--no-analysis",
               "--set", "actuation=rotors",  # rotor limits: it cannot stop in time
               "--set", "initial_state.position=[0, 0, -0.3]", "--set", "initial_state.velocity=[0, 0, 15]"])
    assert run.returncode == 3, run.stdout + run.stderr
    assert "diverged" in run.stderr
    recording = open_recording(out)
    status = final_status(recording)
    assert status["state"] == "diverged" and status["reason"]


@pytest.mark.slow
def test_a_loss_of_control_ends_both_ways_at_the_same_state_with_the_same_reason(tmp_path):
    """The report's law on rotors under noise turns the vehicle over: the simulator node and the in-process loop
    end the flight as diverged at the same state (the same compiled check), exit 3, the same recording."""
    sets = ["--set", "actuation=rotors", "--set", "controller.profile=report", "--set",
            "sensors.odometry={position_std: 0.0005, attitude_std_deg: 0.05, velocity_std: 0.001, "
            "angular_velocity_std: 0.003, seed: 1}"]
    out = {label: tmp_path / f"{label}.mcap" for label in ("graph", "local")}
    for label, extra in (("graph", []), ("local", ["--in-process"])):
        run = fly(["ex4_geometric", "--duration", "5", "--out", str(out[label]), "--no-analysis", *sets, *extra])
        assert run.returncode == 3, run.stdout + run.stderr
    graph, local = open_recording(out["graph"]), open_recording(out["local"])
    ended = [final_status(graph), final_status(local)]
    assert ended[0]["state"] == ended[1]["state"] == "diverged"
    assert ended[0]["reason"] == ended[1]["reason"] and "lost control" in ended[0]["reason"]
    assert ended[0]["sim_time"] == ended[1]["sim_time"] < 5.0
    for topic in ("/odom", "/odom_truth", "/rotor_cmd", "/reference"):
        assert graph.count(topic) == local.count(topic), topic
        assert list(graph.raw(topic)) == list(local.raw(topic)), topic


def test_two_runs_at_once_do_not_see_each_other(tmp_path):
    runs = {name: (tmp_path / f"{name}.mcap") for name in ("ex4_geometric", "step_disturbance")}
    processes = [start_fly([name, "--quiet", "--duration", "1", "--out", str(out), "--no-analysis"])
                 for name, out in runs.items()]
    for process in processes:
        stdout, stderr = process.communicate(timeout=180)
        assert process.returncode == 0, stdout + stderr
    for name, out in runs.items():
        positions = odom_positions(out)
        assert positions.shape == (1001, 3)
        start = -1.0 if name == "ex4_geometric" else -2.0
        assert positions[0, 2] == pytest.approx(start)


def test_three_vehicles_fly_under_their_namespaces(tmp_path):
    out = tmp_path / "fleet.mcap"
    run = fly(["three_vehicles", "--duration", "6", "--out", str(out), "--no-analysis"], timeout=400)
    assert run.returncode == 0, run.stdout + run.stderr
    recording = open_recording(out)
    assert not recording.has("/odom")
    goals = {"/uav1": [2.0, 0.0, -2.0], "/uav2": [1.0, 4.0, -3.0], "/uav3": [1.0, 7.0, -2.0]}
    for namespace, goal in goals.items():
        assert recording.count(f"{namespace}/odom") == 6001
        assert recording.count(f"{namespace}/rotor_cmd") >= 6000
        assert final_status(recording, namespace)["state"] == "finished"
        final = odom_positions(out, f"{namespace}/odom")[-1]
        assert np.linalg.norm(final - goal) < 0.01, (namespace, final)
    # each vehicle is analysed with its own scenario from the fleet in the metadata
    scenarios = {"/uav1": "octo_ground_effect", "/uav2": "ex4_geometric", "/uav3": "ex5_voliro"}
    for namespace, name in scenarios.items():
        metrics = analyze_recording(recording, tmp_path / namespace.strip("/"), namespace=namespace,
                                    figures=False).metrics
        notes = "\n".join(metrics["notes"])
        assert metrics["scenario"] == name and "cannot be used" not in notes and "skipped" not in notes, notes
        assert metrics["saturation"] is not None and metrics["mass"]["true_kg"] is not None, metrics
    # each vehicle's frames and markers are its own: uav1/base_link_frd under world_ned, /uav1/markers
    from mcap_ros2.reader import read_ros2_messages

    static = {(t.header.frame_id, t.child_frame_id) for m in read_ros2_messages(out, topics=["/tf_static"])
              for t in m.ros_msg.transforms}
    moving = {(t.header.frame_id, t.child_frame_id) for m in read_ros2_messages(out, topics=["/tf"])
              for t in m.ros_msg.transforms}
    for namespace in goals:
        prefix = namespace.strip("/") + "/"
        assert (f"{prefix}base_link_frd", f"{prefix}base_link") in static
        assert ("world_ned", f"{prefix}base_link_frd") in moving
        assert recording.count(f"{namespace}/markers") == 301  # 6 s at 50 Hz, and t = 0
    assert ("uav2/base_link_frd", "uav2/rotor_1_link") in static  # fixed rotors: static
    assert ("uav3/base_link_frd", "uav3/rotor_1_link") in moving  # the tilting quadrotor's: with its tilts
    missing = analyze_recording(recording, tmp_path / "uav9", namespace="/uav9", figures=False).metrics["notes"]
    assert any("the fleet in the metadata has no vehicle under /uav9 (it has /uav1, /uav2, /uav3)" in n
               for n in missing), missing
