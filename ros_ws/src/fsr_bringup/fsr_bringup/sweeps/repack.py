"""A sweep's flights set up from its scenario packed once: per flight only what the swept values change is
validated and packed anew, by the functions the full set-up uses.

Setting a flight up from its scenario (:func:`fsr_bringup.runner.in_process_flight.prepare_flight`: every section
validated into configs, the trajectory planned, then the plant, the controller and the observer packed) takes
15-30 ms, about what a 15 s flight takes. Most of it is the same for every flight of a sweep, so
:class:`PackedSweep` sets the sweep's scenario up once and keeps its configs, its packed objects and a copy of their
initial states. A flight is then set up from them in three steps:

1. Validate. The sections its keys are in (:data:`FAST_SECTIONS`; a key elsewhere - the trajectory, the
   duration, the vehicle - sets the flight up in full) are validated by the start-up's own section validators
   (:func:`fsr_sim.config.scenario.plant_vehicle_from_section`, :func:`~fsr_sim.config.scenario.
   disturbances_from_section`, :func:`~fsr_sim.config.sensor_sections.sensors_from_section`,
   :func:`fsr_control.config.controller_config.controller_settings`, :func:`fsr_estimation.config.
   estimator_config.estimator_config`), on the flight's own scenario mapping: a value they refuse is refused
   by the full set-up too, which names it (the flight is set up in full).
2. Compare. What changed is found by comparing the flight's configs with the sweep's, field by field - no list
   of scenario keys is kept here: a key's effect is whatever its section's validator makes of it.
3. Pack. Each changed config field is packed by the start-up's packing function of the arrays it is packed into
   (:data:`PLANT_PACKING`: the plant's mass properties, sensors, disturbances and turbulence; the controller's
   law, :func:`fsr_control.flight_controller.make_control_law`, for a change among the config fields that law's
   packing reads - traced once per sweep, not listed; the observer, :class:`fsr_estimation.estimator.observer.
   MomentumObserver`); every state is put back to its initial values (the plant's made anew from its params).
   A change no packing here covers (another vehicle property, the allocation, an estimator filter the
   controller's own observer has too) sets the flight up in full. A change of what the controller reads of the
   sensor stage (a stage switched on or off: a law may need the IMU; the odometry's delay and rate: INDI's
   bridge) has the controller section validated again too. The truth the estimate is measured against
   takes the plant's new mass properties as :func:`fsr_bringup.sweeps.measured.loop_flight` takes them.

What steps 1-3 make of a section is kept by its raw values (:data:`CACHE_SIZE` of them): a study's conditions
recur in every trial, a trial's gains in each of its conditions, so a flight's set-up is mostly a copy of the
touched sections and the states put back (about 0.5 ms).

The fast path's flight equals the full set-up's, array for array (``test_sweep_fast_paths.py``).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import fields, is_dataclass, replace
from typing import Any

import numpy as np

from fsr_bringup.sweeps.measured import LoopFlight, loop_flight
from fsr_control.config.controller_config import controller_settings
from fsr_control.flight_controller import make_control_law
from fsr_estimation.config.estimator_config import estimator_config
from fsr_estimation.estimator.observer import MomentumObserver
from fsr_sim.config.scenario import Scenario, disturbances_from_section, plant_vehicle_from_section, set_value
from fsr_sim.config.sensor_sections import sensors_from_section
from fsr_sim.config.validation import ConfigError, Section
from fsr_sim.model.disturbances import pack_disturbances
from fsr_sim.model.plant import new_plant_state, pack_mass_properties
from fsr_sim.model.sensors import pack_sensors
from fsr_sim.model.turbulence import pack_turbulence

FAST_SECTIONS = ("plant", "sensors", "disturbances", "controller", "estimator")  # top-level scenario sections
PLANT_SECTIONS = ("plant", "sensors", "disturbances")  # of them, the plant side's
CACHE_SIZE = 1024  # validated and packed sections kept (a study's conditions, a generation's trials)


def _sensors(sim: Any) -> dict[str, Any]:
    """The plant's sensor stages, packed as pack_plant packs them."""
    return {"sensors": pack_sensors(sim.odometry_noise, sim.imu, sim.control_period)}


# A config field of the plant side -> the PlantParams fields it is packed into, by pack_plant's own functions.
PLANT_PACKING = dict(  # noqa: C408 - keywords: the config's field names
    plant_vehicle=lambda sim: dict(zip(("mass", "inertia", "inertia_inv"), pack_mass_properties(sim.plant_vehicle),
                                       strict=True)),
    odometry_noise=_sensors,
    imu=_sensors,
    disturbances=lambda sim: dict(zip(("disturbances", "disturbance_knots"), pack_disturbances(list(sim.disturbances)),
                                      strict=True)),
    turbulence=lambda sim: {"turbulence": pack_turbulence(sim.turbulence, sim.physics_dt)},
)
MASS_PROPERTIES = ("mass", "inertia")  # the plant vehicle's fields PLANT_PACKING["plant_vehicle"] packs


def same(a: Any, b: Any) -> bool:
    """Whether two validated values are equal (arrays, dataclasses, lists and mappings compared item by item,
    NaN equal to NaN); anything it cannot compare counts as changed."""
    if a is b:
        return True
    if type(a) is not type(b):
        return False
    if isinstance(a, np.ndarray):
        return a.shape == b.shape and a.dtype == b.dtype and bool(np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))
    if is_dataclass(a):
        return all(same(getattr(a, f.name), getattr(b, f.name)) for f in fields(a))
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[key], b[key]) for key in a)
    if isinstance(a, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    try:
        return bool(a == b)
    except (TypeError, ValueError):
        return False


def changed_fields(new: Any, old: Any, names: Any = None) -> set[str]:
    """The fields (of ``names``; default: all) of dataclass ``new`` that differ from ``old``'s."""
    names = [f.name for f in fields(new)] if names is None else names
    return {name for name in names if not same(getattr(new, name), getattr(old, name))}


class _Reads:
    """A config whose attribute reads are recorded (which fields a packing function reads)."""

    def __init__(self, config: Any) -> None:
        object.__setattr__(self, "config", config)
        object.__setattr__(self, "names", set())

    def __getattr__(self, name: str) -> Any:
        self.names.add(name)
        return getattr(self.config, name)


def law_fields(config: Any, vehicle: Any) -> frozenset[str]:
    """The controller config fields the packing of its law reads (:func:`make_control_law`), but its type (which
    changes the controller's layout, not only its law's numbers)."""
    reads = _Reads(config)
    make_control_law(reads, vehicle)  # type: ignore[arg-type] - read like the config it wraps
    return frozenset(reads.names - {"type"})


def _snapshot(value: Any) -> Any:
    """A copy of a packed state (NamedTuples of arrays, nested): its arrays copied."""
    if isinstance(value, np.ndarray):
        return value.copy()
    if isinstance(value, tuple) and hasattr(value, "_fields"):
        return type(value)(*(_snapshot(item) for item in value))
    return value


def _restore(target: Any, snapshot: Any) -> None:
    """Put the arrays of ``target`` back to those of ``snapshot`` (same structure), in place."""
    if isinstance(target, np.ndarray):
        np.copyto(target, snapshot)
    elif isinstance(target, tuple) and hasattr(target, "_fields"):
        for item, saved in zip(target, snapshot, strict=True):
            _restore(item, saved)


class _FullSetUp(Exception):  # noqa: N818 - not an error: the flight is set up in full
    """The flight's values need the full set-up (module docstring)."""


def _sensing(sim: Any) -> tuple:
    """What of the sensor stage the controller's settings read (:func:`fsr_control.config.controller_config.
    controller_settings`: the law's checks, INDI's odometry bridge)."""
    odometry = sim.odometry_noise
    return odometry.enabled, odometry.delay_steps, odometry.every_steps, sim.imu.enabled


class PackedSweep:
    """The flights of one sweep's scenario, set up from one packed flight (module docstring)."""

    def __init__(self, setup, band: float) -> None:  # noqa: ANN001 - a FlightSetup, not flown yet
        self.scenario = setup.scenario
        self.flight = loop_flight(setup, band)
        self.simulation = setup.simulation
        self.config = setup.controller.config
        self.estimation = setup.estimation
        self.initial_x = setup.plant.core_state.x.copy()
        self.controller_state = _snapshot(setup.controller.state)
        self.observer_state = _snapshot(setup.observer.state)
        self.law_fields = law_fields(self.config, self.simulation.vehicle)
        # the observer's filter is read by nothing but the observer, unless the controller compensates with an
        # observer of its own (its config holds the filter too)
        self.observer_alone = self.estimation.enabled and self.config.compensation is None
        self.cache: dict[tuple, Any] = {}

    def flight_for(self, values: dict[str, Any]) -> LoopFlight | None:
        """The flight with ``values`` set, ready to fly (its states at their initial values), or None when it
        must be set up in full (module docstring)."""
        sections = {str(key).partition(".")[0] for key in values}
        if not sections <= set(FAST_SECTIONS):
            return None
        try:
            scenario = self._scenario(values, sections)
            data = scenario.data
            plant = sections & set(PLANT_SECTIONS)
            sim, packed = self._cached(("plant", *(repr(data.get(name)) for name in sorted(plant))),
                                       lambda: self._plant(scenario, plant)) if plant else (self.simulation, {})
            sensed = _sensing(sim)
            law = None
            if "controller" in sections or sensed != _sensing(self.simulation):
                key = ("controller", repr(data.get("controller")), repr(data.get("estimator")), sensed)
                law = self._cached(key, lambda: self._law(scenario, sim))
            observer = (self._cached(("estimator", repr(data.get("estimator"))), lambda: self._observer(scenario))
                        if "estimator" in sections else None)
        except (ConfigError, ValueError, _FullSetUp):  # the full set-up names a refused value
            return None
        return self._flight(packed, law, observer)

    def _scenario(self, values: dict[str, Any], sections: set[str]) -> Scenario:
        """The flight's scenario (as :func:`fsr_bringup.sweeps.axes.flight_scenario` makes it, only its changed
        sections copied)."""
        base = self.scenario
        data = dict(base.data)
        for name in sections:
            data[name] = copy.deepcopy(data.get(name))
        for key, value in values.items():
            set_value(data, str(key), copy.deepcopy(value), base.source)
        return Scenario(data=data, source=base.source, base_dir=base.base_dir)

    def _cached(self, key: tuple, make: Callable[[], Any]) -> Any:
        """``make()``, kept by ``key`` (the raw sections it validates: a study's conditions and a trial's gains
        recur from flight to flight)."""
        if key not in self.cache:
            if len(self.cache) >= CACHE_SIZE:
                self.cache.clear()
            self.cache[key] = make()
        return self.cache[key]

    def _plant(self, scenario: Scenario, sections: set[str]) -> tuple[Any, dict[str, Any]]:
        """The flight's plant side and the PlantParams fields packed anew for it (_FullSetUp: a change no
        packing here covers)."""
        base = self.simulation
        sim = self._simulation(scenario, sections)
        changed = changed_fields(sim, base)
        if not changed <= set(PLANT_PACKING):
            raise _FullSetUp
        if "plant_vehicle" in changed and not changed_fields(sim.plant_vehicle, base.plant_vehicle) <= set(
                MASS_PROPERTIES):
            raise _FullSetUp
        packed: dict[str, Any] = {}
        for name in sorted(changed):
            packed.update(PLANT_PACKING[name](sim))
        return sim, packed

    def _simulation(self, scenario: Any, sections: set[str]) -> Any:
        """The flight's plant side: the sweep's, with its changed sections validated anew."""
        base = self.simulation
        root = Section(scenario.data, "", scenario.source)
        changes: dict[str, Any] = {}
        if "plant" in sections:
            changes["plant_vehicle"] = plant_vehicle_from_section(root.section("plant"), base.vehicle)
        if sections & {"plant", "disturbances"}:
            changes["disturbances"], changes["turbulence"] = disturbances_from_section(
                root, changes.get("plant_vehicle", base.plant_vehicle), base.actuation)
        if "sensors" in sections:
            odometry, imu = sensors_from_section(root.section("sensors"), base.control_period)
            changes.update(odometry_noise=odometry, imu=imu)
        return replace(base, **changes) if changes else base

    def _law(self, scenario: Any, sim: Any) -> Any:
        """The flight's law params, packed anew when its config changed (None: the sweep's)."""
        settings = controller_settings(scenario, sim.vehicle, sim)
        config = replace(self.config, **settings)
        changed = changed_fields(config, self.config, settings)
        if not changed:
            return None
        if not changed <= self.law_fields:
            raise _FullSetUp
        return make_control_law(config, sim.vehicle).params

    def _observer(self, scenario: Any) -> tuple[Any, Any] | None:
        """The flight's observer's params and initial state, made anew as the full set-up makes them when its
        config changed (None: the sweep's)."""
        estimation = estimator_config(scenario)
        changed = changed_fields(estimation, self.estimation)
        if not changed:
            return None
        if not (self.observer_alone and changed <= {"c0", "r"}):
            raise _FullSetUp
        observer = MomentumObserver(estimation.mass, estimation.inertia, estimation.c0, estimation.r,
                                    self.simulation.control_period)
        return observer.params, _snapshot(observer.state)

    def _flight(self, packed: dict[str, Any], law: Any, observer: tuple[Any, Any] | None) -> LoopFlight:
        """The sweep's flight with ``packed`` PlantParams fields, ``law`` params and ``observer`` (params, initial
        state) put in (None: the sweep's), every state at its initial values."""
        flight = self.flight
        changes: dict[str, Any] = {}
        _restore(flight.controller_state, self.controller_state)
        if law is not None:
            changes["controller_params"] = flight.controller_params._replace(law=law)
        if observer is None:
            _restore(flight.observer_state, self.observer_state)
        else:
            changes.update(observer_params=observer[0], observer_state=_snapshot(observer[1]))
        params = flight.plant_params._replace(**packed)
        state = new_plant_state(params, self.initial_x)
        changes.update(plant_params=params, plant_state=state)
        if flight.actuator_params is not flight.plant_params:  # the rotors' effective truth: the same packing
            actuator = flight.actuator_params._replace(**packed)
            changes.update(actuator_params=actuator, actuator_state=new_plant_state(actuator, self.initial_x))
        else:
            changes.update(actuator_params=params, actuator_state=state)
        if "mass" in packed:  # the truth the estimate is measured against
            measures = flight.measures
            changes["measures"] = measures._replace(
                mass=params.mass, inertia=params.inertia,
                inertia_delta=np.ascontiguousarray(np.asarray(self.estimation.inertia, float) - params.inertia))
        return flight.replace(**changes)

