"""A sweep's flight measured as it flies (compiled core): the closed loop of :mod:`fsr_bringup.core.flight_loop`
(the same per-step functions in the same order, so the flight is the same bit for bit) with the metrics of the
sweep's row accumulated step by step instead of written out per step.

Per sample ``k = 0..K`` (the state stamped ``t_k = k T``, ``t_k = (k period_ns) 1e-9`` as the loop computes it,
and the controller's answer to it), into the accumulator vector ``acc`` (:data:`SIZE`, indices below):

* position error ``e_k = |p_k - p_d,k|`` [m]: the last finite value, the peak, ``sum e_k^2`` and the samples
  counted (finite ones), and the last sample outside the band (NaN counts as outside); the last sample whose
  position reference moves (its velocity or acceleration not zero);
* attitude error, the angle of ``R_c,k^T R_k`` (``atan2(|vee(E - E^T)| / 2, (tr E - 1) / 2)``): the
  ``(sin, cos)`` parts of the last finite value and of the peak (the angles are taken once, at the end);
* with rotors: the largest commanded speed (NaN if any is NaN), the steps with a commanded speed at a limit
  (NaN counts as the middle of the range) or a tilt at its limit, and per body axis whether the wrench gave way
  (``|shortfall| > tolerance`` at some step);
* with the estimator: the effective truth of sample ``k < K`` (what the observer must converge to,
  :mod:`fsr_bringup.analysis.effective`, from the states ``k`` and ``k + 1``: the external wrench, the actuator's
  wrench against the commanded one - in wrench actuation the turn of ``R`` within the step; with rotors their
  wrench at the thrust ratios of both poses, from the commanded speeds and tilts or, where the rotors lag, the
  actual ones of both ends, computed by the plant's own functions on the plant without actuator dynamics -, the ground's
  contact force, the model mismatch), and per channel the sum of
  the squared estimate errors of the samples at ``t_k >= late_from``, the last sample outside the 3 % band (and
  the same for the estimate and the truth through the ``smoothed`` settling time's low-pass), the
  sum of the truths at ``t_k >= last_from`` (their count too), the band of the last sample, and the samples whose
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

from fsr_bringup.core.flight_loop import (
    CONTROLLER_FAILED,
    DIVERGED,
    FINISHED,
    LOST_CONTROL,
    closed_loop_tick,
    hold_command,
)
from fsr_control.core.allocation import WRENCH
from fsr_control.core.controller import (
    COMMANDED_QUATERNION,
    COMMANDED_ROTATION,
    REFERENCE_ACCELERATION,
    REFERENCE_POSITION,
    REFERENCE_VELOCITY,
    ROTOR_SPEEDS,
    SHORTFALL,
    ControllerParams,
    ControllerState,
)
from fsr_control.core.flatness import ATTITUDE_OK
from fsr_estimation.core.observer_step import ObserverParams, ObserverState
from fsr_sim.core.control_loss import IN_CONTROL, control_loss, held_by_surface
from fsr_sim.core.jit import jit, jit_inline
from fsr_sim.core.lockstep import advance, publish
from fsr_sim.core.odometry import TRUTH_FORCE, TRUTH_TORQUE
from fsr_sim.core.plant import RUNNING, PlantParams, PlantState, period_mean_lagged, set_rotor_command
from fsr_sim.core.rotors import scaled_rotor_wrench
from fsr_sim.core.so3 import Mat3, Vec3, cross3, mat_t_mat3, mat_t_vec3, mat_vec3, rotation_rows_from_quaternion
from fsr_sim.core.surfaces import Surfaces, has_thrust_effects, in_contact, thrust_ratios

# The accumulators (acc).
POSITION_FINAL, POSITION_PEAK, POSITION_SQUARES, POSITION_SAMPLES, POSITION_LAST_OUTSIDE = 0, 1, 2, 3, 4
ATTITUDE_FINAL, ATTITUDE_PEAK = 5, 7  # 2 each: (sin, cos) of the angle (module docstring)
ATTITUDE_SAMPLES = 9
ROTOR_SPEED_PEAK, SATURATED_STEPS, TILT_STEPS = 10, 11, 12
GAVE_WAY = 13  # 6: 1 where that body axis fell short at some step
ESTIMATE_SQUARES = 19  # 6: sum of the squared errors at t >= late_from
ESTIMATE_LATE = 25  # samples summed in ESTIMATE_SQUARES
ESTIMATE_LAST_OUTSIDE = 26  # 6: the last sample outside the band (-1: none)
TRUTH_LAST_SUM = 32  # 6: sum of the truths at t >= last_from
TRUTH_LAST_SAMPLES = 38
FINAL_BAND = 39  # 6: the band of the last sample with a truth
TRUTH_SAMPLES = 45  # samples with a finite truth
TRUTH_UNDEFINED = 46  # samples (before the last) whose truth is not finite
SMOOTHED_ESTIMATE = 47  # 6: the estimate through the smoothed settling time's low-pass
SMOOTHED_TRUTH = 53  # 6: the truth through it
SMOOTHED_LAST_OUTSIDE = 59  # 6: the last sample whose low-passed error is outside the band (-1: none)
SMOOTHED_FINAL_BAND = 65  # 6: the band of the last low-passed truth
REFERENCE_LAST_MOVING = 71  # the last sample whose position reference moves (velocity or acceleration != 0; -1: none)
SIZE = 72
# The rows of rotor_rows (n each): rotor_state of t_k, the thrust ratios of t_k and t_k+1, the speeds and tilts
# acting over the step, work rows.
ACTUAL_SPEEDS, ACTUAL_TILTS, RATIOS, RATIOS_NEXT, SPEEDS, TILTS, GROUND, CEILING = range(8)
ROTOR_ROWS = 8
LARGEST = float(np.finfo(np.float64).max)


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
    mass: float  # kg: the plant's
    mass_model: float  # kg: the observer's model
    inertia: np.ndarray  # (3, 3) kg m^2: the plant's
    inertia_delta: np.ndarray  # (3, 3): the model's minus the plant's
    gravity: float  # m/s^2
    tolerance: float  # the estimate's settling band, relative to |truth|
    smoothing_gain: float  # the smoothed settling time's low-pass gain per sample (fsr_estimation.core.metrics)
    late_from: float  # s: the RMS error from here
    last_from: float  # s: the final truth is the mean from here
    lagging: bool  # rotors: the actual speeds (tilts) act, not the commanded ones (actuator dynamics)
    commanded_tilts: bool  # rotors: the commands carry tilts (a tilting vehicle)
    with_tilts: bool  # rotors: the tilts are applied (commanded tilts on a plant with servos)
    ground: Surfaces  # the surfaces with the ceiling's effect off (the ground's thrust ratios)
    ceiling: Surfaces  # ... with the ground's effect off


@jit
def reset(acc) -> None:  # noqa: ANN001
    """The accumulators before the first sample (NaN: no value yet; -1: no sample outside a band)."""
    acc[:] = 0.0
    acc[POSITION_FINAL] = math.nan
    acc[POSITION_PEAK] = -math.inf
    acc[POSITION_LAST_OUTSIDE] = -1.0
    acc[REFERENCE_LAST_MOVING] = -1.0
    acc[ATTITUDE_FINAL] = acc[ATTITUDE_FINAL + 1] = math.nan
    acc[ATTITUDE_PEAK] = acc[ATTITUDE_PEAK + 1] = math.nan
    acc[ROTOR_SPEED_PEAK] = -math.inf
    for c in range(6):
        acc[ESTIMATE_LAST_OUTSIDE + c] = -1.0
        acc[SMOOTHED_LAST_OUTSIDE + c] = -1.0


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


@jit
def _state_rotation(x) -> Mat3:  # noqa: ANN001
    return rotation_rows_from_quaternion(x[6], x[7], x[8], x[9])


@jit_inline
def measure_sample(m: MeasureParams, acc, k: int, x, rotation: Mat3, row) -> None:  # noqa: ANN001
    """Sample ``k``: the true state ``x`` (13), its rotation and the controller's output ``row``."""
    ex, ey, ez = x[0] - row[REFERENCE_POSITION], x[1] - row[REFERENCE_POSITION + 1], x[2] - row[REFERENCE_POSITION + 2]
    error = math.sqrt(ex * ex + ey * ey + ez * ez)
    if math.isfinite(error):
        acc[POSITION_FINAL] = error
        acc[POSITION_PEAK] = max(acc[POSITION_PEAK], error)
        acc[POSITION_SQUARES] += error * error
        acc[POSITION_SAMPLES] += 1.0
    if not error <= m.band:
        acc[POSITION_LAST_OUTSIDE] = k
    for i in range(3):
        if not (row[REFERENCE_VELOCITY + i] == 0.0 and row[REFERENCE_ACCELERATION + i] == 0.0):
            acc[REFERENCE_LAST_MOVING] = k
    sin_part, cos_part = relative_angle_parts(_rows(row, COMMANDED_ROTATION), rotation)
    if math.isfinite(sin_part) and math.isfinite(cos_part):
        # the peak's (sin, cos) without an atan2 per step: in the upper half plane the larger angle is the one
        # counter-clockwise of the other (a cross product); ties within rounding pick either, the same angle
        peak_sin, peak_cos = acc[ATTITUDE_PEAK], acc[ATTITUDE_PEAK + 1]
        if acc[ATTITUDE_SAMPLES] == 0.0 or peak_cos * sin_part - peak_sin * cos_part > 0.0:
            acc[ATTITUDE_PEAK], acc[ATTITUDE_PEAK + 1] = sin_part, cos_part
        acc[ATTITUDE_FINAL], acc[ATTITUDE_FINAL + 1] = sin_part, cos_part
        acc[ATTITUDE_SAMPLES] += 1.0
    if not m.rotors:
        return
    n = (row.shape[0] - ROTOR_SPEEDS) // 2
    at_limit = False
    for i in range(n):
        speed = row[ROTOR_SPEEDS + i]
        if math.isnan(speed) or math.isnan(acc[ROTOR_SPEED_PEAK]):
            acc[ROTOR_SPEED_PEAK] = math.nan
        elif speed > acc[ROTOR_SPEED_PEAK]:
            acc[ROTOR_SPEED_PEAK] = speed
        held = m.speed_middle if math.isnan(speed) else speed
        if held >= m.speed_upper or held <= m.speed_lower:
            at_limit = True
    if at_limit:
        acc[SATURATED_STEPS] += 1.0
    if m.tilts:
        tilted = False
        for i in range(n):
            tilt = row[ROTOR_SPEEDS + n + i]
            if abs(0.0 if math.isnan(tilt) else tilt) >= m.tilt_limit:
                tilted = True
        if tilted:
            acc[TILT_STEPS] += 1.0
    for c in range(6):
        if abs(row[SHORTFALL + c]) > m.shortfall_tolerance:
            acc[GAVE_WAY + c] = 1.0


@jit
def _finite(value: float) -> float:
    """``numpy.nan_to_num`` of one number: NaN -> 0, +-inf -> the largest finite float."""
    if math.isnan(value):
        return 0.0
    if math.isinf(value):
        return LARGEST if value > 0.0 else -LARGEST
    return value


@jit
def _add(a: Vec3, b: Vec3) -> Vec3:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@jit
def _spin(omega: Vec3, inertia) -> Vec3:  # noqa: ANN001
    """``omega x (I omega)`` with ``I omega`` as ``omega @ I.T``."""
    i_omega = (inertia[0, 0] * omega[0] + inertia[0, 1] * omega[1] + inertia[0, 2] * omega[2],
               inertia[1, 0] * omega[0] + inertia[1, 1] * omega[1] + inertia[1, 2] * omega[2],
               inertia[2, 0] * omega[0] + inertia[2, 1] * omega[1] + inertia[2, 2] * omega[2])
    return cross3(omega, i_omega)


@jit
def _times(inertia, v: Vec3) -> Vec3:  # noqa: ANN001
    return (inertia[0, 0] * v[0] + inertia[0, 1] * v[1] + inertia[0, 2] * v[2],
            inertia[1, 0] * v[0] + inertia[1, 1] * v[1] + inertia[1, 2] * v[2],
            inertia[2, 0] * v[0] + inertia[2, 1] * v[1] + inertia[2, 2] * v[2])


@jit_inline
def measure_estimate(m: MeasureParams, plant: PlantParams, acc, k: int, t: float, t_next: float, x, x_next,
                     rotation: Mat3, rotation_next: Mat3, published, force_cmd: Vec3, torque_cmd: Vec3,
                     force_start: Vec3, torque_start: Vec3, force_end: Vec3, torque_end: Vec3,
                     estimate) -> None:  # noqa: ANN001
    """Sample ``k < K`` of the estimate against the effective truth, from the state ``x`` (13) of ``t`` and
    ``x_next`` of ``t_next`` (and their rotations), the published row of ``t`` (its ``wrench_truth``), the
    commanded body wrench, the actuator's body wrench at the start and at the end of the step, and the estimate
    of ``t``."""
    dt = t_next - t
    f_ext_body = (published[TRUTH_FORCE], published[TRUTH_FORCE + 1], published[TRUTH_FORCE + 2])
    tau_ext = (published[TRUTH_TORQUE], published[TRUTH_TORQUE + 1], published[TRUTH_TORQUE + 2])
    f_ext_body = (_finite(f_ext_body[0]), _finite(f_ext_body[1]), _finite(f_ext_body[2]))
    tau_ext = (_finite(tau_ext[0]), _finite(tau_ext[1]), _finite(tau_ext[2]))
    f_ext = mat_vec3(rotation, f_ext_body)
    commanded_world = mat_vec3(rotation, force_cmd)
    start_world = mat_vec3(rotation, force_start)
    end_world = mat_vec3(rotation_next, force_end)
    mean_actuator = (0.5 * (start_world[0] + end_world[0]), 0.5 * (start_world[1] + end_world[1]),
                     0.5 * (start_world[2] + end_world[2]))
    mean_torque = (0.5 * (torque_start[0] + torque_end[0]), 0.5 * (torque_start[1] + torque_end[1]),
                   0.5 * (torque_start[2] + torque_end[2]))
    accel = ((x_next[3] - x[3]) / dt, (x_next[4] - x[4]) / dt, (x_next[5] - x[5]) / dt)
    omega = (x[10], x[11], x[12])
    omega_dot = ((x_next[10] - x[10]) / dt, (x_next[11] - x[11]) / dt, (x_next[12] - x[12]) / dt)
    gravity = (0.0, 0.0, m.gravity)
    free = (accel[0] - gravity[0], accel[1] - gravity[1], accel[2] - gravity[2])
    thrust_change = (mean_actuator[0] - commanded_world[0], mean_actuator[1] - commanded_world[1],
                     mean_actuator[2] - commanded_world[2])
    held = in_contact(plant.surfaces, x_next[2]) and x_next[3] == 0.0 and x_next[4] == 0.0 and x_next[5] == 0.0 \
        and x_next[10] == 0.0 and x_next[11] == 0.0 and x_next[12] == 0.0
    contact_force = (0.0, 0.0, 0.0)
    contact_torque = (0.0, 0.0, 0.0)
    if held:
        contact_force = (m.mass * free[0] - mean_actuator[0] - f_ext[0], m.mass * free[1] - mean_actuator[1] - f_ext[1],
                         m.mass * free[2] - mean_actuator[2] - f_ext[2])
        spin = _spin(omega, m.inertia)
        turn = _times(m.inertia, omega_dot)
        contact_torque = (turn[0] + spin[0] - mean_torque[0] - tau_ext[0],
                          turn[1] + spin[1] - mean_torque[1] - tau_ext[1],
                          turn[2] + spin[2] - mean_torque[2] - tau_ext[2])
    difference = m.mass_model - m.mass
    mismatch = (difference * free[0], difference * free[1], difference * free[2])
    force_world = _add(_add(_add(f_ext, thrust_change), contact_force), mismatch)
    turn_delta = _times(m.inertia_delta, omega_dot)
    spin_delta = _spin(omega, m.inertia_delta)
    torque = (tau_ext[0] + mean_torque[0] - torque_cmd[0] + contact_torque[0] + turn_delta[0] + spin_delta[0],
              tau_ext[1] + mean_torque[1] - torque_cmd[1] + contact_torque[1] + turn_delta[1] + spin_delta[1],
              tau_ext[2] + mean_torque[2] - torque_cmd[2] + contact_torque[2] + turn_delta[2] + spin_delta[2])
    force_body = mat_t_vec3(rotation, force_world)
    truth = (force_body[0], force_body[1], force_body[2], torque[0], torque[1], torque[2])
    finite = True
    for c in range(6):
        if not math.isfinite(truth[c]):
            finite = False
    if not finite:
        acc[TRUTH_UNDEFINED] += 1.0
        return
    j = acc[TRUTH_SAMPLES]  # the index among the samples with a truth
    acc[TRUTH_SAMPLES] += 1.0
    late = t >= m.late_from
    last = t >= m.last_from
    if late:
        acc[ESTIMATE_LATE] += 1.0
    if last:
        acc[TRUTH_LAST_SAMPLES] += 1.0
    gain, decay = m.smoothing_gain, 1.0 - m.smoothing_gain
    for c in range(6):
        error = estimate[c] - truth[c]
        band = m.tolerance * abs(truth[c])
        if abs(error) > band:
            acc[ESTIMATE_LAST_OUTSIDE + c] = j
        acc[FINAL_BAND + c] = band
        if j == 0.0:
            acc[SMOOTHED_ESTIMATE + c], acc[SMOOTHED_TRUTH + c] = estimate[c], truth[c]
        else:  # g x + (1 - g) y, as scipy's lfilter
            acc[SMOOTHED_ESTIMATE + c] = gain * estimate[c] + decay * acc[SMOOTHED_ESTIMATE + c]
            acc[SMOOTHED_TRUTH + c] = gain * truth[c] + decay * acc[SMOOTHED_TRUTH + c]
        band = m.tolerance * abs(acc[SMOOTHED_TRUTH + c])
        if abs(acc[SMOOTHED_ESTIMATE + c] - acc[SMOOTHED_TRUTH + c]) > band:
            acc[SMOOTHED_LAST_OUTSIDE + c] = j
        acc[SMOOTHED_FINAL_BAND + c] = band
        if late:
            acc[ESTIMATE_SQUARES + c] += error * error
        if last:
            acc[TRUTH_LAST_SUM + c] += truth[c]


@jit_inline
def thrust_ratio_row(m: MeasureParams, x, rotation: Mat3, ground, ceiling, out) -> None:  # noqa: ANN001
    """The rotors' thrust ratios ``T / T_OGE`` at the pose of ``x`` into ``out`` (n,): the ground's times the
    ceiling's, each with the other surface's effect off (1 where a surface has none), as the analysis takes
    them; ``ground`` and ``ceiling`` (n,) scratch."""
    if has_thrust_effects(m.ground):
        thrust_ratios(m.ground, x[2], rotation[2], ground)
    else:
        ground[:] = 1.0
    if has_thrust_effects(m.ceiling):
        thrust_ratios(m.ceiling, x[2], rotation[2], ceiling)
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
        speeds[i] = _finite(actual_speeds[i] if lagging else row[ROTOR_SPEEDS + i])
        tilts[i] = _finite(actual_tilts[i] if lagging else row[ROTOR_SPEEDS + n + i]) if m.commanded_tilts else 0.0


@jit
def fly_measured(plant: PlantParams, plant_state: PlantState, controller: ControllerParams,
                 controller_state: ControllerState, with_estimator: bool, estimator_measured: bool,
                 observer: ObserverParams,
                 observer_state: ObserverState, step_count: int, period_ns: int, measures: MeasureParams,
                 actuator_plant: PlantParams, actuator_state: PlantState, control_bounds: tuple, states, published,
                 row, estimate, rotor_rows, acc) -> tuple:  # noqa: ANN001
    """Steps ``0..step_count`` measured into ``acc`` (module docstring); ``states`` (13,) the state of ``t_k``,
    ``published`` (2, 19) the rows of ``t_k`` and ``t_k+1``, ``row`` the controller's output, ``estimate`` (7)
    the estimator's and ``rotor_rows`` (8, n) the rotors' (:data:`ACTUAL_SPEEDS` ...), all scratch.
    ``actuator_plant`` is the plant without actuator dynamics (its ``actuator_state`` scratch): the rotors'
    wrench of a command, as the analysis computes it. Returns ``(outcome, k, detail)`` as
    :func:`fsr_bringup.core.flight_loop.fly_steps` (never ``GOING_ON``)."""
    reset(acc)
    n = (row.shape[0] - ROTOR_SPEEDS) // 2
    mode = controller.allocation.mode
    rotor_truth = with_estimator and measures.truth and mode != WRENCH
    publish(plant, plant_state, published[0])
    rotation_k = _state_rotation(plant_state.x)  # R of the true state t_k (then of t_k+1, for the next step)
    if rotor_truth:
        thrust_ratio_row(measures, plant_state.x, rotation_k, rotor_rows[GROUND], rotor_rows[CEILING],
                         rotor_rows[RATIOS_NEXT])
    for k in range(step_count + 1):
        t = (k * period_ns) * 1e-9
        now = published[k % 2]
        for i in range(plant_state.x.shape[0]):
            states[i] = plant_state.x[i]
        if rotor_truth:
            for i in range(n):  # rotor_state of t_k; the ratios of t_k (computed at the end of the last step)
                rotor_rows[ACTUAL_SPEEDS, i] = plant_state.speeds[i]
                rotor_rows[ACTUAL_TILTS, i] = plant_state.tilts[i]
                rotor_rows[RATIOS, i] = rotor_rows[RATIOS_NEXT, i]
        status, force, torque = closed_loop_tick(controller, controller_state, with_estimator, estimator_measured,
                                                 observer, observer_state, t, now, plant_state.speeds,
                                                 plant_state.tilts, row, estimate)
        if status != ATTITUDE_OK:
            return CONTROLLER_FAILED, k, status
        measure_sample(measures, acc, k, states, rotation_k, row)
        if k == step_count:
            return FINISHED, k, 0
        lost = control_loss(control_bounds, plant_state.x, row[REFERENCE_POSITION:REFERENCE_POSITION + 3],
                            row[COMMANDED_QUATERNION:COMMANDED_QUATERNION + 4], held_by_surface(plant_state))
        if lost != IN_CONTROL:
            return LOST_CONTROL, k, lost
        hold_command(plant, plant_state, mode, row, force, torque)
        if plant.wrench_lag:  # the applied wrench over the step (as the RK4 steps apply it, lagging the command)
            w = plant_state.body_wrench
            c = plant_state.wrench_command
            d, h, s = plant.speed_decay, plant.speed_mean, plant.substeps
            force_held = (period_mean_lagged(w[0], c[0], d, h, s), period_mean_lagged(w[1], c[1], d, h, s),
                          period_mean_lagged(w[2], c[2], d, h, s))
            torque_held = (period_mean_lagged(w[3], c[3], d, h, s), period_mean_lagged(w[4], c[4], d, h, s),
                           period_mean_lagged(w[5], c[5], d, h, s))
        else:
            force_held, torque_held = force, torque
        code = advance(plant, plant_state, published[(k + 1) % 2])
        if code != RUNNING:
            return DIVERGED, k, code
        rotation_next = _state_rotation(plant_state.x)
        if rotor_truth:
            rotor_command_row(measures, k, row, rotor_rows[ACTUAL_SPEEDS], rotor_rows[ACTUAL_TILTS],
                              rotor_rows[SPEEDS], rotor_rows[TILTS])
            thrust_ratio_row(measures, plant_state.x, rotation_next, rotor_rows[GROUND], rotor_rows[CEILING],
                             rotor_rows[RATIOS_NEXT])
            set_rotor_command(actuator_plant, actuator_state, rotor_rows[SPEEDS], rotor_rows[TILTS],
                              measures.with_tilts)
            force_start, torque_start = scaled_rotor_wrench(actuator_state.columns, actuator_state.speed_sq,
                                                            rotor_rows[RATIOS])
            if measures.lagging:  # the rotors move within the step: at its end, their speeds and tilts of t_k+1
                set_rotor_command(actuator_plant, actuator_state, plant_state.speeds, plant_state.tilts,
                                  measures.with_tilts)
            force_end, torque_end = scaled_rotor_wrench(actuator_state.columns, actuator_state.speed_sq,
                                                        rotor_rows[RATIOS_NEXT])
            measure_estimate(measures, plant, acc, k, t, ((k + 1) * period_ns) * 1e-9, states, plant_state.x,
                             rotation_k, rotation_next, now, force, torque, force_start, torque_start, force_end,
                             torque_end, estimate)
        elif with_estimator and measures.truth:  # wrench actuation: the command, or the wrench lagging it
            measure_estimate(measures, plant, acc, k, t, ((k + 1) * period_ns) * 1e-9, states, plant_state.x,
                             rotation_k, rotation_next, now, force, torque, force_held, torque_held, force_held,
                             torque_held, estimate)
        rotation_k = rotation_next
    return FINISHED, step_count, 0
