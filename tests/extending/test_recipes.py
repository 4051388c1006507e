"""docs/extending.md's recipes, each done once as written there: the code blocks are taken from the document
(a fence ``yaml NAME`` or ``python NAME`` is the file NAME), so the document and these examples cannot drift.
Nothing here touches the package: a vehicle is two YAML files, a figure is registered from outside, and the
control law is added to a copy of ``fsr_control`` in a temporary folder."""

from __future__ import annotations

import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario
from fsr_sim.model.so3 import rotation_from_euler_zyx, rotation_from_quaternion
from fsr_sim.model.vehicle import load_vehicle
from fsr_sim.recording.reader import open_recording

DOC = Path(__file__).resolve().parents[2] / "docs" / "extending.md"
BIN = Path(sys.executable).parent


def recipe_files(folder: Path) -> dict[str, Path]:
    """Write every named code block of docs/extending.md into ``folder``; {name: path}."""
    blocks = re.findall(r"^```(?:yaml|python) (\S+)\n(.*?)^```$", DOC.read_text(), flags=re.M | re.S)
    assert blocks, f"no named code blocks in {DOC}"
    written = {}
    for name, text in blocks:
        written[name] = folder / name
        written[name].write_text(text)
    return written


def test_a_hexacopter_with_canted_arms_is_fully_actuated_and_holds_a_tilted_pose(tmp_path):
    files = recipe_files(tmp_path)
    vehicle = load_vehicle(files["tilted_hexacopter.yaml"])
    assert vehicle.fully_actuated and not vehicle.has_servos and vehicle.rotor_count == 6
    run = fly_in_process(load_scenario(files["hover_tilted.yaml"]))
    assert run.end_reason == "finished" and not run.failures, run.reason
    assert np.max(np.abs(run.state[-1, :3] - (0.5, 0.5, -2.0))) < 1e-6
    # holding 14.7 deg of tilt needs more than the margin leaves (11.3 of 16.1 deg): said, and flown as written
    (adjustment,) = run.plan_adjustments
    assert "no duration keeps the margin" in adjustment and adjustment.endswith("flown as written")
    goal = rotation_from_euler_zyx(np.deg2rad((10.0, -10.0, 20.0)))
    attitude = rotation_from_quaternion(run.state[-1, 6:10])
    assert np.linalg.norm(attitude - goal) < 1e-6  # roll and pitch held with fixed rotors: full actuation
    assert run.saturation["count"] == 0 and run.tilt_angles is None


def assert_graph_equals_in_process(scenario: Path, folder: Path, topics: tuple[str, ...]) -> None:
    """0.3 s of ``scenario`` flown as a node graph and in one process record the same bytes on ``topics``."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    graph, local = folder / "graph.mcap", folder / "local.mcap"
    for out, extra in ((graph, []), (local, ["--in-process"])):
        run = subprocess.run([str(BIN / "fsr-fly"), "--quiet", str(scenario), "--duration", "0.3", "--out", str(out),
                              "--no-analysis", *extra], env=env, capture_output=True, text=True, timeout=180)
        assert run.returncode == 0, run.stdout + run.stderr
    g, loc = open_recording(graph), open_recording(local)
    for topic in topics:
        assert g.count(topic) == 301 and [d for _, d in g.raw(topic)] == [d for _, d in loc.raw(topic)], topic


@pytest.mark.graph
def test_the_hexacopter_flies_the_same_in_the_node_graph(tmp_path):
    """The recipe's vehicle in the node graph gives the in-process flight's messages, byte for byte."""
    files = recipe_files(tmp_path)
    assert_graph_equals_in_process(files["hover_tilted.yaml"], tmp_path, ("/odom", "/rotor_cmd", "/wrench_cmd"))


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_a_figure_registered_in_figures_is_drawn_by_the_analysis(tmp_path, monkeypatch):
    from fsr_bringup.analysis import figures
    from fsr_bringup.analysis.run import analyze_recording

    files = recipe_files(tmp_path)
    spec = importlib.util.spec_from_file_location("altitude_figure", files["altitude_figure.py"])
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    monkeypatch.setitem(figures.FIGURES, "altitude", module.altitude_figure)
    scenario = load_scenario("ex4_geometric")
    fly_in_process(scenario, recording=tmp_path / "ex4.mcap", max_steps=500)
    analysis = analyze_recording(tmp_path / "ex4.mcap", tmp_path / "analysis")
    assert tmp_path / "analysis" / "altitude.png" in analysis.figures
    assert (tmp_path / "analysis" / "altitude.png").stat().st_size > 1000


def recorded_odometry(path: Path) -> np.ndarray:
    """(K, 13) ``odom`` rows (position, quaternion, body velocity, body angular velocity) of a recording."""
    rows = []
    for _, m in open_recording(path).messages("odom"):
        p, q, v, w = m.pose.pose.position, m.pose.pose.orientation, m.twist.twist.linear, m.twist.twist.angular
        rows.append((p.x, p.y, p.z, q.x, q.y, q.z, q.w, v.x, v.y, v.z, w.x, w.y, w.z))
    return np.array(rows)


def test_a_noisy_odometry_has_the_configured_spread_and_the_flight_still_tracks(tmp_path):
    files = recipe_files(tmp_path)
    run = fly_in_process(load_scenario(files["noisy_ex4.yaml"]), recording=tmp_path / "noisy.mcap")
    assert run.end_reason == "finished", run.reason
    odom = recorded_odometry(tmp_path / "noisy.mcap")
    true = run.state  # the true state (FlightRun never holds the measurement)
    assert odom.shape == (4001, 13)
    position_noise = odom[:, :3] - true[:, :3]
    np.testing.assert_allclose(position_noise.std(axis=0), 0.01, rtol=0.1)
    assert np.all(np.abs(position_noise.mean(axis=0)) < 0.001)
    np.testing.assert_allclose((odom[:, 10:13] - true[:, 10:13]).std(axis=0), 0.01, rtol=0.1)
    measured = np.array([rotation_from_quaternion(q) for q in odom[:, 3:7]])
    angles = np.linalg.norm(np.array([_rotation_vector(r.T @ m) for r, m in zip(run.rotation, measured,
                                                                                 strict=True)]), axis=1)
    assert abs(np.sqrt(np.mean(angles**2) / 3.0) - np.deg2rad(0.05)) < 0.1 * np.deg2rad(0.05)
    assert np.all(np.abs(np.linalg.norm(odom[:, 3:7], axis=1) - 1.0) < 1e-12) and np.all(odom[:, 6] >= 0.0)
    assert np.linalg.norm(true[-1, :3] - (0.5, 0.5, -2.0)) < 0.02  # 1 cm noise: still on target


def _rotation_vector(rotation: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(rotation).as_rotvec()


@pytest.mark.graph
def test_the_noise_is_the_same_in_the_node_graph(tmp_path):
    files = recipe_files(tmp_path)
    assert_graph_equals_in_process(files["noisy_ex4.yaml"], tmp_path, ("/odom", "/wrench_cmd", "/wrench_estimate"))


def package_with_the_law(folder: Path, files: dict[str, Path]) -> Path:
    """A copy of ``fsr_control`` with the control-law recipe applied as docs/extending.md says (a new file, an
    import, a field and a branch in ``core/laws.py``, an entry in ``controllers/catalog.py``); the folder
    holding it."""
    import fsr_control

    site = folder / "site"
    package = site / "fsr_control"
    shutil.copytree(Path(fsr_control.__file__).parent, package, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(files["preview_law.py"], package / "core" / "preview_law.py")
    laws = package / "core" / "laws.py"
    text = laws.read_text()
    first_import = "from fsr_control.core.reference import"  # the import goes in alphabetical order
    field, branch = "    # a new law: its parameters here", "    # a new law: its branch here"
    assert all(text.count(place) == 1 for place in (first_import, field, branch)), "the recipe's places moved"
    text = text.replace(first_import, files["preview_import.py"].read_text() + first_import)
    text = text.replace(field, files["preview_field.py"].read_text() + field)
    laws.write_text(text.replace(branch, files["preview_branch.py"].read_text() + branch))
    catalog = package / "controllers" / "catalog.py"
    catalog.write_text(catalog.read_text() + "\n" + files["preview_entry.py"].read_text())
    return site


FLY_WITH_THE_LAW = """
import json, sys
import numpy as np
import fsr_control.core.laws
from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario
from fsr_sim.model.so3 import rotation_from_euler_zyx, rotation_from_quaternion

assert fsr_control.core.laws.__file__.startswith(sys.argv[2]), fsr_control.core.laws.__file__
run = fly_in_process(load_scenario(sys.argv[1]))
goal = rotation_from_euler_zyx(np.deg2rad((20.0, 0.0, 0.0)))
print(json.dumps({"end": run.end_reason, "reason": run.reason, "steps": len(run.state),
                  "position_error": float(np.linalg.norm(run.state[-1, :3] - (0.5, 0.5, -2.0))),
                  "attitude_error": float(np.linalg.norm(rotation_from_quaternion(run.state[-1, 6:10]) - goal))}))
"""


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_a_control_law_reading_the_reference_ahead_flies_the_tilting_quadrotor(tmp_path):
    """The recipe's preview PD, added as written, flies (under CPython: NUMBA_DISABLE_JIT runs the same source
    without compiling the edited core)."""
    files = recipe_files(tmp_path)
    site = package_with_the_law(tmp_path, files)
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1", "PYTHONPATH": os.pathsep.join(
        [str(site), *filter(None, [os.environ.get("PYTHONPATH")])])}
    run = subprocess.run([sys.executable, "-c", FLY_WITH_THE_LAW, str(files["preview_ex5.yaml"]), str(site)],
                         env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    result = json.loads(run.stdout.strip().splitlines()[-1])
    assert result["end"] == "finished" and result["steps"] == 4001, result
    assert result["position_error"] < 1e-3 and result["attitude_error"] < 1e-3, result
