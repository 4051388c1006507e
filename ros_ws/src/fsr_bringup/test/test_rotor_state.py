"""The rotors' actual state (``rotor_state``): recorded with actuator dynamics, what the effective truth is made
of, and the same from the node graph as in one process."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from fsr_bringup.analysis.effective import effective_wrench
from fsr_bringup.analysis.load import load_flight
from fsr_bringup.analysis.metrics import wrench_comparison
from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario
from fsr_sim.recording.reader import open_recording

BIN = os.path.dirname(sys.executable)
LAG = ["actuation=rotors", "plant.rotor_time_constant=0.02", "duration=3.0"]


def test_rotor_state_is_recorded_with_actuator_dynamics_only(tmp_path):
    lagging = fly_in_process(load_scenario("ex4_geometric", LAG), tmp_path / "lag.mcap")
    flight = load_flight(tmp_path / "lag.mcap")
    np.testing.assert_array_equal(flight.rotor_state.speeds, lagging.actual_rotor_speeds)
    assert flight.rotor_state.tilts is None
    # behind the command while it moves; within the limits
    assert np.abs(lagging.actual_rotor_speeds[1:] - lagging.rotor_speeds[1:]).max() > 0.05  # smooth climb: 0.13
    assert lagging.actual_rotor_speeds.max() <= flight.config.plant_vehicle.rotor_speed_max
    plain = fly_in_process(load_scenario("ex4_geometric", [LAG[0], LAG[2]]), tmp_path / "plain.mcap")
    assert "/rotor_state" not in open_recording(tmp_path / "plain.mcap").topics
    assert load_flight(tmp_path / "plain.mcap").rotor_state is None
    np.testing.assert_array_equal(plain.actual_rotor_speeds[1:], plain.rotor_speeds[:-1])  # applied at once


def test_rotor_state_starts_at_the_first_command_not_at_rest(tmp_path):
    """The flight starts with the rotors spun up at the first command (docs/model.md): ``rotor_state``'s first
    message says so (it used to be all zero)."""
    fly_in_process(load_scenario("ex4_geometric", [*LAG[:2], "duration=0.01"]), tmp_path / "lag.mcap")
    flight = load_flight(tmp_path / "lag.mcap")
    vehicle = flight.config.plant_vehicle
    first = np.clip(flight.rotor_cmd.speeds[0], vehicle.rotor_speed_min, vehicle.rotor_speed_max)
    np.testing.assert_array_equal(flight.rotor_state.speeds[0], first)
    assert np.all(flight.rotor_state.speeds[0] > 0.0)  # spinning (near hover), not at rest


def test_the_effective_truth_is_made_of_the_actual_rotor_speeds(tmp_path):
    # With a 20 ms lag the commanded wrench is not the one the rotors give: the observer sees the difference
    # as an external wrench, and the effective truth (from rotor_state) says so - from rotor_cmd it would not.
    # (ex4's climb, 12 s: smooth; measured RMS f_z 1.1e-5 vs 3.5e-4 N, tau_z 2.7e-6 vs 8.5e-5 N m.)
    fly_in_process(load_scenario("ex4_geometric", ["actuation=rotors", "plant.rotor_time_constant=0.02",
                                                   "duration=12.0"]), tmp_path / "lag.mcap")
    flight = load_flight(tmp_path / "lag.mcap")
    from_state = effective_wrench(flight)
    rms_state = np.array(wrench_comparison(flight)["rms_error"])
    flight.rotor_state = None  # as if the actual speeds were the commanded ones
    rms_cmd = np.array(wrench_comparison(flight)["rms_error"])
    from_cmd = effective_wrench(flight)
    defined = np.isfinite(from_state.wrench_body).all(axis=1)
    assert np.abs(from_state.wrench_body[defined] - from_cmd.wrench_body[defined]).max() > 1e-4  # 4.7e-4 N
    f_z, tau_z = 2, 5
    assert rms_state[f_z] < 0.1 * rms_cmd[f_z] and rms_state[tau_z] < 0.1 * rms_cmd[tau_z]


@pytest.mark.graph
@pytest.mark.slow
def test_rotor_state_from_the_node_graph_is_the_in_process_one(tmp_path):
    env = {**os.environ, "MPLBACKEND": "Agg"}
    sets = ["--set", "plant.rotor_time_constant=0.02", "--set", "plant.tilt_time_constant=0.03",
            "--set", "plant.tilt_rate_max_deg_s=120"]
    out = {}
    for label, extra in (("graph", []), ("local", ["--in-process"])):
        out[label] = tmp_path / f"{label}.mcap"
        run = subprocess.run([os.path.join(BIN, "fsr-fly"), "--quiet", "ex5_voliro", *sets, "--duration", "0.3",
                              "--out", str(out[label]), "--no-analysis", *extra],
                             env=env, capture_output=True, text=True, timeout=180)
        assert run.returncode == 0, run.stdout + run.stderr
    graph, local = open_recording(out["graph"]), open_recording(out["local"])
    for topic in ("/rotor_state", "/odom", "/rotor_cmd"):
        assert graph.count(topic) == 301
        assert [d for _, d in graph.raw(topic)] == [d for _, d in local.raw(topic)], topic



def test_a_lagging_wrench_is_in_the_effective_truth(tmp_path):
    # Wrench actuation with a 30 ms rotor time constant: the applied wrench, replayed from wrench_cmd by the
    # plant's own lag, is what the observer's force residual m_e (a_k - g e3) - R_k f_c holds (the limit its
    # estimate converges to); taking the command for the applied wrench misses the lag.
    from dataclasses import replace

    from fsr_sim.core.rigid_body import GRAVITY

    fly_in_process(load_scenario("ex3_estimation", ["plant.rotor_time_constant=0.03", "duration=6.0"]),
                   tmp_path / "lag.mcap")
    flight = load_flight(tmp_path / "lag.mcap")
    odom, cmd, m_e = flight.odom, flight.wrench_cmd, flight.estimator.mass
    assert np.array_equal(cmd.stamp_ns, odom.stamp_ns)  # a command per state (the last one is not flown)
    accel = np.diff(odom.velocity_world, axis=0) / np.diff(odom.t)[:, None]
    residual = m_e * (accel - (0.0, 0.0, GRAVITY)) - np.einsum("kij,kj->ki", odom.rotation[:-1], cmd.force[:-1])
    applied = effective_wrench(flight).force_world[:-1]
    config = flight.config
    flight.config = replace(config, plant_vehicle=replace(config.plant_vehicle, rotor_time_constant=0.0))
    commanded = effective_wrench(flight).force_world[:-1]
    error_applied, error_commanded = np.abs(applied - residual).max(), np.abs(commanded - residual).max()
    # measured 6.9e-6 N (8.6e-6 without the lag: the trapezoid of R over the step) against 0.51 N
    assert error_applied < 2e-5 and error_commanded > 0.1, (error_applied, error_commanded)
