"""Actuator dynamics of the true plant (fsr_sim.core.plant.actuators_at): rotor speeds and servo tilts follow
their commands through a first-order lag (and a rate limit for the servos), within their limits, exactly at
every RK4 stage; with no dynamics the plant is the plant without them, exactly."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from fsr_bringup import simulate
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError
from fsr_sim.model import load_vehicle
from fsr_sim.model.environment import Environment, Surface
from fsr_sim.model.plant import Plant

QUAD = load_vehicle("quadrotor_ex4")
TILTING = load_vehicle("tilting_quadrotor_ex5")
DT = 1e-3


def hover_speed(vehicle) -> float:
    return math.sqrt(vehicle.weight / (vehicle.rotor_count * vehicle.c_f))


def test_a_step_in_commanded_speed_gives_the_first_order_response():
    tau = 0.03
    plant = Plant(replace(QUAD, rotor_time_constant=tau), DT, position=(0.0, 0.0, -50.0))
    start, target = hover_speed(QUAD), 0.8 * QUAD.rotor_speed_max
    plant.set_rotor_command(np.full(4, start))  # the first command is also the rotors' state
    np.testing.assert_array_equal(plant.rotor_speeds, start)
    plant.set_rotor_command(np.full(4, target))
    np.testing.assert_array_equal(plant.rotor_speeds, start)  # a command does not move the rotors at once
    for k in range(1, 201):
        plant.step()
        expected = target + (start - target) * math.exp(-k * DT / tau)
        np.testing.assert_allclose(plant.rotor_speeds, expected, rtol=0.0, atol=1e-9)
    # beyond the limits: the command is clamped, the speed stays within
    plant.set_rotor_command(np.full(4, 2.0 * QUAD.rotor_speed_max))
    for _ in range(500):
        plant.step()
        assert plant.rotor_speeds.max() <= QUAD.rotor_speed_max
    assert plant.rotor_speeds.max() == pytest.approx(QUAD.rotor_speed_max, rel=1e-6)


def test_servo_lag_and_rate_limit():
    rate = math.radians(90.0)  # rad/s
    plant = Plant(replace(TILTING, tilt_time_constant=0.02, tilt_rate_max=rate), DT, position=(0.0, 0.0, -50.0))
    speeds = np.full(4, hover_speed(TILTING))
    plant.set_rotor_command(speeds, np.zeros(4))
    goal = np.array((0.5, -0.5, 0.01, -0.01))
    plant.set_rotor_command(speeds, goal)
    previous = plant.tilt_angles
    history = []
    for _ in range(800):
        plant.step()
        tilts = plant.tilt_angles
        assert np.all(np.abs(tilts - previous) <= rate * DT * (1 + 1e-12))
        history.append(tilts)
        previous = tilts
    history = np.array(history)
    # the large steps are rate limited (0.5 rad at 1.57 rad/s: > 0.3 s); the small ones (0.01 rad: at most 0.5
    # rad/s) lag: 1 - 1/e of the way after one time constant
    np.testing.assert_allclose(history[:10, 0], rate * DT * np.arange(1, 11), rtol=1e-12)
    expected_small = 0.01 * (1.0 - math.exp(-0.02 / 0.02))
    assert history[19, 2] == pytest.approx(expected_small, rel=1e-9)
    np.testing.assert_allclose(history[-1], goal, atol=1e-6)
    # a tilt command beyond the servo limit is clamped
    narrow = replace(TILTING, tilt_angle_max=math.radians(30.0), tilt_time_constant=0.01)
    plant = Plant(narrow, DT, position=(0.0, 0.0, -50.0))
    plant.set_rotor_command(speeds, np.zeros(4))
    plant.set_rotor_command(speeds, np.full(4, 2.0))
    for _ in range(300):
        plant.step()
        assert np.abs(plant.tilt_angles).max() <= narrow.tilt_angle_max
    assert plant.tilt_angles.max() == pytest.approx(narrow.tilt_angle_max, rel=1e-6)


def test_zero_time_constants_are_the_plant_without_dynamics_exactly():
    for name in ("ex4_geometric", "ex5_voliro"):
        plain = simulate(name, duration=2.0, set={"actuation": "rotors"})
        zero = simulate(name, duration=2.0, set={"actuation": "rotors", "plant.rotor_time_constant": 0.0,
                                                  "plant.tilt_time_constant": 0.0})
        np.testing.assert_array_equal(zero.state, plain.state)


def test_a_lagging_plant_still_flies_the_report_exercises():
    # 20 ms rotors and 50 ms servos at 3 rad/s: the controllers (which know nothing of the lag) still arrive
    quad = simulate("ex4_geometric", set={"actuation": "rotors", "plant.rotor_time_constant": 0.02})
    plain = simulate("ex4_geometric", set={"actuation": "rotors"})
    assert quad.end_reason == "finished"
    assert np.abs(quad.position[-1] - plain.position[-1]).max() < 1e-3
    assert np.abs(quad.state - plain.state).max() > 1e-6  # and the lag does act
    tilting = simulate("ex5_voliro", duration=25.0, set={
        "plant.rotor_time_constant": 0.02, "plant.tilt_time_constant": 0.05, "plant.tilt_rate_max_deg_s": 170.0})
    assert tilting.end_reason == "finished"
    assert np.abs(tilting.position[-1] - (1.0, 1.0, -4.0)).max() < 1e-3


def test_bad_values_are_refused_with_the_key():
    for key, value, message in (("plant.rotor_time_constant", -0.1, ">= 0"),
                                ("plant.tilt_rate_max_deg_s", 0.0, "> 0")):
        with pytest.raises(ConfigError, match=rf"{key.split('.')[1]}.*{message}"):
            simulation_config(load_scenario("ex5_voliro", [f"{key}={value}"]))
    with pytest.raises(ValueError, match="tilt_rate_max"):
        replace(TILTING, tilt_rate_max=0.0)


def test_a_lagging_wrench_gives_the_first_order_response_and_is_what_the_plant_flies():
    # wrench actuation with a rotor time constant: each component of the applied wrench lags its command
    tau = 0.025
    lagging = Plant(replace(QUAD, rotor_time_constant=tau), DT, actuation="wrench", position=(0.0, 0.0, -50.0))
    start = np.array((0.0, 0.0, -QUAD.weight, 0.01, -0.02, 0.005))
    target = np.array((0.0, 0.0, -1.3 * QUAD.weight, -0.03, 0.02, -0.01))
    lagging.set_wrench(start[:3], start[3:])  # the first command is also the applied wrench
    np.testing.assert_array_equal(lagging.applied_wrench, start)
    lagging.set_wrench(target[:3], target[3:])
    np.testing.assert_array_equal(lagging.applied_wrench, start)  # a command does not act at once
    for k in range(1, 201):
        lagging.step()
        expected = target + (start - target) * math.exp(-k * DT / tau)
        np.testing.assert_allclose(lagging.applied_wrench, expected, rtol=0.0, atol=1e-9)
    np.testing.assert_array_equal(lagging.force_command, target[:3])
    lagging.cut_thrust()  # the failsafe: the wrench decays to zero
    lagging.step()
    np.testing.assert_allclose(lagging.applied_wrench, expected * math.exp(-DT / tau), rtol=0.0, atol=1e-9)
    # What each RK4 step applies is the lag within it: for a force alone (level, no torque) the velocity changes
    # by dt (g e3 + f / m) with f the exact mean of the exponential over the step
    level = Plant(replace(QUAD, rotor_time_constant=tau), DT, actuation="wrench", position=(0.0, 0.0, -50.0))
    level.set_wrench(start[:3], (0.0, 0.0, 0.0))
    level.set_wrench(target[:3], (0.0, 0.0, 0.0))
    weight = tau / DT * (1.0 - math.exp(-DT / tau))
    for _ in range(50):
        applied, velocity = level.applied_wrench[:3], level.velocity.copy()
        level.step()
        mean = target[:3] + (applied - target[:3]) * weight
        np.testing.assert_allclose(level.velocity - velocity, DT * (mean / QUAD.mass + (0.0, 0.0, 9.81)),
                                   rtol=0.0, atol=1e-15)


def test_a_zero_time_constant_leaves_wrench_actuation_exactly_as_it_was():
    plain = simulate("ex3_estimation", duration=2.0)
    zero = simulate("ex3_estimation", duration=2.0, set={"plant.rotor_time_constant": 0.0})
    np.testing.assert_array_equal(zero.state, plain.state)
    np.testing.assert_array_equal(zero.estimate_force_body, plain.estimate_force_body)
    lagging = simulate("ex3_estimation", duration=2.0, set={"plant.rotor_time_constant": 0.03})
    assert lagging.end_reason == "finished" and np.abs(lagging.state - plain.state).max() > 1e-6


def vertical_flight(tau: float, dt: float, seconds: float, start: float, command: float) -> tuple[float, float]:
    """(v_z, z) after ``seconds`` of a level climb: the rotors from ``start`` to ``command`` [rad/s] with lag tau."""
    plant = Plant(replace(QUAD, rotor_time_constant=tau), dt, position=(0.0, 0.0, -50.0),
                  environment=Environment(ground=Surface(enabled=False)))
    plant.set_rotor_command(np.full(4, start))
    plant.set_rotor_command(np.full(4, command))
    for _ in range(int(round(seconds / dt))):
        plant.step()
    return float(plant.velocity[2]), float(plant.position[2])


def exact_vertical_flight(tau: float, seconds: float, start: float, command: float) -> tuple[float, float]:
    """The same from the closed form: ``w(t) = w_c + d exp(-t / tau)``, ``m v_z' = m g - 4 c_f w^2``."""
    d, t, k = start - command, seconds, 4.0 * QUAD.c_f / QUAD.mass
    if tau == 0.0:
        once, twice = command**2 * t, command**2 * t * t / 2.0
    else:
        once = command**2 * t + 2.0 * command * d * tau * -math.expm1(-t / tau) \
            + d * d * tau / 2.0 * -math.expm1(-2.0 * t / tau)
        twice = command**2 * t * t / 2.0 + 2.0 * command * d * (tau * t + tau * tau * math.expm1(-t / tau)) \
            + d * d * (tau * t / 2.0 + tau * tau / 4.0 * math.expm1(-2.0 * t / tau))
    return 9.81 * t - k * once, -50.0 + 9.81 * t * t / 2.0 - k * twice


def test_the_lag_is_integrated_to_fourth_order_within_each_step():
    # A step in the commanded speed with a 5 ms motor: each RK4 step applies the exact mean of the lagging thrust,
    # so the velocity is the closed form's to rounding, and the position's error falls as dt^4 (16x per halving).
    # Holding each step's speeds over it (the old integration) erred by half a step of lag: first order.
    hover = hover_speed(QUAD)
    velocity, position = exact_vertical_flight(0.005, 0.048, hover, 1.5 * hover)
    errors = []
    for dt in (4e-3, 2e-3, 1e-3):
        v, z = vertical_flight(0.005, dt, 0.048, hover, 1.5 * hover)
        assert v == pytest.approx(velocity, abs=1e-14)
        errors.append(abs(z - position))
    assert errors[0] > 1e-8  # 7.9e-8, 4.5e-9, 2.7e-10 m
    for coarse, fine in zip(errors, errors[1:], strict=False):
        assert 14.0 < coarse / fine < 20.0, errors


def test_a_time_constant_below_the_step_is_almost_no_lag():
    # tau -> 0 approaches tau = 0 as the physics does (the difference falls with tau, as the closed form's), not a
    # step's delay; at 1 ms a 0.1 ms motor is 0.1 ms of lag
    hover = hover_speed(QUAD)
    none = vertical_flight(0.0, 1e-3, 0.02, hover, 1.5 * hover)
    for tau in (1e-3, 1e-4, 1e-5):
        flown = vertical_flight(tau, 1e-3, 0.02, hover, 1.5 * hover)
        exact = exact_vertical_flight(tau, 0.02, hover, 1.5 * hover)
        assert flown[0] == pytest.approx(exact[0], abs=1e-14)
        assert abs(flown[1] - exact[1]) < 2e-7  # 8e-9, 1.2e-7, 1.4e-9 m
        np.testing.assert_allclose(np.subtract(flown, none), np.subtract(exact, exact_vertical_flight(
            0.0, 0.02, hover, 1.5 * hover)), rtol=5e-3)
