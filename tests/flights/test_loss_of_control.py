"""A flight that loses control ends as a divergence, with its time and reason, exit 3: its true thrust axis
further from the commanded one (``R e_3`` against ``R_c e_3``) than ``divergence.attitude_error_deg`` or its
position error beyond ``divergence.position_error_m``, checked by the same compiled function in the graph and in
one process."""

from __future__ import annotations

import numpy as np
import pytest

from fsr_bringup import simulate
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError
from fsr_sim.contract import DIVERGED, EXIT_DIVERGED
from fsr_sim.model.control_loss import DEFAULT_ATTITUDE_ERROR_DEG, DEFAULT_POSITION_ERROR_M

# the report's law on rotors under motion-capture noise: the rotor commands switch between their limits and the
# vehicle turns over (it used to end "finished", upside down, 7.6 m off)
UPSIDE_DOWN = {"actuation": "rotors", "controller.profile": "report",
               "sensors.odometry": {"position_std": 0.0005, "attitude_std_deg": 0.05, "velocity_std": 0.001,
                                    "angular_velocity_std": 0.003, "seed": 1}}


def test_a_vehicle_whose_thrust_turns_against_its_command_ends_diverged_at_the_first_state_beyond_the_bound():
    run = simulate("ex4_geometric", set=UPSIDE_DOWN, duration=5.0)
    assert run.end_reason == DIVERGED and run.exit_code == EXIT_DIVERGED
    assert "lost control at t = " in run.reason and "divergence.attitude_error_deg" in run.reason
    assert run.sim_time < 5.0
    thrust_axes = np.einsum("ki,ki->k", run.rotation[:, :, 2], run.rotation_commanded[:, :, 2])
    angle = np.degrees(np.arccos(np.clip(thrust_axes, -1.0, 1.0)))
    assert angle[-1] > DEFAULT_ATTITUDE_ERROR_DEG and np.all(angle[:-1] <= DEFAULT_ATTITUDE_ERROR_DEG)
    assert f"thrust axis {angle[-1]:.2f} deg from the commanded one" in run.reason
    assert run.metrics()["diagnosis"]["why"] == run.reason  # and the summary says why (see test_diagnosis)


def test_a_heading_that_gives_way_is_not_a_loss_of_control():
    # a yaw of 150 deg in 4 s is beyond the quadrotor's yaw authority: the heading lags far behind R_c, the thrust
    # goes where the law wants it, and the flight goes on
    run = simulate("ex4_geometric", set={"actuation": "rotors", "trajectory.feasibility": "warn",
                                         "trajectory.waypoints.0": {"position": [3, -2, -4],
                                                                    "attitude_rpy_deg": [0, 0, 150],
                                                                    "duration": 4.0}}, duration=4.0)
    assert run.end_reason == "finished", run.reason
    assert run.metrics()["tracking"]["attitude_error_deg"]["peak"] > DEFAULT_ATTITUDE_ERROR_DEG


def test_a_vehicle_landed_on_a_goal_below_the_ground_has_not_lost_control():
    # held by the ground, the law asks to go 5 cm lower: its commanded thrust points down, the vehicle sits still
    run = simulate("ex4_geometric", set={"actuation": "rotors", "initial_state.position": [0.0, 0.0, -0.4],
                                         "environment.ground": {"enabled": True, "height": 0.0},
                                         "trajectory.waypoints": [{"position": [0.0, 0.0, 0.05], "duration": 2.0}]},
                   duration=3.0)
    assert run.end_reason == "finished", run.reason
    assert run.metrics()["tracking"]["attitude_error_deg"]["final"] > DEFAULT_ATTITUDE_ERROR_DEG


def test_a_position_error_beyond_the_scenario_bound_ends_the_flight():
    push = {"disturbances": [{"kind": "step", "start": 0.5, "end": 3.0, "force": [3, 0, 0]}]}  # 0.24 m off at most
    run = simulate("ex4_geometric", set={**push, "divergence.position_error_m": 0.05}, duration=3.0)
    assert run.end_reason == DIVERGED and "position error" in run.reason
    assert "divergence.position_error_m" in run.reason
    error = run.metrics()["tracking"]["position_error_m"]
    assert error["final"] > 0.05 and error["peak_time_s"] == pytest.approx(run.sim_time)
    assert simulate("ex4_geometric", set=push, duration=3.0).end_reason == "finished"  # the default bound: 5 m


def test_the_bounds_are_validated_and_have_documented_defaults():
    config = simulation_config(load_scenario("ex4_geometric"))
    assert config.divergence.attitude_error_deg == DEFAULT_ATTITUDE_ERROR_DEG == 90.0
    assert config.divergence.position_error_m == DEFAULT_POSITION_ERROR_M
    for key, value in (("attitude_error_deg", 0), ("attitude_error_deg", 181), ("position_error_m", -1),
                       ("position_error_m", "far"), ("distance", 1)):
        with pytest.raises(ConfigError, match=f"divergence.{key}"):
            simulation_config(load_scenario("ex4_geometric", values={f"divergence.{key}": value}))
