"""The geometric law's integral term and its anti-windup (fsr_control.controllers.geometric), on the controller's
own tick with the state held away from the reference."""

from __future__ import annotations

import numpy as np
import pytest

from fsr_control.config.controller_config import controller_config
from fsr_control.core import geometric_law, laws
from fsr_control.flight_controller import FlightController
from fsr_sim.config.scenario import load_scenario, simulation_config

PERIOD = 1e-3


def hovering_controller(*overrides: str) -> FlightController:
    """ex4's quadrotor with rotors (or ``overrides``) and the flight profile, holding its start point."""
    scenario = load_scenario("ex4_geometric", ["actuation=rotors", "controller.profile=flight",
                                               "trajectory.waypoints=[]", *overrides])
    sim = simulation_config(scenario)
    return FlightController(controller_config(scenario), sim.vehicle, sim.actuation, sim.initial.position,
                            sim.initial.rotation)


def hold_state(controller: FlightController, offset: tuple[float, float, float], steps: int, first: int = 0
               ) -> np.ndarray:
    """Tick steps ``first .. first + steps - 1`` with the vehicle level and at rest ``offset`` [m] from its start;
    the integral."""
    position = tuple(float(v) for v in np.add((0.0, 0.0, -1.0), offset))
    level = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    for k in range(first, first + steps):
        controller.command_row(k * PERIOD, position, level, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    return controller.law.memory.geometric[0].integral.copy()


def test_the_integral_sums_the_position_error_and_is_clamped_to_its_force_bound():
    """Wrench actuation (never short: held level, the growing tilt command would soon ask the rotors for more roll
    torque than they give, which holds the integral, the next test)."""
    controller = hovering_controller("actuation=wrench")
    params = controller.law.params.geometric
    assert params.integral and params.reference_feedforward
    integral = hold_state(controller, (0.1, 0.0, 0.0), 1001)  # 1 s, 0.1 m off: 0.1 m s (well within the bound)
    np.testing.assert_allclose(integral, (0.1, 0.0, 0.0), rtol=1e-9, atol=1e-15)
    integral = hold_state(controller, (0.1, 0.0, 0.0), 30000, first=1001)  # 30 s more: K_i x 3.1 m s > the bound
    force = params.matrices[geometric_law.K_I] @ integral
    assert np.linalg.norm(force) == pytest.approx(params.integral_limit, rel=1e-12)  # 0.25 m g = 2.94 N
    assert force[0] > 0.0 and abs(force[1]) < 1e-12


def test_the_integral_holds_while_the_rotors_cannot_give_the_thrust():
    """20 m below the reference the vertical loop asks for far more thrust than the rotors give: the allocation
    falls short on f_z at every step and the integral does not grow (conditional integration); 1 cm off it
    grows."""
    controller = hovering_controller()
    np.testing.assert_array_equal(hold_state(controller, (0.0, 0.0, 20.0), 2000), 0.0)
    assert controller.saturation.count == 2000
    controller = hovering_controller()
    assert hold_state(controller, (0.0, 0.0, 0.01), 2000)[2] == pytest.approx(0.01999, rel=1e-9)


def test_the_report_profile_has_no_integral_and_the_measured_feedforward():
    params = hovering_controller("controller.profile=report").law.params.geometric
    assert not params.integral and not params.reference_feedforward
    np.testing.assert_array_equal(params.matrices[geometric_law.K_I], np.zeros((3, 3)))


def test_a_law_packed_under_another_kind_is_refused():
    own = hovering_controller().law.params.geometric
    with pytest.raises(ValueError, match="kind 1 does not hold GeometricParams"):
        laws.law_params(laws.VOLIRO, own)
