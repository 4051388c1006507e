"""Measured inputs over DDS: INDI (the controller subscribes ``imu`` and ``rotor_state``), the geometric law on the
IMU (``controller.use_imu``) and the estimator on the rotors' measured speeds (``estimator.input: measured``: it
subscribes ``rotor_state`` instead of ``wrench_cmd``) fly the node graph as the in-process loop flies them, to
1e-9."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fsr_sim.recording.reader import open_recording

pytestmark = pytest.mark.graph  # slow too (conftest.py)

BIN = Path(sys.executable).parent
STEP = ("disturbances=[{kind: step, frame: world, start: 0.2, end: 1.0, force: [1.0, 0.5, 0.0], "
        "torque: [0.01, -0.01, 0.005]}]")


def fly(args: list[str], timeout: float = 180.0) -> subprocess.CompletedProcess:
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONUNBUFFERED": "1"}
    return subprocess.run([str(BIN / "fsr-fly"), "--quiet", *args], env=env, capture_output=True, text=True,
                          timeout=timeout)


def stamped_rows(path: Path, topic: str) -> np.ndarray:
    """(n, 6) of every message of ``topic`` in stamp order: odom's position and angular velocity, a wrench's
    force and torque."""
    rows = []
    for _, message in open_recording(path).messages(topic):
        stamp = message.header.stamp.sec * 1e9 + message.header.stamp.nanosec
        if topic == "odom":
            p, w = message.pose.pose.position, message.twist.twist.angular
            rows.append((stamp, p.x, p.y, p.z, w.x, w.y, w.z))
        else:
            f, t = message.wrench.force, message.wrench.torque
            rows.append((stamp, f.x, f.y, f.z, t.x, t.y, t.z))
    rows.sort()
    return np.array(rows)[:, 1:]


@pytest.mark.parametrize("sets", [
    ["controller.type=indi", "sensors.preset=ideal", "vehicle=hummingbird", STEP],  # rotor_state and imu
    ["controller.type=indi", "sensors.preset=ideal", STEP],  # imu only (quadrotor_ex4: no motor lag)
    ["estimator.input=measured", "controller.compensation=estimate", "plant.rotor_time_constant=0.05",
     "estimator.c0=100", STEP],  # the estimator node and the compensating observer on rotor_state
    ["sensors.preset=onboard", "vehicle=hummingbird", STEP],  # the flight profile's geometric law on the IMU,
    # bridging the late, noisy odometry (controller.use_imu)
])
def test_measured_inputs_in_the_graph_agree_with_the_in_process_loop(tmp_path, sets):
    graph, local = tmp_path / "graph.mcap", tmp_path / "local.mcap"
    options = [option for value in sets for option in ("--set", value)]
    for out, extra in ((graph, []), (local, ["--in-process"])):
        run = fly(["step_disturbance", "--duration", "1.0", "--out", str(out), "--no-analysis", *options, *extra])
        assert run.returncode == 0, run.stdout + run.stderr
    for topic in ("odom", "wrench_cmd", "wrench_estimate"):
        a, b = stamped_rows(graph, topic), stamped_rows(local, topic)
        if topic == "wrench_estimate" and "estimator.input=measured" not in sets:
            continue
        assert a.shape == b.shape == (1001, 6), (topic, a.shape, b.shape)
        assert np.max(np.abs(a - b)) < 1e-9, topic
    log = (tmp_path / "graph" / "logs" / "controller.log").read_text(errors="replace")
    assert "1001 odom answered" in log
