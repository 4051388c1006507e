"""Validate every section of a scenario before any process starts (each package checks its own part).

``fsr_sim`` checks the plant side; every other section is checked by the validator its package registers as
an ``fsr.scenario_sections`` entry point (``controller`` and ``trajectory``: fsr_control, ``estimator``:
fsr_estimation; a third-party package adds its own the same way), loaded and called here - the registry is
what runs, so a section can never be accepted as known and then left unchecked.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from fsr_sim.config.plausibility import plausibility_warnings
from fsr_sim.config.scenario import Scenario, SimulationConfig, registered_sections, simulation_config
from fsr_sim.config.validation import ConfigError

REQUIRED_SECTIONS = ("controller", "estimator")  # what the flight itself needs


@dataclass
class CheckedScenario:
    scenario: Scenario
    simulation: SimulationConfig
    controller: Any
    estimator: Any
    sections: dict[str, Any] = field(default_factory=dict)  # every registered section -> its validated config
    warnings: list[str] = field(default_factory=list)  # likely slips of units (fsr_sim.config.plausibility)

    @property
    def estimator_enabled(self) -> bool:
        return bool(getattr(self.estimator, "enabled", True))

    def summary_line(self) -> str:
        sim = self.simulation
        kind = getattr(self.controller, "type", None) or getattr(self.controller, "controller_type", "?")
        profile = getattr(self.controller, "profile", None)
        kind += f" controller ({profile} profile)" if profile else " controller"
        return (
            f"{sim.vehicle.name}, {kind}, {sim.actuation} actuation, {sim.duration:g} s at "
            f"{1.0 / sim.control_period:g} Hz, estimator {'on' if self.estimator_enabled else 'off'}"
        )


def check_scenario(scenario: Scenario) -> CheckedScenario:
    """Parse all sections (the plant side, then each registered section in name order, each validator once);
    the first invalid value raises ConfigError naming the key and where its value came from (the file, or the
    ``--set`` that gave it)."""
    try:
        return _checked(scenario)
    except ConfigError as error:
        raise scenario.attribute(error) from None


def _checked(scenario: Scenario) -> CheckedScenario:
    simulation = simulation_config(scenario)
    by_validator: dict[Any, Any] = {}  # a validator owning several sections runs once
    sections = {}
    for name, point in sorted(registered_sections().items()):
        validator = point.load()
        if validator not in by_validator:
            by_validator[validator] = validator(scenario)
        sections[name] = by_validator[validator]
    missing = [name for name in REQUIRED_SECTIONS if name not in sections]
    if missing:
        raise RuntimeError(f"no installed package validates the scenario section(s) {', '.join(missing)} (the "
                           "fsr.scenario_sections entry points of fsr_control and fsr_estimation): reinstall them")
    return CheckedScenario(scenario, simulation, sections["controller"], sections["estimator"], sections,
                           plausibility_warnings(simulation))
