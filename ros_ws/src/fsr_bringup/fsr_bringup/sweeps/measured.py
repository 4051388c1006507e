"""A sweep's flight measured as it flies (:func:`fsr_bringup.core.flight_loop.fly` with ``MEASURE``, the
accumulators of :mod:`fsr_bringup.core.flight_measures`): its row without per-step arrays.

The compiled loop fills the accumulators that :func:`fsr_bringup.sweeps.metrics.flight_row` feeds a flight's
arrays through; :func:`measured_row` turns them into the row (:func:`fsr_bringup.sweeps.metrics.accumulated_row`;
the same numbers to rounding: the effective truth from the loop's state rather than from the published one).
What the loop cannot measure gives None and the flight is measured from its arrays: a flight that ends early
(its windows depend on where it ended) or one with a truth that is not finite.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from fsr_bringup.core import flight_measures as core
from fsr_bringup.core.flight_loop import FINISHED, MEASURE, LoopController, LoopEstimator, LoopPlant, LoopTrace, fly
from fsr_bringup.sweeps.metrics import accumulated_row, measure_params
from fsr_control.core import controller as control_layout
from fsr_sim.config.scenario import plant_from_config
from fsr_sim.core.odometry import PUBLISHED_SIZE


class _Scratch:
    """The loop's scratch rows (two of each: the steps ``k`` and ``k + 1``), reused by this process' flights."""

    def __init__(self, rotors: int) -> None:
        self.states = np.zeros((2, 13))
        self.published = np.zeros((2, PUBLISHED_SIZE))
        self.actuators = np.zeros((2, 2 * rotors))
        self.control = np.zeros((2, control_layout.output_size(rotors)))
        self.estimates = np.zeros((2, 7))
        self.rotor_rows = np.zeros((core.ROTOR_ROWS, rotors))
        self.acc = core.new_accumulators()


_SCRATCH: dict[int, _Scratch] = {}


@dataclass
class LoopFlight:
    """What the measured loop flies: the packed plant, controller and observer with their states, the steps
    and the measurement parameters."""

    plant_params: Any
    plant_state: Any
    controller_params: Any
    controller_state: Any
    with_estimator: bool
    estimator_measured: bool  # estimator.input: measured, where rotor_state is published
    observer_params: Any
    observer_state: Any
    steps: int
    period_ns: int
    rotor_count: int
    measures: core.MeasureParams
    actuator_params: Any  # the plant without actuator dynamics (the rotors' wrench of a command)
    actuator_state: Any  # its scratch state
    control_bounds: tuple  # the scenario's divergence bounds (fsr_sim.model.control_loss.ControlBounds.pack)

    def replace(self, **changes: Any) -> LoopFlight:
        return replace(self, **changes)


def actuator_plant(sim, estimation):  # noqa: ANN001, ANN201 - configs; a fsr_sim.model.plant.Plant or None
    """The plant without actuator dynamics (the rotors' wrench of a command, as the analysis computes it), where
    the rotors' effective truth is measured; None elsewhere."""
    if sim.actuation != "rotors" or not estimation.enabled:
        return None
    return plant_from_config(replace(sim, plant_vehicle=replace(
        sim.plant_vehicle, rotor_time_constant=0.0, tilt_time_constant=0.0, tilt_rate_max=np.inf)))


def loop_flight(setup, band: float) -> LoopFlight:  # noqa: ANN001 - a FlightSetup
    """The loop's flight of ``setup`` with its measurement parameters (:func:`measure_params`)."""
    sim, estimation = setup.simulation, setup.estimation
    steps, period_ns = setup.steps, setup.period_ns
    # the mean spacing of the samples with a truth (0 .. K-1), as the analysis takes it from their stamps
    sample_s = ((steps - 1) * period_ns) * 1e-9 / max(steps - 1, 1)
    measures = measure_params(sim, estimation, 0.0, (steps * period_ns) * 1e-9, sample_s, band,
                              setup.actuator_dynamics)
    actuator = actuator_plant(sim, estimation) or setup.plant  # the plant's own: unused without the rotors' truth
    return LoopFlight(setup.plant.params, setup.plant.core_state, setup.controller.params, setup.controller.state,
                      bool(estimation.enabled), bool(estimation.rotor_state), setup.observer.params,
                      setup.observer.state, setup.steps, setup.period_ns, sim.vehicle.rotor_count, measures,
                      actuator.params, actuator.core_state, setup.control_bounds)


def fly_measured(flight: LoopFlight) -> dict[str, Any] | None:
    """Fly ``flight`` whole, measured in the loop: its row, or None when the loop could not measure it (module
    docstring: the flight is then to be flown again from its arrays)."""
    outcome, _, acc = fly_accumulated(flight)
    if outcome != FINISHED or acc[0].truth_undefined > 0:
        return None
    return measured_row(flight, acc)


def fly_accumulated(flight: LoopFlight) -> tuple[int, int, np.ndarray]:
    """Fly ``flight`` whole in the measuring loop: its outcome (``flight_loop``'s), last step and accumulators
    (this process' scratch row, overwritten by its next flight)."""
    n = flight.rotor_count
    scratch = _SCRATCH.get(n)
    if scratch is None:
        scratch = _SCRATCH[n] = _Scratch(n)
    estimator = LoopEstimator(flight.with_estimator, flight.estimator_measured, flight.observer_params,
                              flight.observer_state)
    trace = LoopTrace(scratch.states, scratch.published, scratch.actuators, scratch.control, scratch.estimates)
    measurement = core.Measurement(flight.measures, flight.actuator_params, flight.actuator_state, scratch.rotor_rows,
                                   scratch.acc)
    outcome, k, _ = fly(LoopPlant(flight.plant_params, flight.plant_state),
                        LoopController(flight.controller_params, flight.controller_state), estimator, 0, flight.steps,
                        flight.steps, flight.period_ns, flight.control_bounds, MEASURE, trace, measurement)
    return outcome, k, scratch.acc


def measured_row(flight: LoopFlight, acc: np.ndarray) -> dict[str, Any]:
    """The row (:data:`fsr_bringup.sweeps.metrics.METRIC_COLUMNS`) of a finished flight from its accumulators."""
    period_ns = flight.period_ns
    return accumulated_row(acc, flight.measures, flight.steps + 1, lambda k: (k * period_ns) * 1e-9)
