import pytest

from fsr_sim.config.scenario import apply_override, load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError, builtin_names


def write(tmp_path, text):
    path = tmp_path / "s.yaml"
    path.write_text(text)
    return path


def test_override_by_dotted_path_with_yaml_value(tmp_path):
    path = write(tmp_path, "vehicle: octocopter\nduration: 1.0\ndisturbances: [{kind: constant}]\n")
    scenario = load_scenario(path, ["disturbances.0.force=[0.5, 0, 0]", "initial_state.position=[0,0,-2]"])
    config = simulation_config(scenario)
    assert config.disturbances[0].force.tolist() == [0.5, 0.0, 0.0]
    assert config.initial.position.tolist() == [0.0, 0.0, -2.0]


@pytest.mark.parametrize(
    ("text", "overrides", "message"),
    [
        ("vehicle: octocopter\nduraton: 1.0\n", [], "duraton: unknown key"),
        ("vehicle: octocopter\nduration: 1.0\nplant: {mass: 0}\n", [], "plant.mass: must be > 0"),
        ("vehicle: hexa\nduration: 1.0\n", [], "vehicle: .*unknown vehicle 'hexa'"),
        ("vehicle: octocopter\nduration: [1.0\n", [], "YAML syntax error at line 3, column 1"),
        ("vehicle: octocopter\nduration: 1.0\nactuation: thrust\n", [], "actuation: must be one of"),
        ("vehicle: octocopter\nduration: 1.0\nenvironment: {ground: {hieght: 0}}\n", [],
         "environment.ground.hieght: unknown key"),
        ("vehicle: octocopter\nduration: 1.0\ndisturbances: [{kind: gust}]\n", [], "disturbances.0.kind"),
        ("vehicle: octocopter\nduration: 1.0\n", ["duration"], "--set: expected KEY=VALUE"),
        ("vehicle: octocopter\nduration: 1.0005\n", [], "duration: must be a whole number of steps"),
    ],
)
def test_invalid_scenarios_are_refused_naming_file_and_key(tmp_path, text, overrides, message):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError, match=message) as error:
        simulation_config(load_scenario(path, overrides))
    assert "s.yaml" in str(error.value)


def test_an_override_into_a_missing_list_is_refused_naming_the_override(tmp_path):
    path = write(tmp_path, "vehicle: octocopter\nduration: 1.0\n")
    with pytest.raises(ConfigError) as error:
        load_scenario(path, ["disturbances.3.force=[1,0,0]"])
    assert str(error.value) == ("--set disturbances.3.force=[1,0,0]: disturbances: is not set, so it has no item 3: "
                                "set the whole list (disturbances=[...])")


def test_apply_override_creates_missing_sections():
    data = {}
    apply_override(data, "environment.ceiling.enabled", "true")
    assert data == {"environment": {"ceiling": {"enabled": True}}}


BUILT_IN_SCENARIOS = (
    "ex3_estimation", "ex4_geometric", "ex5_voliro", "octo_ground_effect", "ceiling_approach", "step_disturbance",
)


def test_built_in_scenarios_ship_and_validate():
    assert set(BUILT_IN_SCENARIOS) <= set(builtin_names("scenarios"))
    for name in BUILT_IN_SCENARIOS:
        config = simulation_config(load_scenario(name))
        assert config.step_count * config.control_period == pytest.approx(config.duration)
        assert config.plant_vehicle.mass > 0.0


def test_numbers_in_exponent_form_are_numbers_in_files_and_overrides(tmp_path):
    """YAML 1.1 (PyYAML's) reads ``2e-2`` as text; fsr reads it as YAML 1.2 does, a float."""
    from fsr_sim.config.scenario import load_scenario, simulation_config

    path = tmp_path / "lag.yaml"
    path.write_text("vehicle: quadrotor_ex4\nduration: 1.0\nplant: {rotor_time_constant: 2e-2}\n")
    assert simulation_config(load_scenario(path)).plant_vehicle.rotor_time_constant == 0.02
    config = simulation_config(load_scenario("step_disturbance", ["plant.rotor_time_constant=3E-2"]))
    assert config.plant_vehicle.rotor_time_constant == 0.03
