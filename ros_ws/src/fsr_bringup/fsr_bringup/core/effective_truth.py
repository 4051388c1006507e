"""Effective truth: the wrench the momentum observer must converge to, one control step at a time (compiled core).

The observer (docs/model.md §3.8, :mod:`fsr_estimation.estimator.momentum`) does not estimate the injected external
wrench alone: it estimates everything its model misses. With its model mass ``m_e`` and inertia ``I_e``
and the commanded body wrench ``(f_c, tau_c)`` (``wrench_cmd``), its force residual over the control step
``[t_k, t_k+1]`` is (world NED, ``e3`` down, ``a_k = (v_k+1 - v_k) / T_s``)::

    f_hat -> m_e a_k - m_e g e3 - R_k f_c,k

while the true plant (mass ``m``, inertia ``I``) obeys, averaged over the same step::

    m a_k = m g e3 + <R f_a> + f_ext + f_contact

with ``f_a`` the body force the rotors really produce (from their speeds and tilts - the command held over the
step, or the actual ones of both ends where actuator dynamics make them lag the command - scaled per rotor by
the ground/ceiling thrust ratio; in wrench actuation ``f_c`` itself, or with a rotor time constant the applied
wrench lagging it) and ``<.>`` the mean over the step (trapezoid of its ends). ``f_ext`` (``wrench_truth``) is
everything beyond the rotors' ``c_f w^2``, ``c_m w^2``: the disturbances and the aerodynamics. Eliminating
``a_k`` gives the effective force::

    f_eff = f_ext + (<R f_a> - R_k f_c) + f_contact + (m_e - m) (a_k - g e3)      [N, world NED]

terms: the injected wrench; the surface-effect thrust change (and the turn of ``R`` within the step); the
ground's contact force; the model mismatch (in steady flight ``(m - m_e) g e3``: a model heavier than the
plant sees an upward, negative-z force). The torque (body FRD, ``omega_dot_k`` by the same difference)::

    tau_eff = tau_ext + (<tau_a> - tau_c) + tau_contact + (I_e - I) omega_dot + omega x (I_e - I) omega

Contact: the plant holds the vehicle on a surface (its state is put back on it with zero velocity and angular
velocity at the end of a step: the contact rule of :func:`fsr_sim.core.surfaces.in_contact` with no motion
left); the contact force is the constraint force of those steps,
``m a_k - m g e3 - <R f_a> - f_ext`` (and ``I omega_dot + omega x I omega - <tau_a> - tau_ext``), zero in
every other step.

:func:`effective_truth` is the one definition: the sweep's measured loop calls it per step
(:mod:`fsr_bringup.core.flight_measures`), the analysis over a log (:func:`effective_truth_log`, from
:mod:`fsr_bringup.analysis.effective`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_sim.core.jit import jit, jit_inline
from fsr_sim.core.so3 import Mat3, Vec3, cross3, mat_t_vec3, mat_vec3, matrix_rows, put3
from fsr_sim.core.surfaces import Surfaces, in_contact

LARGEST = float(np.finfo(np.float64).max)
# The columns of effective_truth_log's output.
FORCE_WORLD, TORQUE_BODY, EXTERNAL_FORCE, THRUST_CHANGE, CONTACT_FORCE, MISMATCH_FORCE = 0, 3, 6, 9, 12, 15
FORCE_BODY, HELD = 18, 21
LOG_COLUMNS = 22


class TruthParams(NamedTuple):
    """The plant and the observer's model as the effective truth takes them."""

    mass: float  # kg: the plant's
    mass_model: float  # kg: the observer's model
    inertia: np.ndarray  # (3, 3) kg m^2: the plant's
    inertia_delta: np.ndarray  # (3, 3): the model's minus the plant's
    gravity: float  # m/s^2


@jit
def finite(value: float) -> float:
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
def _times(inertia, v: Vec3) -> Vec3:  # noqa: ANN001
    """``I v`` for a (3, 3) array ``I``."""
    return (inertia[0, 0] * v[0] + inertia[0, 1] * v[1] + inertia[0, 2] * v[2],
            inertia[1, 0] * v[0] + inertia[1, 1] * v[1] + inertia[1, 2] * v[2],
            inertia[2, 0] * v[0] + inertia[2, 1] * v[1] + inertia[2, 2] * v[2])


@jit
def _spin(omega: Vec3, inertia) -> Vec3:  # noqa: ANN001
    """``omega x (I omega)``."""
    return cross3(omega, _times(inertia, omega))


@jit_inline
def effective_truth(p: TruthParams, surfaces: Surfaces, dt: float, rotation: Mat3, rotation_next: Mat3, velocity: Vec3,
                    velocity_next: Vec3, omega: Vec3, omega_next: Vec3, z_next: float, external: tuple,
                    commanded: tuple, start: tuple, end: tuple) -> tuple:
    """The effective truth of the step ``[t_k, t_k + dt]`` (module docstring) for the plant and model ``p`` (a
    :class:`TruthParams`, or any tuple with its fields, such as the sweep's measurement parameters) and the
    contact rule's ``surfaces`` (``pack_surfaces`` of the environment and the plant vehicle), from the true
    states at its ends
    (``R``, world velocity [m/s], body angular velocity [rad/s], the down-coordinate ``z`` [m] of the end), the
    external wrench of ``t_k`` (``wrench_truth``, body; NaN taken as 0), the commanded body wrench and the
    actuator's body wrench at the start and at the end of the step (each wrench a pair ``(force, torque)``).

    Returns ``(force_world, torque_body, external_force_world, thrust_change_world, contact_force_world,
    mismatch_force_world, held)``: vectors [N, N m], ``held`` the ground's contact at the end of the step."""
    (f_ext_body, tau_ext), (force_cmd, torque_cmd), (force_start, torque_start), (force_end, torque_end) = \
        external, commanded, start, end
    f_ext = mat_vec3(rotation, (finite(f_ext_body[0]), finite(f_ext_body[1]), finite(f_ext_body[2])))
    tau = (finite(tau_ext[0]), finite(tau_ext[1]), finite(tau_ext[2]))
    commanded_world = mat_vec3(rotation, force_cmd)
    start_world = mat_vec3(rotation, force_start)
    end_world = mat_vec3(rotation_next, force_end)
    mean_actuator = (0.5 * (start_world[0] + end_world[0]), 0.5 * (start_world[1] + end_world[1]),
                     0.5 * (start_world[2] + end_world[2]))
    mean_torque = (0.5 * (torque_start[0] + torque_end[0]), 0.5 * (torque_start[1] + torque_end[1]),
                   0.5 * (torque_start[2] + torque_end[2]))
    accel = ((velocity_next[0] - velocity[0]) / dt, (velocity_next[1] - velocity[1]) / dt,
             (velocity_next[2] - velocity[2]) / dt)
    omega_dot = ((omega_next[0] - omega[0]) / dt, (omega_next[1] - omega[1]) / dt, (omega_next[2] - omega[2]) / dt)
    free = (accel[0], accel[1], accel[2] - p.gravity)  # a - g e3
    thrust_change = (mean_actuator[0] - commanded_world[0], mean_actuator[1] - commanded_world[1],
                     mean_actuator[2] - commanded_world[2])
    held = in_contact(surfaces, z_next) and velocity_next[0] == 0.0 and velocity_next[1] == 0.0 \
        and velocity_next[2] == 0.0 and omega_next[0] == 0.0 and omega_next[1] == 0.0 and omega_next[2] == 0.0
    contact_force = (0.0, 0.0, 0.0)
    contact_torque = (0.0, 0.0, 0.0)
    if held:
        contact_force = (p.mass * free[0] - mean_actuator[0] - f_ext[0], p.mass * free[1] - mean_actuator[1] - f_ext[1],
                         p.mass * free[2] - mean_actuator[2] - f_ext[2])
        spin = _spin(omega, p.inertia)
        turn = _times(p.inertia, omega_dot)
        contact_torque = (turn[0] + spin[0] - mean_torque[0] - tau[0], turn[1] + spin[1] - mean_torque[1] - tau[1],
                          turn[2] + spin[2] - mean_torque[2] - tau[2])
    difference = p.mass_model - p.mass
    mismatch = (difference * free[0], difference * free[1], difference * free[2])
    force_world = _add(_add(_add(f_ext, thrust_change), contact_force), mismatch)
    turn_delta = _times(p.inertia_delta, omega_dot)
    spin_delta = _spin(omega, p.inertia_delta)
    torque = (tau[0] + mean_torque[0] - torque_cmd[0] + contact_torque[0] + turn_delta[0] + spin_delta[0],
              tau[1] + mean_torque[1] - torque_cmd[1] + contact_torque[1] + turn_delta[1] + spin_delta[1],
              tau[2] + mean_torque[2] - torque_cmd[2] + contact_torque[2] + turn_delta[2] + spin_delta[2])
    return force_world, torque, f_ext, thrust_change, contact_force, mismatch, held


@jit
def _vec(a, k: int) -> Vec3:  # noqa: ANN001
    return (a[k, 0], a[k, 1], a[k, 2])


@jit
def effective_truth_log(p: TruthParams, surfaces: Surfaces, t, rotation, velocity, omega, z,  # noqa: ANN001
                        external: tuple, commanded: tuple, start: tuple, end: tuple, out) -> None:  # noqa: ANN001
    """:func:`effective_truth` of every step of a log of ``n`` true states (``t`` (n,) [s], ``rotation``
    (n, 3, 3), ``velocity`` world and ``omega`` body (n, 3), ``z`` (n,)) and of the wrenches of each step
    (each a pair ``(force, torque)`` of (n, 3) arrays) into ``out`` (n, :data:`LOG_COLUMNS`): the columns named
    above, ``FORCE_BODY`` ``R_k^T f_eff``; the last row (no step) NaN, its contact force and ``held`` 0."""
    n = t.shape[0]
    (f_ext_body, tau_ext), (force_cmd, torque_cmd), (force_start, torque_start), (force_end, torque_end) = \
        external, commanded, start, end
    for k in range(n - 1):
        rotation_k = matrix_rows(rotation[k])
        parts = effective_truth(p, surfaces, t[k + 1] - t[k], rotation_k, matrix_rows(rotation[k + 1]),
                                _vec(velocity, k), _vec(velocity, k + 1), _vec(omega, k), _vec(omega, k + 1), z[k + 1],
                                (_vec(f_ext_body, k), _vec(tau_ext, k)), (_vec(force_cmd, k), _vec(torque_cmd, k)),
                                (_vec(force_start, k), _vec(torque_start, k)),
                                (_vec(force_end, k), _vec(torque_end, k)))
        force_world, torque, f_ext, thrust_change, contact_force, mismatch, held = parts
        put3(out[k], FORCE_WORLD, force_world)
        put3(out[k], TORQUE_BODY, torque)
        put3(out[k], EXTERNAL_FORCE, f_ext)
        put3(out[k], THRUST_CHANGE, thrust_change)
        put3(out[k], CONTACT_FORCE, contact_force)
        put3(out[k], MISMATCH_FORCE, mismatch)
        put3(out[k], FORCE_BODY, mat_t_vec3(rotation_k, force_world))
        out[k, HELD] = 1.0 if held else 0.0
    if n > 0:
        out[n - 1, :] = math.nan
        put3(out[n - 1], CONTACT_FORCE, (0.0, 0.0, 0.0))
        out[n - 1, HELD] = 0.0
