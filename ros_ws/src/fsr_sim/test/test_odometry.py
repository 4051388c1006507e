"""The odometry arithmetic shared by the simulator, the nodes and the in-process loop."""

import math

import numpy as np

from fsr_sim.config.scenario import load_scenario, plant_from_config, simulation_config
from fsr_sim.model.odometry import odometry_values, odometry_values_ok, state_from_odometry_values
from fsr_sim.nodes.state_messages import StateMessages
from fsr_sim.ros.conversions import state_from_odometry


def test_in_process_round_trip_equals_the_graph_message_path():
    plant = plant_from_config(simulation_config(load_scenario("ex5_voliro")))
    rng = np.random.default_rng(3)
    for _ in range(20):
        plant.state_vector[:] = rng.normal(size=13)
        plant.state_vector[6:10] /= np.linalg.norm(plant.state_vector[6:10])
        messages = StateMessages(plant)
        messages.fill()
        expected = state_from_odometry(messages.odom)
        ours = state_from_odometry_values(*odometry_values(plant.state_vector))
        for mine, theirs in zip(ours, expected, strict=True):
            np.testing.assert_array_equal(mine, theirs)  # bit-identical
        assert odometry_values(plant.state_vector)[1][3] >= 0.0  # published with w >= 0


def test_odometry_values_ok_refuses_non_finite_values_and_a_zero_quaternion():
    pose, twist = (1.0, -2.0, -3.0, 0.0, 0.0, 0.0, 1.0), (0.5, 0.0, 0.0, 0.0, 0.0, 0.1)
    assert odometry_values_ok(pose, twist)
    assert not odometry_values_ok(pose, twist[:5] + (math.nan,))
    assert not odometry_values_ok((math.inf,) + pose[1:], twist)
    assert not odometry_values_ok(pose[:3] + (0.0, 0.0, 0.0, 0.0), twist)
    assert not odometry_values_ok(pose[:3] + (1e-7, 0.0, 0.0, 0.0), twist)  # |q|^2 = 1e-14 <= 1e-12


def test_state_from_odometry_bytes_is_the_message_path_and_names_what_it_refuses():
    """What the controller and estimator nodes read from an ``odom`` payload: the state of the message path
    bit for bit, with its stamp; unreadable bytes and unusable values refused with the reason."""
    import pytest
    from rclpy.serialization import serialize_message

    from fsr_sim.ros.conversions import odometry_from_state, state_from_odometry_bytes

    plant = plant_from_config(simulation_config(load_scenario("ex4_geometric")))
    plant.state_vector[3:6] = (0.5, -0.25, 0.125)
    messages = StateMessages(plant)
    messages.fill()
    stamp, *state = state_from_odometry_bytes(serialize_message(messages.odom))
    assert stamp == 0
    for mine, theirs in zip(state, state_from_odometry(messages.odom), strict=True):
        np.testing.assert_array_equal(mine, theirs)
    with pytest.raises(ValueError, match="cannot be read"):
        state_from_odometry_bytes(b"\x00\x00\x00\x00")
    bad = odometry_from_state(7, np.array([math.nan, 0.0, 0.0]), np.eye(3), np.zeros(3), np.zeros(3))
    with pytest.raises(ValueError, match="odom at 7 ns holds NaN/inf or a zero quaternion"):
        state_from_odometry_bytes(serialize_message(bad))
