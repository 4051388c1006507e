"""Values a scenario accepts but that are likely slips of units give a warning naming the value and the vehicle's
own number; plausible scenarios give none."""

from __future__ import annotations

import pytest

from fsr_sim.config.plausibility import plausibility_warnings
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.config.validation import builtin_names


def warnings_of(name: str, **values: object) -> list[str]:
    return plausibility_warnings(simulation_config(load_scenario(name, values=dict(values))))


@pytest.mark.parametrize("name", builtin_names("scenarios"))
def test_the_built_in_scenarios_look_plausible(name):
    assert warnings_of(name) == []


@pytest.mark.parametrize(("values", "expected"), [
    ({"plant.mass": 1200}, "plant.mass 1200 kg is 1e+03 times quadrotor_ex4's 1.2 kg"),
    ({"plant.mass": 0.0012}, "plant.mass 0.0012 kg is 0.001 times quadrotor_ex4's 1.2 kg"),
    ({"plant.inertia": [1241.6, 1241.6, 2483.2]}, "plant.inertia is 1e+03 times quadrotor_ex4's"),
    ({"plant.rotor_time_constant": 30}, "rotor_time_constant 30 s: real motors and servos take 0.005-0.1 s (did you "
                                        "mean 0.03 s, 30 ms?)"),
    ({"plant.mass": 7.0}, "the rotors give at most 66.3 N of thrust at full speed for the plant's 68.7 N weight"),
])
def test_a_slip_of_units_is_named_with_the_vehicles_own_number(values, expected):
    found = warnings_of("step_disturbance", **values)
    assert any(expected in warning for warning in found), found


def test_a_heavier_vehicle_the_rotors_still_lift_is_no_slip():
    assert warnings_of("step_disturbance", **{"plant.mass": 3.5}) == []


def test_wrench_actuation_has_no_rotor_limit_to_warn_of():
    assert warnings_of("ex4_geometric", **{"plant.mass": 3.5}) == []

