"""The vehicles with published parameters (``hummingbird``, ``crazyflie``): they hover, and the geometric law flies
them with rotor actuation, their motor lag and aerodynamics on."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsr_bringup import simulate
from fsr_sim.model import load_vehicle
from fsr_sim.model.environment import Environment, Surface
from fsr_sim.model.plant import Plant

# Gains from each vehicle's mass and inertia, critically damped: k_p = m w_p^2, k_v = 2 m w_p and k_r = J w_r^2,
# k_w = 2 J w_r per axis. The Hummingbird (5 ms motors): w_p = 4, w_r = 20 (yaw 10) rad/s; the Crazyflie's
# 72 ms motors allow less: w_p = 1.5, w_r = 5 (yaw 3) rad/s.
GAINS = {
    "hummingbird": {"k_p": [8, 8, 8], "k_v": [4, 4, 4], "k_r": [1.46, 1.472, 0.703], "k_w": [0.146, 0.1472, 0.1406]},
    "crazyflie": {"k_p": [0.0675, 0.0675, 0.0675], "k_v": [0.09, 0.09, 0.09], "k_r": [3.575e-4, 3.575e-4, 2.601e-4],
                  "k_w": [1.43e-4, 1.43e-4, 1.734e-4]},
}


@pytest.mark.parametrize("name", ["hummingbird", "crazyflie"])
def test_the_vehicle_hovers_at_its_hover_speed(name):
    vehicle = load_vehicle(name)
    assert vehicle.rotor_time_constant > 0.0 and vehicle.has_aerodynamics
    hover = math.sqrt(vehicle.weight / (vehicle.rotor_count * vehicle.c_f))
    plant = Plant(vehicle, 0.001, position=(0.0, 0.0, -2.0), environment=Environment(ground=Surface(enabled=False)))
    plant.set_rotor_command(np.full(vehicle.rotor_count, hover))
    for _ in range(1000):
        plant.step()
    np.testing.assert_allclose(plant.position, (0.0, 0.0, -2.0), atol=1e-9)
    np.testing.assert_allclose(plant.angular_velocity, 0.0, atol=1e-12)


@pytest.mark.parametrize("name", ["hummingbird", "crazyflie"])
def test_the_geometric_law_flies_the_vehicle_with_rotor_actuation(name):
    run = simulate("ex4_geometric", duration=6.0, set={
        "vehicle": name, "actuation": "rotors", "initial_state.position": [0.0, 0.0, -1.0],
        "trajectory.waypoints": [{"position": [0.5, -0.3, -1.5], "attitude_rpy_deg": [0, 0, 30], "duration": 3.0}],
        "controller.gains": GAINS[name], "estimator.enabled": False})
    assert run.end_reason == "finished"
    assert np.abs(run.position - run.reference_position).max() < 0.05  # 0.017 m, 0.022 m
    np.testing.assert_allclose(run.position[-1], (0.5, -0.3, -1.5), atol=5e-3)
    assert run.actuator_dynamics  # the actual rotor speeds lag the commanded ones
