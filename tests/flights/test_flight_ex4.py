"""Exercise 4 (geometric controller) in the in-process closed loop: climb thrust, hover thrust, converging errors."""

import math
from pathlib import Path

import numpy as np
import pytest

from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario
from fsr_sim.model.so3 import euler_zyx_from_rotation

EX4 = Path(__file__).parents[2] / "ros_ws" / "src" / "fsr_control" / "test" / "scenarios" / "ex4_wrench.yaml"
GOAL = np.array((1.0, 1.0, -4.0))
# Shorter flights where the check does not need the report's 30 s (a 30 s in-process flight costs several
# seconds; the module's 30 s flight is shared by its tests).
SHORT = ["duration=12.0", "trajectory.waypoints.0.duration=8.0", "trajectory.waypoints.0.hold=4.0"]


@pytest.fixture(scope="module")
def ex4():
    return fly_in_process(load_scenario(EX4))


def test_ex4_reaches_goal_and_yaw(ex4):
    assert ex4.end_reason == "finished"
    assert ex4.time[-1] == pytest.approx(30.0)
    assert np.linalg.norm(ex4.position[-1] - GOAL) < 1e-6
    yaw = euler_zyx_from_rotation(ex4.rotation[-1])[2]
    assert abs(math.degrees(yaw) - 20.0) < 1e-6


def test_ex4_thrust_settles_at_weight_and_tracking_error_small(ex4):
    assert ex4.thrust[-1] == pytest.approx(1.2 * 9.81, abs=1e-3)
    climbing = (ex4.time > 1.0) & (ex4.time < 8.0)
    assert np.all(ex4.thrust[climbing] > 11.772)  # upward acceleration while climbing (NED: z decreasing)
    peak = np.linalg.norm(ex4.position - ex4.reference_position, axis=1).max()
    assert peak < 1e-4
    assert ex4.saturation["count"] == 0


@pytest.mark.parametrize("vehicle", ["quadrotor_ex4", "octocopter"])
def test_rotor_actuation_reaches_goal_without_saturation(vehicle):
    scenario = load_scenario(EX4, ["actuation=rotors", f"vehicle={vehicle}", *SHORT])
    result = fly_in_process(scenario)
    assert result.end_reason == "finished"
    assert np.linalg.norm(result.position[-1] - GOAL) < 1e-3
    assert result.saturation["count"] == 0
    assert result.rotor_speeds.shape[1] == (8 if vehicle == "octocopter" else 4)
    # wrench_cmd is what the clamped rotor speeds produce: f_x = f_y = 0 for coplanar rotors.
    np.testing.assert_allclose(result.force_cmd[:, :2], 0.0, atol=1e-9)


def test_rotor_saturation_is_reported_not_silent():
    # A 0.3 s leg needs more than the octocopter's rotors can give: flown as written (feasibility warn, else it
    # would be stretched), its commands get clamped and counted.
    scenario = load_scenario(EX4, ["actuation=rotors", "vehicle=octocopter", "duration=1.5",
                                   "trajectory.waypoints.0.duration=0.3", "trajectory.waypoints.0.hold=0.0",
                                   "trajectory.feasibility=warn"])
    result = fly_in_process(scenario)
    report = result.saturation
    assert report["count"] > 0
    assert report["first_time"] is not None and 0.0 <= report["first_time"] < 0.3
    assert 1 <= report["worst_rotor"] <= 8 and report["worst_excess_rad_s"] > 0.0
    assert result.rotor_speeds.max() <= 900.0 and result.rotor_speeds.min() >= 0.0


def test_constant_external_force_gives_steady_error_f_over_kp():
    scenario = load_scenario(EX4, [
        "duration=8.0", "trajectory.waypoints=[]",
        "disturbances=[{kind: constant, frame: world, force: [1.0, 0.0, 0.0]}]",
    ])
    result = fly_in_process(scenario)
    error = result.position[-1] - np.array((0.0, 0.0, -1.0))
    assert error[0] == pytest.approx(1.0 / 20.0, rel=0.01)  # f / k_p,x
    assert abs(error[1]) < 1e-4 and abs(error[2]) < 1e-4
    # wrench_truth is in the (tilted) body frame: rotated back it is the world force.
    np.testing.assert_allclose(result.rotation[-1] @ result.external_force_body[-1], (1.0, 0.0, 0.0), atol=1e-12)
