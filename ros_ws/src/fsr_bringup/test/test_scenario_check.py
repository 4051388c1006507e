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
