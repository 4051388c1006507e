"""Scenario files: one YAML mapping that describes a whole flight.

Each package reads (and validates) its own sections: ``fsr_sim`` the plant side (this module:
``vehicle``, ``duration``, ``physics_dt``, ``actuation``, ``initial_state``, ``plant``, ``environment``,
``disturbances``, ``lockstep``), ``fsr_control`` the ``trajectory`` and ``controller`` sections, and
``fsr_estimation`` the ``estimator`` section. Unknown keys are refused everywhere, with the file and the
dotted key in the message.

Overrides use dotted paths with YAML values: ``apply_override(data, "disturbances.0.force", "[1, 0, 0]")``.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from fsr_sim.config.validation import (
    ConfigError,
    Section,
    load_yaml_file,
    resolve_config_path,
    yaml_error_text,
)
from fsr_sim.model.disturbances import DisturbanceProfile, disturbance_from_section
from fsr_sim.model.environment import Environment, environment_from_section
from fsr_sim.model.so3 import rotation_from_euler_zyx
from fsr_sim.model.vehicle import Vehicle, checked_inertia, load_vehicle

TOP_LEVEL_KEYS = (
    "name", "description", "vehicle", "duration", "physics_dt", "physics_substeps", "actuation",
    "initial_state", "plant", "environment", "disturbances", "lockstep", "trajectory", "controller",
    "estimator",
)


@dataclass
class Scenario:
    """A scenario's raw (merged) mapping and where it came from; sections are parsed on demand."""

    data: dict[str, Any]
    source: str
    base_dir: Path

    @property
    def name(self) -> str:
        return str(self.data.get("name", Path(self.source).stem))

    def section(self, name: str) -> Section:
        """Checked access to the top-level section ``name`` (an empty mapping if absent)."""
        return Section(self.data.get(name), name, self.source)

    def dump(self) -> str:
        """The merged scenario as YAML text (vehicle path made absolute so it loads from anywhere)."""
        data = copy.deepcopy(self.data)
        vehicle = data.get("vehicle")
        if isinstance(vehicle, str) and (vehicle.endswith((".yaml", ".yml")) or "/" in vehicle):
            data["vehicle"] = str((self.base_dir / vehicle).resolve())
        return yaml.safe_dump(data, sort_keys=False)


def load_scenario(name_or_path: str | Path, overrides: list[str] | None = None) -> Scenario:
    """Load a built-in scenario (``ex4_geometric``) or a YAML file, then apply ``KEY=VALUE`` overrides."""
    path = resolve_config_path(str(name_or_path), "scenarios")
    data = load_yaml_file(path)
    for item in overrides or []:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise ConfigError("--set", f"expected KEY=VALUE, got '{item}'", str(path))
        apply_override(data, key.strip(), value, str(path))
    unknown = sorted(str(k) for k in data if k not in TOP_LEVEL_KEYS)
    if unknown:
        raise ConfigError(unknown[0], f"unknown key (known: {', '.join(TOP_LEVEL_KEYS)})", str(path))
    return Scenario(data=data, source=str(path), base_dir=path.parent)


def apply_override(data: dict[str, Any], dotted_key: str, yaml_value: str, source: str = "") -> None:
    """Set ``data[a][b][0]...`` from ``a.b.0`` to the YAML-parsed ``yaml_value`` (in place)."""
    try:
        value = yaml.safe_load(yaml_value)
    except yaml.YAMLError as error:
        reason = f"--set value {yaml_value!r} is not valid YAML{yaml_error_text(error, single_line=True)}"
        raise ConfigError(dotted_key, reason, source) from None
    parts = dotted_key.split(".")
    node: Any = data
    for depth, part in enumerate(parts[:-1]):
        where = ".".join(parts[: depth + 1])
        if isinstance(node, list):
            node = node[_list_index(node, part, where, source)]
        else:
            if node.get(part) is None:
                node[part] = {}
            node = node[part]
        if not isinstance(node, (dict, list)):
            raise ConfigError(where, f"is a {type(node).__name__}, cannot hold '{parts[depth + 1]}'", source)
    last = parts[-1]
    if isinstance(node, list):
        node[_list_index(node, last, dotted_key, source)] = value
    else:
        node[last] = value


def _list_index(node: list, part: str, where: str, source: str) -> int:
    if not part.isdigit() or int(part) >= len(node):
        raise ConfigError(where, f"index '{part}' out of range for a list of {len(node)}", source)
    return int(part)


@dataclass
class InitialState:
    position: np.ndarray
    rotation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray


@dataclass
class SimulationConfig:
    """The plant side of a scenario, validated."""

    name: str
    vehicle: Vehicle  # nominal model (what the controller and estimator use)
    plant_vehicle: Vehicle  # true plant (mass / inertia may differ: model mismatch)
    duration: float
    physics_dt: float
    physics_substeps: int
    actuation: str
    initial: InitialState
    environment: Environment
    disturbances: list[DisturbanceProfile] = field(default_factory=list)
    lockstep: bool = True
    lockstep_timeout: float = 1.0
    failsafe: str = "hold"
    real_time_factor: float = 1.0

    @property
    def control_period(self) -> float:
        """One lockstep step [s]: ``physics_dt * physics_substeps``."""
        return self.physics_dt * self.physics_substeps

    @property
    def step_count(self) -> int:
        return int(round(self.duration / self.control_period))


def load_vehicle_for(scenario: Scenario) -> Vehicle:
    name = Section(scenario.data, "", scenario.source).string("vehicle")
    candidate = scenario.base_dir / name
    try:
        return load_vehicle(candidate if name.endswith((".yaml", ".yml")) and candidate.is_file() else name)
    except ConfigError as error:
        raise ConfigError("vehicle", str(error), scenario.source) from None


def simulation_config(scenario: Scenario) -> SimulationConfig:
    """Parse and check the plant-side sections of ``scenario``."""
    source = scenario.source
    root = Section(scenario.data, "", source)
    vehicle = load_vehicle_for(scenario)
    root.raw("vehicle")
    for key in ("name", "description", "trajectory", "controller", "estimator"):
        root.raw(key)
    duration = root.number("duration", strictly_positive=True)
    physics_dt = root.number("physics_dt", 0.001, strictly_positive=True, maximum=0.1)
    substeps = root.integer("physics_substeps", 1, minimum=1)
    actuation = root.string("actuation", "rotors", choices=("rotors", "wrench"))

    initial = root.section("initial_state")
    position = initial.vector("position", 3, [0.0, 0.0, 0.0])
    rpy = np.deg2rad(initial.vector("attitude_rpy_deg", 3, [0.0, 0.0, 0.0]))
    velocity = initial.vector("velocity", 3, [0.0, 0.0, 0.0])
    angular_velocity = initial.vector("angular_velocity", 3, [0.0, 0.0, 0.0])
    initial.reject_unknown()

    plant = root.section("plant")
    mass = plant.number("mass", vehicle.mass, strictly_positive=True)
    inertia = checked_inertia(plant.raw("inertia", vehicle.inertia), "plant.inertia", source)
    plant.reject_unknown()

    environment = environment_from_section(root.section("environment"))
    disturbance_list = root.raw("disturbances", [])
    if not isinstance(disturbance_list, list):
        raise root.error("disturbances", f"must be a list, got {type(disturbance_list).__name__}")
    disturbances = [
        disturbance_from_section(Section(item, f"disturbances.{i}", source))
        for i, item in enumerate(disturbance_list)
    ]

    lockstep = root.section("lockstep")
    lockstep_enabled = lockstep.boolean("enabled", True)
    timeout = lockstep.number("timeout", 1.0, strictly_positive=True)
    failsafe = lockstep.string("failsafe", "hold", choices=("hold", "cut"))
    real_time_factor = lockstep.number("real_time_factor", 1.0, strictly_positive=True)
    lockstep.reject_unknown()
    root.reject_unknown()

    duration_steps = duration / (physics_dt * substeps)
    if abs(duration_steps - round(duration_steps)) > 1e-6:
        raise root.error("duration", f"must be a whole number of steps of {physics_dt * substeps} s")
    return SimulationConfig(
        name=scenario.name,
        vehicle=vehicle,
        plant_vehicle=vehicle.with_mass_properties(mass, inertia),
        duration=duration,
        physics_dt=physics_dt,
        physics_substeps=substeps,
        actuation=actuation,
        initial=InitialState(position, rotation_from_euler_zyx(rpy), velocity, angular_velocity),
        environment=environment,
        disturbances=disturbances,
        lockstep=lockstep_enabled,
        lockstep_timeout=timeout,
        failsafe=failsafe,
        real_time_factor=real_time_factor,
    )
