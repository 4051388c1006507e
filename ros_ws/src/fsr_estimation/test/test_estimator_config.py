import numpy as np
import pytest

from fsr_estimation.config.estimator_config import estimator_config
from fsr_estimation.nodes.estimator_params import node_settings
from fsr_sim.config.scenario import load_scenario
from fsr_sim.config.validation import ConfigError


def scenario(tmp_path, estimator_text):
    path = tmp_path / "s.yaml"
    path.write_text("vehicle: quadrotor_ex4\nduration: 1.0\n" + estimator_text)
    return load_scenario(path)


def test_defaults_come_from_the_vehicle(tmp_path):
    config = estimator_config(scenario(tmp_path, ""))
    assert config.enabled and config.c0 == 10.0 and config.r == 1
    assert config.mass == 1.2
    np.testing.assert_array_equal(config.inertia, np.diag([1.2416, 1.2416, 2.4832]))


def test_values_from_the_section(tmp_path):
    config = estimator_config(scenario(tmp_path, "estimator: {enabled: false, c0: 25, r: 3, mass: 1.5, "
                                                 "inertia: [[1, 0.1, 0], [0.1, 1, 0], [0, 0, 2]]}\n"))
    assert (config.enabled, config.c0, config.r, config.mass) == (False, 25.0, 3, 1.5)
    assert config.inertia[0, 1] == 0.1


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("estimator: {c0: 0}\n", "estimator.c0: must be > 0"),
        ("estimator: {c0: .nan}\n", "estimator.c0: must be finite"),
        ("estimator: {r: 0}\n", "estimator.r: must be >= 1"),
        ("estimator: {r: 2.5}\n", "estimator.r: must be an integer"),
        ("estimator: {mass: -1}\n", "estimator.mass: must be > 0"),
        ("estimator: {inertia: [1, 1]}\n", "estimator.inertia: must be 3 numbers"),
        ("estimator: {inertia: [1, -1, 1]}\n", "estimator.inertia: must be positive definite"),
        ("estimator: {inertia: [[1, 2, 0], [0, 1, 0], [0, 0, 1]]}\n", "estimator.inertia: must be symmetric"),
        ("estimator: {c_0: 5}\n", "estimator.c_0: unknown key \\(did you mean 'c0'\\?\\)"),
        ("estimator: {enabled: yes please}\n", "estimator.enabled: must be true or false"),
        ("estimator: [1, 2]\n", "estimator: expected a mapping"),
        ("estimator: {input: rotors}\n", "estimator.input: must be one of commanded, measured"),
        ("actuation: wrench\nestimator: {input: measured}\n", "estimator.input: 'measured' .* 'actuation: rotors'"),
    ],
)
def test_bad_sections_are_refused_naming_file_and_key(tmp_path, text, message):
    with pytest.raises(ConfigError, match=message) as error:
        estimator_config(scenario(tmp_path, text))
    assert "s.yaml" in str(error.value)


def test_node_parameters_override_the_scenario(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text("vehicle: quadrotor_ex4\nduration: 1.0\nphysics_dt: 0.002\nphysics_substeps: 2\n")
    settings = node_settings({"scenario": str(path), "c0": 20, "r": 2, "mass": None, "inertia": [1.0, 1.0, 2.0],
                              "control_period": None})
    assert settings.control_period == pytest.approx(0.004)
    assert (settings.config.c0, settings.config.r, settings.config.mass) == (20.0, 2, 1.2)
    np.testing.assert_array_equal(np.diag(settings.config.inertia), [1.0, 1.0, 2.0])
    no_scenario = node_settings({"mass": 1.5, "inertia": [1, 0, 0, 0, 1, 0, 0, 0, 2]})
    assert no_scenario.control_period is None and no_scenario.config.inertia[2, 2] == 2.0


def test_measured_input_takes_rotor_state_where_the_rotors_lag(tmp_path):
    """``input: measured`` reads rotor_state where the simulator publishes it (a rotor lag); the node then pairs
    odom with it through the nominal allocation; without lag it takes wrench_cmd (the command is what acts)."""
    assert estimator_config(scenario(tmp_path, "")).input == "commanded"
    no_lag = estimator_config(scenario(tmp_path, "actuation: rotors\nestimator: {input: measured}\n"))
    assert no_lag.input == "measured" and not no_lag.rotor_state
    lag = "actuation: rotors\nplant: {rotor_time_constant: 0.02}\nestimator: {input: measured}\n"
    assert estimator_config(scenario(tmp_path, lag)).rotor_state
    settings = node_settings({"scenario": str(tmp_path / "s.yaml")})
    allocation, c_f, tilting = settings.rotor_allocation
    assert allocation.shape == (6, 4) and c_f > 0.0 and not tilting
    assert node_settings({"scenario": "ex3_estimation"}).rotor_allocation is None


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"scenario": "ex3_estimation", "c0": -1.0}, "ROS parameter: c0: must be > 0"),
        ({"scenario": "ex3_estimation", "r": 0}, "ROS parameter: r: must be >= 1"),
        ({"scenario": "ex3_estimation", "mass": 0.0}, "ROS parameter: mass: must be > 0"),
        ({"scenario": "ex3_estimation", "inertia": [1.0, 2.0]}, "ROS parameter: inertia: must be 3 numbers"),
        ({"scenario": "ex3_estimation", "c0": 3000.0}, "ROS parameter: c0: .*unstable"),
        ({"mass": 1.5}, "ROS parameter: inertia: is required when no scenario is given"),
        ({"scenario": "no_such_scenario"}, "unknown scenario 'no_such_scenario'"),
    ],
)
def test_bad_node_parameters_name_the_parameter(values, message):
    with pytest.raises(ConfigError, match=message):
        node_settings(values)
