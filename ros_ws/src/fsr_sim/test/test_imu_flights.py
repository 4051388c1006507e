"""The IMU in flight: ``imu`` at hover, its noise and bias walk with the configured statistics over a long
seeded hover, delay and rate exact, the same seed the same bytes, and a recording that standard readers decode
to the flight's numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsr_bringup.analysis.load import load_flight
from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.recording.reader import open_recording

HOVER = ["trajectory.waypoints=[]", "duration=20.0"]  # ex4 holding [0, 0, -1]
RATE = 1000.0  # Hz: ex4's control rate, the IMU's default


def hover(tmp_path, *sensors: str, name: str = "hover", scenario: str = "ex4_geometric", duration: float = 20.0):
    scenario = load_scenario(scenario, [*HOVER, f"duration={duration}", *sensors])
    return fly_in_process(scenario, tmp_path / f"{name}.mcap")


def errors(run) -> np.ndarray:  # noqa: ANN001
    """measured - true (K+1, 6): angular velocity, specific force."""
    return np.hstack((run.imu_angular_velocity_measured - run.angular_velocity,
                      run.imu_specific_force_measured - run.imu_specific_force_true))


@pytest.mark.parametrize("actuation", ["wrench", "rotors"])
def test_an_ideal_imu_at_hover_reads_minus_g_and_zero_rates(tmp_path, actuation):
    run = hover(tmp_path, "sensors.preset=ideal", f"actuation={actuation}", duration=2.0)
    assert run.end_reason == "finished"
    # from t_1 (at t_0 no command has spun the rotors: free fall)
    assert np.abs(run.imu_specific_force_measured[1:] - [0.0, 0.0, -GRAVITY]).max() < 1e-9
    assert np.abs(run.imu_angular_velocity_measured).max() < 1e-9
    np.testing.assert_array_equal(run.imu_specific_force_measured, run.imu_specific_force_true)
    without = hover(tmp_path, f"actuation={actuation}", duration=2.0, name="plain")
    assert without.imu_specific_force_measured is None and without.imu_specific_force_true is None
    assert "/imu" not in open_recording(tmp_path / "plain.mcap").topics
    np.testing.assert_array_equal(without.state, run.state)  # an IMU measures; it changes nothing


def test_white_noise_has_the_configured_mean_and_deviation(tmp_path):
    density = np.array([2e-4, 3e-4, 4e-4, 2e-3, 3e-3, 4e-3])  # gyro [rad/s/sqrt(Hz)], accelerometer [m/s^2/sqrt(Hz)]
    run = hover(tmp_path, f"sensors.imu.gyro_noise_density={density[:3].tolist()}",
                f"sensors.imu.accelerometer_noise_density={density[3:].tolist()}", "sensors.imu.seed=11")
    error = errors(run)
    sigma = density * math.sqrt(RATE)  # per sample
    assert np.all(np.abs(error.mean(axis=0)) < 0.03 * sigma)  # 20 001 samples: the mean within 3 % of sigma
    np.testing.assert_allclose(error.std(axis=0), sigma, rtol=0.03)
    assert np.abs(np.corrcoef(error.T) - np.eye(6)).max() < 0.03  # independent axes


def test_the_bias_walks_as_documented(tmp_path):
    walk = np.array([1e-4, 2e-4, 4e-4, 1e-3, 2e-3, 4e-3])  # [rad/s^2/sqrt(Hz)], [m/s^3/sqrt(Hz)]
    initial = np.array([0.01, -0.02, 0.0, 0.1, 0.0, -0.3])
    run = hover(tmp_path, f"sensors.imu.gyro_bias_walk={walk[:3].tolist()}",
                f"sensors.imu.accelerometer_bias_walk={walk[3:].tolist()}",
                f"sensors.imu.gyro_initial_bias={initial[:3].tolist()}",
                f"sensors.imu.accelerometer_initial_bias={initial[3:].tolist()}", "sensors.imu.seed=3")
    bias = errors(run)
    np.testing.assert_allclose(bias[0], initial, rtol=0, atol=1e-12)
    T = 1.0 / RATE
    for lag in (1, 10):  # the spread after t = lag T is walk sqrt(t): 20 000 and 2 000 windows per axis
        increments = (bias[lag::lag] - bias[:-lag:lag]) / (walk * math.sqrt(lag * T))
        assert increments.std() == pytest.approx(1.0, rel=0.03)
        np.testing.assert_allclose(increments.std(axis=0), 1.0, rtol=0.03 if lag == 1 else 0.08)


def test_delay_and_rate_are_exact(tmp_path):
    delayed = hover(tmp_path, "sensors.imu.delay_s=0.007", duration=1.0)
    measured, true = delayed.imu_specific_force_measured, delayed.imu_specific_force_true
    np.testing.assert_array_equal(measured[7:], true[:-7])
    np.testing.assert_array_equal(measured[:7], np.repeat(true[:1], 7, axis=0))
    slow = hover(tmp_path, "sensors.imu.rate_hz=100", duration=1.0)
    for k in range(len(slow.time)):
        np.testing.assert_array_equal(slow.imu_angular_velocity_measured[k], slow.angular_velocity[k - k % 10])


def test_one_seed_gives_the_same_bytes_another_seed_other_noise(tmp_path):
    payloads = []
    for name, seed in (("first", 5), ("again", 5), ("other", 6)):
        hover(tmp_path, "sensors.preset=onboard", f"sensors.imu.seed={seed}",
              scenario="ex5_voliro", duration=0.5, name=name)
        payloads.append([data for _, data in open_recording(tmp_path / f"{name}.mcap").raw("imu")])
    assert len(payloads[0]) == 501 and payloads[0] == payloads[1]
    assert sum(a != b for a, b in zip(payloads[0], payloads[2], strict=True)) == 501


def test_the_recording_holds_the_flight_s_imu_for_standard_readers(tmp_path):
    from mcap_ros2.reader import read_ros2_messages
    from rosbags.highlevel import AnyReader

    run = hover(tmp_path, "sensors.preset=onboard", scenario="ex5_voliro", duration=0.3)
    path = tmp_path / "hover.mcap"
    flight = load_flight(path)
    np.testing.assert_array_equal(flight.imu.angular_velocity, run.imu_angular_velocity_measured)
    np.testing.assert_array_equal(flight.imu.linear_acceleration, run.imu_specific_force_measured)
    sigma = flight.config.imu.pack(flight.config.control_period).noise_std
    with AnyReader([path]) as reader:
        connections = [c for c in reader.connections if c.topic == "/imu"]
        assert [c.msgtype for c in connections] == ["sensor_msgs/msg/Imu"]
        messages = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=connections)]
    assert len(messages) == 301
    last = messages[-1]
    assert last.header.frame_id == "base_link_frd" and last.orientation_covariance[0] == -1.0
    assert (last.orientation.x, last.orientation.y, last.orientation.z, last.orientation.w) == (0.0, 0.0, 0.0, 1.0)
    np.testing.assert_array_equal(np.diag(last.angular_velocity_covariance.reshape(3, 3)), np.square(sigma[:3]))
    np.testing.assert_array_equal(np.diag(last.linear_acceleration_covariance.reshape(3, 3)), np.square(sigma[3:]))
    a = last.linear_acceleration
    np.testing.assert_array_equal([a.x, a.y, a.z], run.imu_specific_force_measured[-1])
    decoded = [m.ros_msg for m in read_ros2_messages(str(path), topics=["/imu"])]
    assert len(decoded) == 301 and decoded[-1].angular_velocity.z == run.imu_angular_velocity_measured[-1, 2]
