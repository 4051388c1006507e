"""The sensor stage of a flight (fsr_sim.core.sensors.measure_odometry): white noise and a walking bias with the
configured statistics, a delay and a rate exactly, the same seed the same flight."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError
from fsr_sim.recording.cdr_columns import stamped_columns
from fsr_sim.recording.reader import open_recording

HOVER = ["trajectory.waypoints=[]", "duration=20.0"]  # ex4 (wrench actuation) holding [0, 0, -1]


def flown_odom(tmp_path, *sensors: str) -> tuple[np.ndarray, np.ndarray]:
    """(measured odom position (K, 3), true position (K, 3)) of a hover with ``sensors.odometry`` keys."""
    path = tmp_path / "hover.mcap"
    run = fly_in_process(load_scenario("ex4_geometric", [*HOVER, *sensors]), path)
    _, columns = stamped_columns(open_recording(path), "/odom")
    measured = np.column_stack([columns.numbers[f"pose.pose.position.{axis}"] for axis in "xyz"])
    return measured, run.position


def test_white_noise_has_the_configured_mean_and_deviation(tmp_path):
    measured, true = flown_odom(tmp_path, "sensors.odometry.position_std=0.002", "sensors.odometry.seed=11")
    error = measured - true
    assert np.all(np.abs(error.mean(axis=0)) < 0.03 * 0.002)  # 20 001 samples: mean within 3 % of sigma
    assert error.std(axis=0) == pytest.approx(np.full(3, 0.002), rel=0.03)
    again, _ = flown_odom(tmp_path, "sensors.odometry.position_std=0.002", "sensors.odometry.seed=11")
    np.testing.assert_array_equal(again, measured)


def test_a_bias_walks_with_the_configured_density(tmp_path):
    walk = 0.001  # m / sqrt(s): per 1 ms step an increment of 0.001 sqrt(0.001)
    measured, true = flown_odom(tmp_path, f"sensors.odometry.position_bias_walk={walk}", "sensors.odometry.seed=3")
    increments = np.diff(measured - true, axis=0)
    assert increments.std(axis=0) == pytest.approx(np.full(3, walk * math.sqrt(0.001)), rel=0.03)


def test_delay_and_rate_are_exact(tmp_path):
    delayed, true = flown_odom(tmp_path, "sensors.odometry.delay_steps=7", "duration=2.0")
    np.testing.assert_array_equal(delayed[7:], true[:-7])
    np.testing.assert_array_equal(delayed[:7], np.repeat(true[:1], 7, axis=0))
    slow, true = flown_odom(tmp_path, "sensors.odometry.rate_hz=100", "duration=2.0")
    for k in range(len(slow)):
        np.testing.assert_array_equal(slow[k], true[k - k % 10])  # a new sample every 10 ms, held between


def test_bad_sensor_keys_are_refused():
    with pytest.raises(ConfigError, match=r"rate_hz.*whole number"):
        simulation_config(load_scenario("ex4_geometric", ["sensors.odometry.rate_hz=300"]))
    with pytest.raises(ConfigError, match=r"delay_steps.*>= 0"):
        simulation_config(load_scenario("ex4_geometric", ["sensors.odometry.delay_steps=-1"]))


@pytest.mark.graph
@pytest.mark.slow
def test_the_node_graph_measures_what_one_process_measures(tmp_path):
    import os
    import subprocess
    import sys

    from fsr_bringup.analysis.load import load_flight

    sets = [item for key in ("odometry.position_std=0.002", "odometry.attitude_std_deg=0.1",
                             "odometry.velocity_bias_walk=0.01", "odometry.delay_steps=3", "odometry.rate_hz=250",
                             "odometry.seed=5", "imu.gyro_noise_density=0.0003",
                             "imu.accelerometer_noise_density=0.002", "imu.gyro_bias_walk=0.0001",
                             "imu.accelerometer_bias_walk=0.001", "imu.delay_s=0.002", "imu.rate_hz=500",
                             "imu.gyro_initial_bias=[0.01, 0, 0]", "imu.seed=5")
            for item in ("--set", f"sensors.{key}")]
    out = {}
    for label, extra in (("graph", []), ("local", ["--in-process"])):
        out[label] = tmp_path / f"{label}.mcap"
        run = subprocess.run([os.path.join(os.path.dirname(sys.executable), "fsr-fly"), "--quiet", "ex4_geometric",
                              *sets, "--duration", "0.3", "--out", str(out[label]), "--no-analysis", *extra],
                             env={**os.environ, "MPLBACKEND": "Agg"}, capture_output=True, text=True, timeout=180)
        assert run.returncode == 0, run.stdout + run.stderr
    graph, local = open_recording(out["graph"]), open_recording(out["local"])
    for topic in ("/odom", "/odom_truth", "/imu", "/wrench_cmd", "/wrench_estimate"):
        assert graph.count(topic) == 301
        assert [d for _, d in graph.raw(topic)] == [d for _, d in local.raw(topic)], topic
    recorded = load_flight(out["graph"])
    flown = recorded.imu  # the IMU's numbers to 1e-9 (here: bit for bit) from the graph's bytes
    run = fly_in_process(load_scenario("ex4_geometric", ["duration=0.3", *sets[1::2]]))
    assert np.abs(recorded.odom_truth.position - run.position).max() < 1e-9  # the true state, beside odom
    assert np.abs(recorded.odom_truth.velocity_world - run.velocity).max() < 1e-9
    assert np.abs(flown.linear_acceleration - run.imu_specific_force_measured).max() < 1e-9
    assert np.abs(flown.angular_velocity - run.imu_angular_velocity_measured).max() < 1e-9


def test_a_low_pass_on_the_measured_acceleration_flies_the_geometric_law_through_velocity_noise():
    from fsr_bringup import simulate

    noisy = {"sensors.odometry.velocity_std": 0.002, "sensors.odometry.seed": 0}
    raw = simulate("ex4_geometric", set=noisy)
    filtered = simulate("ex4_geometric", set={**noisy, "controller.acceleration_filter_hz": 2.0})
    assert raw.end_reason == "diverged"  # the 1 kHz velocity difference amplifies 2 mm/s a thousandfold
    assert filtered.end_reason == "finished"
    assert np.linalg.norm(filtered.position - filtered.reference_position, axis=1).max() < 5e-3


def test_the_low_pass_also_smooths_the_compensated_estimates_rates():
    # f_hat_dot and f_hat_ddot are backward differences of a noisy estimate: unfiltered they took the compensated
    # torque's RMS to ~75 N m here (the filtered acceleration alone does not help them)
    from fsr_bringup import simulate

    noisy = {"sensors.odometry.velocity_std": 0.002, "sensors.odometry.seed": 3,
             "controller.acceleration_filter_hz": 2.0}
    rms = {}
    for mode in ("none", "estimate"):
        run = simulate("ex3_estimation", duration=3.0, set={**noisy, "controller.compensation": mode})
        assert run.end_reason == "finished", mode
        rms[mode] = float(np.sqrt(np.mean(np.sum(run.torque_cmd[1000:] ** 2, axis=1))))
    assert rms["estimate"] < 1.2 * rms["none"], rms
