"""A sweep's flight measured as it flies (:mod:`fsr_bringup.core.flight_measures`): its row without per-step arrays.

The compiled loop accumulates what :func:`fsr_bringup.sweeps.metrics.flight_row` takes from the flight's arrays;
:func:`measured_row` turns the accumulators into the same row (the same numbers to rounding: running sums where
numpy sums pairwise). What the loop cannot measure gives None and the flight is measured from its arrays: a
flight that ends early (its windows depend on where it ended) or one with a truth that is not finite.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from fsr_bringup.analysis.metrics import DEFAULT_SETTLE_S, LIMIT_TOLERANCE, MEAN_WINDOW_S, WRENCH_AXES
from fsr_bringup.core import flight_measures as core
from fsr_bringup.sweeps.metrics import SIGNIFICANT_WRENCH, settled_after_arrival
from fsr_control.core import controller as control_layout
from fsr_estimation.core.metrics import TOLERANCE, smoothing_gain
from fsr_sim.config.scenario import plant_from_config
from fsr_sim.contract import FINISHED
from fsr_sim.core.odometry import PUBLISHED_SIZE
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.allocation import SHORTFALL_TOLERANCE


class _Scratch:
    """The loop's scratch rows, reused by this process' flights."""

    def __init__(self, rotors: int) -> None:
        self.states = np.zeros(13)
        self.published = np.zeros((2, PUBLISHED_SIZE))
        self.row = np.zeros(control_layout.output_size(rotors))
        self.estimate = np.zeros(7)
        self.rotor_rows = np.zeros((core.ROTOR_ROWS, rotors))
        self.acc = np.zeros(core.SIZE)


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


def loop_flight(setup, band: float) -> LoopFlight:  # noqa: ANN001 - a FlightSetup
    """The loop's flight of ``setup`` with its measurement parameters (thresholds as
    :mod:`fsr_bringup.analysis.metrics` computes them)."""
    sim, estimation = setup.simulation, setup.estimation
    rotors = setup.rotors
    vehicle, plant = sim.vehicle, sim.plant_vehicle
    surfaces = setup.plant.params.surfaces  # pack_surfaces(environment, plant vehicle), as the analysis packs it
    actuator = setup.plant  # unused without the rotors' effective truth
    if rotors and estimation.enabled:  # the rotors' wrench of a command: the plant without actuator dynamics
        actuator = plant_from_config(replace(sim, plant_vehicle=replace(
            plant, rotor_time_constant=0.0, tilt_time_constant=0.0, tilt_rate_max=np.inf)))
    tol = LIMIT_TOLERANCE * vehicle.rotor_speed_max
    span = (setup.steps * setup.period_ns) * 1e-9
    # the mean spacing of the samples with a truth (0 .. K-1), as the analysis takes it from their stamps
    truth_sample_s = ((setup.steps - 1) * setup.period_ns) * 1e-9 / max(setup.steps - 1, 1)
    inertia = np.ascontiguousarray(plant.inertia, dtype=float)
    measures = core.MeasureParams(
        band=float(band), rotors=rotors, speed_upper=vehicle.rotor_speed_max - tol,
        speed_lower=vehicle.rotor_speed_min + tol,
        speed_middle=0.5 * (vehicle.rotor_speed_min + vehicle.rotor_speed_max),
        tilts=rotors and vehicle.has_servos and vehicle.tilt_angle_max < math.pi,
        tilt_limit=vehicle.tilt_angle_max * (1 - LIMIT_TOLERANCE), shortfall_tolerance=SHORTFALL_TOLERANCE,
        truth=bool(estimation.enabled), mass=float(plant.mass), mass_model=float(estimation.mass), inertia=inertia,
        inertia_delta=np.ascontiguousarray(np.asarray(estimation.inertia, float) - inertia), gravity=GRAVITY,
        tolerance=TOLERANCE, smoothing_gain=smoothing_gain(truth_sample_s),
        late_from=0.0 + min(DEFAULT_SETTLE_S, 0.5 * span), last_from=span - MEAN_WINDOW_S,
        lagging=setup.actuator_dynamics, commanded_tilts=rotors and vehicle.has_servos,
        with_tilts=rotors and vehicle.has_servos and plant.has_servos,
        ground=surfaces._replace(ceiling_effect=False), ceiling=surfaces._replace(ground_effect=False))
    return LoopFlight(setup.plant.params, setup.plant.core_state, setup.controller.params, setup.controller.state,
                      bool(estimation.enabled), bool(estimation.rotor_state), setup.observer.params,
                      setup.observer.state, setup.steps, setup.period_ns, sim.vehicle.rotor_count, measures,
                      actuator.params, actuator.core_state, setup.control_bounds)


def fly_measured(flight: LoopFlight) -> dict[str, Any] | None:
    """Fly ``flight`` whole, measured in the loop: its row, or None when the loop could not measure it (module
    docstring: the flight is then to be flown again from its arrays)."""
    outcome, _, acc = fly_accumulated(flight)
    if outcome != core.FINISHED or acc[core.TRUTH_UNDEFINED] > 0:
        return None
    return measured_row(flight, acc)


def fly_accumulated(flight: LoopFlight) -> tuple[int, int, np.ndarray]:
    """Fly ``flight`` whole in the measuring loop: its outcome (``flight_loop``'s), last step and accumulators
    (this process' scratch row, overwritten by its next flight)."""
    n = flight.rotor_count
    scratch = _SCRATCH.get(n)
    if scratch is None:
        scratch = _SCRATCH[n] = _Scratch(n)
    outcome, k, _ = core.fly_measured(
        flight.plant_params, flight.plant_state, flight.controller_params, flight.controller_state,
        flight.with_estimator, flight.estimator_measured, flight.observer_params, flight.observer_state,
        flight.steps, flight.period_ns, flight.measures, flight.actuator_params, flight.actuator_state,
        flight.control_bounds, scratch.states, scratch.published, scratch.row, scratch.estimate, scratch.rotor_rows,
        scratch.acc)
    return outcome, k, scratch.acc


def _degrees(acc: np.ndarray, at: int) -> float:
    """The angle [deg] of the ``(sin, cos)`` parts at ``acc[at]`` (NaN: no finite sample)."""
    if not acc[core.ATTITUDE_SAMPLES]:
        return math.nan
    return float(np.degrees(np.arctan2(acc[at], acc[at + 1])))


def measured_row(flight: LoopFlight, acc: np.ndarray) -> dict[str, Any]:
    """The row (:data:`fsr_bringup.sweeps.metrics.METRIC_COLUMNS`) of a finished flight from its accumulators."""
    count = flight.steps + 1
    period_ns = flight.period_ns
    measures = flight.measures

    def time(k: int) -> float:
        return (k * period_ns) * 1e-9

    valid = acc[core.POSITION_SAMPLES] > 0
    last = int(acc[core.POSITION_LAST_OUTSIDE])
    row: dict[str, Any] = {
        "end_reason": FINISHED, "end_detail": "", "flown_s": time(count - 1),
        "position_error_final_m": float(acc[core.POSITION_FINAL]) if valid else math.nan,
        "position_error_peak_m": float(acc[core.POSITION_PEAK]) if valid else math.nan,
        "position_error_rms_m": math.sqrt(acc[core.POSITION_SQUARES] / acc[core.POSITION_SAMPLES]) if valid
        else math.nan,
        "attitude_error_final_deg": _degrees(acc, core.ATTITUDE_FINAL),
        "attitude_error_peak_deg": _degrees(acc, core.ATTITUDE_PEAK),
        "settling_time_s": settled_after_arrival(time(count - 1), int(acc[core.REFERENCE_LAST_MOVING]) + 1,
                                                 last + 1, time),
    }
    if not measures.rotors:
        row.update(rotor_speed_peak_rad_s=math.nan, saturated_fraction=math.nan, gave_way="")
    else:
        fraction = acc[core.SATURATED_STEPS] / count
        if measures.tilts:
            fraction = max(fraction, acc[core.TILT_STEPS] / count)
        row.update(rotor_speed_peak_rad_s=float(acc[core.ROTOR_SPEED_PEAK]), saturated_fraction=float(fraction),
                   gave_way="+".join(axis for c, axis in enumerate(WRENCH_AXES) if acc[core.GAVE_WAY + c]))
    row.update(estimate_force_rms_N=math.nan, estimate_torque_rms_N_m=math.nan, estimate_settling_s=math.nan,
               estimate_force_settling_s=math.nan)
    samples = int(acc[core.TRUTH_SAMPLES])
    if measures.truth and samples >= 2 and acc[core.ESTIMATE_LATE] > 0:
        rms = np.sqrt(acc[core.ESTIMATE_SQUARES:core.ESTIMATE_SQUARES + 6] / acc[core.ESTIMATE_LATE])
        last_samples = acc[core.TRUTH_LAST_SAMPLES]
        final_truth = (acc[core.TRUTH_LAST_SUM:core.TRUTH_LAST_SUM + 6] / last_samples if last_samples
                       else np.full(6, math.nan))
        significant = [c for c in range(6) if abs(final_truth[c]) >= SIGNIFICANT_WRENCH]

        def slowest(last_outside: int, final_band: int, channels: list[int]) -> float:
            settled = []
            for c in channels:
                outside = acc[last_outside + c]
                value = math.nan if outside >= samples - 1 else time(int(outside) + 1) - time(0)
                settled.append(value if acc[final_band + c] > 0.0 else math.nan)
            return (math.inf if any(math.isnan(v) for v in settled) else max(settled)) if settled else math.nan

        row.update(estimate_force_rms_N=float(np.sqrt(np.sum(rms[:3] ** 2))),
                   estimate_torque_rms_N_m=float(np.sqrt(np.sum(rms[3:] ** 2))),
                   estimate_settling_s=slowest(core.ESTIMATE_LAST_OUTSIDE, core.FINAL_BAND, significant),
                   estimate_force_settling_s=slowest(core.SMOOTHED_LAST_OUTSIDE, core.SMOOTHED_FINAL_BAND,
                                                     [c for c in significant if c < 3]))
    return row
