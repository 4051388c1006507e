"""A sweep's row measured sample by sample (compiled core): the accumulators that the closed loop
(:func:`fsr_bringup.core.flight_loop.fly` with ``MEASURE``) updates as it flies, instead of writing each step out,
and that a flight's arrays are fed through after the fact (:mod:`fsr_bringup.sweeps.metrics`), so a sweep's row has
one definition.

Per sample ``k = 0..K`` (the state stamped ``t_k = k T``, ``t_k = (k period_ns) 1e-9`` as the loop computes it,
and the controller's answer to it), into the accumulators ``acc`` (a 1-element record array of
:data:`ACCUMULATORS`, :func:`new_accumulators`; the fields below):

* position error ``e_k = |p_k - p_d,k|`` [m]: the last finite value, the peak, ``sum e_k^2`` and the samples
  counted (finite ones), and the last sample outside the band (NaN counts as outside); the last sample whose
  position reference moves (its velocity or acceleration not zero);
* attitude error, the angle of ``R_c,k^T R_k`` (``atan2(|vee(E - E^T)| / 2, (tr E - 1) / 2)``): the
  ``(sin, cos)`` parts of the last finite value and of the peak (the angles are taken once, at the end);
* with rotors: the largest commanded speed (NaN if any is NaN), the steps with a commanded speed at a limit
  (NaN counts as the middle of the range) or a tilt at its limit, and per body axis whether the wrench gave way
  (``|shortfall| > tolerance`` at some step);
* with the estimator: the effective truth of sample ``k < K`` (what the observer must converge to,
  :func:`fsr_bringup.core.effective_truth.effective_truth`, from the states ``k`` and ``k + 1``: the external
  wrench, the actuator's wrench against the commanded one - in wrench actuation the turn of ``R`` within the
  step; with rotors their wrench at the thrust ratios of both poses, from the commanded speeds and tilts or,
  where the rotors lag, the actual ones of both ends, computed by the plant's own functions on the plant without
  actuator dynamics -, the ground's contact force, the model mismatch), and per channel the sum of the squared
  estimate errors of the samples at ``t_k >= late_from``, the last sample outside the 3 % band (and the same for
  the estimate and the truth through the ``smoothed`` settling time's low-pass), the sum of the truths at
  ``t_k >= last_from`` (their count too), the band of the last sample, and the samples whose
  truth is not finite.

The numbers are those of :mod:`fsr_bringup.analysis.metrics` applied to the flight's arrays
(:mod:`fsr_bringup.sweeps.metrics` builds the row from them); sums are running sums where numpy sums pairwise
(the row agrees to rounding). Only finished flights are measured here: a flight that ends early is measured
from its arrays (the flight's windows depend on where it ended).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_bringup.core.effective_truth import effective_truth, finite
from fsr_control.core.controller import (
    COMMANDED_ROTATION,
    REFERENCE_ACCELERATION,
    REFERENCE_POSITION,
    REFERENCE_VELOCITY,
    ROTOR_SPEEDS,
    SHORTFALL,
)
from fsr_estimation.core.smoothing import low_pass_step
from fsr_sim.core.jit import jit, jit_inline, zeroed_record
from fsr_sim.core.odometry import TRUTH_FORCE, TRUTH_TORQUE
from fsr_sim.core.plant import PlantParams, PlantState, period_mean_lagged, set_rotor_command
from fsr_sim.core.rigid_body import (
    POSITION_Z,
    state_angular_velocity,
    state_position,
    state_rotation,
    state_velocity,
)
from fsr_sim.core.rotors import scaled_rotor_wrench
from fsr_sim.core.so3 import Mat3, Vec3, mat_t_mat3, mat_t_vec3
from fsr_sim.core.surfaces import Surfaces, has_thrust_effects, thrust_ratios

ACCUMULATORS = np.dtype([
    ("position_final", np.float64),  # [m] the last finite position error (NaN: none yet)
    ("position_peak", np.float64),
    ("position_squares", np.float64),  # [m^2] sum of the squared finite errors
    ("position_samples", np.int64),  # finite errors summed
    ("position_last_outside", np.int64),  # the last sample outside the band (-1: none)
    ("attitude_final", np.float64, (2,)),  # (sin, cos) of the angle (module docstring)
    ("attitude_peak", np.float64, (2,)),
    ("attitude_samples", np.int64),
    ("rotor_speed_peak", np.float64),  # [rad/s]
    ("saturated_steps", np.int64),
    ("tilt_steps", np.int64),
    ("gave_way", np.uint8, (6,)),  # per body axis: 1 once it fell short (numba's records hold no bool arrays)
    ("estimate_squares", np.float64, (6,)),  # sum of the squared errors at t >= late_from
    ("estimate_late", np.int64),  # samples summed in estimate_squares
    ("estimate_last_outside", np.int64, (6,)),  # the last sample outside the band (-1: none)
    ("truth_last_sum", np.float64, (6,)),  # sum of the truths at t >= last_from
    ("truth_last_samples", np.int64),
    ("final_band", np.float64, (6,)),  # the band of the last sample with a truth
    ("truth_samples", np.int64),  # samples with a finite truth
    ("truth_undefined", np.int64),  # samples (before the last) whose truth is not finite
    ("smoothed_estimate", np.float64, (6,)),  # the estimate through the smoothed settling time's low-pass
    ("smoothed_truth", np.float64, (6,)),  # the truth through it
    ("smoothed_last_outside", np.int64, (6,)),  # the last sample whose low-passed error is outside the band (-1: none)
    ("smoothed_final_band", np.float64, (6,)),  # the band of the last low-passed truth
    ("reference_last_moving", np.int64),  # the last sample whose position reference moves (-1: none)
], align=True)
"""The accumulators' fields (module docstring), read and written in place as ``acc[0].position_peak``."""
# The rows of rotor_rows (n each): rotor_state of t_k, the thrust ratios of t_k and t_k+1, the speeds and tilts
# acting over the step, work rows.
ACTUAL_SPEEDS, ACTUAL_TILTS, RATIOS, RATIOS_NEXT, SPEEDS, TILTS, GROUND, CEILING = range(8)
ROTOR_ROWS = 8


class MeasureParams(NamedTuple):
    """What the measurements need besides the flight (thresholds computed as the analysis does)."""

    band: float  # m: the position band of the settling time
    rotors: bool  # rotor actuation: the saturation and shortfall are measured
    speed_upper: float  # rad/s: a command >= this is at the upper limit
    speed_lower: float  # rad/s: <= this is at the lower limit
    speed_middle: float  # rad/s: what a NaN command counts as
    tilts: bool  # the tilts' limit is measured
    tilt_limit: float  # rad: |tilt| >= this is at the limit
    shortfall_tolerance: float  # N, N m
    truth: bool  # the estimator is measured against the effective truth
    # the plant and the observer's model, as the effective truth takes them (the fields of TruthParams)
    mass: float  # kg: the plant's
    mass_model: float  # kg: the observer's model
    inertia: np.ndarray  # (3, 3) kg m^2: the plant's
    inertia_delta: np.ndarray  # (3, 3): the model's minus the plant's
    gravity: float  # m/s^2
    tolerance: float  # the estimate's settling band, relative to |truth|
    smoothing_gain: float  # the smoothed settling time's low-pass gain per sample (fsr_estimation.estimator.metrics)
    late_from: float  # s: the RMS error from here
    last_from: float  # s: the final truth is the mean from here
    lagging: bool  # rotors: the actual speeds (tilts) act, not the commanded ones (actuator dynamics)
    commanded_tilts: bool  # rotors: the commands carry tilts (a tilting vehicle)
    with_tilts: bool  # rotors: the tilts are applied (commanded tilts on a plant with servos)
    ground: Surfaces  # the surfaces with the ceiling's effect off (the ground's thrust ratios)
    ceiling: Surfaces  # ... with the ground's effect off


class Measurement(NamedTuple):
    """What the loop measures a flight with (:func:`fsr_bringup.core.flight_loop.fly` with ``MEASURE``)."""

    params: MeasureParams
    actuator_plant: PlantParams  # the plant without actuator dynamics: the rotors' wrench of a command
    actuator_state: PlantState  # its scratch state
    rotor_rows: np.ndarray  # (ROTOR_ROWS, n) scratch kept from one call to the next
    acc: np.ndarray  # the accumulators (new_accumulators)


def unmeasured(plant: PlantParams) -> MeasureParams:
    """Measurement parameters that measure nothing (a flight only written out), of the numba types of a measured
    flight's, so that one compilation of the loop serves both: the packed ``plant``'s inertia (read-only, as
    the vehicle's that a measured flight takes) and surfaces, a zero model mismatch (a fresh array, as the
    measured one)."""
    return MeasureParams(0.0, False, 0.0, 0.0, 0.0, False, 0.0, 0.0, False, 1.0, 1.0, plant.inertia,
                         np.zeros((3, 3)), 0.0, 0.0, 0.0, 0.0, 0.0, False, False, False, plant.surfaces,
                         plant.surfaces)


def new_accumulators() -> np.ndarray:
    """Zeroed accumulators (a 1-element :data:`ACCUMULATORS` record array; :func:`reset` before a flight)."""
    return zeroed_record(ACCUMULATORS)


@jit
def reset(acc) -> None:  # noqa: ANN001
    """The accumulators before the first sample (NaN: no value yet; -1: no sample outside a band)."""
    a = acc[0]
    a.position_final = math.nan
    a.position_peak = -math.inf
    a.position_squares = 0.0
    a.position_samples = 0
    a.position_last_outside = -1
    a.attitude_final[:] = math.nan
    a.attitude_peak[:] = math.nan
    a.attitude_samples = 0
    a.rotor_speed_peak = -math.inf
    a.saturated_steps = 0
    a.tilt_steps = 0
    a.gave_way[:] = 0
    a.estimate_squares[:] = 0.0
    a.estimate_late = 0
    a.estimate_last_outside[:] = -1
    a.truth_last_sum[:] = 0.0
    a.truth_last_samples = 0
    a.final_band[:] = 0.0
    a.truth_samples = 0
    a.truth_undefined = 0
    a.smoothed_estimate[:] = 0.0
    a.smoothed_truth[:] = 0.0
    a.smoothed_last_outside[:] = -1
    a.smoothed_final_band[:] = 0.0
    a.reference_last_moving = -1


@jit
def relative_angle_parts(desired: Mat3, rotation: Mat3) -> tuple[float, float]:
    """``(sin, cos)`` of the angle of ``R_d^T R``: ``|vee(E - E^T)| / 2`` and ``(tr E - 1) / 2`` (its angle is
    their ``atan2``, accurate to rounding near 0 and pi)."""
    e = mat_t_mat3(desired, rotation)
    a = e[2][1] - e[1][2]
    b = e[0][2] - e[2][0]
    c = e[1][0] - e[0][1]
    return 0.5 * math.sqrt(a * a + b * b + c * c), 0.5 * (e[0][0] + e[1][1] + e[2][2] - 1.0)


@jit
def _rows(row, at: int) -> Mat3:  # noqa: ANN001
    return ((row[at], row[at + 1], row[at + 2]), (row[at + 3], row[at + 4], row[at + 5]),
            (row[at + 6], row[at + 7], row[at + 8]))


@jit_inline
def measure_sample(m: MeasureParams, acc, k: int, x, rotation: Mat3, row) -> None:  # noqa: ANN001
    """Sample ``k``: the true state ``x`` (13), its rotation and the controller's output ``row``."""
    px, py, pz = state_position(x)
    ex, ey, ez = px - row[REFERENCE_POSITION], py - row[REFERENCE_POSITION + 1], pz - row[REFERENCE_POSITION + 2]
    error = math.sqrt(ex * ex + ey * ey + ez * ez)
    a = acc[0]
    if math.isfinite(error):
        a.position_final = error
        a.position_peak = max(a.position_peak, error)
        a.position_squares += error * error
        a.position_samples += 1
    if not error <= m.band:
        a.position_last_outside = k
    for i in range(3):
        if not (row[REFERENCE_VELOCITY + i] == 0.0 and row[REFERENCE_ACCELERATION + i] == 0.0):
            a.reference_last_moving = k
    sin_part, cos_part = relative_angle_parts(_rows(row, COMMANDED_ROTATION), rotation)
    if math.isfinite(sin_part) and math.isfinite(cos_part):
        # the peak's (sin, cos) without an atan2 per step: in the upper half plane the larger angle is the one
        # counter-clockwise of the other (a cross product); ties within rounding pick either, the same angle
        peak, final = a.attitude_peak, a.attitude_final
        peak_sin, peak_cos = peak[0], peak[1]
        if a.attitude_samples == 0 or peak_cos * sin_part - peak_sin * cos_part > 0.0:
            peak[0], peak[1] = sin_part, cos_part
        final[0], final[1] = sin_part, cos_part
        a.attitude_samples += 1
    if not m.rotors:
        return
    n = (row.shape[0] - ROTOR_SPEEDS) // 2
    at_limit = False
    for i in range(n):
        speed = row[ROTOR_SPEEDS + i]
        if math.isnan(speed) or math.isnan(a.rotor_speed_peak):
            a.rotor_speed_peak = math.nan
        elif speed > a.rotor_speed_peak:
            a.rotor_speed_peak = speed
        held = m.speed_middle if math.isnan(speed) else speed
        if held >= m.speed_upper or held <= m.speed_lower:
            at_limit = True
    if at_limit:
        a.saturated_steps += 1
    if m.tilts:
        tilted = False
        for i in range(n):
            tilt = row[ROTOR_SPEEDS + n + i]
            if abs(0.0 if math.isnan(tilt) else tilt) >= m.tilt_limit:
                tilted = True
        if tilted:
            a.tilt_steps += 1
    for c in range(6):
        if abs(row[SHORTFALL + c]) > m.shortfall_tolerance:
            a.gave_way[c] = 1


@jit_inline
def measure_estimate(m: MeasureParams, surfaces: Surfaces, acc, t: float, t_next: float, x, x_next,  # noqa: ANN001
                     rotation: Mat3, rotation_next: Mat3, published, commanded: tuple, start: tuple, end: tuple,
                     estimate) -> None:  # noqa: ANN001
    """Sample ``k < K`` of the estimate against the effective truth, from the state ``x`` (13) of ``t`` and
    ``x_next`` of ``t_next`` (and their rotations), the published row of ``t`` (its ``wrench_truth``), the
    commanded body wrench, the actuator's body wrench at the start and at the end of the step (each a pair
    ``(force, torque)``), and the estimate of ``t``."""
    parts = effective_truth(m, surfaces, t_next - t, rotation, rotation_next, state_velocity(x),
                            state_velocity(x_next), state_angular_velocity(x), state_angular_velocity(x_next),
                            x_next[POSITION_Z],
                            ((published[TRUTH_FORCE], published[TRUTH_FORCE + 1], published[TRUTH_FORCE + 2]),
                             (published[TRUTH_TORQUE], published[TRUTH_TORQUE + 1], published[TRUTH_TORQUE + 2])),
                            commanded, start, end)
    force_body, torque = mat_t_vec3(rotation, parts[0]), parts[1]
    measure_truth(m, acc, t, (force_body[0], force_body[1], force_body[2], torque[0], torque[1], torque[2]),
                  estimate)


@jit_inline
def measure_truth(m: MeasureParams, acc, t: float, truth: tuple, estimate) -> None:  # noqa: ANN001
    """Sample ``t`` [s] (before the last) of the estimate (7) against the effective truth ``truth`` (6, body)."""
    defined = True
    for c in range(6):
        if not math.isfinite(truth[c]):
            defined = False
    a = acc[0]
    if not defined:
        a.truth_undefined += 1
        return
    j = a.truth_samples  # the index among the samples with a truth
    a.truth_samples += 1
    late = t >= m.late_from
    last = t >= m.last_from
    if late:
        a.estimate_late += 1
    if last:
        a.truth_last_samples += 1
    gain = m.smoothing_gain
    smoothed_estimate, smoothed_truth = a.smoothed_estimate, a.smoothed_truth
    for c in range(6):
        error = estimate[c] - truth[c]
        band = m.tolerance * abs(truth[c])
        if abs(error) > band:
            a.estimate_last_outside[c] = j
        a.final_band[c] = band
        if j == 0:
            smoothed_estimate[c], smoothed_truth[c] = estimate[c], truth[c]
        else:
            smoothed_estimate[c] = low_pass_step(gain, estimate[c], smoothed_estimate[c])
            smoothed_truth[c] = low_pass_step(gain, truth[c], smoothed_truth[c])
        band = m.tolerance * abs(smoothed_truth[c])
        if abs(smoothed_estimate[c] - smoothed_truth[c]) > band:
            a.smoothed_last_outside[c] = j
        a.smoothed_final_band[c] = band
        if late:
            a.estimate_squares[c] += error * error
        if last:
            a.truth_last_sum[c] += truth[c]


@jit_inline
def thrust_ratio_row(m: MeasureParams, x, rotation: Mat3, ground, ceiling, out) -> None:  # noqa: ANN001
    """The rotors' thrust ratios ``T / T_OGE`` at the pose of ``x`` into ``out`` (n,): the ground's times the
    ceiling's, each with the other surface's effect off (1 where a surface has none), as the analysis takes
    them; ``ground`` and ``ceiling`` (n,) scratch."""
    if has_thrust_effects(m.ground):
        thrust_ratios(m.ground, x[POSITION_Z], rotation[2], ground)
    else:
        ground[:] = 1.0
    if has_thrust_effects(m.ceiling):
        thrust_ratios(m.ceiling, x[POSITION_Z], rotation[2], ceiling)
    else:
        ceiling[:] = 1.0
    for i in range(out.shape[0]):
        out[i] = ground[i] * ceiling[i]


@jit_inline
def rotor_command_row(m: MeasureParams, k: int, row, actual_speeds, actual_tilts, speeds, tilts) -> None:  # noqa: ANN001
    """What acts over step ``k`` as the analysis takes it, into ``speeds`` and ``tilts`` (n,): where the rotors
    lag, the actual speeds and tilts of the state (``rotor_state``) but the command at ``k = 0``; else the
    command (``row``); NaN as 0."""
    n = speeds.shape[0]
    lagging = m.lagging and k > 0
    for i in range(n):
        speeds[i] = finite(actual_speeds[i] if lagging else row[ROTOR_SPEEDS + i])
        tilts[i] = finite(actual_tilts[i] if lagging else row[ROTOR_SPEEDS + n + i]) if m.commanded_tilts else 0.0


@jit_inline
def measure_first(m: MeasureParams, x, rotor_rows) -> None:  # noqa: ANN001
    """Before sample 0: the rotors' thrust ratios of the first state ``x`` (13) into ``rotor_rows[RATIOS_NEXT]``."""
    thrust_ratio_row(m, x, state_rotation(x), rotor_rows[GROUND], rotor_rows[CEILING], rotor_rows[RATIOS_NEXT])


@jit_inline
def held_wrench(plant: PlantParams, plant_state: PlantState, force: Vec3, torque: Vec3) -> tuple:
    """The body wrench a wrench-actuated plant applies over the coming step for the command ``force``,
    ``torque`` just held: the command, or with a rotor time constant its mean as the RK4 steps apply it
    (lagging the command)."""
    if not plant.wrench_lag:
        return force, torque
    w = plant_state.body_wrench
    c = plant_state.wrench_command
    d, h, s = plant.speed_decay, plant.speed_mean, plant.substeps
    return ((period_mean_lagged(w[0], c[0], d, h, s), period_mean_lagged(w[1], c[1], d, h, s),
             period_mean_lagged(w[2], c[2], d, h, s)),
            (period_mean_lagged(w[3], c[3], d, h, s), period_mean_lagged(w[4], c[4], d, h, s),
             period_mean_lagged(w[5], c[5], d, h, s)))


@jit_inline
def measure_step(measurement: Measurement, plant: PlantParams, plant_state: PlantState, rotors: bool, k: int,
                 t: float, t_next: float, x, published, row, actual, commanded: tuple, held: tuple,  # noqa: ANN001
                 estimate) -> None:  # noqa: ANN001
    """Step ``k`` (``[t, t_next]``, just flown) of the estimate against the effective truth: ``x`` (13) the state
    of ``t``, ``plant_state`` that of ``t_next``, ``published`` the row of ``t``, ``row`` the controller's answer
    and ``commanded`` its wrench (force, torque), ``actual`` (2n) the rotors' speeds and tilts of ``t``
    (``rotor_state``), ``held`` the wrench a wrench-actuated plant applied (:func:`held_wrench`), ``estimate``
    the estimator's of ``t``. With ``rotors`` their wrench at the thrust ratios of both poses
    (``measurement.rotor_rows``: the ratios of ``t`` in ``RATIOS_NEXT`` on entry, of ``t_next`` on return),
    computed on ``measurement.actuator_plant``, the plant without actuator dynamics, as the analysis computes
    it."""
    m, acc, rotor_rows = measurement.params, measurement.acc, measurement.rotor_rows
    actuator_plant, actuator_state = measurement.actuator_plant, measurement.actuator_state
    rotation = state_rotation(x)
    rotation_next = state_rotation(plant_state.x)
    if not rotors:  # wrench actuation: the command, or the wrench lagging it
        measure_estimate(m, plant.surfaces, acc, t, t_next, x, plant_state.x, rotation, rotation_next, published,
                         commanded, held, held, estimate)
        return
    n = rotor_rows.shape[1]
    for i in range(n):
        rotor_rows[ACTUAL_SPEEDS, i] = actual[i]
        rotor_rows[ACTUAL_TILTS, i] = actual[n + i]
        rotor_rows[RATIOS, i] = rotor_rows[RATIOS_NEXT, i]
    rotor_command_row(m, k, row, rotor_rows[ACTUAL_SPEEDS], rotor_rows[ACTUAL_TILTS], rotor_rows[SPEEDS],
                      rotor_rows[TILTS])
    thrust_ratio_row(m, plant_state.x, rotation_next, rotor_rows[GROUND], rotor_rows[CEILING],
                     rotor_rows[RATIOS_NEXT])
    set_rotor_command(actuator_plant, actuator_state, rotor_rows[SPEEDS], rotor_rows[TILTS], m.with_tilts)
    start = scaled_rotor_wrench(actuator_state.columns, actuator_state.speed_sq, rotor_rows[RATIOS])
    if m.lagging:  # the rotors move within the step: at its end, their speeds and tilts of t_next
        set_rotor_command(actuator_plant, actuator_state, plant_state.speeds, plant_state.tilts, m.with_tilts)
    end = scaled_rotor_wrench(actuator_state.columns, actuator_state.speed_sq, rotor_rows[RATIOS_NEXT])
    measure_estimate(m, plant.surfaces, acc, t, t_next, x, plant_state.x, rotation, rotation_next, published,
                     commanded, start, end, estimate)


@jit
def measure_log(m: MeasureParams, acc, t, x, rotation, rows, truth, estimates) -> None:  # noqa: ANN001
    """The accumulators of a flight's arrays, the samples fed through the loop's functions: per sample ``k`` of
    ``t`` (n,) [s] the true state ``x`` (n, 13: position first), its ``rotation`` (n, 3, 3), the controller's
    output ``rows`` (n, its layout) into :func:`measure_sample`; with ``m.truth`` the effective truth ``truth``
    (n, 6, body; the last sample has none) and the ``estimates`` (n, 7) into :func:`measure_truth`."""
    reset(acc)
    n = t.shape[0]
    for k in range(n):
        r = ((rotation[k, 0, 0], rotation[k, 0, 1], rotation[k, 0, 2]),
             (rotation[k, 1, 0], rotation[k, 1, 1], rotation[k, 1, 2]),
             (rotation[k, 2, 0], rotation[k, 2, 1], rotation[k, 2, 2]))
        measure_sample(m, acc, k, x[k], r, rows[k])
        if m.truth and k < n - 1:
            measure_truth(m, acc, t[k], (truth[k, 0], truth[k, 1], truth[k, 2], truth[k, 3], truth[k, 4],
                                         truth[k, 5]), estimates[k])
