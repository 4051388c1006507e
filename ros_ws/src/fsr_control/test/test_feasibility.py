"""References the vehicle can fly (fsr_control.planning.feasibility): the demands of a leg against the authority,
the angle shaped or the leg stretched to the shortest feasible duration, warn / refuse, goals at run time,
and closed-loop flights of legs beyond the authority."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from numpy.polynomial import polynomial
from scipy.spatial.transform import Rotation

from fsr_bringup import simulate
from fsr_control.config.controller_config import controller_config
from fsr_control.flight_controller import FlightController
from fsr_control.planning.feasibility import (
    DURATION_STEP,
    FACTOR_TOLERANCE,
    InfeasibleReferenceError,
    leg_demand,
    reference_limits,
)
from fsr_control.planning.polynomial import REST_TO_REST, SepticSegment
from fsr_control.planning.trajectory import Trajectory, Waypoint, yaw_rotation
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError, builtin_names
from fsr_sim.model import load_vehicle

QUAD = load_vehicle("quadrotor_ex4")
BUILT_IN = tuple(builtin_names("scenarios"))
# max |s''(tau)| of the rest-to-rest septic s = 35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7 (7.51), on a fine grid
S_DDOT_MAX = float(np.abs(polynomial.polyval(np.linspace(0.0, 1.0, 2_000_001),
                                             polynomial.polyder(REST_TO_REST, 2))).max())


def yaw_leg(yaw_deg: float, duration: float, position: tuple = (0.0, 0.0, -1.0)) -> dict:
    return {"position": list(position), "attitude_rpy_deg": [0.0, 0.0, yaw_deg], "duration": duration}


def ex4_rotors(*extra: str) -> list[str]:
    return ["actuation=rotors", *extra]


def flown_yaw_deg(run: object) -> np.ndarray:
    return np.degrees(np.unwrap(Rotation.from_matrix(run.rotation).as_euler("ZYX")[:, 0]))


def test_per_channel_durations_keep_the_shared_ones_exactly() -> None:
    start, goal = np.array((0.0, 1.0, -1.0, 0.0)), np.array((2.0, -1.0, -3.0, 1.5))
    shared = SepticSegment(1.0, 4.0, start, goal)
    same = SepticSegment(1.0, np.full(4, 4.0), start, goal)
    shaped = SepticSegment(1.0, np.array((4.0, 4.0, 4.0, 9.0)), start, goal)
    for t in (0.5, 1.0, 2.3, 4.99, 5.0, 7.0, 10.0, 12.0):
        assert np.array_equal(shared.evaluate(t), same.evaluate(t))
        assert np.array_equal(shaped.evaluate(t)[:, :3], shared.evaluate(t)[:, :3])
    # the angle runs the same shape over 9 s: value at equal normalised time, rates scaled by 1/T^n
    slow = SepticSegment(1.0, 9.0, start, goal)
    assert np.array_equal(shaped.evaluate(5.5)[:, 3], slow.evaluate(5.5)[:, 3])
    assert shaped.end_time == 10.0 and shaped.duration == 9.0
    assert shaped.evaluate(10.0)[0, 3] == 1.5 and not shaped.evaluate(10.0)[1:, 3].any()


def test_yaw_demand_and_shortest_shaping_match_the_hand_calculation() -> None:
    """A yaw-only leg asks I_zz |dpsi| s''_max / T^2 of yaw torque; the shortest angle duration with the
    margin's torque is sqrt(I_zz |dpsi| s''_max / tau_allowed)."""
    limits = reference_limits(QUAD, 0.7)
    angle = math.radians(150.0)
    trajectory = Trajectory([Waypoint(np.array((0.0, 0.0, -1.0)), yaw_rotation(angle), 4.0)],
                            np.array((0.0, 0.0, -1.0)), np.eye(3), full_attitude=False)
    demand = leg_demand(trajectory.table(), 1, limits)
    inertia_zz = QUAD.inertia[2, 2]
    assert demand.torque[2] == pytest.approx(inertia_zz * angle * S_DDOT_MAX / 16.0, rel=1e-4)  # sampling
    assert demand.torque[:2] == pytest.approx([0.0, 0.0], abs=1e-12)
    assert demand.thrust_max == pytest.approx(QUAD.weight, rel=1e-12)

    shaped = Trajectory([Waypoint(np.array((0.0, 0.0, -1.0)), yaw_rotation(angle), 4.0)],
                        np.array((0.0, 0.0, -1.0)), np.eye(3), full_attitude=False, limits=limits)
    (adjustment,) = shaped.adjustments
    shortest = math.sqrt(inertia_zz * angle * S_DDOT_MAX / limits.allowed.yaw_torque)
    assert adjustment.action == "shaped" and adjustment.position_duration == 4.0
    assert shortest - 1e-3 <= adjustment.angle_duration <= shortest * (1 + 2 * FACTOR_TOLERANCE) + DURATION_STEP
    assert shaped.table().duration[1].tolist() == [4.0, 4.0, 4.0, adjustment.angle_duration]
    assert shaped.end_time == adjustment.angle_duration
    assert "needs 3.05 N m of yaw torque, the rotors give 0.155 N m at hover (0.108 with the margin 0.7)" in \
        adjustment.text()


@pytest.mark.parametrize("name", BUILT_IN)
@pytest.mark.parametrize("actuation", ["rotors", "wrench"])
def test_built_in_legs_are_within_the_authority_and_planned_exactly_as_without_a_check(name: str,
                                                                                      actuation: str) -> None:
    scenario = load_scenario(name, [f"actuation={actuation}"] if actuation == "rotors" else [])
    config = controller_config(scenario)
    assert config.plan_adjustments == ()
    sim = simulation_config(scenario)
    checked = config.trajectory(sim.vehicle, sim.actuation, sim.initial.position, sim.initial.rotation)
    unchecked = Trajectory(config.waypoints, sim.initial.position, sim.initial.rotation,
                           full_attitude=sim.vehicle.fully_actuated, path=config.path)
    for field, value in checked.table()._asdict().items():
        assert np.array_equal(value, getattr(unchecked.table(), field), equal_nan=True), field


def test_modes_refuse_warn_stretch_before_take_off() -> None:
    leg = "trajectory.waypoints.0={position: [2, 3, -6], attitude_rpy_deg: [0, 0, 0], duration: 2.5}"
    with pytest.raises(ConfigError) as refused:
        controller_config(load_scenario("ex4_geometric", ex4_rotors(leg, "trajectory.feasibility=refuse")))
    message = str(refused.value)
    assert "trajectory.waypoints.0: leg 1 (2.5 s) needs" in message and "of roll torque" in message
    assert "refused (trajectory.feasibility: refuse)" in message
    (warned,) = controller_config(load_scenario("ex4_geometric", ex4_rotors(leg, "trajectory.feasibility=warn"))
                                  ).plan_adjustments
    (stretched,) = controller_config(load_scenario("ex4_geometric", ex4_rotors(leg))).plan_adjustments
    assert warned.action == "flown as written" and stretched.action == "stretched"
    assert warned.position_duration == stretched.position_duration == stretched.angle_duration > 2.5
    # wrench actuation: no rotor limits, nothing checked
    assert controller_config(load_scenario("ex4_geometric", [leg])).plan_adjustments == ()
    with pytest.raises(ConfigError, match="trajectory.feasibility: must be one of"):
        controller_config(load_scenario("ex4_geometric", ["trajectory.feasibility=maybe"]))


def test_goals_at_run_time_go_through_the_same_check() -> None:
    start = np.array((0.0, 0.0, -2.0))
    for mode in ("stretch", "refuse"):
        scenario = load_scenario("ex4_geometric", ex4_rotors(f"trajectory.feasibility={mode}",
                                                             "trajectory.waypoints=[]"))
        controller = FlightController(controller_config(scenario), QUAD, "rotors", start, np.eye(3))
        before = controller.trajectory.table()
        if mode == "refuse":
            with pytest.raises(InfeasibleReferenceError, match="goal at t = 1.000 s .* yaw torque"):
                controller.set_goal(start, yaw_rotation(math.radians(120.0)), now=1.0, duration=3.0)
            assert controller.trajectory.table() is before and controller.plan_adjustments == []
            continue
        controller.set_goal(start, yaw_rotation(math.radians(120.0)), now=1.0, duration=3.0)
        (adjustment,) = controller.plan_adjustments
        assert adjustment.label == "goal at t = 1.000 s" and adjustment.action == "shaped"
        assert controller.trajectory.end_time == pytest.approx(1.0 + adjustment.angle_duration, abs=1e-12)


def _yaw_flight(scenario: str, yaw_deg: float, duration: float, position: tuple, extra: dict) -> None:
    settings = {"actuation": "rotors", "trajectory.waypoints": [yaw_leg(yaw_deg, duration, position)], **extra}
    config = controller_config(load_scenario(scenario, [f"{k}={json.dumps(v)}" for k, v in settings.items()]))
    adjustments = config.plan_adjustments
    arrival = max([duration] + [a.angle_duration for a in adjustments])
    run = simulate(scenario, set=settings, duration=arrival + 3.0)
    assert run.end_reason == "finished", run.reason
    yaw = flown_yaw_deg(run)
    goal = math.degrees(math.remainder(math.radians(yaw_deg), 2 * math.pi))
    goal = 180.0 if goal == -180.0 else goal
    yaw_goal = yaw[0] + goal  # unwrapped from the start heading 0
    overshoot = (yaw.max() - yaw_goal) if goal > 0 else (yaw_goal - yaw.min())
    assert overshoot <= 2.0, f"{scenario} {yaw_deg} deg in {duration} s: overshoot {overshoot:.3f} deg"
    assert abs(yaw[-1] - yaw_goal) <= 0.01
    assert np.abs(run.position[-1] - np.array(position)).max() <= 1e-3
    assert run.saturation["count"] == 0, run.saturation


def test_the_issue_yaw_flight_arrives_without_overshoot_or_saturation() -> None:
    _yaw_flight("ex4_geometric", 150.0, 4.0, (3.0, -2.0, -4.0), {})


@pytest.mark.slow
@pytest.mark.parametrize("yaw_deg", [60.0, -60.0, 90.0, -90.0, 120.0, -120.0, 150.0, -150.0, 180.0, -180.0])
@pytest.mark.parametrize("duration", [2.0, 6.0])
@pytest.mark.parametrize("scenario,position,extra", [
    ("ex4_geometric", (3.0, -2.0, -4.0), {}),
    ("octo_ground_effect", (1.0, 1.0, -5.0), {"initial_state.position": [0, 0, -5],
                                              "environment.ground.effect": False}),
], ids=["quadrotor", "octocopter"])
def test_yaw_changes_beyond_the_authority_fly_without_overshoot(scenario: str, position: tuple, extra: dict,
                                                                yaw_deg: float, duration: float) -> None:
    _yaw_flight(scenario, yaw_deg, duration, position, extra)


def test_the_issue_translation_leg_is_stretched_and_flies_and_crashes_as_written() -> None:
    wp = {"position": [2.0, 3.0, -6.0], "attitude_rpy_deg": [0.0, 0.0, 0.0], "duration": 2.5}
    stretched = simulate("ex4_geometric", set={"actuation": "rotors", "trajectory.waypoints": [wp]}, duration=8.0)
    assert stretched.end_reason == "finished"
    assert np.abs(stretched.position[-1] - wp["position"]).max() <= 1e-3
    assert len(stretched.plan_adjustments) == 1 and "stretched to" in stretched.plan_adjustments[0]
    warned = simulate("ex4_geometric", set={"actuation": "rotors", "trajectory.waypoints": [wp],
                                            "trajectory.feasibility": "warn"}, duration=8.0)
    assert warned.end_reason == "diverged" and "flown as written" in warned.plan_adjustments[0]


def test_the_tilting_quadrotor_is_checked_for_its_force_set_and_its_torques() -> None:
    # 8 m sideways in 1 s, level: 90 N of body force mostly along x_b, where the tilting rotors give 37.6 N (two
    # rotors tilted sideways), though 66 N along -z_b: stretched, and then flown without saturation.
    sideways = {"position": [8.0, 0.0, -4.0], "attitude_rpy_deg": [0.0, 0.0, 0.0], "duration": 1.0}
    run = simulate("ex5_voliro", set={"trajectory.waypoints": [sideways]}, duration=4.0)
    (text,) = run.plan_adjustments
    assert "of body force along" in text and "stretched to" in text
    assert run.end_reason == "finished" and run.saturation["count"] == 0
    assert np.abs(run.position[-1] - sideways["position"]).max() <= 1e-3
    warned = simulate("ex5_voliro", set={"trajectory.waypoints": [sideways], "trajectory.feasibility": "warn"},
                      duration=4.0)
    assert "flown as written" in warned.plan_adjustments[0] and warned.saturation["count"] > 0
    # a quarter turn in roll in 0.1 s: the roll torque; the angle alone is shaped, the position keeps its time
    roll = {"position": [0.0, 0.0, -1.0], "attitude_rpy_deg": [90.0, 0.0, 0.0], "duration": 0.1}
    run = simulate("ex5_voliro", set={"trajectory.waypoints": [roll]}, duration=2.0)
    (text,) = run.plan_adjustments
    assert "roll torque" in text and "angle shaped" in text and run.saturation["count"] == 0
    assert Rotation.from_matrix(run.rotation[-1]).magnitude() == pytest.approx(math.pi / 2.0, abs=1e-4)
