"""Validate every section of a scenario before any process starts (each package checks its own part)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from fsr_control.config.controller_config import controller_config
from fsr_estimation.config.estimator_config import estimator_config
from fsr_sim.config.scenario import Scenario, SimulationConfig, simulation_config


@dataclass
class CheckedScenario:
    scenario: Scenario
    simulation: SimulationConfig
    controller: Any
    estimator: Any

    @property
    def estimator_enabled(self) -> bool:
        return bool(getattr(self.estimator, "enabled", True))

    def summary_line(self) -> str:
        sim = self.simulation
        kind = getattr(self.controller, "type", None) or getattr(self.controller, "controller_type", "?")
        return (
            f"{sim.vehicle.name}, {kind} controller, {sim.actuation} actuation, {sim.duration:g} s at "
            f"{1.0 / sim.control_period:g} Hz, estimator {'on' if self.estimator_enabled else 'off'}"
        )


def check_scenario(scenario: Scenario) -> CheckedScenario:
    """Parse all sections; the first invalid value raises ConfigError naming the file and the key."""
    simulation = simulation_config(scenario)
    return CheckedScenario(scenario, simulation, controller_config(scenario), estimator_config(scenario))
