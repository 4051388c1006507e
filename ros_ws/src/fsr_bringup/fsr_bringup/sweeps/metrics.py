"""One flight of a sweep as one row: the accumulators of :mod:`fsr_bringup.core.flight_measures` (the metrics of
the flight summary, :mod:`fsr_bringup.analysis.metrics`, as running sums), flattened to numbers and short texts.
A sweep's flight fills them as it flies (:mod:`fsr_bringup.sweeps.measured`); a flight's arrays - in memory
(:func:`flight_row`) or a recording (:func:`recorded_row`) - are fed through the same functions after the fact.

Columns (:data:`METRIC_COLUMNS`; NaN where a metric does not apply, e.g. no estimator or wrench actuation):

* ``end_reason``: ``finished``, ``diverged`` (then ``end_detail`` says why) or ``invalid`` (the flight's values were
  refused before take-off: ``end_detail`` names the key); ``flown_s``: the simulated time flown [s];
* position error ``|p - p_d|`` [m]: ``position_error_final_m``, ``_peak_m``, ``_rms_m`` over the flight;
* attitude error against the commanded attitude ``R_c`` (angle of ``R_c^T R``) [deg]: ``attitude_error_final_deg``,
  ``_peak_deg``;
* ``settling_time_s``: from the reference's arrival (the first sample from which the position reference is at
  rest to the end) to the first sample from which ``|p - p_d| <= band`` [m] holds to the end (0: within the band on
  arrival; inf: it ends outside; NaN: the reference still moves at the end of the flight);
* ``rotor_speed_peak_rad_s``: the largest commanded rotor speed; ``saturated_fraction``: the fraction of steps
  with a rotor command at a speed limit (or a tilt at its limit); ``gave_way``: the wrench axes that fell short
  of the law's demand at the rotor limits (``torque_z+force_z``; empty: none);
* estimator against the effective truth (what the observer must converge to), body FRD:
  ``estimate_force_rms_N`` and ``estimate_torque_rms_N_m`` (RMS of the error norm after the summary's settle
  window: 5 s, at most half the flight) and ``estimate_settling_s`` (the slowest channel whose final truth is at least
  :data:`SIGNIFICANT_WRENCH` to stay within 3 % of it; inf: one never does; NaN: no such channel) and
  ``estimate_force_settling_s`` (the slowest such force channel, ``smoothed``: the estimate and the truth through
  a first-order low-pass of 0.1 s, :mod:`fsr_estimation.estimator.metrics`; with sensor noise the raw error never stays
  within 3 %, and with an actuator lag the torque's truth holds the lag's error of a noisy command).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from fsr_bringup.analysis.effective import effective_wrench
from fsr_bringup.analysis.load import RecordedFlight, zero_order_hold
from fsr_bringup.analysis.metrics import DEFAULT_SETTLE_S, LIMIT_TOLERANCE, MEAN_WINDOW_S, WRENCH_AXES
from fsr_bringup.core import flight_measures as core
from fsr_control.core import controller as layout
from fsr_estimation.estimator.metrics import TOLERANCE, smoothing_gain
from fsr_sim.contract import FINISHED
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.environment import pack_surfaces
from fsr_sim.model.rotors import SHORTFALL_TOLERANCE

DEFAULT_BAND_M = 0.01  # m: the position band of settling_time_s
SIGNIFICANT_WRENCH = 1e-3  # N, N m: a channel whose final effective truth is smaller has no settling time
METRIC_COLUMNS = (
    "end_reason", "end_detail", "flown_s",
    "position_error_final_m", "position_error_peak_m", "position_error_rms_m",
    "attitude_error_final_deg", "attitude_error_peak_deg", "settling_time_s",
    "rotor_speed_peak_rad_s", "saturated_fraction", "gave_way",
    "estimate_force_rms_N", "estimate_torque_rms_N_m", "estimate_settling_s", "estimate_force_settling_s",
)
RANKABLE_METRICS = tuple(c for c in METRIC_COLUMNS if c not in ("end_reason", "end_detail", "gave_way"))  # numeric
INVALID = "invalid"  # end_reason of a flight whose values were refused


def invalid_row(reason: str) -> dict[str, Any]:
    """The row of a flight that could not be set up (its values refused): ``reason`` names the key."""
    row: dict[str, Any] = dict.fromkeys(METRIC_COLUMNS, math.nan)
    row.update(end_reason=INVALID, end_detail=reason, gave_way="")
    return row


def settled_after_arrival(end: float, arrival: int, settled: int, time: Callable[[int], float]) -> float:
    """The settling time of the module docstring from the sample ``arrival`` at which the reference came to rest
    and the sample ``settled`` from which the error stays within the band (``time(k)`` [s] of sample ``k``, ``end``
    the last sample's): NaN if the reference never rests, inf if the error ends outside."""
    if time(arrival) > end:
        return math.nan
    if time(settled) > end:
        return math.inf
    return max(0.0, time(settled) - time(arrival))


def measure_params(sim, estimation, start: float, end: float, sample_s: float, band: float,  # noqa: ANN001
                   lagging: bool) -> core.MeasureParams:
    """The measurement parameters of a flight from ``start`` to ``end`` [s] with the plant side ``sim``
    (:class:`fsr_sim.config.scenario.SimulationConfig`) and the estimator ``estimation`` (None: none), thresholds
    and windows as :mod:`fsr_bringup.analysis.metrics` takes them; ``sample_s`` the mean spacing of the samples
    with a truth (all but the last); ``lagging``: the rotors lag their commands."""
    vehicle, plant = sim.vehicle, sim.plant_vehicle
    rotors = sim.actuation == "rotors"
    surfaces = pack_surfaces(sim.environment, plant)  # as the analysis packs it (the plant's own)
    tol = LIMIT_TOLERANCE * vehicle.rotor_speed_max
    inertia = np.ascontiguousarray(plant.inertia, dtype=float)
    model = estimation if estimation is not None else plant
    return core.MeasureParams(
        band=float(band), rotors=rotors, speed_upper=vehicle.rotor_speed_max - tol,
        speed_lower=vehicle.rotor_speed_min + tol,
        speed_middle=0.5 * (vehicle.rotor_speed_min + vehicle.rotor_speed_max),
        tilts=rotors and vehicle.has_servos and vehicle.tilt_angle_max < math.pi,
        tilt_limit=vehicle.tilt_angle_max * (1 - LIMIT_TOLERANCE), shortfall_tolerance=SHORTFALL_TOLERANCE,
        truth=estimation is not None and bool(estimation.enabled), mass=float(plant.mass),
        mass_model=float(model.mass), inertia=inertia,
        inertia_delta=np.ascontiguousarray(np.asarray(model.inertia, float) - inertia), gravity=GRAVITY,
        tolerance=TOLERANCE, smoothing_gain=smoothing_gain(sample_s),
        late_from=start + min(DEFAULT_SETTLE_S, 0.5 * (end - start)), last_from=end - MEAN_WINDOW_S,
        lagging=bool(lagging), commanded_tilts=rotors and vehicle.has_servos,
        with_tilts=rotors and vehicle.has_servos and plant.has_servos,
        ground=surfaces._replace(ceiling_effect=False), ceiling=surfaces._replace(ground_effect=False))


def _degrees(acc: np.record, parts: np.ndarray) -> float:
    """The angle [deg] of the ``(sin, cos)`` ``parts`` of the accumulators ``acc`` (NaN: no finite sample)."""
    if not acc.attitude_samples:
        return math.nan
    return float(np.degrees(np.arctan2(parts[0], parts[1])))


def accumulated_row(acc: np.ndarray, measures: core.MeasureParams, count: int, time: Callable[[int], float],
                    end_reason: str = FINISHED, end_detail: str = "") -> dict[str, Any]:
    """The row (:data:`METRIC_COLUMNS`) of a flight of ``count`` samples from its accumulators ``acc``
    (:func:`fsr_bringup.core.flight_measures.new_accumulators`; ``time(k)`` [s] of sample ``k``, inf past the
    last)."""
    acc = acc[0]
    valid = acc.position_samples > 0
    last = int(acc.position_last_outside)
    row: dict[str, Any] = {
        "end_reason": end_reason, "end_detail": end_detail, "flown_s": time(count - 1),
        "position_error_final_m": float(acc.position_final) if valid else math.nan,
        "position_error_peak_m": float(acc.position_peak) if valid else math.nan,
        "position_error_rms_m": math.sqrt(acc.position_squares / acc.position_samples) if valid else math.nan,
        "attitude_error_final_deg": _degrees(acc, acc.attitude_final),
        "attitude_error_peak_deg": _degrees(acc, acc.attitude_peak),
        "settling_time_s": settled_after_arrival(time(count - 1), int(acc.reference_last_moving) + 1,
                                                 last + 1, time),
    }
    if not measures.rotors:
        row.update(rotor_speed_peak_rad_s=math.nan, saturated_fraction=math.nan, gave_way="")
    else:
        fraction = acc.saturated_steps / count
        if measures.tilts:
            fraction = max(fraction, acc.tilt_steps / count)
        row.update(rotor_speed_peak_rad_s=float(acc.rotor_speed_peak), saturated_fraction=float(fraction),
                   gave_way="+".join(axis for c, axis in enumerate(WRENCH_AXES) if acc.gave_way[c]))
    row.update(estimate_force_rms_N=math.nan, estimate_torque_rms_N_m=math.nan, estimate_settling_s=math.nan,
               estimate_force_settling_s=math.nan)
    samples = int(acc.truth_samples)
    if measures.truth and samples >= 2 and acc.estimate_late > 0:
        rms = np.sqrt(acc.estimate_squares / acc.estimate_late)
        last_samples = acc.truth_last_samples
        final_truth = acc.truth_last_sum / last_samples if last_samples else np.full(6, math.nan)
        significant = [c for c in range(6) if abs(final_truth[c]) >= SIGNIFICANT_WRENCH]

        def slowest(last_outside: np.ndarray, final_band: np.ndarray, channels: list[int]) -> float:
            settled = []
            for c in channels:
                outside = last_outside[c]
                value = math.nan if outside >= samples - 1 else time(int(outside) + 1) - time(0)
                settled.append(value if final_band[c] > 0.0 else math.nan)
            return (math.inf if any(math.isnan(v) for v in settled) else max(settled)) if settled else math.nan

        row.update(estimate_force_rms_N=float(np.sqrt(np.sum(rms[:3] ** 2))),
                   estimate_torque_rms_N_m=float(np.sqrt(np.sum(rms[3:] ** 2))),
                   estimate_settling_s=slowest(acc.estimate_last_outside, acc.final_band, significant),
                   estimate_force_settling_s=slowest(acc.smoothed_last_outside, acc.smoothed_final_band,
                                                     [c for c in significant if c < 3]))
    return row


def recorded_row(flight: RecordedFlight, band: float = DEFAULT_BAND_M, end_reason: str | None = None,
                 end_detail: str = "") -> dict[str, Any]:
    """The row of a recorded flight (or one in memory as a :class:`RecordedFlight`, with its scenario): its
    samples at the true state's stamps - the reference, the commanded attitude, the rotor commands and the
    shortfall held there, the effective truth (:func:`fsr_bringup.analysis.effective.effective_wrench`) and the
    estimate - fed through the accumulators the loop fills as it flies (:func:`fsr_bringup.core.flight_measures.
    measure_log`). ``end_reason``: the flight's (default: its last ``sim_status``)."""
    odom, config = flight.true_odom, flight.config
    if odom is None or flight.reference is None or config is None:
        raise ValueError("a sweep row needs the true state, the reference and the scenario")
    target, t = odom.stamp_ns, np.ascontiguousarray(odom.t, dtype=float)
    count, n = len(t), config.vehicle.rotor_count
    rows = np.full((count, layout.output_size(n)), np.nan)

    def hold(series: Any, values: np.ndarray, at: int) -> None:
        rows[:, at:at + values.shape[1]] = zero_order_hold(series.stamp_ns, values, target)

    ref = flight.reference
    hold(ref, ref.position, layout.REFERENCE_POSITION)
    hold(ref, ref.velocity, layout.REFERENCE_VELOCITY)
    hold(ref, ref.acceleration, layout.REFERENCE_ACCELERATION)
    commanded = flight.attitude_cmd or ref  # the law's attitude (the reference's where it is not recorded)
    hold(commanded, commanded.rotation.reshape(-1, 9), layout.COMMANDED_ROTATION)
    if flight.rotor_cmd is not None:
        hold(flight.rotor_cmd, flight.rotor_cmd.speeds, layout.ROTOR_SPEEDS)
        if flight.rotor_cmd.tilts is not None:
            hold(flight.rotor_cmd, flight.rotor_cmd.tilts, layout.ROTOR_SPEEDS + n)
    if flight.wrench_shortfall is not None:
        shortfall = flight.wrench_shortfall
        hold(shortfall, np.hstack((shortfall.force, shortfall.torque)), layout.SHORTFALL)
    estimate = flight.wrench_estimate
    effective = effective_wrench(flight) if estimate is not None else None
    measured = flight.estimator if effective is not None else None
    truth = effective.wrench_body if effective is not None else np.zeros((count, 6))
    estimates = np.zeros((count, 7))
    if estimate is not None:
        estimates[:, :6] = zero_order_hold(estimate.stamp_ns, np.hstack((estimate.force, estimate.torque)), target)
    sample_s = (t[-2] - t[0]) / (count - 2) if count > 2 else 0.0
    measures = measure_params(config, measured, float(t[0]), float(t[-1]), float(sample_s), band,
                              flight.rotor_state is not None)
    acc = core.new_accumulators()
    core.measure_log(measures, acc, t, np.ascontiguousarray(odom.position), np.ascontiguousarray(odom.rotation),
                     rows, np.ascontiguousarray(truth), estimates)
    if end_reason is None:
        end_reason = flight.sim_status[-1].state if flight.sim_status else FINISHED
    return accumulated_row(acc, measures, count, lambda k: float(t[k]) if k < count else math.inf, end_reason,
                           end_detail)


def flight_row(run, band: float = DEFAULT_BAND_M) -> dict[str, Any]:  # noqa: ANN001 - a FlightRun
    """The row of one flight flown in this process (module docstring), in :data:`METRIC_COLUMNS` order."""
    return recorded_row(run.trace, band, run.end_reason, run.reason if run.failures else "")
