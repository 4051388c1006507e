"""Simulator node parameters: checks, messages naming the parameter, and scenario overrides."""

import pytest
import yaml

from fsr_sim.config.validation import ConfigError
from fsr_sim.nodes.simulator_params import (
    PARAMETER_NAMES,
    SimulatorParameters,
    apply_parameter_overrides,
    load_simulation,
    parse_parameters,
)


def given(**values):
    raw = dict.fromkeys(PARAMETER_NAMES)
    raw.update(values)
    return raw


def write(tmp_path, **data):
    scenario = {"vehicle": "quadrotor_ex4", "duration": 1.0}
    scenario.update(data)
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(scenario))
    return str(path)


def test_defaults():
    params = parse_parameters(given(scenario="x.yaml"))
    assert params == SimulatorParameters(scenario="x.yaml")
    assert params.wait_for_subscribers == 1 and params.publish_clock and params.startup_timeout == 20.0


def test_integer_values_are_accepted_for_seconds():
    params = parse_parameters(given(scenario="x.yaml", duration=2, timeout=1, real_time_factor=3))
    assert (params.duration, params.timeout, params.real_time_factor) == (2.0, 1.0, 3.0)


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({}, "ROS parameter: scenario: is required"),
        ({"scenario": "  "}, "ROS parameter: scenario: must name"),
        ({"scenario": 3}, "ROS parameter: scenario: must be a string"),
        ({"duration": -1}, "ROS parameter: duration: must be > 0, got -1.0"),
        ({"timeout": 0.0}, "ROS parameter: timeout: must be > 0"),
        ({"failsafe": "explode"}, "ROS parameter: failsafe: must be one of hold, cut; got 'explode'"),
        ({"real_time_factor": float("nan")}, "ROS parameter: real_time_factor: must be finite"),
        ({"lockstep": "yes"}, "ROS parameter: lockstep: must be true or false"),
        ({"publish_clock": 1}, "ROS parameter: publish_clock: must be true or false"),
        ({"wait_for_subscribers": -1}, "ROS parameter: wait_for_subscribers: must be >= 0"),
        ({"wait_for_subscribers": 1.5}, "ROS parameter: wait_for_subscribers: must be an integer"),
        ({"startup_timeout": 0}, "ROS parameter: startup_timeout: must be > 0"),
    ],
)
def test_bad_values_name_the_parameter(values, message):
    values = {"scenario": "x.yaml", **values} if "scenario" not in values and values else values
    with pytest.raises(ConfigError) as error:
        parse_parameters(given(**values))
    assert str(error.value).startswith(message)


def test_overrides_go_into_the_scenario_sections(tmp_path):
    params = parse_parameters(
        given(scenario=write(tmp_path), duration=0.5, lockstep=False, timeout=0.25, failsafe="cut",
              real_time_factor=4.0)
    )
    _, config = load_simulation(params)
    assert config.duration == 0.5 and config.step_count == 500
    assert not config.lockstep and config.lockstep_timeout == 0.25
    assert config.failsafe == "cut" and config.real_time_factor == 4.0


def test_overrides_keep_other_lockstep_keys():
    data = {"lockstep": {"timeout": 3.0, "failsafe": "cut"}}
    apply_parameter_overrides(data, SimulatorParameters(scenario="x", failsafe="hold"))
    assert data == {"lockstep": {"timeout": 3.0, "failsafe": "hold"}}
    untouched = {"duration": 1.0}
    apply_parameter_overrides(untouched, SimulatorParameters(scenario="x"))
    assert untouched == {"duration": 1.0}


def test_scenario_errors(tmp_path):
    with pytest.raises(ConfigError, match=r"^ROS parameter: scenario: unknown scenario 'no_such'"):
        load_simulation(SimulatorParameters(scenario="no_such"))
    with pytest.raises(ConfigError, match=r"ROS parameter: scenario: .*missing.yaml: no such scenario file"):
        load_simulation(SimulatorParameters(scenario=str(tmp_path / "missing.yaml")))
    with pytest.raises(ConfigError, match=r"s.yaml: duraton: unknown key"):
        load_simulation(SimulatorParameters(scenario=write(tmp_path, duraton=2.0)))
    with pytest.raises(ConfigError, match=r"s.yaml: duration: must be a whole number of steps"):
        load_simulation(SimulatorParameters(scenario=write(tmp_path), duration=0.0015))
