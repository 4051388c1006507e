"""An in-process flight's recording holds the graph's topics, with the payloads the nodes publish."""

from pathlib import Path

import numpy as np
import pytest

from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario
from fsr_sim.config.validation import builtin_names
from fsr_sim.recording.reader import open_recording

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


BUILT_IN = tuple(builtin_names("scenarios"))


@pytest.mark.parametrize("name", BUILT_IN)
def test_every_topic_of_every_built_in_scenario_reads_with_rosbags_and_mcap_ros2(tmp_path, name):
    """Standard payloads (no stray padding): two independent readers decode every message of every topic."""
    from mcap_ros2.reader import read_ros2_messages
    from rosbags.highlevel import AnyReader

    path = tmp_path / f"{name}.mcap"
    fly_in_process(load_scenario(name, ["duration=0.05"]), path)
    recording = open_recording(path)
    with AnyReader([path]) as reader:
        counts = {}
        for connection, _, raw in reader.messages():
            reader.deserialize(raw, connection.msgtype)  # raises on a size mismatch
            counts[connection.topic] = counts.get(connection.topic, 0) + 1
    assert counts == {topic: recording.count(topic) for topic in recording.topics if recording.count(topic)}
    decoded = sum(1 for _ in read_ros2_messages(str(path)))
    assert decoded == sum(counts.values())


def test_two_in_process_runs_write_identical_message_data(tmp_path):
    paths = [tmp_path / f"run{i}.mcap" for i in (1, 2)]
    for path in paths:
        fly_in_process(load_scenario("ex5_voliro", ["duration=0.05"]), path)
    first, second = (open_recording(path) for path in paths)
    assert first.topics == second.topics
    for topic in first.topics:
        assert first.raw(topic) == second.raw(topic), topic


def test_recording_does_not_depend_on_the_block_size(tmp_path, monkeypatch):
    """The in-process recording packs and writes a block of steps at once: blocks of 7 steps (so blocks end
    mid-flight, and the last is partial) give the file of the default block, byte for byte."""
    from fsr_bringup.recording import flight_recording

    scenario = load_scenario("octo_ground_effect", ["duration=0.1"])
    fly_in_process(scenario, tmp_path / "default.mcap")
    monkeypatch.setattr(flight_recording, "BLOCK_STEPS", 7)
    fly_in_process(scenario, tmp_path / "small.mcap")
    assert (tmp_path / "default.mcap").read_bytes() == (tmp_path / "small.mcap").read_bytes()
    assert open_recording(tmp_path / "small.mcap").count("rotor_cmd") == 101
