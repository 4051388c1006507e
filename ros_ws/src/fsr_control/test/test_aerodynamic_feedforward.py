"""The model's aerodynamics along the reference (controller.aerodynamics: model), per sample."""

import numpy as np

from fsr_control.core import aerodynamic_feedforward as aero
from fsr_control.core.reference import ReferenceSample
from fsr_control.flight_controller import pack_aerodynamic_feedforward
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.vehicle import load_vehicle

ZERO = (0.0, 0.0, 0.0)
IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def level_cruise(velocity: tuple, acceleration: tuple = ZERO) -> ReferenceSample:
    return ReferenceSample(ZERO, velocity, acceleration, ZERO, ZERO, IDENTITY, ZERO, ZERO, 0.0, 0.0, 0.0)


def predict(params, memory, t, reference):
    function = aero.aerodynamic_feedforward
    return getattr(function, "py_func", function)(params, memory, t, reference)  # as Python, compiled or not


def test_level_cruise_meets_the_parasitic_drag_and_no_rates():
    vehicle = load_vehicle("hummingbird")
    params = pack_aerodynamic_feedforward(vehicle, "wrench", "model")  # wrench actuation: the parasitic drag only
    assert params.enabled and not params.aerodynamics.rotor
    memory = aero.new_aero_memory(vehicle.rotor_count)
    velocity = (3.0, -4.0, 0.0)
    for step in range(3):
        prediction = predict(params, memory, 0.001 * step, level_cruise(velocity))
    speed = np.linalg.norm(velocity)
    np.testing.assert_allclose(prediction.force, -speed * vehicle.drag_coefficients * velocity, rtol=1e-12)
    np.testing.assert_allclose(prediction.torque, ZERO, atol=1e-15)
    np.testing.assert_allclose((prediction.force_rate, prediction.force_acceleration), np.zeros((2, 3)), atol=1e-9)
    again = predict(params, memory, 0.002, level_cruise((9.0, 9.0, 9.0)))  # a stamp that does not advance
    assert again.force == prediction.force and again.force_rate == prediction.force_rate


def test_the_rotors_turn_at_the_speed_of_the_references_thrust_and_the_rates_are_differences():
    vehicle = load_vehicle("hummingbird")
    params = pack_aerodynamic_feedforward(vehicle, "rotors", "model")
    memory = aero.new_aero_memory(vehicle.rotor_count)
    predict(params, memory, 0.0, level_cruise((2.0, 0.0, 0.0), (0.0, 0.0, -2.0)))  # climbing at 2 m/s^2
    hover_speed = np.sqrt(vehicle.mass * (GRAVITY + 2.0) / (4 * vehicle.c_f))
    np.testing.assert_allclose(memory.speeds, hover_speed, rtol=1e-12)
    first = predict(params, memory, 0.0, level_cruise((2.0, 0.0, 0.0), (0.0, 0.0, -2.0)))
    second = predict(params, memory, 0.01, level_cruise((2.5, 0.0, 0.0), (0.0, 0.0, -2.0)))
    np.testing.assert_allclose(second.force_rate, (np.array(second.force) - first.force) / 0.01, rtol=1e-12)
    assert first.force[0] < 0.0 and second.force[0] < first.force[0]  # drag against the motion, growing with it


def test_none_or_a_model_without_aerodynamics_is_off():
    assert not pack_aerodynamic_feedforward(load_vehicle("hummingbird"), "rotors", "none").enabled
    assert not pack_aerodynamic_feedforward(load_vehicle("quadrotor_ex4"), "rotors", "model").enabled
