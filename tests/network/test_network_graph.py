"""One flight over several hosts: ``fsr-fly --network --nodes ...`` in network namespaces joined by a bridge.

Each test builds its own private network (:class:`harness.netns.NetLab`: a bridge namespace and
one namespace per host, addresses only on those links, multicast routed only there) and deletes it at the
end, also when the test fails. The simulator and the recorder run on host ``sim``, the controller on ``ctl``,
the estimator on ``est``; DDS discovers across the bridge (SUBNET range, UDP only). Link faults unplug the
controller's port on the bridge, triggered by the number of steps in the recording. Skipped, with the reason,
where namespaces cannot be made (not root, no ``ip``).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain
from fsr_sim.recording.reader import RecordingError, open_recording
from harness.graph import wait_for_recorded, wait_for_text
from harness.netns import NetLab, network_environment, unavailable_reason

pytestmark = pytest.mark.graph

BIN = Path(sys.executable).parent
FLY = str(BIN / "fsr-fly")
FLIGHT_TIMEOUT = 150.0  # s: bound on one fsr-fly side (a 1 kHz flight of up to 5 s at >= 0.1x real time + start/stop)


@pytest.fixture
def domain_id() -> Iterator[int]:
    """A leased domain id (the namespaces isolate the network; the lease keeps ids distinct anyway)."""
    with acquire_domain(TEST_RANGE) as lease:
        yield lease.domain_id


@pytest.fixture
def lab_factory() -> Iterator:
    """``lab_factory(hosts)`` builds a NetLab; every lab and every process started on it is gone afterwards."""
    reason = unavailable_reason()
    if reason is not None:
        print(f"skipping: {reason}")
        pytest.skip(reason)
    labs: list[NetLab] = []
    processes: list[subprocess.Popen] = []

    def make(hosts: list[str], multicast: bool = True) -> NetLab:
        lab = NetLab(hosts, multicast)
        labs.append(lab)
        original = lab.popen

        def popen(name: str, argv: list[str], **kwargs: object) -> subprocess.Popen:
            process = original(name, argv, **kwargs)
            processes.append(process)
            return process

        lab.popen = popen
        return lab

    try:
        yield make
    finally:
        for process in processes:  # only what this test started
            if process.poll() is None:
                process.kill()
                process.wait(timeout=10)
        for lab in labs:
            lab.close()


def start_side(lab: NetLab, host: str, domain: int, tmp_path: Path, nodes: str, extra: list[str],
               env: dict[str, str] | None = None) -> subprocess.Popen:
    """``fsr-fly ... --network --nodes NODES`` on ``host``; output in ``tmp_path/<host>.out`` / ``.err``."""
    out = tmp_path / host
    argv = [FLY, *extra, "--network", "--domain-id", str(domain), "--nodes", nodes, "--quiet", "--no-analysis",
            "--out", str(out / f"{host}.mcap")]
    return lab.popen(host, argv, env=env or network_environment(domain), stdout=open(tmp_path / f"{host}.out", "w"),
                     stderr=open(tmp_path / f"{host}.err", "w"), cwd=tmp_path)


def finish(process: subprocess.Popen, name: str, tmp_path: Path) -> int:
    code = process.wait(timeout=FLIGHT_TIMEOUT)
    output = (tmp_path / f"{name}.out").read_text() + (tmp_path / f"{name}.err").read_text()
    print(f"--- {name}: exit {code}\n{output}")
    return code


def in_process_positions(tmp_path: Path, flight: list[str]) -> np.ndarray:
    out = tmp_path / "reference.mcap"
    run = subprocess.run([FLY, *flight, "--in-process", "--no-analysis", "--quiet", "--out", str(out)],
                         capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    return odom_positions(out)


def odom_positions(path: Path, topic: str = "odom") -> np.ndarray:
    return np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z]
                     for _, m in open_recording(path).messages(topic)])


def statuses(path: Path, namespace: str = "") -> list[dict]:
    return [json.loads(m.data) for _, m in open_recording(path).messages(f"{namespace}/sim_status")]


def fly_three_hosts(lab: NetLab, domain: int, tmp_path: Path, flight: list[str]) -> dict[str, subprocess.Popen]:
    """The simulator side first; it must name the nodes it has not discovered; then the other two hosts."""
    sides = {"sim": start_side(lab, "sim", domain, tmp_path, "simulator,recorder", flight)}
    wait_for_text(tmp_path / "sim.err", "not discovered yet", timeout=60)
    sides["ctl"] = start_side(lab, "ctl", domain, tmp_path, "controller", flight)
    sides["est"] = start_side(lab, "est", domain, tmp_path, "estimator", flight)
    return sides


def test_flight_over_three_hosts_equals_in_process_and_is_recorded_on_one(lab_factory, domain_id, tmp_path):
    lab = lab_factory(["sim", "ctl", "est"])
    flight = ["ex4_geometric", "--duration", "1.0"]
    sides = fly_three_hosts(lab, domain_id, tmp_path, flight)
    codes = {name: finish(process, name, tmp_path) for name, process in sides.items()}
    assert codes == {"sim": 0, "ctl": 0, "est": 0}
    missing = (tmp_path / "sim.err").read_text()
    assert "other hosts not discovered yet" in missing and "controller" in missing and "estimator" in missing
    assert "recorder" not in missing and "simulator" not in missing  # only nodes of other hosts are named
    assert "the recording is on the recorder's host" in (tmp_path / "ctl.out").read_text()
    recording = tmp_path / "sim" / "sim.mcap"
    counts = open_recording(recording)
    assert not counts.truncated
    assert counts.count("odom") == counts.count("wrench_truth") == 1001
    for topic in ("wrench_cmd", "reference", "attitude_cmd", "wrench_desired", "wrench_estimate", "mass_estimate"):
        assert counts.count(topic) >= 1000, topic  # from the other hosts, one per answered step
    final = statuses(recording)[-1]
    assert final["state"] == "finished" and final["failsafe_steps"] == 0 and final["incidents"] == 0
    graph = odom_positions(recording)
    reference = in_process_positions(tmp_path, flight)
    assert graph.shape == reference.shape == (1001, 3)
    assert np.max(np.abs(graph - reference)) < 1e-9


def unplug_controller(lab: NetLab, recording: Path, after_steps: int, down_for: float) -> int:
    """Once the recording holds ``after_steps`` states, unplug the controller's cable for ``down_for`` s."""
    recorded = wait_for_recorded(recording, "odom", after_steps)
    lab.set_link("ctl", up=False)
    try:
        time.sleep(down_for)  # the length of the fault itself, not a wait for another process
    finally:
        lab.set_link("ctl", up=True)
    return recorded


def unplug_controller_until_failsafe(lab: NetLab, recording: Path, after_steps: int, timeout: float = 90.0) -> int:
    """Once the recording holds ``after_steps`` states, unplug the controller's cable and plug it back in once the
    simulator has recorded that it flies on the failsafe (an event, whatever the machine's load); returns the
    states recorded before."""
    recorded = wait_for_recorded(recording, "odom", after_steps)
    lab.set_link("ctl", up=False)
    try:
        deadline = time.monotonic() + timeout
        while not any(status["reason"].startswith("failsafe") for status in recorded_statuses(recording)):
            assert time.monotonic() < deadline, f"no failsafe recorded {timeout} s after the link went down"
            time.sleep(0.1)  # polling a file another process writes
    finally:
        lab.set_link("ctl", up=True)
    return recorded


def recorded_statuses(path: Path) -> list[dict]:
    """The sim_status messages of a recording being written (its complete chunks; none before the first)."""
    try:
        return statuses(path)
    except RecordingError:
        return []


def test_brief_link_loss_pauses_the_lockstep_and_loses_nothing(lab_factory, domain_id, tmp_path):
    lab = lab_factory(["sim", "ctl", "est"])
    # After the cable is back, ARP (1 s retransmission) and DDS repair (100 ms heartbeats) can add about a second:
    # a timeout of 3 s keeps a 0.3 s outage a pause (docs/network.md).
    flight = ["ex4_geometric", "--duration", "5.0", "--set", "lockstep.timeout=3.0"]
    sides = fly_three_hosts(lab, domain_id, tmp_path, flight)
    recording = tmp_path / "sim" / "sim.mcap"
    recorded = unplug_controller(lab, recording, after_steps=300, down_for=0.3)
    assert sides["sim"].poll() is None, "the fault must happen mid-flight"
    codes = {name: finish(process, name, tmp_path) for name, process in sides.items()}
    assert codes == {"sim": 0, "ctl": 0, "est": 0}
    assert recorded < 5001
    final = statuses(recording)[-1]
    # The simulator waited for the controller's answer (its command, or the reference and attitude_cmd sent right
    # after it, whichever the outage cut off) at least as long as the outage (simulated time stood still), and
    # took no step on the failsafe, so the flight is the in-process one.
    assert final["state"] == "finished" and final["failsafe_steps"] == 0 and final["incidents"] == 0
    assert 0.25 <= final["longest_wait_s"] < 3.0, f"unplugged at the {recorded}th recorded state: {final}"
    print(f"longest lockstep pause: {final['longest_wait_s']:.3f} s for a 0.3 s outage")
    assert open_recording(recording).count("wrench_cmd") == 5001  # every state answered, the last one too
    graph = odom_positions(recording)
    assert np.max(np.abs(graph - in_process_positions(tmp_path, flight))) < 1e-9


def test_link_loss_beyond_the_timeout_engages_the_failsafe_then_the_controller_returns(
    lab_factory, domain_id, tmp_path
):
    lab = lab_factory(["sim", "ctl", "est"])
    # Event-driven: the cable is plugged back in once the failsafe is recorded, and then the simulator waits for
    # the controller while its late answers come in (it works through the states it missed, at whatever pace the
    # machine's load gives it) until it answers one in time (docs/network.md). What stays bound to time is only
    # that this happens before the flight's end: the steps on the failsafe are taken at the degraded wait (4x the
    # typical answer time, at least 2 ms) while the cable is out: 19-105 in the lab, of the 3000 or more left.
    flight = ["ex4_geometric", "--duration", "4.0", "--set", "lockstep.timeout=0.5"]
    sides = fly_three_hosts(lab, domain_id, tmp_path, flight)
    recording = tmp_path / "sim" / "sim.mcap"
    unplug_controller_until_failsafe(lab, recording, after_steps=300)
    assert sides["sim"].poll() is None, "the fault must happen mid-flight"
    codes = {name: finish(process, name, tmp_path) for name, process in sides.items()}
    assert codes == {"sim": 0, "ctl": 0, "est": 0}
    history = statuses(recording)
    final = history[-1]
    assert final["state"] == "finished" and final["steps"] == 4000
    assert final["incidents"] >= 1 and 0 < final["failsafe_steps"] < 4000  # one outage (a loaded CI may add one)
    reasons = [status["reason"] for status in history]
    assert any(reason.startswith("failsafe 'hold'") for reason in reasons)
    assert "controller back in the loop" in reasons  # the controller was taken back into the loop
    data = open_recording(recording)
    assert data.count("odom") == data.count("wrench_truth") == 4001  # the flight and the recording went on
    # Every state reached the controller once the link was back; it answered each (late ones are ignored).
    assert data.count("wrench_cmd") == 4001 and data.count("wrench_estimate") >= 4000
    assert final["late_commands"] > 0
    print(f"{final['failsafe_steps']} steps on the failsafe in {final['incidents']} incident(s), "
          f"{final['late_commands']} late command(s)")
    from fsr_bringup.analysis.metrics import flight_metrics
    from fsr_bringup.analysis.summary import summary_rows

    rows = dict(summary_rows(flight_metrics(recording)))
    assert rows["lockstep failsafe"] == (f"**{final['failsafe_steps']} steps** on the failsafe in {final['incidents']} "
                                         f"incident(s), {final['late_commands']} late command(s) ignored")


def test_fleet_with_each_controller_on_its_own_host(lab_factory, domain_id, tmp_path):
    lab = lab_factory(["sim", "c1", "c2", "c3"])
    flight = ["three_vehicles", "--duration", "1.0"]
    sim = start_side(lab, "sim", domain_id, tmp_path, "simulator,estimator,recorder", flight)
    wait_for_text(tmp_path / "sim.err", "not discovered yet", timeout=60)
    controllers = {f"c{i}": start_side(lab, f"c{i}", domain_id, tmp_path, f"uav{i}/controller", flight)
                   for i in (1, 2, 3)}
    codes = {name: finish(process, name, tmp_path) for name, process in {"sim": sim, **controllers}.items()}
    assert codes == {"sim": 0, "c1": 0, "c2": 0, "c3": 0}
    recording = tmp_path / "sim" / "sim.mcap"
    data = open_recording(recording)
    positions = {}
    for i in (1, 2, 3):
        ns = f"/uav{i}"
        assert data.count(f"{ns}/odom") == 1001 and data.count(f"{ns}/rotor_cmd") >= 1000
        final = statuses(recording, ns)[-1]
        assert final["state"] == "finished" and final["failsafe_steps"] == 0
        positions[i] = odom_positions(recording, f"{ns}/odom")
    for a, b in ((1, 2), (2, 3), (1, 3)):  # the vehicles do not cross: they stay metres apart
        assert np.min(np.linalg.norm(positions[a] - positions[b], axis=1)) > 1.0


def test_static_peers_join_hosts_on_a_network_without_multicast(lab_factory, domain_id, tmp_path):
    lab = lab_factory(["sim", "ctl"], multicast=False)
    routes = subprocess.run(lab.command("ctl", ["ip", "route"]), capture_output=True, text=True, check=True).stdout
    assert "224.0.0.0/4" not in routes  # SUBNET discovery alone cannot find the other host
    flight = ["ex4_geometric", "--duration", "0.5"]
    sides = {}
    for host, other, nodes in (("sim", "ctl", "simulator,estimator,recorder"), ("ctl", "sim", "controller")):
        env = {**network_environment(domain_id), "ROS_STATIC_PEERS": lab.address(other)}
        sides[host] = start_side(lab, host, domain_id, tmp_path, nodes, flight, env)
    codes = {name: finish(process, name, tmp_path) for name, process in sides.items()}
    assert codes == {"sim": 0, "ctl": 0}
    recording = open_recording(tmp_path / "sim" / "sim.mcap")
    assert recording.count("odom") == 501 and recording.count("wrench_cmd") == 501
