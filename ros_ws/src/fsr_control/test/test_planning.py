import math

import numpy as np
import pytest

from fsr_control.core import reference as core_reference
from fsr_control.planning.flatness import flat_attitude_rates
from fsr_control.planning.polynomial import SepticSegment
from fsr_control.planning.trajectory import Trajectory, Waypoint, yaw_rotation
from fsr_sim.model.so3 import rotation_from_euler_zyx, rotation_log, vee

START = np.array((0.0, 0.0, -1.0))
GOAL = np.array((1.0, 1.0, -4.0))


def test_rest_to_rest_boundary_conditions_and_midpoint():
    segment = SepticSegment(2.0, 10.0, START, GOAL)
    at_start, at_end = segment.evaluate(2.0), segment.evaluate(12.0)
    np.testing.assert_allclose(at_start[0], START, atol=1e-15)
    np.testing.assert_allclose(at_start[1:4], 0.0, atol=1e-15)  # velocity, acceleration, jerk
    np.testing.assert_allclose(at_end[0], GOAL, atol=1e-12)
    np.testing.assert_allclose(at_end[1:4], 0.0, atol=1e-12)
    # Just before the end the polynomial itself must also come to rest (not only the hold branch).
    np.testing.assert_allclose(segment.evaluate(12.0 - 1e-9)[1:4], 0.0, atol=1e-9)
    np.testing.assert_allclose(segment.evaluate(7.0)[0], (START + GOAL) / 2, atol=1e-12)  # s(1/2) = 1/2
    np.testing.assert_allclose(segment.evaluate(50.0)[0], GOAL)


def test_derivatives_match_finite_differences():
    segment = SepticSegment(0.0, 4.0, START, GOAL)
    h = 1e-5
    for t in (0.3, 1.7, 3.1):
        d = segment.evaluate(t)
        numeric = (segment.evaluate(t + h)[:4] - segment.evaluate(t - h)[:4]) / (2 * h)
        np.testing.assert_allclose(d[1:5], numeric, rtol=1e-6, atol=1e-8)


def test_progress_is_monotone():
    segment = SepticSegment(0.0, 20.0, START, GOAL)
    t = np.linspace(0.0, 20.0, 2001)
    positions = np.array([segment.evaluate(ti)[0] for ti in t])
    progress = (positions - START) @ (GOAL - START) / np.dot(GOAL - START, GOAL - START)
    assert np.all(np.diff(progress) >= -1e-15)
    assert progress[0] == 0.0 and progress[-1] == pytest.approx(1.0, abs=1e-12)
    # Straight line: no sideways motion.
    off_line = positions - START - np.outer(progress, GOAL - START)
    assert np.abs(off_line).max() < 1e-12


def test_moving_start_keeps_velocity_acceleration_and_jerk():
    rates = np.array([[0.5, -0.2], [0.1, 0.3], [-0.05, 0.02]])  # (3, channels)
    segment = SepticSegment(1.0, 5.0, np.array((2.0, -1.0)), np.array((4.0, 0.0)), rates)
    d0, d1 = segment.evaluate(1.0), segment.evaluate(6.0 - 1e-9)
    np.testing.assert_allclose(d0[0], (2.0, -1.0))
    np.testing.assert_allclose(d0[1:4], rates, atol=1e-12)
    np.testing.assert_allclose(d1[0], (4.0, 0.0), atol=1e-8)
    np.testing.assert_allclose(d1[1:4], 0.0, atol=1e-7)


def test_waypoints_with_hold_then_hold_after_last():
    waypoints = [
        Waypoint(GOAL, yaw_rotation(math.radians(20.0)), 10.0, 2.0),
        Waypoint(np.array((0.0, 2.0, -2.0)), None, 5.0, 0.0),
    ]
    trajectory = Trajectory(waypoints, START, np.eye(3), full_attitude=False)
    assert trajectory.end_time == pytest.approx(17.0)
    for t in (10.0, 11.0, 12.0):  # hold at the first waypoint
        ref = trajectory.evaluate(t)
        np.testing.assert_allclose(ref.position, GOAL, atol=1e-12)
        np.testing.assert_allclose(ref.velocity, 0.0, atol=1e-12)
        assert ref.yaw == pytest.approx(math.radians(20.0), abs=1e-12)
    ref = trajectory.evaluate(100.0)
    np.testing.assert_allclose(ref.position, (0.0, 2.0, -2.0), atol=1e-12)
    assert ref.yaw == pytest.approx(math.radians(20.0), abs=1e-12)  # attitude kept (None)
    # Evaluating back in time still works (the cursor resets).
    np.testing.assert_allclose(trajectory.evaluate(0.0).position, START)


def test_yaw_takes_the_short_way():
    trajectory = Trajectory([Waypoint(START, yaw_rotation(math.radians(-170.0)), 4.0)], START,
                            yaw_rotation(math.radians(170.0)), full_attitude=False)
    mid = trajectory.evaluate(2.0)
    assert math.degrees(mid.yaw) == pytest.approx(180.0, abs=1e-9)
    assert mid.yaw_rate > 0.0


def test_tilting_attitude_moves_about_one_fixed_axis():
    goal_rotation = rotation_from_euler_zyx(np.radians((45.0, 45.0, 0.0)))
    trajectory = Trajectory([Waypoint(GOAL, goal_rotation, 20.0)], START, np.eye(3), full_attitude=True)
    axis, angle = rotation_log(goal_rotation)
    h = 1e-5
    for t in (0.0, 3.0, 10.0, 17.5, 20.0, 25.0):
        ref = trajectory.evaluate(t)
        relative_axis, relative_angle = rotation_log(ref.rotation)
        if relative_angle > 1e-9:
            np.testing.assert_allclose(relative_axis, axis, atol=1e-9)  # R_0 = I: R_d = exp(theta S(a))
        # omega_d = a theta_dot (desired body frame), checked against R_d^T dR_d/dt.
        numeric = vee(ref.rotation.T @ (trajectory.evaluate(t + h).rotation
                                        - trajectory.evaluate(max(t - h, 0.0)).rotation) / (h + min(h, t)))
        np.testing.assert_allclose(ref.angular_velocity, numeric, atol=1e-8)
        assert np.linalg.norm(np.cross(ref.angular_velocity, axis)) < 1e-12
    np.testing.assert_allclose(trajectory.evaluate(20.0).rotation, goal_rotation, atol=1e-12)
    assert angle == pytest.approx(rotation_log(goal_rotation)[1])


def test_replan_from_moving_reference_is_smooth():
    trajectory = Trajectory([Waypoint(GOAL, yaw_rotation(0.5), 10.0)], START, np.eye(3), full_attitude=False)
    before = trajectory.evaluate(4.0)
    trajectory.replan(np.array((3.0, 0.0, -2.0)), yaw_rotation(-0.3), 4.0, 6.0)
    after = trajectory.evaluate(4.0)
    for name in ("position", "velocity", "acceleration", "jerk"):
        np.testing.assert_allclose(getattr(after, name), getattr(before, name), atol=1e-12)
    assert after.yaw == pytest.approx(before.yaw) and after.yaw_rate == pytest.approx(before.yaw_rate)
    end = trajectory.evaluate(10.0)
    np.testing.assert_allclose(end.position, (3.0, 0.0, -2.0), atol=1e-12)
    assert end.yaw == pytest.approx(-0.3, abs=1e-12)
    assert trajectory.end_time == pytest.approx(10.0)


def test_flat_attitude_rates_match_finite_differences():
    trajectory = Trajectory([Waypoint(GOAL, yaw_rotation(math.radians(20.0)), 5.0)], START, np.eye(3), False)

    def rates(t):
        r = trajectory.evaluate(t)
        return flat_attitude_rates(r.acceleration, r.jerk, r.snap, r.yaw, r.yaw_rate, r.yaw_acceleration)

    h = 1e-5
    for t in (0.7, 2.2, 4.1):
        rotation, omega, omega_dot = rates(t)
        r_plus, w_plus, _ = rates(t + h)
        r_minus, w_minus, _ = rates(t - h)
        np.testing.assert_allclose(omega, vee(rotation.T @ (r_plus - r_minus)) / (2 * h), atol=1e-8)
        np.testing.assert_allclose(omega_dot, (w_plus - w_minus) / (2 * h), atol=1e-7)
        np.testing.assert_allclose(rotation.T @ rotation, np.eye(3), atol=1e-14)


def test_the_horizon_holds_the_reference_ahead_row_by_row():
    """sample_horizon (compiled): row i is the reference at t + (i + 1) dt, across a segment's end and the hold."""
    goal_rotation = rotation_from_euler_zyx(np.radians((20.0, -10.0, 30.0)))
    trajectory = Trajectory([Waypoint(GOAL, goal_rotation, 2.0, 0.5), Waypoint(START, np.eye(3), 1.0)], START,
                            np.eye(3), full_attitude=True)
    layout = core_reference
    horizon = np.full((60, layout.HORIZON_WIDTH), np.nan)
    core_reference.sample_horizon(trajectory.table(), 1.3, 0.05, np.zeros((5, 4)), horizon)
    for i, row in enumerate(horizon):
        expected = trajectory.evaluate(1.3 + (i + 1) * 0.05)
        assert row[layout.HORIZON_TIME] == 1.3 + (i + 1) * 0.05
        for at, value in ((layout.HORIZON_POSITION, expected.position), (layout.HORIZON_VELOCITY, expected.velocity),
                          (layout.HORIZON_ACCELERATION, expected.acceleration),
                          (layout.HORIZON_ROTATION, expected.rotation.ravel()),
                          (layout.HORIZON_ANGULAR_VELOCITY, expected.angular_velocity)):
            np.testing.assert_allclose(row[at:at + len(value)], value, rtol=0, atol=1e-12)
        assert row[layout.HORIZON_YAW] == pytest.approx(expected.yaw, abs=1e-12)
    assert horizon[-1, layout.HORIZON_TIME] > 3.5  # the last rows hold the end pose
