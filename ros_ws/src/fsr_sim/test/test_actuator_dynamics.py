"""Actuator dynamics of the true plant (fsr_sim.core.plant.advance_actuators): rotor speeds and servo tilts follow
their commands through a first-order lag (and a rate limit for the servos), within their limits; with no
dynamics the plant is the plant without them, exactly."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from fsr_bringup import simulate
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError
from fsr_sim.model import load_vehicle
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
    plain = Plant(QUAD, DT, actuation="wrench", position=(0.0, 0.0, -50.0))  # flown with the applied wrench
    start = np.array((0.0, 0.0, -QUAD.weight, 0.01, -0.02, 0.005))
    target = np.array((0.0, 0.0, -1.3 * QUAD.weight, -0.03, 0.02, -0.01))
    lagging.set_wrench(start[:3], start[3:])  # the first command is also the applied wrench
    np.testing.assert_array_equal(lagging.applied_wrench, start)
    lagging.set_wrench(target[:3], target[3:])
    np.testing.assert_array_equal(lagging.applied_wrench, start)  # a command does not act at once
    for k in range(1, 201):
        applied = lagging.applied_wrench
        plain.set_wrench(applied[:3], applied[3:])
        lagging.step()
        plain.step()
        expected = target + (start - target) * math.exp(-k * DT / tau)
        np.testing.assert_allclose(lagging.applied_wrench, expected, rtol=0.0, atol=1e-9)
        np.testing.assert_array_equal(lagging.state_vector, plain.state_vector)
    np.testing.assert_array_equal(lagging.force_command, target[:3])
    lagging.cut_thrust()  # the failsafe: the wrench decays to zero
    lagging.step()
    np.testing.assert_allclose(lagging.applied_wrench, expected * math.exp(-DT / tau), rtol=0.0, atol=1e-9)


def test_a_zero_time_constant_leaves_wrench_actuation_exactly_as_it_was():
    plain = simulate("ex3_estimation", duration=2.0)
    zero = simulate("ex3_estimation", duration=2.0, set={"plant.rotor_time_constant": 0.0})
    np.testing.assert_array_equal(zero.state, plain.state)
    np.testing.assert_array_equal(zero.estimate_force_body, plain.estimate_force_body)
    lagging = simulate("ex3_estimation", duration=2.0, set={"plant.rotor_time_constant": 0.03})
    assert lagging.end_reason == "finished" and np.abs(lagging.state - plain.state).max() > 1e-6
