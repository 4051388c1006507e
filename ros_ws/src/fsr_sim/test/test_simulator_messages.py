"""Simulator command decoding and state messages (no ROS graph; message classes only)."""

import math

import numpy as np
import pytest
import yaml
from sensor_msgs.msg import JointState

from fsr_sim.config.scenario import load_scenario, plant_from_config, simulation_config
from fsr_sim.nodes.commands import RotorCommandReader, wrench_command
from fsr_sim.nodes.state_messages import StateMessages
from fsr_sim.ros.conversions import rotor_command, state_from_odometry, wrench_stamped


def test_rotor_reader_plain_and_tilting_orders():
    plain = RotorCommandReader(4, tilting=False)
    speeds, tilts = plain.read(rotor_command(0, [1.0, 2.0, 3.0, 4.0]))
    np.testing.assert_array_equal(speeds, [1, 2, 3, 4])
    assert tilts is None
    tilting = RotorCommandReader(4, tilting=True)
    speeds, tilts = tilting.read(rotor_command(0, [1.0, 2.0, 3.0, 4.0], [0.1, 0.2, 0.3, 0.4]))
    np.testing.assert_array_equal(speeds, [1, 2, 3, 4])
    np.testing.assert_array_equal(tilts, [0.1, 0.2, 0.3, 0.4])


def test_rotor_reader_any_name_order():
    msg = JointState(name=["rotor_2", "rotor_1"], velocity=[20.0, 10.0], position=[0.0, 0.0])
    speeds, tilts = RotorCommandReader(2, tilting=False).read(msg)
    np.testing.assert_array_equal(speeds, [10.0, 20.0])
    assert tilts is None


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_rotor_reader_refuses_non_finite(bad):
    reader = RotorCommandReader(4, tilting=True)
    with pytest.raises(ValueError, match="NaN or inf"):
        reader.read(rotor_command(0, [1.0, bad, 3.0, 4.0]))
    with pytest.raises(ValueError, match="NaN or inf"):
        reader.read(rotor_command(0, [1.0, 2.0, 3.0, 4.0], [0.0, 0.0, bad, 0.0]))


def test_rotor_reader_refuses_missing_rotor():
    with pytest.raises(ValueError, match="rotor_4"):
        RotorCommandReader(4, tilting=False).read(rotor_command(0, [1.0, 2.0, 3.0]))


def test_wrench_command_is_the_whole_body_wrench():
    """Every component reaches the plant: the in-process loop applies the controller's wrench as it is."""
    wrench = wrench_command(wrench_stamped(0, np.array((0.5, -0.25, -11.0)), np.array((1.0, 2.0, 3.0))))
    np.testing.assert_array_equal(wrench, [0.5, -0.25, -11.0, 1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="NaN or inf"):
        wrench_command(wrench_stamped(0, np.array((math.nan, 0.0, -11.0)), np.zeros(3)))


def make_plant(tmp_path, **data):
    scenario = {"vehicle": "quadrotor_ex4", "duration": 1.0, "actuation": "wrench"}
    scenario.update(data)
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(scenario))
    return plant_from_config(simulation_config(load_scenario(path)))


def test_state_messages_round_trip_the_plant_state(tmp_path):
    plant = make_plant(
        tmp_path,
        initial_state={
            "position": [1.0, 2.0, -3.0], "attitude_rpy_deg": [10.0, -20.0, 130.0],
            "velocity": [0.5, -0.2, 0.1], "angular_velocity": [0.1, 0.2, -0.3],
        },
        disturbances=[{"kind": "constant", "force": [1.0, 0.0, 0.0], "frame": "world", "torque": [0.0, 0.0, 0.2]}],
    )
    for _ in range(7):
        plant.step()
    messages = StateMessages(plant)
    messages.fill()
    assert messages.stamp_ns == 7_000_000
    assert (messages.odom.header.stamp.sec, messages.odom.header.stamp.nanosec) == (0, 7_000_000)
    assert (messages.clock.clock.sec, messages.clock.clock.nanosec) == (0, 7_000_000)
    assert messages.odom.pose.pose.orientation.w >= 0.0
    position, rotation, velocity, omega = state_from_odometry(messages.odom)
    np.testing.assert_allclose(position, plant.position, atol=1e-15)
    np.testing.assert_allclose(rotation, plant.rotation, atol=1e-14)
    np.testing.assert_allclose(velocity, plant.velocity, atol=1e-14)
    np.testing.assert_allclose(omega, plant.angular_velocity, atol=1e-15)
    w = messages.wrench.wrench
    force_world, torque_body = plant.external_wrench()
    np.testing.assert_allclose(plant.rotation @ [w.force.x, w.force.y, w.force.z], force_world, atol=1e-14)
    np.testing.assert_allclose([w.torque.x, w.torque.y, w.torque.z], torque_body, atol=1e-15)
    assert messages.wrench.header.frame_id == "base_link_frd" and messages.odom.header.frame_id == "world_ned"


def test_state_messages_stamp_past_one_second(tmp_path):
    plant = make_plant(tmp_path, duration=2.0, physics_dt=0.01)
    plant.step_index = 123
    messages = StateMessages(plant)
    messages.fill()
    assert (messages.odom.header.stamp.sec, messages.odom.header.stamp.nanosec) == (1, 230_000_000)
    assert messages.is_finite()
    plant.state_vector[0] = math.nan
    assert not messages.is_finite()


@pytest.mark.parametrize("disturbed", [False, True])
def test_packed_state_messages_equal_the_message_objects(disturbed):
    """StatePackets (the bytes the simulator publishes) holds exactly StateMessages' values."""
    from geometry_msgs.msg import WrenchStamped
    from nav_msgs.msg import Odometry
    from rclpy.serialization import deserialize_message
    from rosgraph_msgs.msg import Clock

    from fsr_sim.nodes.state_packets import StatePackets

    rng = np.random.default_rng(1)
    messages, packets = StateMessages(), StatePackets()
    for k in range(100):
        state = rng.normal(size=13)
        state[6:10] /= np.linalg.norm(state[6:10])
        external = (rng.normal(size=3), rng.normal(size=3)) if disturbed else None
        messages.fill_from(k * 1_234_567, state, external)
        packets.fill_from(k * 1_234_567, state, external)
        assert deserialize_message(packets.odom, Odometry) == messages.odom
        assert deserialize_message(packets.wrench, WrenchStamped) == messages.wrench
        assert deserialize_message(packets.clock, Clock) == messages.clock


@pytest.mark.parametrize("tilting", [False, True])
def test_commands_read_from_cdr_bytes_equal_the_message_path(tilting):
    """read_raw / wrench_command_raw (what the simulator runs) give read / wrench_command's numbers, for packed
    bytes and for rclpy's own serialisation (uninitialised padding: the general path), and refuse NaN."""
    from rclpy.serialization import serialize_message

    from fsr_sim.nodes.commands import wrench_command_raw
    from fsr_sim.ros import cdr_pack

    reader = RotorCommandReader(4, tilting)
    names = [f"rotor_{i + 1}" for i in range(4)] + ([f"tilt_{i + 1}" for i in range(4)] if tilting else [])
    packer = cdr_pack.joint_state("base_link_frd", names, len(names), len(names))
    rng = np.random.default_rng(3)
    for _ in range(20):
        speeds, tilts = rng.uniform(0, 900, 4), (rng.uniform(-1, 1, 4) if tilting else None)
        msg = rotor_command(7_000_000, speeds, tilts)
        expected = reader.read(msg)
        packed = packer.pack(7_000_000, [*msg.position, *msg.velocity])
        for data in (packed, serialize_message(msg)):
            got = reader.read_raw(data)
            assert np.array_equal(got[0], expected[0])
            stamp_ns, *stamped = reader.read_stamped(data)
            assert stamp_ns == 7_000_000 and np.array_equal(stamped[0], got[0])
            assert (got[1] is None) == (expected[1] is None) and (got[1] is None or np.array_equal(got[1], expected[1]))
        wrench = wrench_stamped(5, rng.normal(size=3), rng.normal(size=3))
        assert wrench_command_raw(serialize_message(wrench)).tolist() == wrench_command(wrench).tolist()
    bad = rotor_command(0, np.array([1.0, math.nan, 1.0, 1.0]), np.zeros(4) if tilting else None)
    with pytest.raises(ValueError):
        reader.read_raw(serialize_message(bad))
    with pytest.raises(ValueError):
        wrench_command_raw(serialize_message(wrench_stamped(0, np.array((math.inf, 0, 0)), np.zeros(3))))
