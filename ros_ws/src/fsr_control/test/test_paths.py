"""Paths at speed (trajectory.kind minsnap, circle, lissajous): the minimum-snap solution and its continuity, the
analytic derivatives of the periodic paths and their ramps, the yaw modes, replanning from mid-path, the
feasibility check of a path, and the trajectory section's validation."""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from fsr_control.config.controller_config import controller_config
from fsr_control.core import reference as core
from fsr_control.flight_controller import FlightController
from fsr_control.planning.feasibility import path_demand, reference_limits
from fsr_control.planning.minsnap import minimum_snap, peak_speed, snap_cost
from fsr_control.planning.paths import CIRCLE_NORMALS, CirclePath, LissajousPath, MinSnapPath, YawSpec
from fsr_control.planning.trajectory import Trajectory, Waypoint, yaw_rotation
from fsr_sim.config.scenario import scenario_from_mapping, simulation_config
from fsr_sim.config.validation import ConfigError
from fsr_sim.model import load_vehicle
from fsr_sim.model.so3 import rotation_from_euler_zyx

POINTS = np.array([[0.0, 0.0, -1.0], [2.0, 0.0, -2.0], [2.0, 3.0, -2.0], [-1.0, 2.0, -3.0], [0.0, 0.0, -1.5]])
DURATIONS = np.array([1.5, 2.0, 0.7, 3.0])
OCTO = load_vehicle("octocopter")


VELOCITY = YawSpec("velocity")


def circle(yaw: YawSpec = VELOCITY, rate: float = 1.5, laps: float = 2.0, ramp: float = 2.0,
           normal: tuple = CIRCLE_NORMALS["xy"]) -> CirclePath:
    return CirclePath(centre=np.array((0.0, 0.0, -2.0)), radius=2.0, normal=np.array(normal), rate=rate,
                      duration=laps * 2.0 * math.pi / rate + ramp, ramp=ramp, yaw=yaw)


def figure8(yaw: YawSpec = VELOCITY) -> LissajousPath:
    return LissajousPath(centre=np.array((0.0, 0.0, -2.0)), amplitude=np.array((2.0, 1.0, 0.3)),
                         frequency=2.0 * math.pi * np.array((0.25, 0.5, 0.25)), phase=np.array((0.0, 0.0, 0.5)),
                         duration=10.0, ramp=2.0, yaw=yaw)


def rows_at(table: core.TrajectoryTable, row: int, tau: float) -> np.ndarray:
    """(5, 4): the value and time derivatives 1..4 of a polynomial row's channels at ``tau`` (its coefficients)."""
    return table.coefficients[row] @ tau ** np.arange(core.DEGREE + 1)


def path_rows(trajectory: Trajectory, kind: float) -> list[int]:
    table = trajectory.table()
    return [row for row in range(len(table.start_time)) if table.path[row, core.PATH_KIND] == kind
            and table.path[row, core.PATH_END] > table.path[row, core.PATH_START]]


def test_minimum_snap_is_the_quadratic_program_s_minimum():
    """The C^6 spline of the linear system equals the minimiser of the snap integral under the QP's own
    constraints (positions, rest at both ends, continuity up to the jerk only) solved by its KKT system."""
    coefficients = minimum_snap(POINTS, DURATIONS)
    segments, size = len(DURATIONS), 8 * len(DURATIONS)
    cost = np.zeros((size, size))
    for i, duration in enumerate(DURATIONS):
        for k in range(4, 8):
            for m in range(4, 8):
                cost[8 * i + k, 8 * i + m] = math.perm(k, 4) * math.perm(m, 4) / (k + m - 7) / duration**7
    rows, targets = [], []

    def constraint(pieces: list[tuple[int, np.ndarray]], target: np.ndarray | float = 0.0) -> None:
        row = np.zeros(size)
        for segment, values in pieces:
            row[8 * segment:8 * segment + 8] += values
        rows.append(row)
        targets.append(np.broadcast_to(target, 3))

    at_one = np.array([[math.perm(k, n) for k in range(8)] for n in range(4)], dtype=float)
    for n in range(4):
        constraint([(0, np.eye(8)[n])], POINTS[0] if n == 0 else 0.0)
        constraint([(segments - 1, at_one[n])], POINTS[-1] if n == 0 else 0.0)
    for knot in range(1, segments):
        constraint([(knot - 1, at_one[0])], POINTS[knot])
        constraint([(knot, np.eye(8)[0])], POINTS[knot])
        for n in range(1, 4):
            constraint([(knot - 1, at_one[n] / DURATIONS[knot - 1] ** n),
                        (knot, -math.factorial(n) * np.eye(8)[n] / DURATIONS[knot] ** n)])
    a, b = np.array(rows), np.array(targets)
    kkt = np.block([[2.0 * cost, a.T], [a, np.zeros((len(a), len(a)))]])
    optimum = np.linalg.solve(kkt, np.vstack((np.zeros((size, 3)), b)))[:size]
    np.testing.assert_allclose(optimum.reshape(segments, 8, 3).transpose(0, 2, 1), coefficients, atol=1e-9)
    assert snap_cost(coefficients, DURATIONS) <= snap_cost(optimum.reshape(segments, 8, 3).transpose(0, 2, 1),
                                                           DURATIONS) * (1 + 1e-12)


def test_minsnap_passes_through_the_points_continuous_to_snap_and_at_rest_at_both_ends():
    path = MinSnapPath(points=POINTS[1:], durations=DURATIONS, speed=None)
    trajectory = Trajectory([], POINTS[0], np.eye(3), False, path=path)
    table = trajectory.table()
    rows = path_rows(trajectory, core.KIND_POLYNOMIAL)
    assert len(rows) == len(DURATIONS)
    np.testing.assert_allclose(rows_at(table, rows[0], 0.0)[0, :3], POINTS[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(rows_at(table, rows[0], 0.0)[1:4, :3], 0.0, atol=1e-9)  # at rest: v, a, j
    for knot, (left, right) in enumerate(zip(rows, rows[1:], strict=False), start=1):
        before, after = rows_at(table, left, 1.0), rows_at(table, right, 0.0)
        np.testing.assert_allclose(before[0, :3], POINTS[knot], rtol=0, atol=1e-9)
        np.testing.assert_allclose(after[0, :3], POINTS[knot], rtol=0, atol=1e-9)
        scale = np.abs(before[:, :3]).max(axis=1, keepdims=True) + 1.0
        np.testing.assert_allclose(before[:, :3] / scale, after[:, :3] / scale, rtol=0, atol=1e-9)
        assert table.start_time[right] == pytest.approx(table.start_time[left] + DURATIONS[knot - 1], abs=1e-12)
    end = rows_at(table, rows[-1], 1.0)
    np.testing.assert_allclose(end[0, :3], POINTS[-1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(end[1:4, :3], 0.0, atol=1e-9)
    assert trajectory.end_time == pytest.approx(DURATIONS.sum())
    final = trajectory.evaluate(trajectory.end_time + 1.0)  # then held at rest
    np.testing.assert_allclose(final.position, POINTS[-1], atol=1e-9)
    assert not final.velocity.any() and not final.snap.any()


def test_minsnap_times_from_a_speed_peak_at_that_speed():
    path = MinSnapPath(points=POINTS[1:], durations=None, speed=3.0)
    shape = path.shape(POINTS[0])
    assert peak_speed(shape.coefficients, shape.row_durations) == pytest.approx(3.0, rel=1e-9)
    distances = np.linalg.norm(np.diff(POINTS, axis=0), axis=1)
    np.testing.assert_allclose(shape.row_durations / distances, shape.row_durations[0] / distances[0], rtol=1e-12)
    trajectory = Trajectory([], POINTS[0], np.eye(3), False, path=path)
    speeds = [np.linalg.norm(trajectory.evaluate(t).velocity) for t in np.linspace(0.0, trajectory.end_time, 4001)]
    assert max(speeds) == pytest.approx(3.0, rel=1e-4)


def finite_difference_check(trajectory: Trajectory, times: np.ndarray, h: float = 1e-4) -> None:
    """Each derivative of the position (velocity .. snap) against central differences of the one below it."""
    names = ("position", "velocity", "acceleration", "jerk", "snap")
    for t in times:
        at, plus, minus = trajectory.evaluate(t), trajectory.evaluate(t + h), trajectory.evaluate(t - h)
        for lower, upper in zip(names, names[1:], strict=False):
            numeric = (getattr(plus, lower) - getattr(minus, lower)) / (2.0 * h)
            analytic = getattr(at, upper)
            scale = 1.0 + np.abs(analytic).max()
            np.testing.assert_allclose(numeric, analytic, rtol=0, atol=2e-6 * scale, err_msg=f"{upper} at {t}")
        for lower, upper in (("yaw", "yaw_rate"), ("yaw_rate", "yaw_acceleration")):
            step = getattr(plus, lower) - getattr(minus, lower)
            if lower == "yaw":
                step = math.remainder(step, 2.0 * math.pi)
            assert step / (2.0 * h) == pytest.approx(getattr(at, upper), abs=2e-6 * (1.0 + abs(getattr(at, upper)))
                                                     ), f"{upper} at {t}"


@pytest.mark.parametrize("yaw", [YawSpec("velocity"), YawSpec("rate", rate=0.4), YawSpec("fixed", 0.3)],
                         ids=["velocity", "rate", "fixed"])
@pytest.mark.parametrize("kind", ["circle", "lissajous"])
def test_periodic_paths_analytic_derivatives_equal_finite_differences(kind: str, yaw: YawSpec):
    path = circle(yaw) if kind == "circle" else figure8(yaw)
    start = path.start_point(np.zeros(3)) if kind == "lissajous" else np.array((2.0, 0.0, -2.0))
    trajectory = Trajectory([], start, yaw_rotation(0.3 if yaw.mode == "fixed" else 0.0), False, path=path)
    (row,) = path_rows(trajectory, core.KIND_PERIODIC)
    table = trajectory.table()
    begin, end = table.path[row, core.PATH_START], table.path[row, core.PATH_END]
    ramp = table.path[row, core.PATH_RAMP]
    times = np.concatenate((begin + np.array((0.01, 0.3, 0.5, 0.97, 1.7, 1.99)) * ramp, np.linspace(begin + ramp,
                            end - ramp, 7)[1:-1], end - np.array((1.99, 1.3, 0.5, 0.02)) * ramp))
    finite_difference_check(trajectory, times)
    for t in (begin, end):  # from hover, to rest: every derivative zero, yaw rate and acceleration too
        reference = trajectory.evaluate(t)
        for name in ("velocity", "acceleration", "jerk", "snap"):
            np.testing.assert_allclose(getattr(reference, name), 0.0, atol=1e-12)
        assert reference.yaw_rate == pytest.approx(0.0, abs=1e-12)
        assert reference.yaw_acceleration == pytest.approx(0.0, abs=1e-12)
    for t in (begin + ramp, end - ramp):  # the ramps join the cruise: continuous to the snap
        left, right = trajectory.evaluate(t - 1e-9), trajectory.evaluate(t + 1e-9)
        for name in ("velocity", "acceleration", "jerk", "snap"):
            np.testing.assert_allclose(getattr(left, name), getattr(right, name), atol=1e-6)


def test_circle_geometry_speed_and_direction():
    path = circle(YawSpec("fixed"), rate=1.5)
    trajectory = Trajectory([], np.array((2.0, 0.0, -2.0)), np.eye(3), False, path=path)
    (row,) = path_rows(trajectory, core.KIND_PERIODIC)
    table = trajectory.table()
    begin, end = table.path[row, core.PATH_START], table.path[row, core.PATH_END]
    for t in np.linspace(begin, end, 200):
        reference = trajectory.evaluate(t)
        assert np.linalg.norm(reference.position - (0.0, 0.0, -2.0)) == pytest.approx(2.0, abs=1e-12)
    cruise = trajectory.evaluate(0.5 * (begin + end))
    assert np.linalg.norm(cruise.velocity) == pytest.approx(3.0, abs=1e-12)  # speed = radius x rate
    assert np.linalg.norm(cruise.acceleration) == pytest.approx(4.5, abs=1e-9)  # v^2 / R
    # counterclockwise seen from above (north up, east right): from north, first towards the west
    assert trajectory.evaluate(begin + 2.0).velocity[1] < 0.0
    np.testing.assert_allclose(trajectory.evaluate(end).position, (2.0, 0.0, -2.0), atol=1e-9)  # two whole laps
    assert cruise.yaw == pytest.approx(0.0, abs=1e-12)


def test_a_path_away_from_the_start_is_approached_and_yaw_velocity_faces_the_motion():
    trajectory = Trajectory([], np.array((0.0, 0.0, -1.0)), np.eye(3), False, path=circle())
    table = trajectory.table()
    assert table.path[1, core.PATH_KIND] == core.KIND_POLYNOMIAL and table.path[1, core.PATH_YAW] == core.YAW_CHANNEL
    (row,) = path_rows(trajectory, core.KIND_PERIODIC)
    begin = table.path[row, core.PATH_START]
    at_start = trajectory.evaluate(begin)
    np.testing.assert_allclose(at_start.position, (2.0, 0.0, -2.0), atol=1e-12)  # the point nearest the start
    assert math.remainder(at_start.yaw + math.pi / 2, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)  # faces west
    for t in np.linspace(begin + 2.0, table.path[row, core.PATH_END] - 2.0, 50):  # between the ramps
        reference = trajectory.evaluate(t)
        heading = math.atan2(reference.velocity[1], reference.velocity[0])
        assert math.remainder(reference.yaw - heading, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def test_a_vertical_path_has_no_heading_to_follow():
    from fsr_control.planning.paths import PathError

    with pytest.raises(PathError, match="no horizontal direction of motion"):
        Trajectory([], np.array((2.0, 0.0, -2.0)), np.eye(3), False, path=circle(normal=CIRCLE_NORMALS["xz"]))
    Trajectory([], np.array((2.0, 0.0, -2.0)), np.eye(3), False,
               path=circle(YawSpec("fixed"), normal=CIRCLE_NORMALS["xz"]))  # a fixed yaw flies it


def test_a_fully_actuated_vehicle_keeps_its_tilt_and_turns_about_the_vertical():
    tilted = rotation_from_euler_zyx(np.radians((10.0, -5.0, 30.0)))
    trajectory = Trajectory([], np.array((2.0, 0.0, -2.0)), tilted, True, path=circle(YawSpec("rate", rate=0.5)))
    (row,) = path_rows(trajectory, core.KIND_PERIODIC)
    begin = trajectory.table().path[row, core.PATH_START]
    for t in np.linspace(begin, begin + 8.0, 9):
        reference = trajectory.evaluate(t)
        turn = reference.yaw - math.radians(30.0)
        np.testing.assert_allclose(reference.rotation, yaw_rotation(turn) @ tilted, atol=1e-12)
        assert reference.yaw_rate == pytest.approx(np.linalg.norm(reference.rotation @ reference.angular_velocity))


@pytest.mark.parametrize("kind", ["circle", "minsnap"])
def test_a_goal_mid_path_is_planned_from_the_reference(kind: str):
    quad = load_vehicle("quadrotor_ex4")
    scenario = scenario_from_mapping({
        "name": "mid_path", "vehicle": "octocopter", "duration": 20.0, "initial_state": {"position": [2, 0, -2]},
        "trajectory": {"kind": "circle", "centre": [0, 0, -2], "radius": 2, "speed": 2, "laps": 2,
                       "yaw": "velocity"} if kind == "circle" else
                      {"kind": "minsnap", "waypoints": [{"position": list(p)} for p in POINTS[1:] + (2, 0, -1)],
                       "speed": 2.0, "yaw": {"mode": "rate", "rate_deg_s": 10}},
        "controller": {"type": "geometric"}, "estimator": {"enabled": False}})
    config = controller_config(scenario)
    sim = simulation_config(scenario)
    controller = FlightController(config, quad, "wrench", sim.initial.position, sim.initial.rotation)
    now = 5.0
    before = controller.reference(now)
    assert np.linalg.norm(before.velocity) > 0.5
    controller.set_goal(np.array((0.0, 0.0, -3.0)), yaw_rotation(1.0), now=now, duration=6.0)
    after = controller.reference(now)
    for name in ("position", "velocity", "acceleration", "jerk"):
        np.testing.assert_allclose(getattr(after, name), getattr(before, name), atol=1e-9)
    assert after.yaw_rate == pytest.approx(before.yaw_rate, abs=1e-9)
    assert math.remainder(after.yaw - before.yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    final = controller.reference(now + 6.0)
    np.testing.assert_allclose(final.position, (0.0, 0.0, -3.0), atol=1e-9)
    assert math.remainder(final.yaw - 1.0, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    assert controller.trajectory.end_time == pytest.approx(now + 6.0)


def circle_scenario(speed: float, **extra: object) -> dict:
    return {"name": "fast_circle", "vehicle": "octocopter", "duration": 20.0, "actuation": "rotors",
            "initial_state": {"position": [2, 0, -2]},
            "trajectory": {"kind": "circle", "centre": [0, 0, -2], "radius": 2.0, "speed": speed, "laps": 2,
                           **extra},
            "controller": {"type": "geometric"}, "estimator": {"enabled": False}}


def test_feasibility_refuses_stretches_or_flies_an_over_fast_circle_as_it_does_a_leg():
    """8 m/s on a 2 m circle asks 32 m/s^2 sideways: 83.7 N of thrust from the octocopter's 77.8 N (61.8 with the
    margin 0.7), and its tilt of 73 deg turning at 4 rad/s asks torques beyond them too."""
    with pytest.raises(ConfigError) as refused:
        controller_config(scenario_from_mapping(circle_scenario(8.0, feasibility="refuse")))
    message = str(refused.value)
    assert "trajectory.speed: circle path (3.927 s) needs 83.7 N of thrust, the rotors give 77.8 N" in message
    assert "refused (trajectory.feasibility: refuse)" in message
    written = controller_config(scenario_from_mapping(circle_scenario(8.0, feasibility="warn")))
    (warned,) = written.plan_adjustments
    assert warned.action == "flown as written" and warned.label == "circle path"
    stretched = controller_config(scenario_from_mapping(circle_scenario(8.0)))
    (adjustment,) = stretched.plan_adjustments
    assert adjustment.action == "stretched" and adjustment.position_duration > adjustment.duration
    assert f"stretched to {adjustment.position_duration:.2f} s" in adjustment.text()
    factor = adjustment.position_duration / adjustment.duration
    sim = simulation_config(scenario_from_mapping(circle_scenario(8.0)))
    trajectory = stretched.trajectory(OCTO, "rotors", sim.initial.position, sim.initial.rotation)
    limits = reference_limits(OCTO, 0.7)
    table = trajectory.table()
    assert not path_demand(table, limits).shortfalls(limits)  # the flown path is within the authority
    (row,) = path_rows(trajectory, core.KIND_PERIODIC)
    cruise = trajectory.evaluate(0.5 * (table.path[row, core.PATH_START] + table.path[row, core.PATH_END]))
    assert np.linalg.norm(cruise.velocity) == pytest.approx(8.0 / factor, rel=1e-9)  # the same circle, slower
    assert trajectory.end_time == pytest.approx(adjustment.position_duration, abs=1e-9)
    assert controller_config(scenario_from_mapping(circle_scenario(3.0))).plan_adjustments == ()


SOURCE = "<python>"


@pytest.mark.parametrize(("trajectory", "key", "reason"), [
    ({"kind": "circle", "centre": [0, 0, -2], "raduis": 2, "speed": 1}, "trajectory.radius",
     "is required (found unknown key 'raduis': a typo?)"),
    ({"kind": "circle", "centre": [0, 0, -2], "radius": 2, "speed": 1, "lap": 2}, "trajectory.lap",
     "did you mean 'laps'"),
    ({"kind": "circle", "centre": [0, 0, -2], "radius": 2}, "trajectory.speed", "is required (or period)"),
    ({"kind": "circle", "centre": [0, 0, -2], "radius": 2, "speed": 1, "period": 3}, "trajectory.period",
     "give speed or period, not both"),
    ({"kind": "circle", "centre": [0, 0, -2], "radius": 2, "speed": 1, "laps": 1, "duration": 9},
     "trajectory.duration", "give laps or duration, not both"),
    ({"kind": "circle", "centre": [0, 0, -2], "radius": 2, "speed": 1, "laps": 0.5, "ramp": 9}, "trajectory.ramp",
     "must be at most the laps' time"),
    ({"kind": "circle", "centre": [0, 0, -2], "radius": 2, "speed": 1, "plane": "ab"}, "trajectory.plane",
     "must be one of xy, xz, yz"),
    ({"kind": "circle", "centre": [0, 0, -2], "radius": 2, "speed": 1, "normal": [0, 0, 0]}, "trajectory.normal",
     "must not be zero"),
    ({"kind": "circle", "centre": [0, 0, -2], "radius": 2, "speed": 1, "yaw": "sideways"}, "trajectory.yaw.mode",
     "must be one of fixed, velocity, rate"),
    ({"kind": "circle", "centre": [0, 0, -2], "radius": 2, "speed": 1, "yaw": {"mode": "rate"}},
     "trajectory.yaw.rate_deg_s", "is required"),
    ({"kind": "circle", "centre": [0, 0, -2], "radius": 2, "speed": 1, "yaw": {"mode": "velocity", "yaw_deg": 3}},
     "trajectory.yaw.yaw_deg", "is for mode fixed"),
    ({"kind": "circle", "centre": [0, 0, -2], "radius": 2, "speed": 1, "waypoints": []}, "trajectory.waypoints",
     "is a key of kind waypoints and minsnap, not of kind circle"),
    ({"kind": "waypoints", "speed": 1}, "trajectory.speed", "is a key of kind minsnap and circle, not of kind"),
    ({"kind": "spiral"}, "trajectory.kind", "must be one of waypoints, minsnap, circle, lissajous"),
    ({"kind": "lissajous", "centre": [0, 0, -2], "amplitude": [1, 1, 0], "frequency": [0.2, 0.2 * 2 ** 0.5, 0]},
     "trajectory.laps", "no common period"),
    ({"kind": "lissajous", "centre": [0, 0, -2], "amplitude": [0, 0, 0], "frequency": [1, 1, 1]},
     "trajectory.amplitude", "no axis moves"),
    ({"kind": "minsnap", "waypoints": [{"position": [1, 0, -2]}]}, "trajectory.speed", "is required"),
    ({"kind": "minsnap", "waypoints": [{"position": [1, 0, -2], "duration": 2}, {"position": [2, 0, -2]}]},
     "trajectory.waypoints.1.duration", "give every point a duration, or none"),
    ({"kind": "minsnap", "speed": 2, "waypoints": [{"position": [1, 0, -2]}, {"position": [1, 0, -2]}]},
     "trajectory.waypoints.1.position", "is the point before it"),
    ({"kind": "minsnap", "speed": 2, "waypoints": [{"position": [0, 0, -2]}]},
     "trajectory.waypoints.0.position", "is the start (initial_state.position)"),
    ({"kind": "minsnap", "speed": 2, "waypoints": [{"position": [1, 0, -2], "hold": 1}]},
     "trajectory.waypoints.0.hold", "is for kind waypoints"),
    ({"kind": "minsnap", "speed": 2, "ramp": 5, "waypoints": [{"position": [1, 0, -2]}]}, "trajectory.ramp",
     "must be at most half the path's duration"),
    ({"kind": "minsnap", "speed": 2, "yaw": "velocity", "waypoints": [{"position": [0, 0, -3]}]}, "trajectory.yaw",
     "no horizontal direction of motion"),
])
def test_every_trajectory_key_is_validated_with_file_and_key(trajectory: dict, key: str, reason: str):
    scenario = scenario_from_mapping({"name": "bad", "vehicle": "octocopter", "duration": 5.0,
                                      "initial_state": {"position": [0, 0, -2]}, "trajectory": trajectory,
                                      "controller": {"type": "geometric"}, "estimator": {"enabled": False}},
                                     source="paths.yaml")
    with pytest.raises(ConfigError) as error:
        controller_config(scenario)
    assert error.value.key == key and reason in error.value.reason, str(error.value)
    assert str(error.value).startswith(f"paths.yaml: {key}: ") and "\n" not in str(error.value)


def test_every_example_of_docs_scenarios_is_a_valid_trajectory():
    """The YAML examples of each kind in docs/scenarios.md (*Trajectories*) validate as written."""
    text = (Path(__file__).parents[4] / "docs" / "scenarios.md").read_text(encoding="utf-8")
    examples = [yaml.safe_load(block)["trajectory"] for block in re.findall(r"^```yaml\n(.*?)^```", text, re.S | re.M)
                if block.startswith("trajectory:") and "kind:" in block]
    assert sorted(example["kind"] for example in examples) == ["circle", "lissajous", "minsnap"]
    for example in examples:
        scenario = scenario_from_mapping({"name": "docs", "vehicle": "octocopter", "duration": 60.0,
                                          "initial_state": {"position": [0, 0, -2]}, "trajectory": example,
                                          "controller": {"type": "geometric"}, "estimator": {"enabled": False}})
        config = controller_config(scenario)
        assert config.trajectory_kind == example["kind"] and config.plan_end_time > 5.0


SAMPLED = """
import json, sys
sys.path.insert(0, sys.argv[1])
from test_paths import sampled_references
print(json.dumps(sampled_references()))
"""


def sampled_references() -> list[float]:
    """Every kind and yaw mode (and a goal replanned mid-path) sampled by the compiled core's sample_reference and
    sample_horizon, as one list of floats."""
    start = np.array((2.0, 0.0, -2.0))
    trajectories = [
        Trajectory([Waypoint(np.array((1.0, 1.0, -4.0)), yaw_rotation(0.3), 5.0, 1.0)], start, np.eye(3), False),
        Trajectory([Waypoint(np.array((1.0, 1.0, -4.0)), rotation_from_euler_zyx((0.5, 0.5, 0.0)), 5.0)], start,
                   np.eye(3), True),
        Trajectory([], start, np.eye(3), False, path=MinSnapPath(points=POINTS[1:] + (2, 0, -1), durations=DURATIONS,
                                                                 speed=None, yaw=YawSpec("velocity"))),
        Trajectory([], start, np.eye(3), False, path=MinSnapPath(points=POINTS[1:] + (2, 0, -1), durations=None,
                                                                 speed=2.0, yaw=YawSpec("rate", rate=0.3))),
        Trajectory([], start, np.eye(3), False, path=circle()),
        Trajectory([], np.zeros(3), yaw_rotation(1.0), False, path=figure8(YawSpec("rate", rate=0.2))),
        Trajectory([], start, rotation_from_euler_zyx((0.1, 0.0, 0.2)), True, path=figure8(YawSpec("velocity"))),
    ]
    replanned = Trajectory([], start, np.eye(3), False, path=circle())
    replanned.replan(np.zeros(3) + (0.0, 0.0, -3.0), yaw_rotation(2.0), 7.3, 4.0)
    trajectories.append(replanned)
    values: list[float] = []
    scratch = np.zeros((core.DERIVATIVES, core.CHANNELS))
    horizon = np.zeros((20, core.HORIZON_WIDTH))
    for trajectory in trajectories:
        table = trajectory.table()
        for t in np.linspace(-0.5, trajectory.end_time + 1.0, 613):
            values += [value for part in core.sample_reference(table, t, scratch)
                       for value in np.ravel(np.asarray(part, dtype=float)).tolist()]
        core.sample_horizon(table, 3.7, 0.05, scratch, horizon)
        values += horizon.ravel().tolist()
    return values


@pytest.mark.slow
def test_the_compiled_sampler_equals_cpython_for_every_kind():
    """The core's sampler of every kind and yaw mode, compiled and under CPython (NUMBA_DISABLE_JIT=1): the same
    numbers, bit for bit."""
    results = []
    for disable in ("0", "1"):
        out = subprocess.run([sys.executable, "-c", SAMPLED, str(Path(__file__).parent)], capture_output=True,
                             text=True, check=True, timeout=600, env={**os.environ, "NUMBA_DISABLE_JIT": disable})
        results.append(np.array(json.loads(out.stdout)))
    compiled, python = results
    assert compiled.shape == python.shape and len(compiled) > 100_000
    assert np.array_equal(compiled, python), np.abs(compiled - python).max()
