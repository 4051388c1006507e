"""Foxglove's own decoders (@mcap/core, @foxglove/rosmsg2-serialization, pinned in package-lock.json, installed
into a temporary folder with npm: conftest.py) read /tf, /tf_static and markers of a graph and an in-process
recording: what the Foxglove app shows is what fsr wrote. Needs node and npm (and the package registry)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fsr_bringup.analysis.load import load_flight
from fsr_bringup.visualization.frames import WORLD_IN_MAP
from fsr_sim.contract import BODY_FRAME, MAP_FRAME, MARKERS, TF, TF_STATIC, WORLD_FRAME

BIN = Path(sys.executable).parent
pytestmark = pytest.mark.graph  # starts fsr-fly's node graph (its own ROS domain); graph tests are slow


def read_with_foxglove(decoders: Path, recording: Path) -> dict:
    topics = [TF.name, TF_STATIC.name, "/" + MARKERS.name]
    run = subprocess.run(["node", str(decoders / "read_mcap.cjs"), str(recording), *topics], capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


def fly(tmp_path: Path, *extra: str) -> Path:
    out = tmp_path / ("local.mcap" if extra else "graph.mcap")
    run = subprocess.run([str(BIN / "fsr-fly"), "ex5_voliro", "--duration", "0.3", "--out", str(out), "--no-analysis",
                          "--quiet", *extra], env={**os.environ, "MPLBACKEND": "Agg"}, capture_output=True, text=True,
                         timeout=180)
    assert run.returncode == 0, run.stdout + run.stderr
    return out


@pytest.mark.parametrize("mode", ["graph", "in-process"])
def test_foxglove_reads_the_frames_and_markers(tmp_path, decoders, mode):
    recording = fly(tmp_path, *(["--in-process"] if mode == "in-process" else []))
    shown = read_with_foxglove(decoders, recording)
    (static,) = shown[TF_STATIC.name]
    transforms = {(t["header"]["frame_id"], t["child_frame_id"]): t["transform"]
                  for t in static["message"]["transforms"]}
    rotation = transforms[(MAP_FRAME, WORLD_FRAME)]["rotation"]
    assert [rotation[a] for a in "xyzw"] == WORLD_IN_MAP.tolist()
    flight = load_flight(recording)
    poses = {int(stamp): np.concatenate((p, q)) for stamp, p, q in
             zip(flight.odom.stamp_ns, flight.odom.position, flight.odom.quaternion, strict=True)}
    bodies = [(int(entry["logTime"]), t) for entry in shown[TF.name] for t in entry["message"]["transforms"]
              if t["child_frame_id"] == BODY_FRAME]
    assert len(bodies) == len(poses) == 301
    for stamp, t in bodies:
        header = t["header"]["stamp"]
        assert header["sec"] * 1_000_000_000 + header["nanosec"] == stamp
        got = [t["transform"]["translation"][a] for a in "xyz"] + [t["transform"]["rotation"][a] for a in "xyzw"]
        assert np.max(np.abs(np.subtract(got, poses[stamp]))) <= 1e-12
    markers = shown["/" + MARKERS.name]
    assert len(markers) == 16  # 0.3 s at 50 Hz and t = 0
    for entry in markers:
        stamp = int(entry["logTime"])
        arms = next(m for m in entry["message"]["markers"] if m["ns"] == "arms")
        assert arms["header"]["frame_id"] == WORLD_FRAME
        assert [arms["points"][0][a] for a in "xyz"] == pytest.approx(poses[stamp][:3], abs=1e-12)
