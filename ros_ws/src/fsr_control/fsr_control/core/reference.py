"""The planner's reference at a time ``t`` (compiled core): sampling a table of segments.

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

A row of a path (``trajectory.kind`` minsnap, circle, lissajous; docs/model.md §3.5) says in ``path`` how its
channels are made beyond that (``PATH_*`` columns):

* its kind: ``KIND_POLYNOMIAL`` (the polynomials above: a rest-to-rest leg, or a minimum-snap segment) or
  ``KIND_PERIODIC``: the position ``p_k = c_k + A_k sin(w_k s + phi_k)`` per world axis (``periodic``) of the
  path time ``s(t)`` of :func:`ramp_clock`, whose rate ``r = ds/dt`` rises from 0 to 1 over the path's ramp at
  its start and falls back to 0 over the one at its end (the septic smoothstep, so the velocity, acceleration,
  jerk and snap are continuous and zero at both ends);
* its angle: ``YAW_CHANNEL`` (the angle's polynomial), ``YAW_RATE`` (``psi = psi_s + Omega s(t)``: the yaw
  rate ramped with the path) or ``YAW_VELOCITY`` (the heading ``h`` of the horizontal direction of motion,
  blended in at the ends: ``psi = A + r wrap(h - A)``, ``A`` the heading the path leaves in for the first half
  and the one it arrives in for the second), with ``theta = psi - PATH_YAW_ORIGIN``. The direction of
  motion is the path's tangent ``dp/ds`` (periodic), or the velocity divided by the powers of ``tau`` and
  ``1 - tau`` it vanishes with at a rest end (``heading``, polynomial): defined at rest too.

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
from fsr_sim.core.so3 import Mat3, Vec3, mat_vec3, put3, put_rows3, yaw_rotation_rows

DERIVATIVES = 5  # value, velocity, acceleration, jerk, snap
CHANNELS = 4  # x, y, z, theta
DEGREE = 7
# A horizon row (sample_horizon)
HORIZON_TIME, HORIZON_POSITION, HORIZON_VELOCITY, HORIZON_ACCELERATION = 0, 1, 4, 7
HORIZON_ROTATION, HORIZON_ANGULAR_VELOCITY, HORIZON_YAW = 10, 19, 22  # R_d: 9 entries row by row
HORIZON_WIDTH = 23
# A row's path columns (TrajectoryTable.path; module docstring)
PATH_KIND, PATH_YAW = 0, 1  # KIND_*, YAW_*
PATH_START, PATH_END, PATH_RAMP = 2, 3, 4  # the path's clock (ramp_clock) [s]
PATH_YAW_RATE = 5  # Omega [rad/s] (YAW_RATE)
PATH_HEADING_START, PATH_HEADING_END = 6, 7  # [rad]: psi_s (YAW_RATE) / the anchors A (YAW_VELOCITY)
PATH_YAW_ORIGIN = 8  # [rad]: theta = psi - origin
PATH_WIDTH = 9
KIND_POLYNOMIAL, KIND_PERIODIC = 0.0, 1.0
YAW_CHANNEL, YAW_RATE, YAW_VELOCITY = 0.0, 1.0, 2.0
# TrajectoryTable.periodic rows (each (3,): per world axis)
PERIODIC_CENTRE, PERIODIC_AMPLITUDE, PERIODIC_FREQUENCY, PERIODIC_PHASE = 0, 1, 2, 3  # m, m, rad/s, rad
HEADING_DERIVATIVES = 3  # TrajectoryTable.heading: the direction of motion and its 1st and 2nd time derivatives


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
    path: np.ndarray  # (s, PATH_WIDTH): kind, angle and clock of a path's row (module docstring)
    periodic: np.ndarray  # (s, 4, 3): centre [m], amplitude [m], angular frequency [rad/s], phase [rad] per axis
    heading: np.ndarray  # (s, 3, 2, 8): a polynomial row's direction of motion (x, y) and its 2 time derivatives


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


@jit
def ramp_clock(t: float, start: float, end: float, ramp: float) -> tuple:
    """The path time ``s`` [s] at ``t`` [s], its rate ``r = ds/dt`` and ``r'``, ``r''``, ``r'''`` (module
    docstring): ``r = q(u)`` over a ramp, ``u`` the share of the ramp ``T_r`` [s] gone (at the end: left),
    ``q(u) = 35 u^4 - 84 u^5 + 70 u^6 - 20 u^7`` (0 -> 1, its first three derivatives zero at both ends); ``r = 1``
    between the ramps and 0 before ``start`` and after ``end``; ``s = T_r Q(u)`` over the first ramp with
    ``Q(u) = 7 u^5 - 14 u^6 + 10 u^7 - 2.5 u^8`` (``Q(1) = 1/2``): the path time runs from 0 to
    ``end - start - T_r``."""
    total = end - start - ramp
    if t <= start:
        return 0.0, 0.0, 0.0, 0.0, 0.0
    if t >= end:
        return total, 0.0, 0.0, 0.0, 0.0
    elapsed, left = t - start, end - t
    if elapsed >= ramp and left >= ramp:
        return elapsed - 0.5 * ramp, 1.0, 0.0, 0.0, 0.0
    rising = elapsed < ramp
    u = elapsed / ramp if rising else left / ramp
    v = 1.0 - u
    u2 = u * u
    rate = u2 * u2 * (35.0 + u * (-84.0 + u * (70.0 - 20.0 * u)))
    first = 140.0 * u2 * u * v * v * v / ramp
    second = 420.0 * u2 * v * v * (1.0 - 2.0 * u) / (ramp * ramp)
    third = 840.0 * u * v * (5.0 * u2 - 5.0 * u + 1.0) / (ramp * ramp * ramp)
    integral = ramp * u2 * u2 * u * (7.0 + u * (-14.0 + u * (10.0 - 2.5 * u)))
    if rising:
        return integral, rate, first, second, third
    return total - integral, rate, -first, second, -third


@jit
def _periodic_position(table: TrajectoryTable, segment: int, t: float, out) -> None:  # noqa: ANN001
    """A periodic row's position and its 4 time derivatives into ``out[:, 0:3]``: the chain rule of ``p(s(t))``,
    ``p' = P1 r``, ``p'' = P2 r^2 + P1 r'``, ``p''' = P3 r^3 + 3 P2 r r' + P1 r''``,
    ``p'''' = P4 r^4 + 6 P3 r^2 r' + P2 (3 r'^2 + 4 r r'') + P1 r'''`` with ``Pn = d^n p / ds^n``."""
    path, periodic = table.path[segment], table.periodic[segment]
    s, r, r1, r2, r3 = ramp_clock(t, path[PATH_START], path[PATH_END], path[PATH_RAMP])
    for k in range(3):
        amplitude, frequency = periodic[PERIODIC_AMPLITUDE, k], periodic[PERIODIC_FREQUENCY, k]
        angle = frequency * s + periodic[PERIODIC_PHASE, k]
        sine = amplitude * math.sin(angle)
        p1 = frequency * amplitude * math.cos(angle)
        p2 = -frequency * frequency * sine
        p3 = -frequency * frequency * p1
        p4 = -frequency * frequency * p2
        out[0, k] = periodic[PERIODIC_CENTRE, k] + sine
        out[1, k] = p1 * r
        out[2, k] = p2 * r * r + p1 * r1
        out[3, k] = p3 * r * r * r + 3.0 * p2 * r * r1 + p1 * r2
        out[4, k] = p4 * r * r * r * r + 6.0 * p3 * r * r * r1 + p2 * (3.0 * r1 * r1 + 4.0 * r * r2) + p1 * r3


@jit
def heading_rates(x: float, y: float, x1: float, y1: float, x2: float, y2: float) -> tuple:
    """``(h, h', h'')``: the heading ``h = atan2(y, x)`` of a horizontal vector ``(x, y)`` and its first two
    derivatives from the vector's: ``h' = (x y' - y x') / n``, ``h'' = (x y'' - y x'') / n - 2 h' (x x' + y y') / n``
    with ``n = x^2 + y^2``."""
    norm = x * x + y * y
    rate = (x * y1 - y * x1) / norm
    return math.atan2(y, x), rate, (x * y2 - y * x2) / norm - 2.0 * rate * (x * x1 + y * y1) / norm


@jit
def _periodic_tangent(periodic, s: float, k: int) -> tuple:  # noqa: ANN001
    """``d^n p_k / ds^n``, n = 1, 2, 3, of axis ``k`` of a periodic row at path time ``s``."""
    amplitude, frequency = periodic[PERIODIC_AMPLITUDE, k], periodic[PERIODIC_FREQUENCY, k]
    angle = frequency * s + periodic[PERIODIC_PHASE, k]
    first = amplitude * frequency * math.cos(angle)
    return first, -amplitude * frequency * frequency * math.sin(angle), -frequency * frequency * first


@jit
def _heading_polynomial(coefficients, n: int, c: int, tau: float) -> float:  # noqa: ANN001
    """Row ``n``, channel ``c`` of a polynomial row's ``heading`` at ``tau`` (Horner)."""
    total = 0.0
    for k in range(DEGREE, -1, -1):
        total = total * tau + coefficients[n, c, k]
    return total


@jit
def direction_heading(table: TrajectoryTable, segment: int, t: float) -> tuple:
    """``(h, h', h'')`` [rad, rad/s, rad/s^2]: the heading of the row's direction of motion at ``t`` [s] and its
    time derivatives (module docstring)."""
    path = table.path[segment]
    if path[PATH_KIND] == KIND_PERIODIC:
        s, r, r1, _, _ = ramp_clock(t, path[PATH_START], path[PATH_END], path[PATH_RAMP])
        x1, x2, x3 = _periodic_tangent(table.periodic[segment], s, 0)
        y1, y2, y3 = _periodic_tangent(table.periodic[segment], s, 1)
        h, g1, g2 = heading_rates(x1, y1, x2, y2, x3, y3)  # per path time
        return h, g1 * r, g2 * r * r + g1 * r1
    tau = min(max((t - table.start_time[segment]) / table.duration[segment, 0], 0.0), 1.0)
    d = table.heading[segment]
    return heading_rates(_heading_polynomial(d, 0, 0, tau), _heading_polynomial(d, 0, 1, tau),
                         _heading_polynomial(d, 1, 0, tau), _heading_polynomial(d, 1, 1, tau),
                         _heading_polynomial(d, 2, 0, tau), _heading_polynomial(d, 2, 1, tau))


@jit
def wrap_angle(angle: float) -> float:
    """``angle`` [rad] wrapped to [-pi, pi)."""
    return angle - 2.0 * math.pi * math.floor((angle + math.pi) / (2.0 * math.pi))


@jit
def _path_angle(table: TrajectoryTable, segment: int, t: float, out) -> None:  # noqa: ANN001
    """A path row's yaw (``YAW_RATE``, ``YAW_VELOCITY``; module docstring) as ``theta`` and its first three time
    derivatives into ``out[:, 3]`` (the 4th is 0)."""
    path = table.path[segment]
    s, r, r1, r2, _ = ramp_clock(t, path[PATH_START], path[PATH_END], path[PATH_RAMP])
    if path[PATH_YAW] == YAW_RATE:
        rate = path[PATH_YAW_RATE]
        yaw, yaw1, yaw2, yaw3 = path[PATH_HEADING_START] + rate * s, rate * r, rate * r1, rate * r2
    else:
        middle = 0.5 * (path[PATH_START] + path[PATH_END])
        anchor = path[PATH_HEADING_START] if t < middle else path[PATH_HEADING_END]
        yaw, yaw1, yaw2, yaw3 = anchor, 0.0, 0.0, 0.0
        if r > 0.0:  # moving: blend the heading of the motion in (at rest it may be undefined)
            h, h1, h2 = direction_heading(table, segment, t)
            delta = wrap_angle(h - anchor)
            yaw, yaw1, yaw2 = anchor + r * delta, r1 * delta + r * h1, r2 * delta + 2.0 * r1 * h1 + r * h2
    out[0, 3] = yaw - path[PATH_YAW_ORIGIN]
    out[1, 3], out[2, 3], out[3, 3], out[4, 3] = yaw1, yaw2, yaw3, 0.0


@jit_inline
def channel_derivatives(table: TrajectoryTable, segment: int, t: float, out) -> None:  # noqa: ANN001
    """The value and 4 time derivatives of the 4 channels of ``segment`` at ``t`` [s] into ``out`` (5, 4):
    :func:`polynomial_derivatives`, then a path row's periodic position and its yaw (module docstring)."""
    polynomial_derivatives(table.coefficients[segment], table.goal[segment], table.start_time[segment],
                           table.duration[segment], t, out)
    path = table.path[segment]
    if path[PATH_KIND] == KIND_PERIODIC:
        _periodic_position(table, segment, t, out)
    if path[PATH_YAW] != YAW_CHANNEL:
        _path_angle(table, segment, t, out)


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
        put3(row, HORIZON_POSITION, sample.position)
        put3(row, HORIZON_VELOCITY, sample.velocity)
        put3(row, HORIZON_ACCELERATION, sample.acceleration)
        put3(row, HORIZON_ANGULAR_VELOCITY, sample.angular_velocity)
        put_rows3(row, HORIZON_ROTATION, sample.rotation)
        row[HORIZON_YAW] = sample.yaw


# A row of sample_references: what a reference asks of the vehicle (fsr_control.planning.feasibility)
SAMPLE_ACCELERATION, SAMPLE_JERK, SAMPLE_SNAP, SAMPLE_ROTATION = 0, 3, 6, 9  # R_d: 9 entries row by row
SAMPLE_ANGULAR_VELOCITY, SAMPLE_ANGULAR_ACCELERATION = 18, 21  # omega_d, omega_dot_d (desired body)
SAMPLE_YAW, SAMPLE_YAW_RATE, SAMPLE_YAW_ACCELERATION = 24, 25, 26
SAMPLE_WIDTH = 27


@jit
def sample_references(table: TrajectoryTable, rows, times, scratch, out) -> None:  # noqa: ANN001
    """The reference of row ``rows[i]`` (int64) at ``times[i]`` [s] into row ``i`` of ``out`` (n, ``SAMPLE_WIDTH``),
    laid out by the ``SAMPLE_*`` constants (acceleration, jerk, snap world NED, ``R_d`` row by row, ``omega_d``,
    ``omega_dot_d`` desired body, heading, its rate and acceleration); ``scratch`` (5, 4) as in
    :func:`sample_reference`. One call for a whole table's samples: what the feasibility check reads."""
    for i in range(times.shape[0]):
        segment = rows[i]
        channel_derivatives(table, segment, times[i], scratch)
        sample = reference_from_derivatives(table, segment, scratch)
        row = out[i]
        put3(row, SAMPLE_ACCELERATION, sample.acceleration)
        put3(row, SAMPLE_JERK, sample.jerk)
        put3(row, SAMPLE_SNAP, sample.snap)
        put_rows3(row, SAMPLE_ROTATION, sample.rotation)
        put3(row, SAMPLE_ANGULAR_VELOCITY, sample.angular_velocity)
        put3(row, SAMPLE_ANGULAR_ACCELERATION, sample.angular_acceleration)
        row[SAMPLE_YAW], row[SAMPLE_YAW_RATE] = sample.yaw, sample.yaw_rate
        row[SAMPLE_YAW_ACCELERATION] = sample.yaw_acceleration
