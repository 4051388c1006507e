"""Priority allocation in closed loop (in-process): yaw gives way at the rotor limits, the vehicle does not fall.

* ex4_geometric with rotor actuation and 90 deg of yaw in 5 s: with ``clamp`` (per-rotor clamping) it loses
  altitude and crashes (exit 3); with ``priority`` it tracks position within 0.5 m and ends on the goal.
* A flight that never saturates is the same with either strategy (to 1e-12).
* The octocopter with 520 rad/s rotors (3 % above hover) holds its altitude while a fast yaw move saturates.
* The shortfall is recorded (``wrench_shortfall``) and summed per axis by fsr-analyze.
"""

from pathlib import Path

import numpy as np
import pytest

import fsr_sim
from fsr_bringup.analysis.metrics import flight_metrics
from fsr_bringup.analysis.summary import markdown_summary
from fsr_bringup.runner.in_process_flight import EXIT_DIVERGED, fly_in_process
from fsr_sim.config.scenario import load_scenario
from fsr_sim.model.rotors import WRENCH_AXES
from fsr_sim.model.so3 import rotation_from_euler_zyx

GOAL = np.array((5.0, -3.0, -6.0))
GOAL_RPY_DEG = np.array((0.0, 0.0, 90.0))
YAW_MOVE = "trajectory.waypoints.0={position: [5, -3, -6], attitude_rpy_deg: [0, 0, 90], duration: 5.0, hold: %s}"


def yaw_move(allocation: str, hold: float, duration: float) -> list[str]:
    # feasibility warn: the leg as written, beyond the yaw authority (the default would shape it: no saturation)
    return ["actuation=rotors", YAW_MOVE % hold, f"duration={duration}", f"controller.allocation={allocation}",
            "trajectory.feasibility=warn"]


def attitude_error_deg(rotation: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Angle of ``R_target^T R`` [deg] for (n, 3, 3) ``rotation``."""
    cosine = (np.einsum("nij,ij->n", rotation, target) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))


def gave_way(report: dict) -> list[str]:
    return [axis for axis in WRENCH_AXES if report["gave_way"][axis]["steps"]]


def test_ninety_degrees_of_yaw_in_five_seconds_gives_way_in_yaw_and_reaches_the_goal():
    # 25 s hold: the yaw torque the rotors can give (0.15 N m on I_zz = 2.48 kg m^2) needs ~20 s to settle.
    result = fly_in_process(load_scenario("ex4_geometric", yaw_move("priority", 25.0, 30.0)))
    assert result.end_reason == "finished", result.reason
    error = np.linalg.norm(result.position - result.reference_position, axis=1)
    assert error.max() < 0.5
    assert np.linalg.norm(result.position[-1] - GOAL) < 1e-3
    final = attitude_error_deg(result.rotation[-1:], rotation_from_euler_zyx(np.radians(GOAL_RPY_DEG)))[0]
    assert final < 0.01
    report = result.saturation
    assert report["count"] > 0.5 * 5000 and report["first_time"] < 0.5  # it did saturate, a lot
    assert gave_way(report) == ["torque_z"]  # and only yaw gave way
    speeds = result.rotor_speeds
    assert speeds.max() <= 1000.0 and speeds.min() >= 0.0


def test_the_same_flight_with_per_rotor_clamping_crashes():
    result = fly_in_process(load_scenario("ex4_geometric", yaw_move("clamp", 0.0, 10.0)))
    # the thrust axis turns away from the commanded one (then it would crash into the ground): lost control
    assert result.exit_code == EXIT_DIVERGED and "lost control" in result.reason and "thrust axis" in result.reason
    assert {"force_z", "torque_x", "torque_y", "torque_z"} <= set(gave_way(result.saturation))


@pytest.mark.parametrize("name", ["ex4_geometric", "ex5_voliro"])
def test_a_flight_that_never_saturates_is_unchanged(name):
    flights = [fly_in_process(load_scenario(name, ["actuation=rotors", "duration=3.0",
                                                   f"controller.allocation={allocation}"]))
               for allocation in ("clamp", "priority")]
    for flight in flights:
        assert flight.end_reason == "finished" and flight.saturation["count"] == 0
    clamp, priority = flights
    np.testing.assert_allclose(priority.state, clamp.state, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(priority.rotor_speeds, clamp.rotor_speeds, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(priority.torque_cmd, clamp.torque_cmd, rtol=0.0, atol=1e-12)


@pytest.fixture(scope="module")
def octocopter_520(tmp_path_factory) -> Path:
    """octocopter.yaml with rotor_speed_max 520 rad/s (hover: 505 rad/s)."""
    text = (Path(fsr_sim.__file__).parent / "config" / "vehicles" / "octocopter.yaml").read_text()
    assert "rotor_speed_max: 900.0" in text
    path = tmp_path_factory.mktemp("vehicles") / "octocopter_520.yaml"
    path.write_text(text.replace("rotor_speed_max: 900.0", "rotor_speed_max: 520.0"))
    return path


@pytest.mark.parametrize("allocation", ["priority", "clamp"])
def test_octocopter_at_its_speed_limit_keeps_altitude_while_yaw_gives_way(octocopter_520, allocation):
    overrides = ["actuation=rotors", f"vehicle={octocopter_520}", "duration=5.0", "estimator.enabled=false",
                 "trajectory.waypoints.0={position: [0, 0, -1], attitude_rpy_deg: [0, 0, 90], duration: 2, hold: 3}",
                 f"controller.allocation={allocation}", "trajectory.feasibility=warn"]  # as written: saturates
    result = fly_in_process(load_scenario("ex4_geometric", overrides))
    altitude_error = np.abs(result.position[:, 2] - result.reference_position[:, 2])
    assert result.saturation["count"] > 2000  # the yaw move saturates most of the flight
    assert result.rotor_speeds.max() <= 520.0
    if allocation == "priority":
        assert altitude_error.max() < 0.1
        assert gave_way(result.saturation) == ["torque_z"]
    else:  # per-rotor clamping gives away thrust as well and the vehicle sinks
        assert altitude_error.max() > 0.1
        assert "force_z" in gave_way(result.saturation)


def test_shortfall_is_recorded_and_summed_per_axis(tmp_path):
    recording = tmp_path / "yaw.mcap"
    result = fly_in_process(load_scenario("ex4_geometric", yaw_move("priority", 0.0, 1.0)), recording)
    metrics = flight_metrics(recording)
    shortfall = metrics["wrench_shortfall"]
    assert shortfall["steps"] == metrics["message_counts"]["/wrench_cmd"] == len(result.time)
    report = result.saturation["gave_way"]
    for axis in WRENCH_AXES:
        assert shortfall[axis]["steps"] == report[axis]["steps"]
        assert shortfall[axis]["max_shortfall"] == pytest.approx(report[axis]["max_shortfall"], rel=1e-12)
    assert shortfall["torque_z"]["steps"] > 500 and shortfall["force_z"]["steps"] == 0
    assert "gave way at the rotor limits [N, N m] | torque_z" in markdown_summary(metrics)
