"""Flight metrics from a recording: tracking errors, saturation, estimator accuracy, surfaces, end state.

Errors are taken on the true state (``odom``, or ``odom_truth`` where ``odom`` is a measurement: a sensor stage
on; ``tracking.measured_on`` says which) at its stamps t_k against the reference stamped t_k (zero-order hold when
a stamp has no exact partner); with a measured ``odom`` its own error against the true state is given as
``odometry_error`` (what the controller was fed, not how it flew):

* position ``e_p = p - p_d`` [m] (world NED), velocity ``e_v = R v_b - p_dot_d`` [m/s] (world);
* attitude: the angle of ``R_c^T R`` [deg] with ``R_c`` the attitude the controller commanded
  (``attitude_cmd``: the geometric controller's thrust-vector attitude, the Voliro controller's reference);
  the angle of ``R_d^T R`` against the planner's attitude ``R_d`` is kept as ``attitude_vs_reference``
  (it counts the tilt the geometric controller commands on purpose as error). Recordings without
  ``attitude_cmd`` fall back to ``R_d``, with a note;
* angular velocity ``e_w = omega_b - R^T R_d omega_d`` [rad/s] (body FRD; the reference carries
  ``R_d omega_d`` in world axes).

Each is summarised as final (last sample), peak (max of the norm, with its time) and RMS of the norm.
Saturation counts the rotor commands at or beyond the vehicle's limits (speed ``<= rotor_speed_min`` or
``>= rotor_speed_max``, tilt ``|alpha| >= tilt_angle_max``). The online wrench estimate (body FRD) is
compared with the *effective truth* (:mod:`fsr_bringup.analysis.effective`: external wrench + surface-effect
thrust change + contact + model mismatch, what the observer must converge to) with the functions of
``fsr-estimate`` (:mod:`fsr_estimation.estimator.metrics`): settling time per channel (standard or the report's
definition), MAE over the whole flight, max error after ``after`` (default: the last 5 s) and RMS error after
a settling time; the pure external wrench (``wrench_truth``) is reported next to it. Thrust ratios
``T / T_OGE`` near the ground and the ceiling follow the odometry through the scenario's environment
(:mod:`fsr_sim.model.environment`); the states at which a rotor's ratio is held at the surface's
``max_ratio`` (closer to the surface than the effect model is valid for) are counted per surface
(``thrust_ratio.at_cap``) and named in ``notes``. Which wrench axis gave way at the rotor limits comes from
``wrench_shortfall`` (demanded minus commanded body wrench): per axis the steps with ``|shortfall|`` above
``SHORTFALL_TOLERANCE`` and the largest ``|shortfall|`` (N or N m) with its time.

The path (``path``): the peak (with its time) and RMS speed and acceleration and the length of the reference
(``planned``) and of the flight (``flown``: the true state's velocity and its central differences). The plan
(``plan``): the scenario's ``trajectory.kind`` and when its plan comes to rest; a flight that finished at the
scenario's duration before that ended mid-path (``ended_mid_path``, with a note).

Every value is JSON-ready (NaN -> None); a metric whose topics or scenario are missing is None and the
reason is in ``notes``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fsr_bringup.analysis.diagnosis import diagnosis
from fsr_bringup.analysis.effective import effective_wrench, thrust_ratio_series
from fsr_bringup.analysis.load import RecordedFlight, load_flight, zero_order_hold
from fsr_control.planning.trajectory import mid_path, mid_path_note
from fsr_estimation.estimator import metrics as estimator_metrics
from fsr_estimation.estimator.metrics import DEFAULT_LAST_SECONDS
from fsr_sim.contract import (
    ATTITUDE_CMD,
    FINISHED,
    GOAL,
    ODOM,
    ODOM_TRUTH,
    REFERENCE,
    SIM_STATUS,
    STOPPED,
    WRENCH_SHORTFALL,
    SimStatus,
    resolve,
)
from fsr_sim.model.environment import contact_mask
from fsr_sim.model.rotors import SHORTFALL_TOLERANCE, WRENCH_AXES
from fsr_sim.model.so3 import relative_rotation_angles
from fsr_sim.recording.reader import Recording

DEFAULT_SETTLE_S = 5.0  # s, start of the window for the wrench-estimate RMS error (at most half the run)
MEAN_WINDOW_S = 1.0  # s, final-value window for the wrench estimate and truth
WRENCH_CHANNELS = estimator_metrics.CHANNELS
LIMIT_TOLERANCE = 1e-9  # relative: a command this close to a limit counts as at the limit


@dataclass
class TrackingErrors:
    """Errors at the odometry stamps (NaN before the first reference)."""

    t: np.ndarray  # (n,) s
    position: np.ndarray  # (n, 3) m, world
    velocity: np.ndarray  # (n, 3) m/s, world
    attitude_deg: np.ndarray  # (n,) deg, angle of R_c^T R (commanded attitude; R_d^T R without attitude_cmd)
    attitude_reference_deg: np.ndarray  # (n,) deg, angle of R_d^T R (planner's attitude)
    attitude_commanded: bool  # attitude_deg is against the recorded attitude_cmd
    angular_velocity: np.ndarray  # (n, 3) rad/s, body


def tracking_errors(flight: RecordedFlight) -> TrackingErrors | None:
    """Position, velocity, attitude and angular-velocity errors of the true state (module docstring); None without
    odom or reference."""
    odom, ref = flight.true_odom, flight.reference
    if odom is None or ref is None:
        return None
    target = odom.stamp_ns
    p_d = zero_order_hold(ref.stamp_ns, ref.position, target)
    reference_attitude = _angle_deg(zero_order_hold(ref.stamp_ns, ref.rotation.reshape(-1, 9), target), odom.rotation)
    cmd = flight.attitude_cmd
    commanded = (_angle_deg(zero_order_hold(cmd.stamp_ns, cmd.rotation.reshape(-1, 9), target), odom.rotation)
                 if cmd is not None else reference_attitude)
    return TrackingErrors(
        t=odom.t,
        position=odom.position - p_d,
        velocity=odom.velocity_world - zero_order_hold(ref.stamp_ns, ref.velocity, target),
        attitude_deg=commanded,
        attitude_reference_deg=reference_attitude,
        attitude_commanded=cmd is not None,
        angular_velocity=odom.angular_velocity
        - np.einsum("nji,nj->ni", odom.rotation, zero_order_hold(ref.stamp_ns, ref.angular_velocity_world, target)),
    )


def _angle_deg(desired_rows: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Angle of ``R_d^T R`` [deg] per sample; ``desired_rows`` (n, 9) held rotations (NaN before the first)."""
    angle = np.degrees(relative_rotation_angles(desired_rows.reshape(-1, 3, 3), rotation))
    angle[np.isnan(desired_rows).any(axis=1)] = np.nan
    return angle


def error_summary(t: np.ndarray, error: np.ndarray) -> dict[str, float | None]:
    """final / peak (and its time) / RMS of ``|error|`` over the samples where it is defined."""
    magnitude = np.linalg.norm(error, axis=1) if error.ndim == 2 else np.abs(error)
    valid = np.isfinite(magnitude)
    if not valid.any():
        return {"final": None, "peak": None, "peak_time_s": None, "rms": None}
    values, times = magnitude[valid], t[valid]
    peak = int(np.argmax(values))
    return {
        "final": float(values[-1]),
        "peak": float(values[peak]),
        "peak_time_s": float(times[peak]),
        "rms": float(np.sqrt(np.mean(values**2))),
    }


def _motion(t: np.ndarray, position: np.ndarray, velocity: np.ndarray,
            acceleration: np.ndarray) -> dict[str, Any]:
    """Peak (with its time) and RMS of the speed [m/s] and of the acceleration's norm [m/s^2], and the path length
    [m] (the polyline through the positions)."""
    speed = error_summary(t, velocity)
    accel = error_summary(t, acceleration)
    return {
        "speed_m_s": {key: speed[key] for key in ("peak", "peak_time_s", "rms")},
        "acceleration_m_s2": {key: accel[key] for key in ("peak", "peak_time_s", "rms")},
        "length_m": float(np.linalg.norm(np.diff(position, axis=0), axis=1).sum()) if len(position) > 1 else 0.0,
    }


def path_motion(flight: RecordedFlight) -> dict[str, Any] | None:
    """Speed, acceleration and path length (:func:`_motion`) of the reference (``planned``: its own velocity and
    acceleration) and of the flight (``flown``: ``odom``'s velocity, world, and its central differences); None
    without odom or reference."""
    odom, ref = flight.true_odom, flight.reference
    if odom is None or ref is None:
        return None
    flown_acceleration = (np.gradient(odom.velocity_world, odom.t, axis=0) if len(odom.t) > 1
                          else np.zeros_like(odom.velocity_world))
    return {"planned": _motion(ref.t, ref.position, ref.velocity, ref.acceleration),
            "flown": _motion(odom.t, odom.position, odom.velocity_world, flown_acceleration),
            "flown_from": ODOM_TRUTH.name if flight.odom_measured else ODOM.name}


def odometry_error(flight: RecordedFlight) -> dict[str, Any] | None:
    """How far the measured ``odom`` is from the true state (``odom_truth``): final / peak / RMS of the position
    [m], attitude [deg] and velocity [m/s] errors; None when ``odom`` is the true state (or a topic is missing)."""
    measured, true = flight.odom, flight.odom_truth
    if measured is None or true is None:
        return None
    target = measured.stamp_ns
    rows = zero_order_hold(true.stamp_ns, np.hstack((true.position, true.velocity_world, true.rotation.reshape(-1, 9))),
                           target)
    return {
        "position_m": error_summary(measured.t, measured.position - rows[:, :3]),
        "attitude_deg": error_summary(measured.t, _angle_deg(rows[:, 6:], measured.rotation)),
        "velocity_m_s": error_summary(measured.t, measured.velocity_world - rows[:, 3:6]),
    }


def plan_end(flight: RecordedFlight, end_time: float | None) -> dict[str, Any] | None:
    """The scenario's plan: its ``kind``, when it comes to rest (``end_s``) and whether the flight ended before
    (``ended_mid_path``: it finished at the scenario's duration while the plan was still moving; None when a goal
    received at run time changed the plan, or the flight did not run to its end); None without the scenario."""
    plan = flight.plan
    if plan is None:
        return None
    status = flight.sim_status[-1] if flight.sim_status else None
    goals = flight.message_counts.get(resolve(GOAL.name, flight.namespace), 0)
    ended = None
    if end_time is not None and not goals:
        ended = mid_path(FINISHED if status is None else status.state, end_time, plan["end_s"])
    return {"kind": plan["kind"], "end_s": plan["end_s"], "ended_mid_path": ended}


def _limit_hits(values: np.ndarray, t: np.ndarray, hits: np.ndarray) -> dict[str, Any]:
    per_step = hits.any(axis=1)
    per_channel = hits.sum(axis=0)
    steps = int(per_step.sum())
    return {
        "steps": steps,
        "fraction": steps / len(values) if len(values) else 0.0,
        "first_time_s": float(t[np.argmax(per_step)]) if steps else None,
        "worst_rotor": int(np.argmax(per_channel)) + 1 if steps else None,
        "per_rotor_steps": [int(v) for v in per_channel],
    }


def saturation(flight: RecordedFlight) -> dict[str, Any] | None:
    """Rotor commands at or beyond the vehicle's speed (and tilt) limits; None without rotor_cmd or
    scenario. Rotors are numbered from 1."""
    cmd, config = flight.rotor_cmd, flight.config
    if cmd is None or config is None:
        return None
    vehicle = config.vehicle
    tol = LIMIT_TOLERANCE * vehicle.rotor_speed_max
    speeds = np.nan_to_num(cmd.speeds, nan=0.5 * (vehicle.rotor_speed_min + vehicle.rotor_speed_max))
    upper = speeds >= vehicle.rotor_speed_max - tol
    lower = speeds <= vehicle.rotor_speed_min + tol
    result: dict[str, Any] = {
        "limits_rad_s": [vehicle.rotor_speed_min, vehicle.rotor_speed_max],
        "rotor_speed": _limit_hits(speeds, cmd.t, upper | lower),
        "at_max_steps": int(upper.any(axis=1).sum()),
        "at_min_steps": int(lower.any(axis=1).sum()),
        "tilt": None,
    }
    if cmd.tilts is not None and vehicle.tilt_angle_max < math.pi:
        tilts = np.abs(np.nan_to_num(cmd.tilts))
        result["tilt"] = _limit_hits(tilts, cmd.t, tilts >= vehicle.tilt_angle_max * (1 - LIMIT_TOLERANCE))
        result["tilt"]["limit_deg"] = math.degrees(vehicle.tilt_angle_max)
    return result


def compensation(flight: RecordedFlight) -> dict[str, Any] | None:
    """Whether the controller cancelled the estimated external wrench (``controller.compensation`` of the
    scenario in the metadata) and, if so, the states in which the contact rule switched it off
    (the contact rule, :func:`fsr_sim.model.environment.contact_mask`, on ``odom``) and the late estimates: 0, the
    observer runs inside the controller (:mod:`fsr_control.compensation`). None without a scenario."""
    if flight.compensation_mode is None:
        return None
    if flight.compensation is None:
        return {"mode": flight.compensation_mode}
    contact = None
    if flight.odom is not None:
        contact = int(contact_mask(flight.compensation.surfaces, flight.odom.position[:, 2]).sum())
    return {"mode": "estimate", "observer": "controller", "late_estimates": 0, "contact_steps": contact,
            "c0": flight.compensation.c0, "r": flight.compensation.r}


def wrench_shortfall(flight: RecordedFlight) -> dict[str, Any] | None:
    """Per body axis (``force_x`` .. ``torque_z``): steps that gave way (``|demanded - commanded| >
    SHORTFALL_TOLERANCE``), their fraction, and the largest shortfall [N or N m] with its time; None without
    ``wrench_shortfall``."""
    shortfall = flight.wrench_shortfall
    if shortfall is None:
        return None
    values = np.abs(np.hstack((shortfall.force, shortfall.torque)))  # (n, 6)
    gave_way = values > SHORTFALL_TOLERANCE
    result: dict[str, Any] = {"steps": len(values), "any_axis_steps": int(gave_way.any(axis=1).sum())}
    for axis, name in enumerate(WRENCH_AXES):
        steps = int(gave_way[:, axis].sum())
        worst = int(np.argmax(values[:, axis])) if len(values) else 0
        result[name] = {
            "steps": steps,
            "fraction": steps / len(values) if len(values) else 0.0,
            "max_shortfall": float(values[worst, axis]) if steps else 0.0,
            "max_time_s": float(shortfall.t[worst]) if steps else None,
        }
    return result


def _channels(values: np.ndarray) -> dict[str, float | None]:
    return {name: (float(v) if math.isfinite(v) else None) for name, v in zip(WRENCH_CHANNELS, values, strict=True)}


def wrench_comparison(flight: RecordedFlight, settle_time: float = DEFAULT_SETTLE_S, settling: str = "standard",
                      after: float | None = None) -> dict[str, Any] | None:
    """Online wrench estimate vs the effective truth (and vs the external wrench alone), body FRD [N, N m].

    Per channel (``fx fy fz tx ty tz``): settling time (``settling``: ``standard``, ``report`` or ``smoothed``;
    and ``settling_time_smoothed_s``, the ``smoothed`` one, whatever ``settling`` is), MAE over
    the flight, max error at time >= ``after`` [s] (default: the last 5 s), RMS error after ``settle_time``
    (at most half the flight), all with :mod:`fsr_estimation.estimator.metrics` on the estimate's samples where
    the effective truth is defined. None without ``wrench_estimate``; without the scenario's estimator model
    only the external-wrench comparison is given.
    """
    est = flight.wrench_estimate
    if est is None or (flight.wrench_truth is None and flight.odom is None):
        return None
    estimate = np.hstack((est.force, est.torque))
    span = est.t[-1] - est.t[0]
    skip = min(settle_time, 0.5 * span)
    late = est.t >= est.t[0] + skip
    last = est.t >= est.t[-1] - MEAN_WINDOW_S
    result: dict[str, Any] = {
        "frame": "body FRD", "components": list(WRENCH_CHANNELS), "rms_from_s": float(est.t[0] + skip),
        "estimate_mean_last_s": estimate[last].mean(axis=0).tolist(),
        "truth_mean_last_s": None, "rms_error_vs_external": None,
        "effective_truth_mean_last_s": None, "rms_error": None, "max_abs_error": None,
        "settling": settling, "settling_time_s": None, "settling_time_smoothed_s": None, "mae": None,
        "max_error_after": None, "after_s": None,
    }
    if flight.wrench_truth is not None:
        truth = flight.wrench_truth
        true = zero_order_hold(truth.stamp_ns, np.hstack((truth.force, truth.torque)), est.stamp_ns)
        ok = late & np.all(np.isfinite(true), axis=1)
        result["truth_mean_last_s"] = true[last].mean(axis=0).tolist()
        if ok.any():
            result["rms_error_vs_external"] = np.sqrt(np.mean((estimate[ok] - true[ok]) ** 2, axis=0)).tolist()
    effective = effective_wrench(flight)
    if effective is None:
        return result
    true = zero_order_hold(effective.stamp_ns, effective.wrench_body, est.stamp_ns)
    defined = np.all(np.isfinite(true), axis=1)
    if defined.sum() < 2:
        return result
    t, w, truth_eff = est.t[defined], estimate[defined], true[defined]
    error = w - truth_eff
    ok = late[defined]
    after_s = max(0.0, float(t[-1] - t[0]) - DEFAULT_LAST_SECONDS) if after is None else float(after)
    result.update({
        "effective_truth_mean_last_s": truth_eff[last[defined]].mean(axis=0).tolist(),
        "rms_error": np.sqrt(np.mean(error[ok] ** 2, axis=0)).tolist() if ok.any() else None,
        "max_abs_error": np.abs(error[ok]).max(axis=0).tolist() if ok.any() else None,
        "settling_time_s": _channels(estimator_metrics.settling_time(t, w, truth_eff, settling)),
        "settling_time_smoothed_s": _channels(estimator_metrics.settling_time(t, w, truth_eff, "smoothed")),
        "mae": _channels(estimator_metrics.mean_absolute_error(w, truth_eff)),
        "max_error_after": _channels(estimator_metrics.max_error_after(t, w, truth_eff, after_s, settling)),
        "after_s": after_s,
    })
    return result


def masses(flight: RecordedFlight) -> dict[str, Any] | None:
    """Which part of the flight uses which mass [kg]: the true plant's (``plant.mass``), the controller's model
    (the vehicle file's) and the estimator's model (``estimator.mass``; None without the estimator). None without
    the scenario."""
    if flight.config is None:
        return None
    return {"plant_kg": flight.config.plant_vehicle.mass, "controller_model_kg": flight.config.vehicle.mass,
            "vehicle": flight.config.vehicle.name,
            "estimator_model_kg": flight.estimator.mass if flight.estimator is not None and flight.estimator.enabled
            else None}


def mass_comparison(flight: RecordedFlight) -> dict[str, Any] | None:
    """Final mass estimate [kg] vs the true plant mass (and the nominal model's) from the scenario."""
    if flight.mass_estimate is None:
        return None
    final = float(flight.mass_estimate.value[-1])
    true = flight.config.plant_vehicle.mass if flight.config else None
    return {
        "estimate_final_kg": final,
        "true_kg": true,
        "nominal_kg": flight.config.vehicle.mass if flight.config else None,
        "error_kg": final - true if true is not None else None,
    }


def _range(values: np.ndarray) -> list[float]:
    return [float(np.min(values)), float(np.max(values))]


def surface_caps(flight: RecordedFlight, t: np.ndarray, ground: np.ndarray, ceiling: np.ndarray) -> dict[str, Any]:
    """Per surface whose effect is on (and ``max_ratio > 1``): ``{steps, first_time_s, max_ratio}`` of the
    states at which any rotor's ratio (from :func:`thrust_ratio_series`) equals the cap ``max_ratio``."""
    env = flight.config.environment
    caps: dict[str, Any] = {}
    for name, surface, ratios in (("ground", env.ground, ground), ("ceiling", env.ceiling, ceiling)):
        if not (surface.enabled and surface.effect and surface.max_ratio > 1.0):
            continue
        at_cap = np.any(ratios >= surface.max_ratio * (1.0 - 1e-12), axis=1)
        steps = int(np.count_nonzero(at_cap))
        first = float(t[np.argmax(at_cap)]) if steps else None
        caps[name] = {"steps": steps, "first_time_s": first, "max_ratio": surface.max_ratio}
    return caps


def interrupted_at(status: SimStatus | None) -> float | None:
    """Simulated time [s] at which a signal stopped the flight (final ``sim_status`` ``stopped`` with reason
    ``received SIGINT`` / ``SIGTERM``), or None for a flight that ended on its own (or never started)."""
    if status is None or status.state != STOPPED or not str(status.reason).startswith("received "):
        return None
    return float(status.sim_time)


def _odom_measured_by_config(flight: RecordedFlight) -> bool:
    """The flight's ``odom`` is a measurement: ``odom_truth`` was recorded, or the scenario's odometry has noise,
    bias, delay or a lower rate."""
    return flight.odom_measured or (flight.config is not None and flight.config.odometry_noise.enabled)


def flight_metrics(
    recording: Recording | RecordedFlight | str | Path, settle_time: float = DEFAULT_SETTLE_S,
    settling: str = "standard", after: float | None = None,
) -> dict[str, Any]:
    """All metrics of one flight as a JSON-ready dict (see the module docstring for definitions).

    ``settling`` (``standard`` | ``report``) and ``after`` [s] select the estimator metrics' settling-time
    definition and the start of the max-error window (default: the last 5 s)."""
    flight = recording if isinstance(recording, RecordedFlight) else load_flight(recording)
    notes = list(flight.notes)
    odom = flight.true_odom
    status = flight.sim_status[-1] if flight.sim_status else None
    metrics: dict[str, Any] = {
        "recording": None if flight.recording is None else str(flight.recording.path),  # None: in memory
        "scenario": flight.scenario_name,
        "namespace": flight.namespace,
        "truncated": flight.truncated,
        "duration_s": float(odom.t[-1] - odom.t[0]) if odom is not None else None,
        "end_time_s": float(odom.t[-1]) if odom is not None else None,
        "steps": int(status.steps) if status is not None and isinstance(status.steps, int) else None,
        "odom_messages": len(flight.odom.t) if flight.odom is not None else 0,
        "message_counts": dict(flight.message_counts),
        SIM_STATUS.name: None if status is None else status.as_dict(),
        "interrupted_at_s": interrupted_at(status),
    }
    errors = tracking_errors(flight)
    if errors is None:
        notes.append("tracking errors skipped: odom or reference missing")
        metrics["tracking"] = None
    else:
        metrics["tracking"] = {
            "position_error_m": error_summary(errors.t, errors.position),
            "velocity_error_m_s": error_summary(errors.t, errors.velocity),
            "attitude_error_deg": error_summary(errors.t, errors.attitude_deg),
            "attitude_vs": ATTITUDE_CMD.name if errors.attitude_commanded else REFERENCE.name,
            "attitude_vs_reference_deg": error_summary(errors.t, errors.attitude_reference_deg),
            "angular_velocity_error_rad_s": error_summary(errors.t, errors.angular_velocity),
            "measured_on": ODOM_TRUTH.name if flight.odom_measured else ODOM.name,
            "odom_is_true_state": not _odom_measured_by_config(flight),
        }
        if _odom_measured_by_config(flight) and not flight.odom_measured:
            notes.append("odom is a measurement (sensors.odometry) and odom_truth is not recorded: the tracking "
                         "errors are against the measured odom, not the true state")
    metrics["odometry_error"] = odometry_error(flight)
    if flight.wrench_cmd is not None:
        thrust = np.linalg.norm(flight.wrench_cmd.force, axis=1)
        last = flight.wrench_cmd.t >= flight.wrench_cmd.t[-1] - MEAN_WINDOW_S
        metrics["commanded_thrust_N"] = {
            "final": float(thrust[-1]), "peak": float(thrust.max()), "mean_last_s": float(thrust[last].mean()),
        }
    else:
        metrics["commanded_thrust_N"] = None
    metrics["compensation"] = compensation(flight)
    metrics["plan_adjustments"] = flight.plan_adjustments
    metrics["plan"] = plan_end(flight, metrics["end_time_s"])
    if metrics["plan"] is not None and metrics["plan"]["ended_mid_path"]:
        notes.append(mid_path_note(metrics["end_time_s"], metrics["plan"]["end_s"]))
    metrics["path"] = path_motion(flight)
    if flight.config is not None and flight.config.actuation == "wrench":  # no rotors: nothing can saturate
        metrics["saturation"] = metrics[WRENCH_SHORTFALL.name] = None
        notes.append("no rotor saturation: wrench actuation applies the commanded wrench as it is")
    else:
        metrics["saturation"] = saturation(flight)
        if metrics["saturation"] is None:
            notes.append("saturation skipped: rotor_cmd or scenario missing")
        metrics[WRENCH_SHORTFALL.name] = wrench_shortfall(flight)
        if metrics[WRENCH_SHORTFALL.name] is None:
            notes.append("wrench shortfall skipped: wrench_shortfall missing")
    metrics["diagnosis"] = diagnosis(flight, metrics)
    if errors is not None and not errors.attitude_commanded:
        notes.append("no attitude_cmd: attitude error measured against the planner's attitude R_d")
    metrics["external_wrench"] = wrench_comparison(flight, settle_time, settling, after)
    if metrics["external_wrench"] is None:
        notes.append("wrench estimate comparison skipped: wrench_estimate or wrench_truth missing")
    elif metrics["external_wrench"]["settling_time_s"] is None:
        notes.append("effective truth unavailable (odom, wrench_cmd or the scenario's estimator model missing): "
                     "the estimate is compared with the external wrench only")
    metrics["mass"] = mass_comparison(flight)
    metrics["masses"] = masses(flight)
    ratios = thrust_ratio_series(flight)
    if ratios is None:
        metrics["thrust_ratio"] = None
        notes.append("thrust ratios skipped: odom or scenario missing")
    else:
        t, ground, ceiling = ratios
        caps = surface_caps(flight, t, ground, ceiling)
        metrics["thrust_ratio"] = {
            "ground": _range(ground), "ceiling": _range(ceiling), "combined": _range(ground * ceiling),
            "at_cap": caps,
        }
        for name, cap in caps.items():
            if cap["steps"]:
                notes.append(
                    f"{name} effect at its cap (thrust ratio {cap['max_ratio']:g} = max_ratio) for {cap['steps']} "
                    f"state(s) from t = {cap['first_time_s']:.3f} s: closer to the {name} than the model is valid for"
                )
    metrics["notes"] = notes
    return json_ready(metrics)


def json_ready(value: Any) -> Any:
    """Nested dicts/lists of plain Python numbers, NaN and inf replaced by None."""
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
