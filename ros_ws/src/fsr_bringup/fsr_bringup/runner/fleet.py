"""Fleets: several vehicles in one run, each under its own namespace (``/uav1``, ``/uav2``, ...).

A fleet file is a YAML mapping with ``name``, ``description`` and ``fleet``: a list of entries
``{namespace: /uav1, scenario: <built-in name or path relative to the file>, set: [KEY=VALUE, ...]}``.
Built-in fleets ship in ``fsr_bringup/fleets``. Each vehicle gets its own simulator, controller and
estimator (the vehicles do not interact, so one simulator per vehicle keeps each lockstep independent);
one recorder records every namespace.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from fsr_bringup.runner.scenario_check import CheckedScenario, check_scenario
from fsr_sim.config.scenario import load_scenario
from fsr_sim.config.validation import ConfigError, Section, load_yaml_file

NAMESPACE_PATTERN = re.compile(r"^/[A-Za-z][A-Za-z0-9_]*$")


@dataclass
class FleetMember:
    namespace: str
    checked: CheckedScenario


@dataclass
class Fleet:
    name: str
    source: str
    members: list[FleetMember]


def builtin_fleet_dir() -> Path:
    return Path(str(resources.files("fsr_bringup").joinpath("fleets")))


def builtin_fleet_names() -> list[str]:
    return sorted(p.stem for p in builtin_fleet_dir().glob("*.yaml"))


def fleet_path(name_or_path: str) -> Path | None:
    """The fleet file for a built-in fleet name or a YAML path holding a ``fleet`` list, else None."""
    builtin = builtin_fleet_dir() / f"{name_or_path}.yaml"
    if builtin.is_file():
        return builtin
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml") and path.is_file():
        data = load_yaml_file(path)
        if "fleet" in data:
            return path
    return None


def load_fleet(path: Path, overrides: list[str]) -> Fleet:
    """Parse and validate every member's scenario; ``overrides`` apply to all members after their own."""
    root = Section(load_yaml_file(path), "", str(path))
    name = root.string("name", path.stem)
    root.string("description", "")
    entries = root.raw("fleet")
    root.reject_unknown()
    if not isinstance(entries, list) or not entries:
        raise root.error("fleet", "must be a non-empty list of {namespace, scenario, set}")
    members: list[FleetMember] = []
    for index, entry in enumerate(entries):
        item = Section(entry, f"fleet.{index}", str(path))
        namespace = item.string("namespace")
        if not NAMESPACE_PATTERN.match(namespace):
            raise item.error("namespace", f"must look like /uav1 (a slash and a ROS name), got '{namespace}'")
        if namespace in {m.namespace for m in members}:
            raise item.error("namespace", f"'{namespace}' is used twice")
        scenario_name = item.string("scenario")
        candidate = path.parent / scenario_name
        scenario_ref = candidate if scenario_name.endswith((".yaml", ".yml")) else scenario_name
        sets = item.raw("set", [])
        if not isinstance(sets, list) or not all(isinstance(s, str) for s in sets):
            raise item.error("set", "must be a list of 'KEY=VALUE' strings")
        item.reject_unknown()
        try:
            scenario = load_scenario(scenario_ref, [*sets, *overrides])
        except ConfigError as error:
            raise ConfigError(f"fleet.{index}", str(error), str(path)) from None
        members.append(FleetMember(namespace, check_scenario(scenario)))
    return Fleet(name, str(path), members)
