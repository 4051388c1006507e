"""A sweep's flights set up from its scenario packed once: per flight only the swept values are packed anew.

Setting a flight up from its scenario (validating every section into configs, then packing the plant, the
controller and the observer: :func:`fsr_bringup.runner.in_process_flight.prepare_flight`) takes 3-4 ms for
ex4, about what its 5 s flight takes. Most of it is the same for every flight of a sweep, so :class:`PackedSweep` sets
the sweep's scenario up once and keeps the packed objects and a copy of their initial states; a flight whose
swept keys are all in :data:`REPACKED_KEYS` then only has those values checked and packed (exactly as the
full set-up packs them) and every state put back to its initial values. Any other key, or a value the quick
check does not take, gives None: the flight is set up in full (which also names a refused value).

:data:`REPACKED_KEYS`:

* ``plant.mass`` and ``plant.inertia``: the true plant's mass properties, read by nothing but the plant's packed
  ``mass``, ``inertia`` and ``inertia_inv`` (the controller and the observer know the nominal vehicle) and by
  the effective truth the estimate is measured against;
* ``estimator.c0`` and ``estimator.r``: the observer's filter, read by nothing but the observer (a new one is
  made, as the full set-up makes it) - unless the controller compensates with the estimate (its own observer
  then has them too: set up in full), or the estimator is off.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from fsr_bringup.sweeps.measured import LoopFlight, loop_flight
from fsr_estimation.core.observer import MomentumObserver
from fsr_sim.model.checks import InvalidValueError, symmetric_positive_definite
from fsr_sim.model.plant import new_plant_state

REPACKED_KEYS = ("plant.mass", "plant.inertia", "estimator.c0", "estimator.r")
PLANT_KEYS = ("plant.mass", "plant.inertia")


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


def _positive(value: Any) -> float | None:
    """``plant.mass`` or ``estimator.c0`` as the scenario's validation takes it (a finite number > 0), or None."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    value = float(value)
    return value if math.isfinite(value) and value > 0.0 else None


def _r(value: Any) -> int | None:
    """``estimator.r`` as the scenario's validation takes it (an integer >= 1), or None."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        return None
    return int(value)


def _inertia(value: Any) -> np.ndarray | None:
    """``plant.inertia`` as the scenario's validation takes it (3 numbers or a 3x3, SPD), or None."""
    try:
        return np.array(symmetric_positive_definite(value, "plant.inertia"), dtype=float)
    except (InvalidValueError, TypeError, ValueError):
        return None


class PackedSweep:
    """The flights of one sweep's scenario, set up from one packed flight (module docstring)."""

    def __init__(self, setup, band: float) -> None:  # noqa: ANN001 - a FlightSetup, not flown yet
        self.flight = loop_flight(setup, band)
        self.plant_vehicle = setup.simulation.plant_vehicle
        self.initial_x = setup.plant.core_state.x.copy()
        self.controller_state = _snapshot(setup.controller.state)
        self.observer_state = _snapshot(setup.observer.state)
        self.model_inertia = np.asarray(setup.estimation.inertia, dtype=float)
        self.estimation = setup.estimation
        self.control_period = setup.simulation.control_period
        self.filter_keys = setup.estimation.enabled and not setup.controller.params.compensation.enabled

    def flight_for(self, values: dict[str, Any]) -> LoopFlight | None:
        """The flight with ``values`` set, ready to fly (its states at their initial values), or None when
        it must be set up in full (module docstring)."""
        keys = set(values)
        if not keys <= set(REPACKED_KEYS):
            return None
        if keys - set(PLANT_KEYS) and not self.filter_keys:
            return None
        mass, inertia = self.plant_vehicle.mass, self.plant_vehicle.inertia
        if "plant.mass" in values:
            mass = _positive(values["plant.mass"])
            if mass is None:
                return None
        if "plant.inertia" in values:
            inertia = _inertia(values["plant.inertia"])
            if inertia is None:
                return None
        observer = None
        if keys & {"estimator.c0", "estimator.r"}:
            c0 = _positive(values.get("estimator.c0", self.estimation.c0))
            r = _r(values.get("estimator.r", self.estimation.r))
            if c0 is None or r is None:
                return None
            try:  # as prepare_flight makes it
                observer = MomentumObserver(self.estimation.mass, self.estimation.inertia, c0, r, self.control_period)
            except ValueError:  # the full set-up names the refused value
                return None
        flight = self.flight
        inertia = np.ascontiguousarray(inertia, dtype=float)  # as fsr_sim.model.plant.pack_plant packs them
        if not flight.plant_params.inertia.flags.writeable:  # read-only there too (the vehicle's): the compiled
            inertia.flags.writeable = False  # loop's signature is the full set-up's, not a second compilation
        params = flight.plant_params._replace(mass=float(mass), inertia=inertia, inertia_inv=np.linalg.inv(inertia))
        _restore(flight.controller_state, self.controller_state)
        if observer is None:
            _restore(flight.observer_state, self.observer_state)
        else:
            flight = flight.replace(observer_params=observer.params, observer_state=observer.state)
        measures = flight.measures._replace(mass=float(mass), inertia=inertia,
                                            inertia_delta=np.ascontiguousarray(self.model_inertia - inertia))
        state = new_plant_state(params, self.initial_x)
        rotor_truth = flight.actuator_params is not flight.plant_params  # else the plant's own (unused)
        actuator = flight.actuator_params._replace(mass=params.mass, inertia=inertia, inertia_inv=params.inertia_inv)
        return flight.replace(plant_params=params, plant_state=state, measures=measures,
                              actuator_params=actuator if rotor_truth else params,
                              actuator_state=flight.actuator_state if rotor_truth else state)
