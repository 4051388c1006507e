"""fsr-fly's view of a flight from its watcher process (fsr_bringup.runner.watcher): events parsed line by line,
a watcher stuck in its teardown cannot hold the run (it is stopped like a node, its exit code ignored), and a
node ended by its teardown watchdog after its work was done is a warning, not a failure."""

from __future__ import annotations

import importlib.util
import json
import sys
import textwrap
import time
from pathlib import Path

import pytest

from fsr_bringup.runner import flight as flight_module
from fsr_bringup.runner import watcher as watcher_module
from fsr_bringup.runner.domains import fixed_domain
from fsr_bringup.runner.flight import Console, VehicleLaunch, fly_graph
from fsr_bringup.runner.watcher import FlightWatcher, watcher_command
from fsr_sim.contract import DIVERGED, FINISHED, RUNNING, SimStatus


def event(**fields: object) -> str:
    return json.dumps(fields)


def test_progress_gives_simulated_time_and_stepping_rate():
    watcher = FlightWatcher([""])
    assert watcher.stepping_rate != watcher.stepping_rate  # NaN before two progress messages
    assert watcher.feed(event(progress=0.1, at=100.0))
    assert watcher.feed(event(progress=0.5, at=100.2))
    assert watcher.sim_time == 0.5
    assert abs(watcher.stepping_rate - 2.0) < 1e-12


def test_final_statuses_need_every_vehicle():
    watcher = FlightWatcher(["/uav1", "/uav2"])
    assert not watcher.started() and watcher.final_statuses() is None
    finished = SimStatus(FINISHED, "duration", 2.0, 2000)
    watcher.feed(event(status="/uav1", value=finished.as_dict()))
    watcher.feed(event(status="/uav2", value=SimStatus(RUNNING, "", 0.5, 500).as_dict()))
    assert watcher.started() and watcher.final_statuses() is None
    diverged = SimStatus(DIVERGED, "crash", 1.0, 1000)
    watcher.feed(event(status="/uav2", value=diverged.as_dict()))
    assert watcher.final_statuses() == {"/uav1": finished, "/uav2": diverged}


def test_missing_nodes_unknown_until_the_first_list():
    watcher = FlightWatcher([""])
    expected = {"/controller": "controller", "/fsr_recorder": "recorder"}
    assert watcher.missing(expected) is None
    watcher.feed(event(nodes=["/fsr_fly_watcher", "/fsr_recorder"]))
    assert watcher.missing(expected) == ["controller"]


def test_log_lines_and_malformed_events_are_not_taken():
    watcher = FlightWatcher([""])
    for line in ["[INFO] ready 0.4 s after the process started", "{not json", "[1, 2]", event(other=1),
                 event(progress="x", at=1.0), event(progress=1.0)]:
        assert not watcher.feed(line), line
    assert watcher.sim_time == 0.0 and watcher.first is None


def test_wait_returns_when_an_event_arrives():
    watcher = FlightWatcher([""])
    watcher.feed(event(progress=0.1, at=1.0))
    start = time.monotonic()
    watcher.wait(5.0)  # the event is already there
    assert time.monotonic() - start < 1.0


def test_watcher_command_runs_the_watcher_module_for_every_namespace():
    """The command fsr-fly starts is this interpreter running the watcher module, which reads back the
    namespaces it was given."""
    from fsr_bringup.runner import watcher_node

    command = watcher_command(["", "/uav2"])
    assert command[0] == sys.executable and command[1] == "-m"
    assert importlib.util.find_spec(command[2]).origin == watcher_node.__file__
    assert watcher_node.parse_args(command[3:]).namespace == ["", "/uav2"]


HUNG_WATCHER = textwrap.dedent('''
    import json, signal, time
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # as stuck as a deadlocked DDS teardown
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    print(json.dumps({"progress": 0.9, "at": time.monotonic()}), flush=True)
    status = {"state": "finished", "reason": "", "sim_time": 1.0, "steps": 1000}
    print(json.dumps({"status": "", "value": status}), flush=True)
    time.sleep(600)
''')


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_a_watcher_stuck_at_exit_does_not_hold_the_run(tmp_path, monkeypatch):
    """Every node runs elsewhere (``--nodes`` selected none here): the flight ends with the watcher's final
    status; the watcher ignores SIGINT and SIGTERM and is killed; the run's result stands."""
    monkeypatch.setattr(watcher_module, "watcher_command", lambda namespaces: [sys.executable, "-c", HUNG_WATCHER])
    members = [VehicleLaunch("", tmp_path / "scenario.yaml", True)]
    start = time.monotonic()
    result = fly_graph(members, tmp_path / "flight.mcap", tmp_path / "scenario.yaml", tmp_path / "logs",
                       fixed_domain(0), 1.0, Console(quiet=True), nodes=set())
    elapsed = time.monotonic() - start
    assert result.exit_code == 0 and result.failures == [] and not result.interrupted
    assert result.sim_time == 1.0
    assert elapsed < 30.0  # SIGINT, SIGTERM, SIGKILL waves: about 9 s
    assert Path(tmp_path / "logs" / "flight_watcher.log").exists()


FINAL_STATUS_WATCHER = textwrap.dedent('''
    import json, sys, time
    status = {"state": sys.argv[1], "reason": "", "sim_time": 1.0, "steps": 1000}
    print(json.dumps({"status": "", "value": status}), flush=True)
    time.sleep(600)
''')

SIMULATOR_TEARDOWN_HUNG = "import os, signal, time; time.sleep(0.5); os.kill(os.getpid(), signal.SIGALRM)"


@pytest.mark.parametrize("state, code", [("finished", 0), ("diverged", 3)])
def test_a_simulator_ended_by_its_teardown_watchdog_keeps_the_flight_result(tmp_path, monkeypatch, state, code):
    """Killed by TEARDOWN_HUNG_SIGNAL after its final status: a warning, and the result from that status."""
    monkeypatch.setattr(watcher_module, "watcher_command",
                        lambda namespaces: [sys.executable, "-c", FINAL_STATUS_WATCHER, state])
    monkeypatch.setattr(flight_module, "node_commands",
                        lambda *args: [("simulator", [sys.executable, "-c", SIMULATOR_TEARDOWN_HUNG])])
    members = [VehicleLaunch("", tmp_path / "scenario.yaml", True)]
    result = fly_graph(members, tmp_path / "flight.mcap", tmp_path / "scenario.yaml", tmp_path / "logs",
                       fixed_domain(0), 1.0, Console(quiet=True), nodes={"simulator"})
    assert result.exit_code == code
    assert len(result.notes) == 1 and result.notes[0].startswith("simulator: its rcl/DDS teardown hung")
    assert result.failures == ([] if state == "finished" else [result.failures[0]])
    if state == "diverged":
        assert "the flight diverged" in result.failures[0]


def test_a_controller_ended_by_its_teardown_watchdog_is_a_warning(tmp_path, monkeypatch):
    """It had ended by itself with the flight (exit_on_finish), then its teardown hung: not 'died'."""
    monkeypatch.setattr(watcher_module, "watcher_command",
                        lambda namespaces: [sys.executable, "-c", FINAL_STATUS_WATCHER, "finished"])
    simulator = "import time; time.sleep(2.0)"  # exits 0 once the controller is gone
    controller = SIMULATOR_TEARDOWN_HUNG  # the same hang, in the controller
    monkeypatch.setattr(flight_module, "node_commands", lambda *args: [
        ("controller", [sys.executable, "-c", controller]), ("simulator", [sys.executable, "-c", simulator])])
    members = [VehicleLaunch("", tmp_path / "scenario.yaml", True)]
    result = fly_graph(members, tmp_path / "flight.mcap", tmp_path / "scenario.yaml", tmp_path / "logs",
                       fixed_domain(0), 1.0, Console(quiet=True))
    assert result.exit_code == 0 and result.failures == []
    assert len(result.notes) == 1 and result.notes[0].startswith("controller: its rcl/DDS teardown hung")


RECORDER_TEARDOWN_HUNG = textwrap.dedent('''
    import os, signal, time
    signal.signal(signal.SIGINT, lambda *_: os.kill(os.getpid(), signal.SIGALRM))  # stopped: file closed, then hung
    time.sleep(600)
''')


def test_a_recorder_ended_by_its_teardown_watchdog_after_the_flight_is_a_warning(tmp_path, monkeypatch):
    monkeypatch.setattr(watcher_module, "watcher_command",
                        lambda namespaces: [sys.executable, "-c", FINAL_STATUS_WATCHER, "finished"])
    monkeypatch.setattr(flight_module, "node_commands", lambda *args: [
        ("recorder", [sys.executable, "-c", RECORDER_TEARDOWN_HUNG]),
        ("simulator", [sys.executable, "-c", "import time; time.sleep(1.0)"])])
    members = [VehicleLaunch("", tmp_path / "scenario.yaml", True)]
    result = fly_graph(members, tmp_path / "flight.mcap", tmp_path / "scenario.yaml", tmp_path / "logs",
                       fixed_domain(0), 1.0, Console(quiet=True))
    assert result.exit_code == 0 and result.failures == []
    assert len(result.notes) == 1 and result.notes[0].startswith("recorder: its rcl/DDS teardown hung")
