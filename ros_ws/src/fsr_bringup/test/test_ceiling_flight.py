"""The ceiling is solid, and a surface effect held at its cap is reported (in-process flights)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fsr_bringup.analysis.metrics import flight_metrics
from fsr_bringup.analysis.summary import markdown_summary
from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario
from fsr_sim.model.vehicle import load_vehicle

CEILING = -3.0


def test_a_goal_beyond_the_ceiling_stops_at_the_ceiling(tmp_path: Path) -> None:
    """A waypoint 0.3 m above the ceiling used to be reached through it (hovering 0.34 m above)."""
    scenario = load_scenario("ceiling_approach", ["trajectory.waypoints.0.position=[0,0,-3.3]", "duration=10.0"])
    result = fly_in_process(scenario, recording=tmp_path / "ceiling.mcap")
    top = load_vehicle("quadrotor_ex4").top_height
    assert result.end_reason == "finished", result.reason
    assert result.position[:, 2].min() >= CEILING + top - 1e-9  # the top never goes through the ceiling
    assert result.position[-1, 2] == pytest.approx(CEILING + top, abs=1e-9)  # pressed against it
    metrics = flight_metrics(tmp_path / "ceiling.mcap")
    assert metrics["thrust_ratio"]["ceiling"][1] < 1.5  # rotor plane 0.1 m from the ceiling: below the cap
    assert metrics["thrust_ratio"]["at_cap"]["ceiling"]["steps"] == 0


def test_ceiling_effect_at_its_cap_is_reported(tmp_path: Path) -> None:
    # Held 0.1 m below the ceiling with max_ratio 1.1: the ceiling ratio there (~1.12) is beyond the cap.
    scenario = load_scenario("ceiling_approach", [
        "initial_state.position=[0,0,-2.9]", "trajectory.waypoints.0.position=[0,0,-2.9]", "duration=0.5",
        "environment.ceiling.max_ratio=1.1", "estimator.enabled=false",
    ])
    result = fly_in_process(scenario, recording=tmp_path / "cap.mcap")
    assert result.end_reason == "finished"
    metrics = flight_metrics(tmp_path / "cap.mcap")
    caps = metrics["thrust_ratio"]["at_cap"]
    assert caps["ceiling"]["steps"] == len(result.time) and caps["ceiling"]["first_time_s"] == 0.0
    assert caps["ground"]["steps"] == 0
    assert any(note.startswith("ceiling effect at its cap (thrust ratio 1.1") for note in metrics["notes"])
    assert f"| ceiling effect at its cap 1.10 (outside the model) | **{len(result.time)} states**" in \
        markdown_summary(metrics)
