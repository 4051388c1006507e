"""A circle flown by the node graph and in one process: the same reference and the same flight (the controller
node samples the compiled planner as the in-process loop does)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from fsr_sim.recording.reader import open_recording

pytestmark = pytest.mark.graph

CIRCLE = {"name": "circle_graph", "vehicle": "octocopter", "duration": 1.0, "actuation": "rotors",
          "initial_state": {"position": [1.0, 0.0, -2.0]},
          "trajectory": {"kind": "circle", "centre": [0, 0, -2], "radius": 1.0, "speed": 2.0, "laps": 1,
                         "ramp": 0.4, "yaw": {"mode": "rate", "rate_deg_s": 30}},
          "controller": {"type": "geometric"}, "estimator": {"enabled": True}}


def test_a_circle_flies_the_same_in_the_graph_and_in_process(tmp_path: Path):
    scenario = tmp_path / "circle.yaml"
    scenario.write_text(yaml.safe_dump(CIRCLE))
    recordings = {}
    for mode, extra in (("graph", []), ("local", ["--in-process"])):
        out = recordings[mode] = tmp_path / f"{mode}.mcap"
        run = subprocess.run([str(Path(sys.executable).parent / "fsr-fly"), str(scenario), "--quiet", "--out",
                              str(out), "--no-analysis", *extra], capture_output=True, text=True, timeout=180,
                             env={**os.environ, "MPLBACKEND": "Agg"})
        assert run.returncode == 0, run.stdout + run.stderr
    graph, local = open_recording(recordings["graph"]), open_recording(recordings["local"])
    for topic in ("/reference", "/odom", "/rotor_cmd", "/wrench_estimate"):
        assert [data for _, data in graph.raw(topic)] == [data for _, data in local.raw(topic)], topic
    points = [m.points[0] for _, m in local.messages("/reference")]
    radii = [np.hypot(point.transforms[0].translation.x, point.transforms[0].translation.y) for point in points]
    speeds = [np.hypot(point.velocities[0].linear.x, point.velocities[0].linear.y) for point in points]
    assert len(points) == 1001 and np.allclose(radii, 1.0, rtol=0, atol=1e-12)  # on the circle from the start
    assert max(speeds) > 0.3  # ... and moving along it
