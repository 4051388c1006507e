"""The compensated loop (controller.compensation: estimate) in the node graph agrees with the in-process loop."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fsr_sim.recording.reader import open_recording

pytestmark = pytest.mark.graph

BIN = Path(sys.executable).parent


def fly(args: list[str], timeout: float = 180.0) -> subprocess.CompletedProcess:
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONUNBUFFERED": "1"}
    return subprocess.run([str(BIN / "fsr-fly"), "--quiet", *args], env=env, capture_output=True, text=True,
                          timeout=timeout)


def recorded(path: Path, topic: str, field: str) -> np.ndarray:
    """(n, 3) ``field`` (``odom`` position or ``wrench_cmd`` force) of every message, in stamp order."""
    recording = open_recording(path)
    rows = []
    for _, message in recording.messages(topic):
        if topic == "odom":
            p = message.pose.pose.position
            rows.append((message.header.stamp.sec * 1e9 + message.header.stamp.nanosec, p.x, p.y, p.z))
        else:
            f = getattr(message.wrench, field)
            rows.append((message.header.stamp.sec * 1e9 + message.header.stamp.nanosec, f.x, f.y, f.z))
    rows.sort()
    return np.array(rows)[:, 1:]


WIND = "disturbances=[{kind: constant, frame: world, force: [1, -0.5, 0.8], torque: [0.05, -0.05, 0.1]}]"


@pytest.mark.parametrize(("scenario", "sets"), [("ex3_estimation", []), ("ex5_voliro", ["--set", WIND])])
def test_compensated_graph_and_in_process_runs_agree(tmp_path, scenario, sets):
    graph, local = tmp_path / "graph.mcap", tmp_path / "local.mcap"
    for out, extra in ((graph, []), (local, ["--in-process"])):
        run = fly([scenario, "--duration", "0.5", "--out", str(out), "--no-analysis",
                   "--set", "controller.compensation=estimate", *sets, *extra])
        assert run.returncode == 0, run.stdout + run.stderr
    for topic, field in (("odom", ""), ("wrench_cmd", "force"), ("wrench_cmd", "torque")):
        a, b = recorded(graph, topic, field), recorded(local, topic, field)
        assert a.shape == b.shape == (501, 3)
        assert np.max(np.abs(a - b)) < 1e-9
    # The compensation acted (the commands differ from the uncompensated flight's) ...
    plain = tmp_path / "plain.mcap"
    run = fly([scenario, "--duration", "0.5", "--out", str(plain), "--no-analysis", "--in-process", *sets])
    assert run.returncode == 0, run.stdout + run.stderr
    assert np.max(np.abs(recorded(plain, "wrench_cmd", "torque") - recorded(local, "wrench_cmd", "torque"))) > 1e-6
    # ... and the controller node reports it, with no late estimate (its observer runs in its process).
    log = (tmp_path / "graph" / "logs" / "controller.log").read_text(errors="replace")
    assert "compensation: estimate (own observer)" in log and "0 late estimates" in log
