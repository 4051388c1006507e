"""Effective truth: the wrench the momentum observer must converge to, from a recording and its scenario.

The observer (docs/model.md §3.8, :mod:`fsr_estimation.core.momentum`) does not estimate the injected external
wrench alone: it estimates everything its model misses. With its model mass ``m_e`` and inertia ``I_e``
and the commanded body wrench ``(f_c, tau_c)`` (``wrench_cmd``), its force residual over the control step
``[t_k, t_k+1]`` is (world NED, ``e3`` down, ``a_k = (v_k+1 - v_k) / T_s``)::

    f_hat -> m_e a_k - m_e g e3 - R_k f_c,k

while the true plant (mass ``m``, inertia ``I``) obeys, averaged over the same step::

    m a_k = m g e3 + <R f_a> + f_ext + f_contact

with ``f_a`` the body force the rotors really produce (from their speeds and tilts - ``rotor_cmd``'s held over
the step, or ``rotor_state``'s of both ends where actuator dynamics make them lag the command - scaled per rotor
by the ground/ceiling thrust ratio; in wrench actuation ``f_c`` itself, or with a rotor time constant the
applied wrench lagging it, replayed from the commands by the plant's own lag as its RK4 steps apply it) and
``<.>`` the mean over the step (trapezoid of its ends). ``f_ext`` (``wrench_truth``) is everything beyond the
rotors' ``c_f w^2``, ``c_m w^2``: the disturbances and the aerodynamics. Eliminating ``a_k`` gives the effective
force::

    f_eff = f_ext + (<R f_a> - R_k f_c) + f_contact + (m_e - m) (a_k - g e3)      [N, world NED]

terms: the injected wrench; the surface-effect thrust change (and the turn of ``R`` within the step); the
ground's contact force; the model mismatch (in steady flight ``(m - m_e) g e3``: a model heavier than the
plant sees an upward, negative-z force). The torque (body FRD, ``omega_dot_k`` by the same difference)::

    tau_eff = tau_ext + (<tau_a> - tau_c) + tau_contact + (I_e - I) omega_dot + omega x (I_e - I) omega

Contact: the plant holds the vehicle on a surface (its state is put back on it with zero velocity and angular
velocity at the end of a step: the contact rule of :func:`fsr_sim.core.surfaces.in_contact` with no motion
left); the contact force is the constraint force of those steps,
``m a_k - m g e3 - <R f_a> - f_ext`` (and ``I omega_dot + omega x I omega - <tau_a> - tau_ext``), zero in
every other step. Everything else comes from the recording and the scenario, not from the estimate.
``f_eff`` of step k is stamped ``t_k`` (the last sample, which has no step, is NaN) and given in body FRD
(``R_k^T f_eff``, like ``wrench_estimate``) and world NED.

No physics is written here: the actuator wrench, the thrust ratios and the contact rule are the plant's own
compiled functions (:func:`fsr_sim.core.plant.actuator_wrench_log`, :func:`fsr_sim.model.environment.
thrust_ratio_log`, :func:`fsr_sim.model.environment.contact_mask`), applied to the whole log.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fsr_bringup.analysis.load import RecordedFlight, zero_order_hold
from fsr_sim.config.scenario import SimulationConfig, plant_from_config
from fsr_sim.core.plant import actuator_wrench_log, applied_wrench_log
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.environment import contact_mask, pack_surfaces, thrust_ratio_log
from fsr_sim.model.frames import E3


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
    i_true, i_est = np.asarray(plant.inertia, float), np.asarray(model.inertia, float)
    f_cmd = zero_order_hold(cmd.stamp_ns, cmd.force, target)
    tau_cmd = zero_order_hold(cmd.stamp_ns, cmd.torque, target)
    if flight.wrench_truth is not None:
        f_ext_body = np.nan_to_num(zero_order_hold(flight.wrench_truth.stamp_ns, flight.wrench_truth.force, target))
        tau_ext = np.nan_to_num(zero_order_hold(flight.wrench_truth.stamp_ns, flight.wrench_truth.torque, target))
    else:
        f_ext_body, tau_ext = np.zeros((n, 3)), np.zeros((n, 3))
    f_ext = np.einsum("kij,kj->ki", rotation, f_ext_body)
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
    next_rotation = np.concatenate((rotation[1:], rotation[-1:]))
    mean_actuator_world = 0.5 * (np.einsum("kij,kj->ki", rotation, f_start)
                                 + np.einsum("kij,kj->ki", next_rotation, f_end))
    mean_actuator_torque = 0.5 * (tau_start + tau_end)
    dt = np.diff(odom.t)[:, None]
    accel = np.full((n, 3), np.nan)
    accel[:-1] = np.diff(odom.velocity_world, axis=0) / dt
    omega = odom.angular_velocity
    omega_dot = np.full((n, 3), np.nan)
    omega_dot[:-1] = np.diff(omega, axis=0) / dt
    gravity = GRAVITY * E3
    thrust_change = mean_actuator_world - np.einsum("kij,kj->ki", rotation, f_cmd)
    # Contact: a surface held the vehicle at the end of the step (state put back at rest on it).
    in_contact = np.zeros(n, dtype=bool)
    held = contact_mask(pack_surfaces(config.environment, plant), odom.position[:, 2]) \
        & ~np.any(odom.velocity_world, axis=1) & ~np.any(omega, axis=1)
    in_contact[:-1] = held[1:]
    contact_force = np.zeros((n, 3))
    contact_torque = np.zeros((n, 3))
    if in_contact.any():
        c = in_contact
        contact_force[c] = m_true * (accel[c] - gravity) - mean_actuator_world[c] - f_ext[c]
        spin = np.cross(omega[c], omega[c] @ i_true.T)
        contact_torque[c] = omega_dot[c] @ i_true.T + spin - mean_actuator_torque[c] - tau_ext[c]
    mismatch = (m_est - m_true) * (accel - gravity)
    force_world = f_ext + thrust_change + contact_force + mismatch
    delta_i = i_est - i_true
    torque = (tau_ext + mean_actuator_torque - tau_cmd + contact_torque + omega_dot @ delta_i.T
              + np.cross(omega, omega @ delta_i.T))
    force_world[-1] = np.nan
    torque[-1] = np.nan
    return EffectiveWrench(
        stamp_ns=target, t=odom.t, force_world=force_world,
        force_body=np.einsum("kji,kj->ki", rotation, force_world), torque_body=torque,
        external_force_world=f_ext, thrust_change_world=thrust_change, contact_force_world=contact_force,
        mismatch_force_world=mismatch, in_contact=in_contact,
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
