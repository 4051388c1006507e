"""Effective truth: the wrench the momentum observer must converge to, from a recording and its scenario.

The equations are those of :mod:`fsr_bringup.core.effective_truth` (one compiled function per step, the one the
sweep's measured loop calls); here its inputs are taken from the recording and the scenario, not from the
estimate: the true states (``odom``, or ``odom_truth`` beside a measured ``odom``), ``wrench_truth`` and
``wrench_cmd`` held at their stamps, and the actuator's wrench at the start and at the end of each step (from
``rotor_cmd``'s speeds and tilts held over the step, or ``rotor_state``'s of both ends where actuator dynamics
make them lag the command - scaled per rotor by the ground/ceiling thrust ratio; in wrench actuation ``f_c``
itself, or with a rotor time constant the applied wrench lagging it, replayed from the commands by the plant's
own lag as its RK4 steps apply it). ``f_eff`` of step k is stamped ``t_k`` (the last sample, which has no step,
is NaN) and given in body FRD (``R_k^T f_eff``, like ``wrench_estimate``) and world NED.

No physics is written here: the actuator wrench and the thrust ratios are the plant's own compiled functions
(:func:`fsr_sim.core.plant.actuator_wrench_log`, :func:`fsr_sim.model.environment.thrust_ratio_log`), applied
to the whole log.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fsr_bringup.analysis.load import RecordedFlight, zero_order_hold
from fsr_bringup.core.effective_truth import (
    CONTACT_FORCE,
    EXTERNAL_FORCE,
    FORCE_BODY,
    FORCE_WORLD,
    HELD,
    LOG_COLUMNS,
    MISMATCH_FORCE,
    THRUST_CHANGE,
    TORQUE_BODY,
    TruthParams,
    effective_truth_log,
)
from fsr_sim.config.scenario import SimulationConfig, plant_from_config
from fsr_sim.core.plant import actuator_wrench_log, applied_wrench_log
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.environment import pack_surfaces, thrust_ratio_log


@dataclass
class EffectiveWrench:
    """The effective truth and its parts at the odometry stamps, shape (n, 3) each (NaN at the last sample).

    Forces [N] in world NED unless named ``*_body``; torques [N m] in body FRD.
    """

    stamp_ns: np.ndarray
    t: np.ndarray
    force_world: np.ndarray
    force_body: np.ndarray
    torque_body: np.ndarray
    external_force_world: np.ndarray
    thrust_change_world: np.ndarray  # <R f_a> - R f_c
    contact_force_world: np.ndarray
    mismatch_force_world: np.ndarray  # (m_e - m)(a - g e3)
    in_contact: np.ndarray  # (n,) bool: the ground held the vehicle at the end of the step

    @property
    def wrench_body(self) -> np.ndarray:
        """``[f_eff body; tau_eff body]``, shape (n, 6), comparable with ``wrench_estimate``."""
        return np.hstack((self.force_body, self.torque_body))


def actuator_wrench(config: SimulationConfig, speeds: np.ndarray, tilts: np.ndarray | None,
                    ratios: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Body wrench the rotors produce for commands along a log, computed by the plant itself
    (:func:`fsr_sim.core.plant.actuator_wrench_log`: speeds clamped to the limits, tilts to theirs, thrust and
    lever-arm torque scaled by the thrust ratio, drag torque not).

    speeds (n, r) commanded rotor speeds [rad/s] (NaN: 0); tilts (n, r) [rad] or None; ratios (n, r) thrust
    ratio ``T / T_OGE`` per rotor. Returns force (n, 3) [N] and torque (n, 3) [N m] in body FRD.
    """
    # the speeds and tilts are what the rotors do: applied as they are (no actuator dynamics in between)
    vehicle = replace(config.plant_vehicle, rotor_time_constant=0.0, tilt_time_constant=0.0, tilt_rate_max=np.inf)
    plant = plant_from_config(replace(config, plant_vehicle=vehicle))
    speeds = np.ascontiguousarray(np.nan_to_num(np.asarray(speeds, dtype=float)))
    with_tilts = tilts is not None and config.plant_vehicle.has_servos
    tilt_values = np.ascontiguousarray(np.nan_to_num(np.asarray(tilts, dtype=float))) if with_tilts else speeds
    force, torque = np.zeros((len(speeds), 3)), np.zeros((len(speeds), 3))
    actuator_wrench_log(plant.params, plant.core_state, speeds, tilt_values, with_tilts,
                        np.ascontiguousarray(ratios, dtype=float), force, torque)
    return force, torque


def applied_wrench(config: SimulationConfig, force: np.ndarray, torque: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Body wrench a wrench-actuated plant applies along a log of commands ``force``, ``torque`` (n, 3) [N, N m],
    body FRD, one per control period, computed by the plant itself (:func:`fsr_sim.core.plant.applied_wrench_log`:
    with a rotor time constant each component lags its command, the first command applied at once), as its mean
    over each period's RK4 steps as they apply it (their stages). Returns force and torque, (n, 3) each; rows
    whose command is not finite are NaN (the lag is carried through them with a zero command)."""
    plant = plant_from_config(config)
    commands = np.ascontiguousarray(np.nan_to_num(np.hstack((force, torque)).astype(float)))
    mean = np.zeros_like(commands)
    applied_wrench_log(plant.params, plant.core_state, commands, mean)
    mean[~np.isfinite(np.hstack((force, torque))).all(axis=1)] = np.nan
    return mean[:, :3], mean[:, 3:]


def effective_wrench(flight: RecordedFlight) -> EffectiveWrench | None:
    """The effective truth of the module docstring; None without odom, wrench_cmd, scenario or estimator model."""
    odom, cmd, config, model = flight.true_odom, flight.wrench_cmd, flight.config, flight.estimator
    if odom is None or cmd is None or config is None or model is None or len(odom.t) < 2:
        return None
    target = odom.stamp_ns
    n = len(target)
    rotation = odom.rotation
    plant = config.plant_vehicle
    m_true, m_est = plant.mass, model.mass
    i_true, i_est = np.ascontiguousarray(plant.inertia, dtype=float), np.asarray(model.inertia, float)
    f_cmd = zero_order_hold(cmd.stamp_ns, cmd.force, target)
    tau_cmd = zero_order_hold(cmd.stamp_ns, cmd.torque, target)
    if flight.wrench_truth is not None:
        f_ext_body = zero_order_hold(flight.wrench_truth.stamp_ns, flight.wrench_truth.force, target)
        tau_ext = zero_order_hold(flight.wrench_truth.stamp_ns, flight.wrench_truth.torque, target)
    else:
        f_ext_body, tau_ext = np.zeros((n, 3)), np.zeros((n, 3))
    # Actuator wrench at the start and at the end of each step, the command of the start held over it.
    rotors = flight.rotor_state or flight.rotor_cmd  # the actual speeds where they lag the command
    if config.actuation == "rotors" and rotors is not None:
        speeds = zero_order_hold(rotors.stamp_ns, rotors.speeds, target)
        tilts = zero_order_hold(rotors.stamp_ns, rotors.tilts, target) if rotors.tilts is not None else None
        if rotors is flight.rotor_state and flight.rotor_cmd is not None:
            # rotor_state's first state is before any command (rotors at rest); the first command spins them
            # up at once (fsr_sim.core.plant.set_rotor_command), so step 0 flies rotor_cmd's first row
            speeds[0] = zero_order_hold(flight.rotor_cmd.stamp_ns, flight.rotor_cmd.speeds, target[:1])[0]
            if tilts is not None and flight.rotor_cmd.tilts is not None:
                tilts[0] = zero_order_hold(flight.rotor_cmd.stamp_ns, flight.rotor_cmd.tilts, target[:1])[0]
        series = thrust_ratio_series(flight)
        ratios = series[1] * series[2] if series is not None else np.ones_like(speeds)
        # The same command acts at the end of the step, where the ratios (pose) have moved on - and, where the
        # rotors lag, their speeds and tilts too (rotor_state of t_k+1).
        f_start, tau_start = actuator_wrench(config, speeds, tilts, ratios)
        next_ratios = np.vstack((ratios[1:], ratios[-1:]))
        if rotors is flight.rotor_state:
            speeds = np.vstack((speeds[1:], speeds[-1:]))
            tilts = np.vstack((tilts[1:], tilts[-1:])) if tilts is not None else None
        f_end, tau_end = actuator_wrench(config, speeds, tilts, next_ratios)
    elif config.actuation == "wrench" and plant.rotor_time_constant > 0.0:
        f_start, tau_start = f_end, tau_end = applied_wrench(config, f_cmd, tau_cmd)
    else:
        f_start = f_end = f_cmd
        tau_start = tau_end = tau_cmd
    params = TruthParams(mass=float(m_true), mass_model=float(m_est), inertia=i_true,
                         inertia_delta=np.ascontiguousarray(i_est - i_true), gravity=GRAVITY)
    out = np.zeros((n, LOG_COLUMNS))

    def c(values: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(values, dtype=float)

    effective_truth_log(params, pack_surfaces(config.environment, plant), c(odom.t), c(rotation),
                        c(odom.velocity_world), c(odom.angular_velocity), c(odom.position[:, 2]),
                        (c(f_ext_body), c(tau_ext)), (c(f_cmd), c(tau_cmd)), (c(f_start), c(tau_start)),
                        (c(f_end), c(tau_end)), out)

    def part(at: int) -> np.ndarray:
        return out[:, at:at + 3]

    return EffectiveWrench(
        stamp_ns=target, t=odom.t, force_world=part(FORCE_WORLD), force_body=part(FORCE_BODY),
        torque_body=part(TORQUE_BODY), external_force_world=part(EXTERNAL_FORCE),
        thrust_change_world=part(THRUST_CHANGE), contact_force_world=part(CONTACT_FORCE),
        mismatch_force_world=part(MISMATCH_FORCE), in_contact=out[:, HELD] > 0.0,
    )


def thrust_ratio_series(flight: RecordedFlight) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(t, ground, ceiling)``: per-rotor ``T / T_OGE`` of each surface along the flight, shape (n, rotors)
    (1 where a surface is off); None without odom or scenario."""
    odom, config = flight.true_odom, flight.config
    if odom is None or config is None:
        return None
    surfaces = pack_surfaces(config.environment, config.plant_vehicle)
    ground = thrust_ratio_log(surfaces._replace(ceiling_effect=False), odom.position[:, 2], odom.rotation)
    ceiling = thrust_ratio_log(surfaces._replace(ground_effect=False), odom.position[:, 2], odom.rotation)
    return odom.t, ground, ceiling
