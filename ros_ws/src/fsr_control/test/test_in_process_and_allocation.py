from pathlib import Path

import numpy as np
import pytest

from fsr_bringup.runner.in_process_flight import fly_in_process, odometry_round_trip
from fsr_control.allocation import TiltingActuation
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.model.allocation import static_tilting_allocation
from fsr_sim.model.plant import Plant
from fsr_sim.model.vehicle import load_vehicle

SCENARIOS = Path(__file__).parent / "scenarios"


def test_round_trip_equals_the_graph_message_path():
    from fsr_sim.nodes.state_messages import StateMessages
    from fsr_sim.ros.conversions import state_from_odometry

    plant = Plant(simulation_config(load_scenario(SCENARIOS / "ex5_voliro.yaml")))
    rng = np.random.default_rng(3)
    for _ in range(20):
        plant.state[:] = rng.normal(size=13)
        plant.state[6:10] /= np.linalg.norm(plant.state[6:10])
        messages = StateMessages(plant)
        messages.fill()
        expected = state_from_odometry(messages.odom)
        _, position, rotation, velocity, omega = odometry_round_trip(plant.state)
        for ours, theirs in zip((position, rotation, velocity, omega), expected, strict=True):
            np.testing.assert_array_equal(ours, theirs)  # bit-identical


def test_reports_null_space_step_is_a_no_op_and_ours_keeps_the_wrench():
    vehicle = load_vehicle("tilting_quadrotor_ex5")
    allocation = static_tilting_allocation(vehicle)
    plain = TiltingActuation.with_objective(vehicle, "none")
    ours = TiltingActuation.with_objective(vehicle, "min_peak_speed")
    wrench = np.array((6.0, -4.5, -4.5, 0.01, -0.02, 0.003))  # roughly the 45/45 deg hover
    u_p = plain.inverse @ wrench
    assert np.abs(plain.null_basis.T @ u_p).max() < 1e-12  # z = -N^T u_p = 0
    a, b = plain.allocate(0.0, wrench[:3], wrench[3:]), ours.allocate(0.0, wrench[:3], wrench[3:])
    np.testing.assert_allclose(np.concatenate((b.force_body, b.torque_body)), wrench, atol=1e-9)
    np.testing.assert_allclose(allocation @ (plain.inverse @ wrench), wrench, atol=1e-12)
    assert b.rotor_speeds.max() < a.rotor_speeds.max() - 1.0


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
