"""One flight of a sweep as one row: the metrics of the flight summary (:mod:`fsr_bringup.analysis.metrics`,
applied to the flight in memory: :mod:`fsr_bringup.analysis.in_memory`), flattened to numbers and short texts.

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
  a first-order low-pass of 0.1 s, :mod:`fsr_estimation.core.metrics`; with sensor noise the raw error never stays
  within 3 %, and with an actuator lag the torque's truth holds the lag's error of a noisy command).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from fsr_bringup.analysis import metrics as summary
from fsr_bringup.analysis.in_memory import recorded_flight_of_run
from fsr_bringup.analysis.load import zero_order_hold

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


def settling_time(t: np.ndarray, error: np.ndarray, band: float, moving: np.ndarray) -> float:
    """``settling_time_s`` (module docstring) of the errors ``error`` [m] at times ``t`` [s]; ``moving``: where
    the position reference moves."""
    def last(mask: np.ndarray) -> int:
        return len(mask) - 1 - int(np.argmax(mask[::-1])) if mask.any() else -1

    def time(k: int) -> float:
        return float(t[k]) if k < len(t) else math.inf

    return settled_after_arrival(float(t[-1]), last(moving) + 1, last(~(error <= band)) + 1, time)  # NaN: outside


def reference_moving(flight: Any) -> np.ndarray:
    """Per ``odom`` sample of a recorded flight: whether the position reference held there moves (its velocity
    or acceleration is not zero)."""
    ref = flight.reference
    motion = np.concatenate((ref.velocity, ref.acceleration), axis=1)
    held = zero_order_hold(ref.stamp_ns, motion, flight.odom.stamp_ns)
    return ~np.all(held == 0.0, axis=1)


def _number(value: Any) -> float:
    return math.nan if value is None else float(value)


def flight_row(run, band: float = DEFAULT_BAND_M) -> dict[str, Any]:  # noqa: ANN001 - a FlightRun
    """The row of one flight (module docstring), in :data:`METRIC_COLUMNS` order."""
    flight = recorded_flight_of_run(run)
    row: dict[str, Any] = {"end_reason": run.end_reason, "end_detail": run.reason if run.failures else "",
                           "flown_s": float(run.time[-1])}
    errors = summary.tracking_errors(flight)
    position = summary.error_summary(errors.t, errors.position)
    attitude = summary.error_summary(errors.t, errors.attitude_deg)
    row.update(position_error_final_m=_number(position["final"]), position_error_peak_m=_number(position["peak"]),
               position_error_rms_m=_number(position["rms"]),
               attitude_error_final_deg=_number(attitude["final"]), attitude_error_peak_deg=_number(attitude["peak"]),
               settling_time_s=settling_time(errors.t, np.linalg.norm(errors.position, axis=1), band,
                                             reference_moving(flight)))
    saturation = summary.saturation(flight)
    if saturation is None:  # wrench actuation: nothing saturates
        row.update(rotor_speed_peak_rad_s=math.nan, saturated_fraction=math.nan, gave_way="")
    else:
        fraction = saturation["rotor_speed"]["fraction"]
        if saturation["tilt"] is not None:
            fraction = max(fraction, saturation["tilt"]["fraction"])
        shortfall = summary.wrench_shortfall(flight) or {}
        row.update(rotor_speed_peak_rad_s=float(np.max(run.rotor_speeds)), saturated_fraction=float(fraction),
                   gave_way="+".join(axis for axis in summary.WRENCH_AXES if shortfall.get(axis, {}).get("steps")))
    row.update(estimate_force_rms_N=math.nan, estimate_torque_rms_N_m=math.nan, estimate_settling_s=math.nan,
               estimate_force_settling_s=math.nan)
    comparison = summary.wrench_comparison(flight) if flight.wrench_estimate is not None else None
    if comparison is not None and comparison["rms_error"] is not None:
        rms = np.asarray(comparison["rms_error"], dtype=float)
        final_truth = np.asarray(comparison["effective_truth_mean_last_s"], dtype=float)
        significant = [name for name, truth in zip(summary.WRENCH_CHANNELS, final_truth, strict=True)
                       if abs(truth) >= SIGNIFICANT_WRENCH]

        def slowest(channels: dict, names: list[str]) -> float:
            settled = [_number(channels[name]) for name in names]
            return (math.inf if any(math.isnan(v) for v in settled) else max(settled)) if settled else math.nan

        row.update(estimate_force_rms_N=float(np.sqrt(np.sum(rms[:3] ** 2))),
                   estimate_torque_rms_N_m=float(np.sqrt(np.sum(rms[3:] ** 2))),
                   estimate_settling_s=slowest(comparison["settling_time_s"], significant),
                   estimate_force_settling_s=slowest(comparison["settling_time_smoothed_s"],
                                                     [n for n in significant if n in summary.WRENCH_CHANNELS[:3]]))
    return row
