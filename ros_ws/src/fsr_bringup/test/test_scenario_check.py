"""check_scenario runs the validators the packages register (fsr.scenario_sections), each once."""

from __future__ import annotations

import pytest

from fsr_bringup.runner import scenario_check
from fsr_sim.config.scenario import load_scenario, registered_sections
from fsr_sim.config.validation import ConfigError


class Registered:
    """A stand-in entry point: ``load()`` gives the validator."""

    def __init__(self, validator) -> None:  # noqa: ANN001
        self.validator = validator

    def load(self):  # noqa: ANN201
        return self.validator


def test_the_installed_sections_are_validated_by_their_packages():
    checked = scenario_check.check_scenario(load_scenario("ex5_voliro"))
    assert set(checked.sections) == set(registered_sections()) >= {"controller", "trajectory", "estimator"}
    assert checked.sections["trajectory"] is checked.controller  # one validator, called once, for two sections
    assert checked.controller.type == "voliro" and checked.estimator.enabled


def test_a_registered_validator_runs_and_its_error_stops_the_check(monkeypatch):
    calls = []

    def payload_validator(scenario):  # noqa: ANN001, ANN202
        calls.append(scenario.name)
        raise ConfigError("payload.mass", "must be > 0, got -1", scenario.source)

    sections = {**registered_sections(), "payload": Registered(payload_validator)}
    monkeypatch.setattr(scenario_check, "registered_sections", lambda: sections)
    with pytest.raises(ConfigError, match="payload.mass"):
        scenario_check.check_scenario(load_scenario("ex4_geometric"))
    assert calls == ["ex4_geometric"]


def test_a_missing_required_validator_is_named(monkeypatch):
    sections = {name: point for name, point in registered_sections().items() if name != "estimator"}
    monkeypatch.setattr(scenario_check, "registered_sections", lambda: sections)
    with pytest.raises(RuntimeError, match="estimator"):
        scenario_check.check_scenario(load_scenario("ex4_geometric"))


@pytest.mark.parametrize(("override", "message"), [
    ("plant.mass=-1", "--set plant.mass=-1: plant.mass: must be > 0, got -1.0"),
    ("controller.gains.k_p=[10,10]", "--set controller.gains.k_p=[10,10]: controller.gains.k_p: must be 3 numbers "
                                     "(the diagonal) or a 3 x 3 matrix, got [10.0, 10.0]"),
    ("disturbances.3.force=[1,0,0]", "--set disturbances.3.force=[1,0,0]: disturbances: is not set, so it has no "
                                     "item 3: set the whole list (disturbances=[...])"),
])
def test_an_invalid_override_is_named_as_the_source_of_the_error(override, message):
    with pytest.raises(ConfigError) as error:
        scenario_check.check_scenario(load_scenario("ex4_geometric", [override]))
    assert str(error.value) == message


def test_an_error_in_the_file_still_names_the_file_when_other_keys_are_overridden(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("vehicle: quadrotor_ex4\nduration: 1.0\nplant: {mass: -2}\n")
    with pytest.raises(ConfigError) as error:
        scenario_check.check_scenario(load_scenario(path, ["duration=2.0"]))
    assert str(error.value).startswith(f"{path}: plant.mass: must be > 0")
    checked = scenario_check.check_scenario(load_scenario("ex4_geometric", ["controller.gains.k_p=[1,2,3]"]))
    assert checked.controller.gains["k_p"].tolist() == [[1, 0, 0], [0, 2, 0], [0, 0, 3]]
