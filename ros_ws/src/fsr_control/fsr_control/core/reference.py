"""The planner's reference at a time ``t`` (compiled core): sampling a table of 7th-order segments.

A trajectory (built and replanned in Python by :class:`fsr_control.planning.trajectory.Trajectory`) is a
table of segments, one row each (:class:`TrajectoryTable`). Segment ``s`` moves 4 channels (x, y, z and one
angle ``theta``), channel ``c`` over ``[t0, t0 + T_c]`` with polynomials in ``tau = (t - t0) / T_c``: its
``coefficients[s, n, c, k]`` are those of the ``n``-th time derivative of channel ``c`` in ``tau^k``; after its
end a channel holds its goal with every derivative zero. The position channels share one duration; the
angle's is the same or, where the planner shaped it to the vehicle's authority, longer. The attitude
turns about the segment's fixed axis ``a``:
``R_d = R_0 exp(theta S(a)) = R_0 + sin(theta) R_0 S + (1 - cos(theta)) R_0 S^2``, ``omega_d = a theta_dot``,
``omega_dot_d = a theta_ddot`` (desired body frame). A yaw-only segment (fixed rotors: ``yaw_start`` finite)
is ``R_d = Rz(psi_0 + theta)``.

The active segment at ``t`` is the last one starting at or before ``t`` (the first one before that).

A law that looks ahead (a preview or a model-predictive law) gets the reference over a horizon:
:func:`sample_horizon` writes the samples at ``t + dt, ..., t + N dt`` as rows laid out by the ``HORIZON_*``
constants (time [s], position, velocity, acceleration world NED, ``R_d`` row by row, ``omega_d`` desired
body, heading ``psi`` [rad]).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_sim.core.jit import jit, jit_inline
from fsr_sim.core.so3 import Mat3, Vec3, mat_vec3, yaw_rotation_rows

DERIVATIVES = 5  # value, velocity, acceleration, jerk, snap
CHANNELS = 4  # x, y, z, theta
DEGREE = 7
# A horizon row (sample_horizon)
HORIZON_TIME, HORIZON_POSITION, HORIZON_VELOCITY, HORIZON_ACCELERATION = 0, 1, 4, 7
HORIZON_ROTATION, HORIZON_ANGULAR_VELOCITY, HORIZON_YAW = 10, 19, 22  # R_d: 9 entries row by row
HORIZON_WIDTH = 23


class TrajectoryTable(NamedTuple):
    start_time: np.ndarray  # (s,) [s]
    duration: np.ndarray  # (s, 4) [s] per channel (the angle may take longer than the position: shaping)
    coefficients: np.ndarray  # (s, 5, 4, 8)
    goal: np.ndarray  # (s, 4) x, y, z [m], theta [rad] at the end
    rotation_start: np.ndarray  # (s, 3, 3) R_0
    r0_s: np.ndarray  # (s, 3, 3) R_0 S(a)
    r0_s2: np.ndarray  # (s, 3, 3) R_0 S(a)^2
    axis: np.ndarray  # (s, 3) a (unit)
    yaw_start: np.ndarray  # (s,) psi_0 [rad] of a yaw-only segment, NaN for a full-attitude one


class ReferenceSample(NamedTuple):
    """The desired state: position, velocity, acceleration, jerk, snap (world NED, m/s^k), ``R_d`` rows,
    ``omega_d`` and ``omega_dot_d`` (desired body frame), and the heading of ``R_d``'s x axis with the world-z
    components of ``R_d omega_d`` and ``R_d omega_dot_d`` (for a yaw-only reference: ``psi``, its rate and
    acceleration)."""

    position: Vec3
    velocity: Vec3
    acceleration: Vec3
    jerk: Vec3
    snap: Vec3
    rotation: Mat3
    angular_velocity: Vec3
    angular_acceleration: Vec3
    yaw: float
    yaw_rate: float
    yaw_acceleration: float


@jit_inline
def active_segment(table: TrajectoryTable, t: float) -> int:
    """Index of the last segment starting at or before ``t`` [s] (0 if none)."""
    starts = table.start_time
    index = 0
    for s in range(starts.shape[0]):
        if starts[s] <= t:
            index = s
    return index


@jit
def polynomial_derivatives(coefficients, goal, start_time: float, durations, t: float, out) -> None:  # noqa: ANN001
    """Value and time derivatives 1..4 at ``t`` [s] of ``c`` channels of a 7th-order segment into ``out`` (5, c):
    ``coefficients`` (5, c, 8) in powers of channel ``c``'s ``tau = (t - t0) / T_c`` (``durations`` (c,) [s];
    ``t`` before the start is clamped to it), ``goal`` (c,) held with zero derivatives from each channel's end
    on."""
    for c in range(goal.shape[0]):
        tau = (t - start_time) / durations[c]
        if tau >= 1.0:
            out[0, c] = goal[c]
            for n in range(1, coefficients.shape[0]):
                out[n, c] = 0.0
            continue
        if tau < 0.0:
            tau = 0.0
        # tau^k, k = 0..7, by products (a pow with a constant exponent would be folded differently by LLVM)
        tau2 = tau * tau
        tau4 = tau2 * tau2
        powers = (1.0, tau, tau2, tau2 * tau, tau4, tau4 * tau, tau4 * tau2, tau4 * tau2 * tau)
        for n in range(coefficients.shape[0]):
            total = 0.0
            for k in range(DEGREE + 1):
                total += coefficients[n, c, k] * powers[k]
            out[n, c] = total


@jit_inline
def channel_derivatives(table: TrajectoryTable, segment: int, t: float, out) -> None:  # noqa: ANN001
    """:func:`polynomial_derivatives` of the 4 channels of ``segment`` into ``out`` (5, 4)."""
    polynomial_derivatives(table.coefficients[segment], table.goal[segment], table.start_time[segment],
                           table.duration[segment], t, out)


@jit
def _rodrigues_row(r0, r0_s, r0_s2, sin_theta: float, versine: float) -> Vec3:  # noqa: ANN001
    """A row of ``R_0 + sin(theta) R_0 S + (1 - cos(theta)) R_0 S^2``."""
    return (r0[0] + sin_theta * r0_s[0] + versine * r0_s2[0], r0[1] + sin_theta * r0_s[1] + versine * r0_s2[1],
            r0[2] + sin_theta * r0_s[2] + versine * r0_s2[2])


@jit_inline
def reference_from_derivatives(table: TrajectoryTable, segment: int, d) -> ReferenceSample:  # noqa: ANN001
    """The :class:`ReferenceSample` of ``segment`` from its channel derivatives ``d`` (5, 4)."""
    theta, theta_dot, theta_ddot = d[0, 3], d[1, 3], d[2, 3]
    axis = (table.axis[segment, 0], table.axis[segment, 1], table.axis[segment, 2])
    yaw_start = table.yaw_start[segment]
    if yaw_start == yaw_start:  # yaw only
        yaw = yaw_start + theta
        rotation = yaw_rotation_rows(yaw)
        yaw_rate, yaw_acceleration = theta_dot, theta_ddot
    else:
        sin_theta, versine = math.sin(theta), 1.0 - math.cos(theta)
        r0, r0_s, r0_s2 = table.rotation_start[segment], table.r0_s[segment], table.r0_s2[segment]
        rotation = (_rodrigues_row(r0[0], r0_s[0], r0_s2[0], sin_theta, versine),
                    _rodrigues_row(r0[1], r0_s[1], r0_s2[1], sin_theta, versine),
                    _rodrigues_row(r0[2], r0_s[2], r0_s2[2], sin_theta, versine))
        world_axis = mat_vec3(rotation, axis)
        yaw = math.atan2(rotation[1][0], rotation[0][0])
        yaw_rate, yaw_acceleration = world_axis[2] * theta_dot, world_axis[2] * theta_ddot
    return ReferenceSample(
        (d[0, 0], d[0, 1], d[0, 2]), (d[1, 0], d[1, 1], d[1, 2]), (d[2, 0], d[2, 1], d[2, 2]),
        (d[3, 0], d[3, 1], d[3, 2]), (d[4, 0], d[4, 1], d[4, 2]), rotation,
        (axis[0] * theta_dot, axis[1] * theta_dot, axis[2] * theta_dot),
        (axis[0] * theta_ddot, axis[1] * theta_ddot, axis[2] * theta_ddot),
        yaw, yaw_rate, yaw_acceleration,
    )


@jit_inline
def sample_reference(table: TrajectoryTable, t: float, scratch) -> ReferenceSample:  # noqa: ANN001
    """The reference at ``t`` [s]; ``scratch`` (5, 4) receives the active segment's channel derivatives."""
    segment = active_segment(table, t)
    channel_derivatives(table, segment, t, scratch)
    return reference_from_derivatives(table, segment, scratch)


@jit
def sample_horizon(table: TrajectoryTable, t: float, dt: float, scratch, horizon) -> None:  # noqa: ANN001
    """The reference at ``t + (i + 1) dt`` [s] into row ``i`` of ``horizon`` (N, ``HORIZON_WIDTH``), for each of
    its rows (module docstring); ``scratch`` (5, 4) as in :func:`sample_reference`."""
    for i in range(horizon.shape[0]):
        time = t + (i + 1) * dt
        sample = sample_reference(table, time, scratch)
        row = horizon[i]
        row[HORIZON_TIME] = time
        for k in range(3):
            row[HORIZON_POSITION + k] = sample.position[k]
            row[HORIZON_VELOCITY + k] = sample.velocity[k]
            row[HORIZON_ACCELERATION + k] = sample.acceleration[k]
            row[HORIZON_ANGULAR_VELOCITY + k] = sample.angular_velocity[k]
            for j in range(3):
                row[HORIZON_ROTATION + 3 * k + j] = sample.rotation[k][j]
        row[HORIZON_YAW] = sample.yaw
