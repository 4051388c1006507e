"""Flight metrics from a recording: tracking errors, saturation, estimator accuracy, surfaces, end state.

Errors are taken at the odometry stamps t_k against the reference stamped t_k (zero-order hold when a
stamp has no exact partner):

* position ``e_p = p - p_d`` [m] (world NED), velocity ``e_v = R v_b - p_dot_d`` [m/s] (world);
* attitude: the angle of ``R_d^T R``, ``2 acos(|<q, q_d>|)`` [deg];
* angular velocity ``e_w = omega_b - R^T R_d omega_d`` [rad/s] (body FRD; the reference carries
  ``R_d omega_d`` in world axes).

Each is summarised as final (last sample), peak (max of the norm, with its time) and RMS of the norm.
Saturation counts the rotor commands at or beyond the vehicle's limits (speed ``<= rotor_speed_min`` or
``>= rotor_speed_max``, tilt ``|alpha| >= tilt_angle_max``); which wrench axis gave way comes from
``wrench_shortfall`` (demanded minus commanded body wrench): per axis the steps with ``|shortfall|`` above
``SHORTFALL_TOLERANCE`` and the largest ``|shortfall|`` (N or N m) with its time. The external-wrench
estimate is compared with the truth at the estimate's stamps: mean of each over the last second, RMS of the
error after a settling time. Thrust ratios ``T / T_OGE`` near the ground and the ceiling follow the odometry through the
scenario's environment (:mod:`fsr_sim.model.environment`); the states at which a rotor's ratio is held at
the surface's ``max_ratio`` (closer to the surface than the effect model is valid for) are counted per
surface (``thrust_ratio.at_cap``) and named in ``notes``.

Every value is JSON-ready (NaN -> None); a metric whose topics or scenario are missing is None and the
reason is in ``notes``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fsr_bringup.analysis.load import Flight, hold, load_flight
from fsr_sim.model.allocation import SHORTFALL_TOLERANCE, WRENCH_AXES
from fsr_sim.model.environment import (
    ThrustEffects,
    ceiling_effect_ratio,
    ground_effect_ratio,
    multirotor_ground_effect_ratio,
)
from fsr_sim.recording.reader import Recording

DEFAULT_SETTLE_S = 5.0  # s, start of the window for the wrench-estimate RMS error (at most half the run)
MEAN_WINDOW_S = 1.0  # s, final-value window for the wrench estimate and truth
LIMIT_TOLERANCE = 1e-9  # relative: a command this close to a limit counts as at the limit


@dataclass
class TrackingErrors:
    """Errors at the odometry stamps (NaN before the first reference)."""

    t: np.ndarray  # (n,) s
    position: np.ndarray  # (n, 3) m, world
    velocity: np.ndarray  # (n, 3) m/s, world
    attitude_deg: np.ndarray  # (n,) deg
    angular_velocity: np.ndarray  # (n, 3) rad/s, body


def tracking_errors(flight: Flight) -> TrackingErrors | None:
    """Position, velocity, attitude and angular-velocity errors (module docstring); None without odom or
    reference."""
    odom, ref = flight.odom, flight.reference
    if odom is None or ref is None:
        return None
    target = odom.stamp_ns
    p_d = hold(ref.stamp_ns, ref.position, target)
    q_d = hold(ref.stamp_ns, ref.quaternion, target)
    q_d /= np.linalg.norm(q_d, axis=1, keepdims=True)
    q = odom.quaternion / np.linalg.norm(odom.quaternion, axis=1, keepdims=True)
    dot = np.abs(np.sum(q * q_d, axis=1))
    attitude = np.degrees(2.0 * np.arccos(np.clip(dot, 0.0, 1.0)))
    attitude[np.isnan(dot)] = np.nan
    return TrackingErrors(
        t=odom.t,
        position=odom.position - p_d,
        velocity=odom.velocity_world - hold(ref.stamp_ns, ref.velocity, target),
        attitude_deg=attitude,
        angular_velocity=odom.angular_velocity
        - np.einsum("nji,nj->ni", odom.rotation, hold(ref.stamp_ns, ref.angular_velocity_world, target)),
    )


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


def saturation(flight: Flight) -> dict[str, Any] | None:
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


def wrench_shortfall(flight: Flight) -> dict[str, Any] | None:
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


def wrench_comparison(flight: Flight, settle_time: float = DEFAULT_SETTLE_S) -> dict[str, Any] | None:
    """Estimated vs true external wrench ``[f_x, f_y, f_z, tau_x, tau_y, tau_z]`` (body FRD, N and N m)."""
    est, truth = flight.wrench_estimate, flight.wrench_truth
    if est is None or truth is None:
        return None
    estimate = np.hstack((est.force, est.torque))
    true = np.hstack((truth.force, truth.torque))
    true_at_est = hold(truth.stamp_ns, true, est.stamp_ns)
    span = est.t[-1] - est.t[0]
    skip = min(settle_time, 0.5 * span)
    late = (est.t >= est.t[0] + skip) & np.all(np.isfinite(true_at_est), axis=1)
    error = estimate[late] - true_at_est[late]
    last_est = est.t >= est.t[-1] - MEAN_WINDOW_S
    last_true = truth.t >= truth.t[-1] - MEAN_WINDOW_S
    return {
        "components": ["f_x", "f_y", "f_z", "tau_x", "tau_y", "tau_z"],
        "estimate_mean_last_s": estimate[last_est].mean(axis=0).tolist(),
        "truth_mean_last_s": true[last_true].mean(axis=0).tolist(),
        "rms_error": np.sqrt(np.mean(error**2, axis=0)).tolist() if len(error) else None,
        "max_abs_error": np.abs(error).max(axis=0).tolist() if len(error) else None,
        "rms_from_s": float(est.t[0] + skip),
    }


def mass_comparison(flight: Flight) -> dict[str, Any] | None:
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


def thrust_ratio_series(flight: Flight) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(t, ground, ceiling)``: per-rotor ``T / T_OGE`` of each surface along the flight, shape (n, rotors)
    (1 where a surface is off); None without odom or scenario."""
    odom, config = flight.odom, flight.config
    if odom is None or config is None:
        return None
    env, vehicle = config.environment, config.plant_vehicle
    # World z of each rotor centre: p_z + (R p_i)_z, vectorised over the flight.
    rotor_down = odom.position[:, 2:3] + odom.rotation[:, 2, :] @ vehicle.positions.T
    ground = np.ones_like(rotor_down)
    ceiling = np.ones_like(rotor_down)
    if env.ground.enabled and env.ground.effect:
        distance = env.ground.height - rotor_down
        if env.ground_model == "multirotor":
            effects = ThrustEffects(env, vehicle.positions, vehicle.rotor_radius)
            ground = np.array([
                multirotor_ground_effect_ratio(
                    row, vehicle.rotor_radius, effects.separation, effects.arm_lengths, env.body_factor,
                    env.ground.max_ratio,
                )
                for row in distance
            ]).reshape(distance.shape)
        else:
            ground = ground_effect_ratio(distance, vehicle.rotor_radius, env.ground.max_ratio)
    if env.ceiling.enabled and env.ceiling.effect:
        ceiling = ceiling_effect_ratio(
            rotor_down - env.ceiling.height, vehicle.rotor_radius, env.ceiling_k1, env.ceiling_k2,
            env.ceiling.max_ratio,
        )
    return odom.t, ground, ceiling


def _range(values: np.ndarray) -> list[float]:
    return [float(np.min(values)), float(np.max(values))]


def surface_caps(flight: Flight, t: np.ndarray, ground: np.ndarray, ceiling: np.ndarray) -> dict[str, Any]:
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


def interrupted_at(status: dict[str, Any] | None) -> float | None:
    """Simulated time [s] at which a signal stopped the flight (final ``sim_status`` ``stopped`` with reason
    ``received SIGINT`` / ``SIGTERM``), or None for a flight that ended on its own (or never started)."""
    if not status or status.get("state") != "stopped" or not str(status.get("reason", "")).startswith("received "):
        return None
    sim_time = status.get("sim_time")
    return float(sim_time) if isinstance(sim_time, int | float) else None


def flight_metrics(
    recording: Recording | Flight | str | Path, settle_time: float = DEFAULT_SETTLE_S
) -> dict[str, Any]:
    """All metrics of one flight as a JSON-ready dict (see the module docstring for definitions)."""
    flight = recording if isinstance(recording, Flight) else load_flight(recording)
    notes = list(flight.notes)
    odom = flight.odom
    status = flight.sim_status[-1] if flight.sim_status else None
    metrics: dict[str, Any] = {
        "recording": str(flight.recording.path),
        "scenario": flight.scenario_name,
        "namespace": flight.namespace,
        "truncated": flight.truncated,
        "duration_s": float(odom.t[-1] - odom.t[0]) if odom is not None else None,
        "end_time_s": float(odom.t[-1]) if odom is not None else None,
        "steps": int(status["steps"]) if status and isinstance(status.get("steps"), int) else None,
        "odom_messages": len(odom.t) if odom is not None else 0,
        "message_counts": dict(flight.message_counts),
        "sim_status": (
            {key: status.get(key) for key in ("state", "reason", "sim_time", "steps")} if status else None
        ),
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
            "angular_velocity_error_rad_s": error_summary(errors.t, errors.angular_velocity),
        }
    if flight.wrench_cmd is not None:
        thrust = np.linalg.norm(flight.wrench_cmd.force, axis=1)
        last = flight.wrench_cmd.t >= flight.wrench_cmd.t[-1] - MEAN_WINDOW_S
        metrics["commanded_thrust_N"] = {
            "final": float(thrust[-1]), "peak": float(thrust.max()), "mean_last_s": float(thrust[last].mean()),
        }
    else:
        metrics["commanded_thrust_N"] = None
    metrics["saturation"] = saturation(flight)
    if metrics["saturation"] is None:
        notes.append("saturation skipped: rotor_cmd or scenario missing")
    metrics["wrench_shortfall"] = wrench_shortfall(flight)
    if metrics["wrench_shortfall"] is None:
        notes.append("wrench shortfall skipped: wrench_shortfall missing")
    metrics["external_wrench"] = wrench_comparison(flight, settle_time)
    if metrics["external_wrench"] is None:
        notes.append("wrench estimate comparison skipped: wrench_estimate or wrench_truth missing")
    metrics["mass"] = mass_comparison(flight)
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
