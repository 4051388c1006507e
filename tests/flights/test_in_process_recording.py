"""An in-process flight's recording holds the graph's topics, built with the nodes' own message functions."""

from pathlib import Path

import numpy as np
import pytest

from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario

SCENARIOS = Path(__file__).parents[2] / "ros_ws" / "src" / "fsr_control" / "test" / "scenarios"


def test_recording_has_the_graph_topics(tmp_path):
    from fsr_sim.recording.reader import open_recording

    scenario = load_scenario(SCENARIOS / "ex5_voliro.yaml", ["duration=0.05", "estimator.enabled=true"])
    path = tmp_path / "flight.mcap"
    result = fly_in_process(scenario, path)
    recording = open_recording(path)
    steps = 51  # states t_0..t_50, each answered
    for topic in ("odom", "wrench_truth", "rotor_cmd", "wrench_cmd", "reference", "wrench_estimate", "mass_estimate"):
        assert recording.count(topic) == steps, topic
    assert recording.count("sim_status") == 2
    assert "ex5_voliro" in recording.scenario_yaml
    stamp, odom = recording.messages("odom")[-1]
    assert stamp == 50_000_000 and odom.pose.pose.position.z == pytest.approx(result.position[-1, 2])
    _, command = recording.messages("rotor_cmd")[10]
    assert list(command.name) == [f"rotor_{i}" for i in range(1, 5)] + [f"tilt_{i}" for i in range(1, 5)]
    np.testing.assert_allclose(command.velocity[:4], result.rotor_speeds[10])
    assert result.mass_estimate is not None and result.mass_estimate[-1] == pytest.approx(1.32, abs=0.05)
