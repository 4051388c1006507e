"""Aerodynamics at speed (fsr_sim.core.aerodynamics): the parasitic drag ``-|v_a| C v_a`` in still air and in a
wind, each rotor term against a hand computation, what wrench_truth holds, and what the plant feels."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from fsr_sim.model import load_vehicle
from fsr_sim.model.environment import Environment, Surface
from fsr_sim.model.plant import Plant
from fsr_sim.model.so3 import rotation_from_euler_zyx
from fsr_sim.model.turbulence import DrydenTurbulence

HUMMINGBIRD = load_vehicle("hummingbird")
FREE = Environment(ground=Surface(enabled=False))
NONE = {"drag_coefficients": np.zeros(3), "rotor_drag_coefficient": 0.0, "induced_inflow_coefficient": 0.0,
        "translational_lift_coefficient": 0.0, "flapping_coefficient": 0.0}


def plant(vehicle, actuation="rotors", speeds=None, **state):  # noqa: ANN001, ANN201
    made = Plant(vehicle, 0.001, actuation=actuation, position=(0.0, 0.0, -10.0), environment=FREE, **state)
    if actuation == "rotors":
        made.set_rotor_command(np.full(vehicle.rotor_count, 500.0) if speeds is None else speeds)
    return made


def body_wrench(made: Plant) -> tuple[np.ndarray, np.ndarray]:
    force_world, torque = made.external_wrench()
    return made.rotation.T @ force_world, torque


def test_the_parasitic_drag_acts_in_still_air_as_rotorpys_law():
    drag = np.array((0.02, 0.02, 0.05))
    vehicle = replace(HUMMINGBIRD, **{**NONE, "drag_coefficients": drag})
    # along a body axis: -c v |v|
    force, torque = body_wrench(plant(vehicle, velocity=(3.0, 0.0, 0.0)))
    np.testing.assert_allclose(force, (-0.02 * 9.0, 0.0, 0.0), rtol=1e-15)
    np.testing.assert_array_equal(torque, 0.0)
    # at 45 deg between two body axes: RotorPy's -|v| C v (|f| = c |v|^2), not 0.71 of it as per axis
    v = 4.0 * np.array((math.sqrt(0.5), math.sqrt(0.5), 0.0))
    force, _ = body_wrench(plant(vehicle, velocity=v))
    np.testing.assert_allclose(force, -np.linalg.norm(v) * drag * v, rtol=1e-14)
    assert np.linalg.norm(force) == pytest.approx(0.02 * 16.0, rel=1e-14)
    # turned: the law holds in the body frame, v_a = R^T v
    rotation = rotation_from_euler_zyx(np.radians((20.0, -35.0, 50.0)))
    v = np.array((2.0, -1.0, 0.5))
    force, _ = body_wrench(plant(vehicle, velocity=v, rotation=rotation))
    air = rotation.T @ v
    np.testing.assert_allclose(force, -np.linalg.norm(air) * drag * air, rtol=1e-13, atol=1e-16)
    # in wrench actuation (no rotors modelled) the airframe's drag still acts, the rotor terms do not
    both = replace(HUMMINGBIRD, drag_coefficients=drag)
    force, torque = body_wrench(plant(both, actuation="wrench", velocity=v, rotation=rotation))
    np.testing.assert_allclose(force, -np.linalg.norm(air) * drag * air, rtol=1e-13, atol=1e-16)
    np.testing.assert_array_equal(torque, 0.0)


def test_each_rotor_term_against_a_hand_computation():
    # Level, no rotation, 2 m/s forward, 1 m/s down: every rotor sees v_i = (2, 0, 1) (body FRD), axis z_i = -e3,
    # so its in-plane air velocity is (2, 0, 0) and its axial one v . z = -1. Rotor speeds 400, 500, 600, 700.
    speeds = np.array((400.0, 500.0, 600.0, 700.0))
    p = HUMMINGBIRD.positions
    w_sum, moment_y, moment_x = speeds.sum(), (speeds * p[:, 1]).sum(), (speeds * p[:, 0]).sum()
    cases = {
        # H-force -w k_d (2, 0, 0) at each hub: force x -2 k_d sum w; torque p x H = (0, 0, -p_y H_x)
        "rotor_drag_coefficient": (1e-4, (-2e-4 * w_sum, 0.0, 0.0), (0.0, 0.0, 2e-4 * moment_y)),
        # inflow -w k_z (v . z) z = -w k_z (-1)(0, 0, -1) = (0, 0, -w k_z): torque p x (0, 0, f) = (p_y f, -p_x f, 0)
        "induced_inflow_coefficient": (2e-4, (0.0, 0.0, -2e-4 * w_sum), (-2e-4 * moment_y, 2e-4 * moment_x, 0.0)),
        # lift k_h |v_p|^2 along z_i: (0, 0, -4 k_h) each, whatever the speed; the symmetric hubs cancel its torque
        "translational_lift_coefficient": (3e-3, (0.0, 0.0, -4 * 4 * 3e-3), (0.0, 0.0, 0.0)),
        # flapping -k_flap w (v x z) = -k_flap w ((2, 0, 1) x (0, 0, -1)) = -k_flap w (0, 2, 0): a pure torque
        "flapping_coefficient": (1e-6, (0.0, 0.0, 0.0), (0.0, -2e-6 * w_sum, 0.0)),
    }
    for name, (value, force, torque) in cases.items():
        vehicle = replace(HUMMINGBIRD, **{**NONE, name: value})
        got_force, got_torque = body_wrench(plant(vehicle, speeds=speeds, velocity=(2.0, 0.0, 1.0)))
        np.testing.assert_allclose(got_force, force, rtol=1e-13, atol=1e-17, err_msg=name)
        np.testing.assert_allclose(got_torque, torque, rtol=1e-13, atol=1e-17, err_msg=name)


def reference_wrench(vehicle, speeds, rotation, velocity, omega, wind, axes):  # noqa: ANN001, ANN201
    """RotorPy's compute_body_wrench, written out with numpy for rotor axes ``axes`` (n, 3) body FRD."""
    air = rotation.T @ (np.asarray(velocity) - wind)
    local = air + np.cross(omega, vehicle.positions)
    axial = np.sum(local * axes, axis=1)
    in_plane = local - axial[:, None] * axes
    rotor = -speeds[:, None] * (vehicle.rotor_drag_coefficient * in_plane
                                + vehicle.induced_inflow_coefficient * axial[:, None] * axes)
    rotor += vehicle.translational_lift_coefficient * np.sum(in_plane**2, axis=1)[:, None] * axes
    flap = -vehicle.flapping_coefficient * speeds[:, None] * np.cross(local, axes)
    force = -np.linalg.norm(air) * vehicle.drag_coefficients * air + rotor.sum(axis=0)
    return force, np.cross(vehicle.positions, rotor).sum(axis=0) + flap.sum(axis=0)


def test_every_term_in_a_wind_turning_and_on_tilted_rotors():
    wind = np.array((3.0, -2.0, 0.5))
    steady = [DrydenTurbulence(wind_speed=0.0, altitude=10.0, mean=wind)]
    rotation = rotation_from_euler_zyx(np.radians((10.0, 25.0, -40.0)))
    velocity, omega = np.array((4.0, 1.0, -0.5)), np.array((0.8, -0.4, 1.5))
    speeds = np.array((420.0, 510.0, 470.0, 560.0))
    vehicle = replace(HUMMINGBIRD, flapping_coefficient=1e-6)
    made = plant(vehicle, speeds=speeds, rotation=rotation, velocity=velocity, angular_velocity=omega,
                 turbulence=steady)
    force, torque = body_wrench(made)
    expected = reference_wrench(vehicle, speeds, rotation, velocity, omega, wind, vehicle.thrust_axes)
    np.testing.assert_allclose(force, expected[0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(torque, expected[1], rtol=1e-12, atol=1e-15)
    # rotors on servos: each rotor's axis is its tilted one
    tilting = load_vehicle("tilting_quadrotor_ex5")
    tilting = replace(tilting, **{name: getattr(vehicle, name) for name in NONE})
    tilts = np.array((0.3, -0.5, 0.8, -0.1))
    made = plant(tilting, speeds=speeds, rotation=rotation, velocity=velocity, angular_velocity=omega,
                 turbulence=steady)
    made.set_rotor_command(speeds, tilts)
    from fsr_sim.model.rotors import rotor_axes

    axes = rotor_axes(tilting, tilts)
    force, torque = body_wrench(made)
    expected = reference_wrench(tilting, speeds, rotation, velocity, omega, wind, axes)
    np.testing.assert_allclose(force, expected[0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(torque, expected[1], rtol=1e-12, atol=1e-15)


def test_the_plant_flies_its_aerodynamics_and_vehicles_without_them_are_unchanged():
    # Coasting at 5 m/s with the rotors holding the weight: the velocity changes over a short step by the
    # acceleration of the aerodynamic force (wrench_truth) - the plant feels what it publishes
    hover = math.sqrt(HUMMINGBIRD.weight / (4 * HUMMINGBIRD.c_f))
    made = plant(HUMMINGBIRD, speeds=np.full(4, hover), velocity=(5.0, 0.0, 0.0))
    force, _ = made.external_wrench()
    before = made.velocity.copy()
    made.step()
    np.testing.assert_allclose((made.velocity - before) / 0.001, force / HUMMINGBIRD.mass, rtol=2e-3, atol=2e-3)
    assert force[0] < -0.5  # 5 m/s of rotor drag and parasitic drag: 0.57 N back
    # a vehicle without coefficients has none: the external wrench is exactly zero at any speed
    quad = load_vehicle("quadrotor_ex4")
    assert not quad.has_aerodynamics
    made = plant(quad, velocity=(5.0, -3.0, 1.0), angular_velocity=(1.0, 2.0, 3.0))
    np.testing.assert_array_equal(np.concatenate(made.external_wrench()), 0.0)


def test_a_scenario_overrides_the_vehicles_coefficients_and_refuses_bad_ones():
    from fsr_sim.config.scenario import load_scenario, simulation_config
    from fsr_sim.config.validation import ConfigError

    config = simulation_config(load_scenario("ex4_geometric", [
        "vehicle=hummingbird", "actuation=rotors", "plant.rotor_drag_coefficient=2.0e-4",
        "plant.flapping_coefficient=1.0e-6", "plant.drag_coefficients=[0.0, 0.0, 0.0]"]))
    plant_vehicle = config.plant_vehicle
    assert plant_vehicle.rotor_drag_coefficient == 2e-4 and plant_vehicle.flapping_coefficient == 1e-6
    assert plant_vehicle.induced_inflow_coefficient == HUMMINGBIRD.induced_inflow_coefficient  # the vehicle's
    np.testing.assert_array_equal(plant_vehicle.drag_coefficients, 0.0)
    assert config.vehicle.rotor_drag_coefficient == HUMMINGBIRD.rotor_drag_coefficient  # the model is the file's
    for key, value, message in (("plant.translational_lift_coefficient", -1.0, "must be >= 0"),
                                ("plant.induced_inflow_coefficient", "[1, 2]", "must be a number")):
        with pytest.raises(ConfigError, match=rf"{key}: {message}") as error:
            simulation_config(load_scenario("ex4_geometric", ["vehicle=hummingbird", f"{key}={value}"]))
        assert "\n" not in str(error.value)
    # a wind needs something to push on: refused without any aerodynamics, accepted with the rotors' alone
    wind = "disturbances=[{kind: dryden, wind_speed: 3.0, altitude: 2.0}]"
    with pytest.raises(ConfigError, match=r"disturbances\.0.*aerodynamics, and they are all zero"):
        simulation_config(load_scenario("ex4_geometric", [wind]))
    simulation_config(load_scenario("ex4_geometric", ["vehicle=hummingbird", "actuation=rotors", wind,
                                                      "plant.drag_coefficients=[0.0, 0.0, 0.0]"]))
    with pytest.raises(ConfigError, match=r"disturbances\.0"):  # wrench actuation: no rotors, no rotor terms
        simulation_config(load_scenario("ex4_geometric", ["vehicle=hummingbird", "actuation=wrench", wind,
                                                          "plant.drag_coefficients=[0.0, 0.0, 0.0]"]))
