"""Scenario files: one YAML mapping that describes a whole flight.

Each package reads (and validates) its own sections: ``fsr_sim`` the plant side (this module:
``vehicle``, ``duration``, ``physics_dt``, ``actuation``, ``initial_state``, ``plant``, ``environment``,
``disturbances``, ``lockstep``); other packages register theirs under the entry-point group
``fsr.scenario_sections`` (name = top-level key, value = the function that validates the section from a
:class:`Scenario`), so this module names none of their keys (:func:`registered_sections`). Unknown keys are
refused everywhere, with the file and the dotted key in the message.

Overrides use dotted paths with YAML values: ``apply_override(data, "disturbances.0.force", "[1, 0, 0]")``.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field, replace
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from fsr_sim.config.plant_sections import disturbance_from_section, environment_from_section
from fsr_sim.config.sensor_sections import sensors_from_section
from fsr_sim.config.validation import (
    ConfigError,
    Section,
    checked_spd,
    load_yaml_file,
    resolve_config_path,
    yaml_error_text,
)
from fsr_sim.config.validation import yaml_value as parse_yaml_value
from fsr_sim.config.vehicle_file import dynamics_and_drag, load_vehicle_file
from fsr_sim.core.aerodynamics import has_aerodynamics
from fsr_sim.model.control_loss import DEFAULT_ATTITUDE_ERROR_DEG, DEFAULT_POSITION_ERROR_M, ControlBounds
from fsr_sim.model.disturbances import DisturbanceProfile
from fsr_sim.model.environment import Environment
from fsr_sim.model.plant import Plant, actuator_lags, pack_aerodynamics
from fsr_sim.model.sensors import ImuModel, OdometryNoise
from fsr_sim.model.so3 import rotation_from_euler_zyx
from fsr_sim.model.turbulence import DrydenTurbulence
from fsr_sim.model.vehicle import ROTOR_AERODYNAMICS, Vehicle

SECTION_GROUP = "fsr.scenario_sections"
PLANT_KEYS = (
    "name", "description", "vehicle", "duration", "physics_dt", "physics_substeps", "actuation",
    "initial_state", "plant", "environment", "disturbances", "lockstep", "sensors", "divergence",
)


def registered_sections() -> dict[str, Any]:
    """Top-level scenario sections other installed packages validate: name -> entry point (``.load()`` gives
    the validator ``f(scenario) -> config``)."""
    return dict(_registered_sections())


@cache
def _registered_sections() -> tuple[tuple[str, Any], ...]:
    """Scanning the installed distributions' entry points costs ~10 ms: once per process."""
    from importlib.metadata import entry_points

    return tuple((point.name, point) for point in entry_points(group=SECTION_GROUP))


def top_level_keys() -> tuple[str, ...]:
    """Every key a scenario may have at its top level: fsr_sim's own and the registered sections."""
    return (*PLANT_KEYS, *sorted(registered_sections()))


@dataclass
class Scenario:
    """A scenario's raw (merged) mapping and where it came from; sections are parsed on demand."""

    data: dict[str, Any]
    source: str
    base_dir: Path
    overridden: dict[str, str] = field(default_factory=dict)  # dotted key -> how it was set ("--set k=v")

    @property
    def name(self) -> str:
        return str(self.data.get("name", Path(self.source).stem))

    def attribute(self, error: ConfigError) -> ConfigError:
        """``error`` with the override that set the refused value as its source (``--set plant.mass=-1``), when
        an override set that key, one inside it or one containing it; else ``error`` itself (the file)."""
        for key, how in self.overridden.items():
            if error.key == key or error.key.startswith(f"{key}.") or key.startswith(f"{error.key}."):
                return ConfigError(error.key, error.reason, how)
        return error

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


def load_scenario(name_or_path: str | Path, overrides: list[str] | None = None,
                  values: dict[str, Any] | None = None) -> Scenario:
    """Load a built-in scenario (``ex4_geometric``) or a YAML file, then apply overrides.

    ``overrides``: ``KEY=VALUE`` strings with YAML values (``--set``); ``values``: ``{dotted key: Python value}``
    (the Python API), applied after them. Unknown top-level keys raise :class:`ConfigError`.
    """
    path = resolve_config_path(str(name_or_path), "scenarios")
    return scenario_from_mapping(load_yaml_file(path), str(path), path.parent, overrides, values)


def scenario_from_mapping(data: dict[str, Any], source: str = "<python>", base_dir: Path | None = None,
                          overrides: list[str] | None = None, values: dict[str, Any] | None = None) -> Scenario:
    """A scenario from a mapping (a copy is taken), with ``KEY=VALUE`` ``overrides`` and dotted-key ``values``;
    relative vehicle paths are resolved from ``base_dir`` (default: the working directory)."""
    if not isinstance(data, dict):
        raise ConfigError("", f"a scenario must be a mapping, got {type(data).__name__}", source)
    data = copy.deepcopy(data)
    overridden = {}
    for item in overrides or []:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise ConfigError("--set", f"expected KEY=VALUE, got '{item}'", source)
        overridden[key.strip()] = f"--set {item}"
        apply_override(data, key.strip(), value, overridden[key.strip()])
    for key, value in (values or {}).items():
        overridden[str(key)] = f"set {key}={value!r}"
        set_value(data, str(key), copy.deepcopy(value), overridden[str(key)])
    Section(data, "", source).reject_unknown(top_level_keys())  # names the closest known key of a typo
    return Scenario(data=data, source=source, base_dir=Path.cwd() if base_dir is None else Path(base_dir),
                    overridden=overridden)


def apply_override(data: dict[str, Any], dotted_key: str, yaml_value: str, source: str = "") -> None:
    """Set ``data[a][b][0]...`` from ``a.b.0`` to the YAML-parsed ``yaml_value`` (in place)."""
    try:
        value = parse_yaml_value(yaml_value)
    except yaml.YAMLError as error:
        reason = f"--set value {yaml_value!r} is not valid YAML{yaml_error_text(error, single_line=True)}"
        raise ConfigError(dotted_key, reason, source) from None
    set_value(data, dotted_key, value, source)


def set_value(data: dict[str, Any], dotted_key: str, value: Any, source: str = "") -> None:
    """Set ``data[a][b][0]...`` from the dotted key ``a.b.0`` to ``value`` (in place; missing mappings made)."""
    parts = dotted_key.split(".")
    node: Any = data
    for depth, part in enumerate(parts[:-1]):
        where = ".".join(parts[: depth + 1])
        if isinstance(node, list):
            node = node[_list_index(node, part, where, source)]
        else:
            if node.get(part) is None:
                if parts[depth + 1].isdigit():  # an item of a list the scenario does not have
                    raise ConfigError(where, f"is not set, so it has no item {parts[depth + 1]}: set the whole list "
                                             f"({where}=[...])", source)
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
    turbulence: list[DrydenTurbulence] = field(default_factory=list)  # the disturbances of kind dryden
    lockstep: bool = True
    lockstep_timeout: float = 1.0
    failsafe: str = "hold"
    real_time_factor: float = 1.0
    odometry_noise: OdometryNoise = field(default_factory=OdometryNoise)
    imu: ImuModel = field(default_factory=ImuModel)  # the vehicle's IMU (imu published when enabled)
    divergence: ControlBounds = field(default_factory=ControlBounds)  # when the flight has lost control

    @property
    def control_period(self) -> float:
        """One lockstep step [s]: ``physics_dt * physics_substeps``."""
        return self.physics_dt * self.physics_substeps

    @property
    def step_count(self) -> int:
        return int(round(self.duration / self.control_period))

    @property
    def publishes_rotor_state(self) -> bool:
        """The simulator publishes ``rotor_state`` (the rotors' measured speeds and tilts): the plant's rotors
        or servos lag their commands (without, they follow them within the step: the command is the measurement)."""
        return any(actuator_lags(self.plant_vehicle, self.actuation))


def load_vehicle_for(scenario: Scenario) -> Vehicle:
    """The scenario's nominal vehicle (a built-in name, or a YAML path relative to the scenario file)."""
    name = Section(scenario.data, "", scenario.source).string("vehicle")
    candidate = scenario.base_dir / name
    try:
        return load_vehicle_file(candidate if name.endswith((".yaml", ".yml")) and candidate.is_file() else name)
    except ConfigError as error:
        raise ConfigError("vehicle", str(error), scenario.source) from None


def simulation_config(scenario: Scenario) -> SimulationConfig:
    """Parse and check the plant-side sections of ``scenario`` (once per :class:`Scenario` object: a run's
    set-up asks for them from every package; a scenario's mapping is not changed once made - overrides make a
    new one - and the config is checked again if it has been)."""
    fingerprint = repr(scenario.data)
    cached = _SIMULATION_CONFIGS.get(id(scenario))
    if cached is not None and cached[0] is scenario and cached[1] == fingerprint:
        return cached[2]
    config = _simulation_config(scenario)
    if len(_SIMULATION_CONFIGS) >= 16:
        _SIMULATION_CONFIGS.clear()
    _SIMULATION_CONFIGS[id(scenario)] = (scenario, fingerprint, config)
    return config


_SIMULATION_CONFIGS: dict[int, tuple[Scenario, str, SimulationConfig]] = {}


def _simulation_config(scenario: Scenario) -> SimulationConfig:
    source = scenario.source
    root = Section(scenario.data, "", source)
    vehicle = load_vehicle_for(scenario)
    root.raw("vehicle")
    for key in ("name", "description"):
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

    plant_vehicle = plant_vehicle_from_section(root.section("plant"), vehicle)
    environment = environment_from_section(root.section("environment"))
    disturbances, turbulence = disturbances_from_section(root, plant_vehicle, actuation)

    lockstep = root.section("lockstep")
    lockstep_enabled = lockstep.boolean("enabled", True)
    timeout = lockstep.number("timeout", 1.0, strictly_positive=True)
    failsafe = lockstep.string("failsafe", "hold", choices=("hold", "cut"))
    real_time_factor = lockstep.number("real_time_factor", 1.0, strictly_positive=True)
    lockstep.reject_unknown()
    odometry_noise, imu = sensors_from_section(root.section("sensors"), physics_dt * substeps)
    divergence = root.section("divergence")
    bounds = ControlBounds(
        attitude_error_deg=divergence.number("attitude_error_deg", DEFAULT_ATTITUDE_ERROR_DEG, strictly_positive=True,
                                             maximum=180.0),
        position_error_m=divergence.number("position_error_m", DEFAULT_POSITION_ERROR_M, strictly_positive=True))
    divergence.reject_unknown()
    root.reject_unknown(known=(*PLANT_KEYS, *registered_sections()))

    duration_steps = duration / (physics_dt * substeps)
    if abs(duration_steps - round(duration_steps)) > 1e-6:
        raise root.error("duration", f"must be a whole number of steps of {physics_dt * substeps} s")
    return SimulationConfig(
        name=scenario.name,
        vehicle=vehicle,
        plant_vehicle=plant_vehicle,
        duration=duration,
        physics_dt=physics_dt,
        physics_substeps=substeps,
        actuation=actuation,
        initial=InitialState(position, rotation_from_euler_zyx(rpy), velocity, angular_velocity),
        environment=environment,
        disturbances=disturbances,
        turbulence=turbulence,
        lockstep=lockstep_enabled,
        lockstep_timeout=timeout,
        failsafe=failsafe,
        real_time_factor=real_time_factor,
        odometry_noise=odometry_noise,
        imu=imu,
        divergence=bounds,
    )


def plant_vehicle_from_section(plant: Section, vehicle: Vehicle) -> Vehicle:
    """The true plant of the ``plant`` section over the nominal ``vehicle``: its mass [kg], inertia [kg m^2],
    actuator dynamics and drag (the controller knows none of them)."""
    mass = plant.number("mass", vehicle.mass, strictly_positive=True)
    inertia = checked_spd(plant.raw("inertia", vehicle.inertia), plant.key("inertia"), plant.source)
    plant_overrides = dynamics_and_drag(plant, {name: getattr(vehicle, name) for name in (
        "rotor_time_constant", "tilt_time_constant", "tilt_rate_max", "drag_coefficients", *ROTOR_AERODYNAMICS)})
    plant.reject_unknown()
    return replace(vehicle.with_mass_properties(mass, inertia), **plant_overrides)


def disturbances_from_section(root: Section, plant_vehicle: Vehicle, actuation: str
                              ) -> tuple[list[DisturbanceProfile], list[DrydenTurbulence]]:
    """The scenario's ``disturbances`` (``root``: the whole scenario): the profiles and the Dryden winds, each
    wind checked to push through ``plant_vehicle``'s aerodynamics."""
    disturbance_list = root.raw("disturbances", [])
    if not isinstance(disturbance_list, list):
        raise root.error("disturbances", f"must be a list, got {type(disturbance_list).__name__}")
    parsed = [disturbance_from_section(Section(item, f"disturbances.{i}", root.source))
              for i, item in enumerate(disturbance_list)]
    disturbances = [item for item in parsed if isinstance(item, DisturbanceProfile)]
    turbulence = [item for item in parsed if isinstance(item, DrydenTurbulence)]
    if turbulence and not has_aerodynamics(pack_aerodynamics(plant_vehicle, actuation)):
        index = next(i for i, item in enumerate(parsed) if isinstance(item, DrydenTurbulence))
        raise root.error(f"disturbances.{index}", "a dryden wind pushes through the vehicle's aerodynamics, and "
                         "they are all zero: set plant.drag_coefficients (or the vehicle file's aerodynamic "
                         "coefficients)")
    return disturbances, turbulence


def plant_from_config(config: SimulationConfig) -> Plant:
    """The :class:`fsr_sim.model.plant.Plant` a scenario's plant side describes (true mass and inertia)."""
    initial = config.initial
    return Plant(
        config.plant_vehicle, dt=config.physics_dt, actuation=config.actuation, position=initial.position,
        rotation=initial.rotation, velocity=initial.velocity, angular_velocity=initial.angular_velocity,
        environment=config.environment, disturbances=config.disturbances, substeps=config.physics_substeps,
        odometry_noise=config.odometry_noise, turbulence=config.turbulence, imu=config.imu,
    )
