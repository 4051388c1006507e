"""The simulator node's parameters: typed checks and how they override the scenario (no rclpy here).

ROS parameters (``--ros-args -p name:=value``):

* ``scenario`` (string, required): a built-in scenario name or a path to a scenario YAML file.
* ``wait_for_subscribers`` (int >= 0, default 1): ``odom`` subscribers to wait for before step 0.
* ``publish_clock`` (bool, default true): publish ``/clock`` (one simulator per graph should).
* ``startup_timeout`` (s > 0, default 20): how long the start-up handshake may take.
* ``recorded_topics`` (comma-separated, default none): the handshake also waits for a reader on each of
  these the simulator publishes (:mod:`fsr_sim.ros.recorder_match`).
* Overrides of the scenario: ``lockstep`` (bool) -> ``lockstep.enabled``, ``timeout`` (s > 0) ->
  ``lockstep.timeout``, ``failsafe`` (hold | cut) -> ``lockstep.failsafe``, ``real_time_factor`` (> 0) ->
  ``lockstep.real_time_factor``, ``duration`` (s > 0, a whole number of control periods) -> ``duration``.

A refused value raises :class:`ConfigError` reading ``ROS parameter: <name>: <reason>``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from fsr_sim.config.scenario import Scenario, SimulationConfig, load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError, Section, resolve_config_path
from fsr_sim.contract import (
    EXIT_CONFIG_ERROR,
    EXIT_DIVERGED,
    EXIT_FAILURE,
    EXIT_OK,
    ROTOR_CMD,
    SIMULATOR,
    WRENCH_CMD,
)
from fsr_sim.ros.node_usage import NodeUsage, Parameter
from fsr_sim.ros.recorder_match import RECORDED_TOPICS, parse_recorded_topics

PARAMETER_SOURCE = "ROS parameter"

USAGE = NodeUsage(
    SIMULATOR,
    "Steps the plant in lockstep with the controller and publishes the state (docs/model.md section 4).",
    (
        Parameter("scenario", "", "built-in scenario name or scenario YAML path (required)"),
        Parameter("wait_for_subscribers", "1", "odom subscribers to wait for before step 0"),
        Parameter("publish_clock", "true", "publish /clock (one simulator per graph should)"),
        Parameter("startup_timeout", "20.0", "s the start-up handshake may take"),
        Parameter("lockstep", "", "true | false: overrides the scenario's lockstep.enabled"),
        Parameter("timeout", "", "s without a command before the failsafe (lockstep.timeout)"),
        Parameter("failsafe", "", "hold | cut (lockstep.failsafe)"),
        Parameter("real_time_factor", "", "free-running pace (lockstep.real_time_factor)"),
        Parameter("duration", "", "s, a whole number of control periods (the scenario's duration)"),
        RECORDED_TOPICS,
    ),
    (ROTOR_CMD, WRENCH_CMD),  # the one the scenario's actuation names
    (EXIT_OK, EXIT_FAILURE, EXIT_CONFIG_ERROR, EXIT_DIVERGED),
)
PARAMETER_NAMES = tuple(parameter.name for parameter in USAGE.parameters)


@dataclass(frozen=True)
class SimulatorParameters:
    """Checked node parameters; ``None`` overrides keep the scenario's value."""

    scenario: str
    wait_for_subscribers: int = 1
    publish_clock: bool = True
    startup_timeout: float = 20.0
    lockstep: bool | None = None
    timeout: float | None = None
    failsafe: str | None = None
    real_time_factor: float | None = None
    duration: float | None = None
    recorded_topics: frozenset[str] = frozenset()  # its publishers on these wait for a reader (handshake)


def parse_parameters(values: dict[str, Any]) -> SimulatorParameters:
    """Check raw parameter values (``None`` = not given) and return them typed.

    Raises :class:`ConfigError` naming the parameter, e.g.
    ``ROS parameter: failsafe: must be one of hold, cut; got 'explode'``.
    """
    given = {name: value for name, value in values.items() if value is not None}
    section = Section(given, "", PARAMETER_SOURCE)
    scenario = section.string("scenario")
    if not scenario.strip():
        raise section.error("scenario", "must name a built-in scenario or a scenario YAML file")
    parsed = SimulatorParameters(
        scenario=scenario,
        wait_for_subscribers=section.integer("wait_for_subscribers", 1, minimum=0),
        publish_clock=section.boolean("publish_clock", True),
        startup_timeout=section.number("startup_timeout", 20.0, strictly_positive=True),
        lockstep=section.boolean("lockstep") if section.has("lockstep") else None,
        timeout=section.number("timeout", strictly_positive=True) if section.has("timeout") else None,
        failsafe=section.string("failsafe", choices=("hold", "cut")) if section.has("failsafe") else None,
        real_time_factor=(
            section.number("real_time_factor", strictly_positive=True) if section.has("real_time_factor") else None
        ),
        duration=section.number("duration", strictly_positive=True) if section.has("duration") else None,
        recorded_topics=parse_recorded_topics(section.string(RECORDED_TOPICS.name, "")),
    )
    section.reject_unknown()
    return parsed


def apply_parameter_overrides(data: dict[str, Any], params: SimulatorParameters) -> None:
    """Write the given overrides into a scenario mapping (in place), before it is validated."""
    if params.duration is not None:
        data["duration"] = params.duration
    lockstep_overrides = {
        "enabled": params.lockstep,
        "timeout": params.timeout,
        "failsafe": params.failsafe,
        "real_time_factor": params.real_time_factor,
    }
    lockstep_overrides = {k: v for k, v in lockstep_overrides.items() if v is not None}
    if not lockstep_overrides:
        return
    section = data.get("lockstep")
    if section is None:
        section = data["lockstep"] = {}
    if isinstance(section, dict):  # anything else is refused by simulation_config with the file's name
        section.update(lockstep_overrides)


def load_simulation(params: SimulatorParameters) -> tuple[Scenario, SimulationConfig]:
    """Load the scenario named by the parameters, apply the overrides and validate the plant side."""
    try:
        resolve_config_path(params.scenario, "scenarios")
    except ConfigError as error:
        where = f"{error.source}: " if error.source else ""
        raise ConfigError("scenario", f"{where}{error.reason}", PARAMETER_SOURCE) from None
    scenario = load_scenario(params.scenario)
    apply_parameter_overrides(scenario.data, params)
    return scenario, simulation_config(scenario)
