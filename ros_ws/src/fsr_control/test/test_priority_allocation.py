"""controller.allocation: clamp | priority in the actuations (fsr_control.allocation) and the scenario."""

from pathlib import Path

import numpy as np
import pytest

from fsr_control.allocation import FixedRotorActuation, TiltingActuation
from fsr_control.config import controller_config
from fsr_sim.config.scenario import load_scenario
from fsr_sim.config.validation import ConfigError
from fsr_sim.model.rotors import WRENCH_AXES
from fsr_sim.model.vehicle import load_vehicle

SCENARIOS = Path(__file__).parent / "scenarios"


def both(name: str, secondary: str = "none"):
    vehicle = load_vehicle(name)
    if vehicle.has_servos:
        return vehicle, [TiltingActuation.with_objective(vehicle, secondary, strategy=s) for s in ("clamp", "priority")]
    return vehicle, [FixedRotorActuation(vehicle, s) for s in ("clamp", "priority")]


def assert_same(a, b):
    for field in ("rotor_speeds", "force_body", "torque_body", "shortfall"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    np.testing.assert_array_equal(a.tilt_angles if a.tilt_angles is not None else [],
                                  b.tilt_angles if b.tilt_angles is not None else [])
    assert a.saturated is b.saturated is False


@pytest.mark.parametrize("name", ["quadrotor_ex4", "octocopter"])
def test_feasible_fixed_rotor_wrench_is_bit_identical_with_either_strategy(name):
    vehicle, (clamp, priority) = both(name)
    rng = np.random.default_rng(3)
    for _ in range(50):
        force = np.array((0.0, 0.0, -vehicle.weight * rng.uniform(0.5, 1.5)))
        torque = rng.normal(0.0, 0.05, 3) * np.array((1.0, 1.0, 0.1))
        assert_same(clamp.allocate(0.0, force, torque), priority.allocate(0.0, force, torque))
    assert priority.saturation.count == 0


@pytest.mark.parametrize("secondary", ["none", "min_peak_speed"])
def test_feasible_tilting_wrench_is_bit_identical_with_either_strategy(secondary):
    vehicle, (clamp, priority) = both("tilting_quadrotor_ex5", secondary)
    for force, torque in [((1.0, -2.0, -14.0), (0.1, -0.2, 0.05)), ((0.0, 0.0, -13.0), (0.0, 0.0, 0.3))]:
        a = clamp.allocate(0.0, np.array(force), np.array(torque))
        b = priority.allocate(0.0, np.array(force), np.array(torque))
        assert_same(a, b)


@pytest.mark.parametrize("name", ["quadrotor_ex4", "octocopter"])
def test_yaw_gives_way_alone_with_priority_and_clamping_costs_thrust(name):
    vehicle, (clamp, priority) = both(name)
    force, torque = np.array((0.0, 0.0, -1.2 * vehicle.weight)), np.array((0.1, -0.05, 3.0))
    kept = priority.allocate(1.0, force, torque)
    assert kept.saturated and kept.rotor_speeds.max() <= vehicle.rotor_speed_max
    assert kept.rotor_speeds.min() >= vehicle.rotor_speed_min
    np.testing.assert_allclose(kept.force_body, force, atol=1e-9)
    np.testing.assert_allclose(kept.torque_body[:2], torque[:2], atol=1e-9)
    assert 0.0 < kept.torque_body[2] < torque[2]
    np.testing.assert_allclose(kept.shortfall, np.concatenate((force, torque)) - np.concatenate(
        (kept.force_body, kept.torque_body)), atol=0.0)
    gave_way = priority.saturation.as_dict()["gave_way"]
    assert [axis for axis in WRENCH_AXES if gave_way[axis]["steps"]] == ["torque_z"]
    assert gave_way["torque_z"]["max_shortfall"] == pytest.approx(torque[2] - kept.torque_body[2])
    clamped = clamp.allocate(1.0, force, torque)
    assert abs(clamped.shortfall[2]) > 0.1  # per-rotor clamping loses thrust (the crash the priority rules prevent)
    assert clamp.saturation.as_dict()["gave_way"]["force_z"]["steps"] == 1


def test_tilting_yaw_gives_way_first_within_speed_limits():
    vehicle, (clamp, priority) = both("tilting_quadrotor_ex5")
    force, torque = np.array((1.0, 0.5, -1.2 * vehicle.weight)), np.array((0.2, -0.1, 30.0))
    kept = priority.allocate(0.0, force, torque)
    assert kept.saturated and kept.rotor_speeds.max() <= vehicle.rotor_speed_max
    np.testing.assert_allclose(kept.force_body, force, atol=1e-9)
    np.testing.assert_allclose(kept.torque_body[:2], torque[:2], atol=1e-9)
    assert 0.0 < kept.torque_body[2] < torque[2]
    assert np.all(np.abs(clamp.allocate(0.0, force, torque).shortfall[:5]) > 1e-3)  # clamping: every axis suffers


def test_nan_demand_is_not_desaturated_and_stays_nan():
    vehicle, (_, priority) = both("quadrotor_ex4")
    result = priority.allocate(0.0, np.array((0.0, 0.0, np.nan)), np.zeros(3))
    assert np.isnan(result.rotor_speeds).all()


def test_unknown_strategy_is_refused():
    with pytest.raises(ValueError, match="unknown allocation strategy 'clip'"):
        FixedRotorActuation(load_vehicle("quadrotor_ex4"), "clip")


def test_scenario_key_defaults_to_priority_and_names_itself_when_wrong():
    assert controller_config(load_scenario(SCENARIOS / "ex4_wrench.yaml")).allocation == "priority"
    clamp = load_scenario(SCENARIOS / "ex5_voliro.yaml", ["controller.allocation=clamp"])
    assert controller_config(clamp).allocation == "clamp"
    with pytest.raises(ConfigError) as error:
        controller_config(load_scenario(SCENARIOS / "ex4_wrench.yaml", ["controller.allocation=prority"]))
    assert error.value.key == "controller.allocation"
    assert "must be one of clamp, priority; got 'prority'" in str(error.value)


def test_air_mode_key_defaults_to_true_and_false_keeps_the_thrust():
    assert controller_config(load_scenario(SCENARIOS / "ex4_wrench.yaml")).air_mode is True
    off = controller_config(load_scenario(SCENARIOS / "ex4_wrench.yaml", ["controller.air_mode=false"]))
    assert off.air_mode is False
    with pytest.raises(ConfigError) as error:
        controller_config(load_scenario(SCENARIOS / "ex4_wrench.yaml", ["controller.air_mode=maybe"]))
    assert error.value.key == "controller.air_mode"
    vehicle = load_vehicle("quadrotor_ex4")
    force, torque = np.array((0.0, 0.0, -vehicle.weight)), np.array((0.0, 12.0, 0.0))
    kept = FixedRotorActuation(vehicle, "priority", air_mode=False).allocate(0.0, force, torque)
    raised = FixedRotorActuation(vehicle, "priority").allocate(0.0, force, torque)
    assert kept.saturated and raised.saturated
    assert -kept.force_body[2] == pytest.approx(vehicle.weight, rel=1e-12) and 0.0 < kept.torque_body[1] < 12.0
    assert -raised.force_body[2] > 2.0 * vehicle.weight  # air mode: up to 2.8 x the weight for this torque
