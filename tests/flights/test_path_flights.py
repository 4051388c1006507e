"""Paths at speed flown in the closed loop (in process): a circle on the octocopter, a minimum-snap path on
quadrotor_ex4, and a flight that ends before its plan comes to rest (told in the result, the summary and by
fsr-fly)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from fsr_bringup import simulate
from fsr_bringup.analysis.in_memory import recorded_flight_of_run
from fsr_bringup.analysis.metrics import flight_metrics, path_motion, plan_end
from fsr_bringup.analysis.summary import markdown_summary, summary_rows

CIRCLE = {"name": "circle_octocopter", "vehicle": "octocopter", "duration": 13.0, "actuation": "rotors",
          "initial_state": {"position": [2.0, 0.0, -2.0]},
          "trajectory": {"kind": "circle", "centre": [0, 0, -2], "radius": 2.0, "speed": 3.0, "laps": 2,
                         "yaw": "velocity"},
          "controller": {"type": "geometric"}, "estimator": {"enabled": False}}
MINSNAP = {"name": "minsnap_quadrotor", "vehicle": "quadrotor_ex4", "duration": 10.0, "actuation": "rotors",
           "initial_state": {"position": [0.0, 0.0, -1.0]},
           "trajectory": {"kind": "minsnap", "speed": 2.0, "waypoints": [
               {"position": [2.0, 0.0, -1.5]}, {"position": [2.0, 2.0, -2.0]}, {"position": [0.0, 2.0, -1.5]},
               {"position": [0.0, 0.0, -1.0]}]},
           "controller": {"type": "geometric"}, "estimator": {"enabled": False}}


def position_errors(run: object) -> np.ndarray:
    return np.linalg.norm(run.position - run.reference_position, axis=1)


def test_a_circle_at_3_m_s_on_the_octocopter_finishes_and_tracks():
    run = simulate(CIRCLE)
    assert run.end_reason == "finished" and not run.ended_mid_path and run.notes == []
    assert run.saturation["count"] == 0
    errors = position_errors(run)
    assert np.sqrt(np.mean(errors**2)) < 0.005 and errors.max() < 0.01  # measured 1.4 mm / 2.1 mm
    assert np.linalg.norm(run.velocity, axis=1).max() == pytest.approx(3.0, abs=0.02)
    np.testing.assert_allclose(run.position[-1], (2.0, 0.0, -2.0), atol=2e-3)  # two laps, back at the start
    flight = recorded_flight_of_run(run)
    path = path_motion(flight)
    assert path["planned"]["speed_m_s"]["peak"] == pytest.approx(3.0, abs=1e-9)
    assert path["planned"]["acceleration_m_s2"]["peak"] == pytest.approx(4.5, rel=0.05)  # v^2 / R, the ramps
    assert path["flown"]["speed_m_s"]["peak"] == pytest.approx(3.0, abs=0.02)
    assert path["planned"]["length_m"] == pytest.approx(2 * 2 * np.pi * 2.0, rel=1e-4)
    summary = dict(summary_rows({"path": path, "plan": plan_end(flight, run.sim_time)}))
    assert summary["speed [m/s] peak / RMS"].startswith("planned 3.000 / ")
    assert summary["plan (trajectory.kind)"] == f"circle, at rest from {run.plan_end_time:.3f} s"


def test_a_minimum_snap_path_on_quadrotor_ex4_finishes_and_tracks():
    run = simulate(MINSNAP)
    assert run.end_reason == "finished" and not run.ended_mid_path
    assert run.saturation["count"] == 0 and run.plan_adjustments == []
    errors = position_errors(run)
    assert np.sqrt(np.mean(errors**2)) < 0.003 and errors.max() < 0.005  # measured 0.30 mm / 0.67 mm
    assert np.linalg.norm(run.reference_velocity, axis=1).max() == pytest.approx(2.0, rel=1e-3)
    np.testing.assert_allclose(run.position[-1], (0.0, 0.0, -1.0), atol=2e-3)
    for point in ((2.0, 0.0, -1.5), (2.0, 2.0, -2.0), (0.0, 2.0, -1.5)):  # through every point
        assert np.linalg.norm(run.reference_position - point, axis=1).min() < 2e-3


def test_a_flight_that_ends_before_its_plan_is_told_it_ended_mid_path(tmp_path: Path):
    """A circle stretched beyond the flight (the octocopter's yaw authority: 5 m/s asks 0.87 N m) ends at the
    scenario's duration mid-path: the result, the summary and fsr-fly say so."""
    fast = {**CIRCLE, "duration": 10.0, "trajectory": {**CIRCLE["trajectory"], "speed": 5.0}}
    run = simulate(fast, record=tmp_path / "fast.mcap", record_topics="odom,reference")
    assert run.plan_adjustments and "stretched to" in run.plan_adjustments[-1]
    assert run.end_reason == "finished" and run.ended_mid_path and run.plan_end_time > 10.0
    (note,) = run.notes
    assert note.startswith("the flight ended mid-path: it finished at 10.000 s") and "raise duration" in note
    metrics = flight_metrics(tmp_path / "fast.mcap")
    assert metrics["plan"]["ended_mid_path"] is True and note in metrics["notes"]
    assert "**the flight ended mid-path at 10.000 s**" in markdown_summary(metrics)


@pytest.mark.slow
def test_fsr_fly_says_before_the_flight_that_it_will_end_mid_path(tmp_path: Path):
    scenario = tmp_path / "circle.yaml"
    scenario.write_text(yaml.safe_dump(CIRCLE))
    fly = subprocess.run([str(Path(sys.executable).parent / "fsr-fly"), str(scenario), "--in-process", "--duration",
                          "0.2", "--out", str(tmp_path / "run.mcap"), "--quiet"], capture_output=True, text=True,
                         timeout=300, cwd=tmp_path, env={"MPLBACKEND": "Agg", "PATH": "/usr/bin:/bin"})
    assert fly.returncode == 0, fly.stderr
    assert "WARNING: the plan comes to rest at 12.512 s, after the flight's 0.2 s: the flight will end mid-path " \
           "(raise duration to at least 12.52 s)" in fly.stderr
    assert "**the flight ended mid-path at 0.200 s**" in fly.stdout  # the summary


def test_legs_stretched_beyond_the_flight_end_it_mid_path_and_say_so():
    """The waypoints kind too: a 2.5 s leg stretched to 4.43 s in a 4 s flight."""
    leg = {"trajectory.waypoints.0": {"position": [2, 3, -6], "attitude_rpy_deg": [0, 0, 0], "duration": 2.5}}
    run = simulate("ex4_geometric", duration=4.0, set={"actuation": "rotors", **leg})
    assert "stretched to 4.43 s" in run.plan_adjustments[0]
    assert run.ended_mid_path and run.plan_end_time == pytest.approx(4.43)
    assert run.notes == ["the flight ended mid-path: it finished at 4.000 s (the scenario's duration) and its plan "
                         "comes to rest at 4.430 s; raise duration to at least 4.43 s"]
    assert not simulate("ex4_geometric", duration=4.5, set={"actuation": "rotors", **leg}).ended_mid_path
