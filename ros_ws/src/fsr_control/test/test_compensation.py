"""controller.compensation: configuration, the contact rule, the one-step delay, and the laws' cancellation."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from fsr_control.compensation import CONTACT_TOLERANCE, WrenchCompensator
from fsr_control.config.controller_config import controller_config
from fsr_control.flight_controller import FlightController
from fsr_control.planning.trajectory import Trajectory, Waypoint
from fsr_sim.config.scenario import Scenario, load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError
from fsr_sim.core.surfaces import ceiling_rest_z, ground_rest_z, in_contact
from fsr_sim.model.environment import Environment, Surface, contact_mask, pack_surfaces
from fsr_sim.model.so3 import rotation_from_euler_zyx
from fsr_sim.model.vehicle import load_vehicle


def with_keys(name: str, **changes: object) -> Scenario:
    """A copy of built-in scenario ``name`` with ``{"section.key": value}`` changes (dots as ``__``)."""
    scenario = load_scenario(name)
    data = copy.deepcopy(scenario.data)
    for dotted, value in changes.items():
        section, key = dotted.split("__")
        data.setdefault(section, {})[key] = value
    return Scenario(data=data, source=scenario.source, base_dir=scenario.base_dir)


def test_none_is_the_default_and_builds_no_observer():
    for scenario in (load_scenario("ex3_estimation"), with_keys("ex3_estimation", controller__compensation="none")):
        config = controller_config(scenario)
        assert config.compensation is None
        sim = simulation_config(scenario)
        controller = FlightController(config, sim.vehicle, sim.actuation, sim.initial.position, sim.initial.rotation)
        assert controller.compensator is None
        assert controller.compensation_summary() == {"mode": "none"}


def test_estimate_takes_the_estimator_filter_and_the_surfaces():
    config = controller_config(with_keys("octo_ground_effect", controller__compensation="estimate",
                                         estimator__c0=25.0, estimator__r=3))
    assert (config.compensation.c0, config.compensation.r) == (25.0, 3)
    assert config.compensation.control_period == pytest.approx(0.001)
    surfaces = config.compensation.surfaces
    assert ground_rest_z(surfaces) == pytest.approx(-0.15)  # octocopter feet 0.15 m down
    assert surfaces.ground and not surfaces.ceiling


def test_estimate_is_refused_without_the_estimator():
    scenario = with_keys("ex3_estimation", controller__compensation="estimate", estimator__enabled=False)
    with pytest.raises(ConfigError) as error:
        controller_config(scenario)
    assert error.value.key == "controller.compensation"
    assert "estimator.enabled" in str(error.value)


def test_unknown_mode_is_refused():
    with pytest.raises(ConfigError, match="none, estimate"):
        controller_config(with_keys("ex3_estimation", controller__compensation="integral"))


def test_contact_rule_feet_or_top_within_the_tolerance():
    octocopter = load_vehicle("octocopter")  # feet 0.15 m below, top 0.1 m above the centre
    surfaces = pack_surfaces(Environment(ceiling=Surface(enabled=True, height=-3.0)), octocopter)
    assert ceiling_rest_z(surfaces) == pytest.approx(-3.0 + octocopter.top_height)
    rest = ground_rest_z(surfaces)
    assert in_contact(surfaces, rest)  # standing on the ground
    assert in_contact(surfaces, rest - 0.5 * CONTACT_TOLERANCE)
    assert not in_contact(surfaces, rest - 0.01)  # octo_ground_effect's low hover: 1 cm clearance
    top = ceiling_rest_z(surfaces)
    assert in_contact(surfaces, top) and not in_contact(surfaces, top + 0.1)
    mask = contact_mask(surfaces, np.array([rest, rest - 0.01, -1.0, top]))
    assert mask.tolist() == [True, False, False, True]
    free = pack_surfaces(Environment(ground=Surface(enabled=False)), octocopter)
    assert not in_contact(free, 100.0)


def hover_compensator(c0: float = 10.0) -> tuple[WrenchCompensator, float]:
    scenario = with_keys("step_disturbance", controller__compensation="estimate", estimator__c0=c0)
    config = controller_config(scenario)
    vehicle = simulation_config(scenario).vehicle
    return WrenchCompensator(config.compensation, vehicle), vehicle.mass


def test_estimate_of_the_previous_stamp_and_its_convergence():
    """Hover at rest, the commanded thrust 1 N short of the weight: the observer must see +1 N (down); the
    estimate used at t_k is the one recorded at t_(k-1)."""
    compensator, mass = hover_compensator()
    rotation, zero = np.eye(3), np.zeros(3)
    force_cmd = np.array([0.0, 0.0, -(mass * 9.81 - 1.0)])
    position = np.array([0.0, 0.0, -2.0])
    assert compensator.estimate(0.0, position) is None  # nothing recorded yet
    compensator.record(rotation, zero, zero, force_cmd, zero)
    estimates = []
    for k in range(1, 1001):
        estimate = compensator.estimate(k * 1e-3, position)
        assert estimate is not None
        used = estimate[0][2]
        compensator.record(rotation, zero, zero, force_cmd, zero)
        estimates.append((used, float(compensator.observer.estimate[2])))
    for k in range(1, len(estimates)):  # one step of delay, exactly
        assert estimates[k][0] == estimates[k - 1][1]
    assert estimates[-1][0] == pytest.approx(-1.0, abs=1e-3)  # residual up: f_e,z = -(weight - thrust)
    assert compensator.report.compensated_steps == 1000 and compensator.report.late_estimates == 0


def converged_compensator() -> WrenchCompensator:
    """Hovering 200 steps at 2 m with the thrust 1 N short: an estimate far from zero."""
    compensator, mass = hover_compensator()
    rotation, zero = np.eye(3), np.zeros(3)
    force_cmd = np.array([0.0, 0.0, -(mass * 9.81 - 1.0)])
    for k in range(200):
        compensator.estimate(k * 1e-3, np.array([0.0, 0.0, -2.0]))
        compensator.record(rotation, zero, zero, force_cmd, zero)
    assert abs(compensator.observer.estimate[2]) > 0.5
    return compensator


def test_a_stamp_gap_restarts_the_observer():
    compensator = converged_compensator()
    assert compensator.estimate(0.5, np.array([0.0, 0.0, -2.0])) is None  # 0.199 -> 0.5 s: not one period
    assert compensator.report.gaps == 1 and not compensator.in_contact
    assert not np.any(compensator.observer.estimate)


def test_touching_the_ground_restarts_the_observer():
    compensator = converged_compensator()
    rest = ground_rest_z(compensator.config.surfaces)
    assert rest == pytest.approx(-0.1)  # step_disturbance: ground at 0, quadrotor feet 0.1 m down
    assert compensator.estimate(0.2, np.array([0.0, 0.0, rest])) is None
    assert compensator.in_contact and compensator.report.contact_steps == 1 and compensator.report.gaps == 0
    assert not np.any(compensator.observer.estimate)


def test_ground_contact_gates_the_compensation():
    scenario = with_keys("octo_ground_effect", controller__compensation="estimate")
    config = controller_config(scenario)
    vehicle = simulation_config(scenario).vehicle
    compensator = WrenchCompensator(config.compensation, vehicle)
    zero = np.zeros(3)
    standing = np.array([0.0, 0.0, -0.15])
    for k in range(50):
        assert compensator.estimate(k * 1e-3, standing) is None
        compensator.record(np.eye(3), zero, zero, np.array([0.0, 0.0, -5.0]), zero)
    assert compensator.report.contact_steps == 50 and compensator.report.compensated_steps == 0
    estimate = compensator.estimate(0.05, np.array([0.0, 0.0, -0.16]))  # lifted off: from a zero estimate
    assert estimate is not None and estimate[0] == (0.0, 0.0, 0.0)


def law_inputs(tilting: bool):
    name = "ex5_voliro" if tilting else "ex3_estimation"
    scenario = load_scenario(name)
    config, sim = controller_config(scenario), simulation_config(scenario)
    rotation = rotation_from_euler_zyx(np.deg2rad([10.0, -5.0, 30.0] if tilting else [2.0, -3.0, 30.0]))
    trajectory = Trajectory([Waypoint(np.array([0.3, -0.2, -2.0]), None, 2.0, 0.0)], np.zeros(3), rotation,
                            full_attitude=tilting)
    reference = trajectory.evaluate(0.7)
    state = (np.array([0.1, 0.0, -1.1]), rotation, np.array([0.2, -0.1, 0.05]), np.array([0.1, -0.2, 0.3]))
    controller = FlightController(config, sim.vehicle, sim.actuation)
    return controller.law, reference, state


def test_voliro_cancels_the_whole_wrench():
    law, reference, state = law_inputs(tilting=True)
    plain = law.compute(reference, *state)
    f_hat, tau_hat = (1.0, -0.5, 0.8), (0.05, -0.05, 0.1)
    compensated = law.compute(reference, *state, (f_hat, tau_hat, (0.0,) * 3, (0.0,) * 3))
    rotation = state[1]
    np.testing.assert_allclose(compensated.force_body, plain.force_body - rotation.T @ np.array(f_hat), atol=1e-12)
    np.testing.assert_allclose(compensated.torque_body, plain.torque_body - np.array(tau_hat), atol=1e-12)


def test_geometric_meets_a_force_by_tilting_and_cancels_the_torque():
    law, reference, state = law_inputs(tilting=False)
    state = (reference.position, state[1], reference.velocity, state[3])  # on the reference: |a| ~ m g
    plain = law.compute(reference, *state)
    law.reset()  # the same first step for both calls (measured acceleration)
    zero = (0.0, 0.0, 0.0)
    tau_hat = (0.0, 0.0, -0.4)
    compensated = law.compute(reference, *state, ((2.0, 0.0, 0.0), tau_hat, zero, zero))
    # z_bd = -a / |a| with a -> a - f_hat: the body z axis gains f_hat / |a| along x (the thrust, along -z_b,
    # leans against the +x force), |a| ~ u_T.
    z_plain, z_comp = plain.rotation_commanded[:, 2], compensated.rotation_commanded[:, 2]
    assert z_comp[0] - z_plain[0] == pytest.approx(2.0 / plain.thrust, rel=0.05)
    assert compensated.thrust - plain.thrust == pytest.approx(2.0 * state[1][0, 2], abs=1e-12)  # u_T = -a^T R_b e3
    law.reset()
    only_torque = law.compute(reference, *state, (zero, tau_hat, zero, zero))
    np.testing.assert_allclose(only_torque.torque_body, plain.torque_body - np.array(tau_hat), atol=1e-12)
    np.testing.assert_array_equal(only_torque.force_body, plain.force_body)


def test_a_filter_too_fast_for_the_compensated_loop_is_refused():
    """c0 T = 1 diverges with compensation (ex3, measured); the config refuses c0 T > 0.5 and names the key."""
    controller_config(with_keys("ex3_estimation", controller__compensation="estimate", estimator__c0=500.0))
    with pytest.raises(ConfigError, match="lower estimator.c0") as error:
        controller_config(with_keys("ex3_estimation", controller__compensation="estimate", estimator__c0=1000.0))
    assert error.value.key == "controller.compensation"
    assert controller_config(with_keys("ex3_estimation", estimator__c0=1000.0)).compensation is None  # none: no limit
