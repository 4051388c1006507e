"""External wrench profiles evaluated per step (compiled core): constant, step, sinusoid, table.

Each profile is one row of a float64 table (columns below) with a force [N] and a torque [N m] in its frame
(world NED or body FRD); a ``table`` profile's knots are rows ``[time, force xyz, torque xyz]`` of a second
array. Profiles add up. The plant applies the force in the world frame and the torque in the body frame,
so with ``R`` the attitude (body -> world): ``frame: world``: ``f_world = f``, ``tau_body = R^T tau``;
``frame: body``: ``f_world = R f``, ``tau_body = tau``.

* constant and step: the values for ``start <= t < end`` (constant: ``[0, inf)``), zero outside;
* sinusoid: ``offset + amplitude sin(2 pi f (t - start) + phase)`` for ``start <= t < end``;
* table: linear between knots, held at the ends (``numpy.interp``'s arithmetic).
"""

from __future__ import annotations

import math

from fsr_sim.core.jit import jit
from fsr_sim.core.so3 import Mat3, mat_t_vec3, mat_vec3

CONSTANT, STEP, SINUSOID, TABLE = 0.0, 1.0, 2.0, 3.0  # KIND column values
KIND, BODY_FRAME, START, END, FREQUENCY, PHASE = 0, 1, 2, 3, 4, 5
FORCE, TORQUE, OFFSET_FORCE, OFFSET_TORQUE = 6, 9, 12, 15  # first of 3 columns each
KNOT_START, KNOT_COUNT = 18, 19
WIDTH = 20
KNOT_TIME, KNOT_FORCE, KNOT_TORQUE = 0, 1, 4  # columns of the knot rows
KNOT_WIDTH = 7


@jit
def _interpolated(knots, first: int, count: int, t: float, column: int) -> float:  # noqa: ANN001
    """``numpy.interp(t, times, values)`` over knot rows ``first .. first + count - 1``."""
    last = first + count - 1
    if t < knots[first, KNOT_TIME]:
        return knots[first, column]
    if t >= knots[last, KNOT_TIME]:
        return knots[last, column]
    j = first
    while knots[j + 1, KNOT_TIME] <= t:
        j += 1
    x0, x1 = knots[j, KNOT_TIME], knots[j + 1, KNOT_TIME]
    y0, y1 = knots[j, column], knots[j + 1, column]
    slope = (y1 - y0) / (x1 - x0)
    return slope * (t - x0) + y0


@jit
def profile_wrench(profile, knots, t: float) -> tuple:  # noqa: ANN001
    """(force, torque) 3-tuples of one profile row at time ``t`` [s], in the profile's frame."""
    kind = profile[KIND]
    if kind == TABLE:
        first, count = int(profile[KNOT_START]), int(profile[KNOT_COUNT])
        force = (_interpolated(knots, first, count, t, KNOT_FORCE),
                 _interpolated(knots, first, count, t, KNOT_FORCE + 1),
                 _interpolated(knots, first, count, t, KNOT_FORCE + 2))
        torque = (_interpolated(knots, first, count, t, KNOT_TORQUE),
                  _interpolated(knots, first, count, t, KNOT_TORQUE + 1),
                  _interpolated(knots, first, count, t, KNOT_TORQUE + 2))
        return force, torque
    if t < profile[START] or t >= profile[END]:
        return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    fx, fy, fz = profile[FORCE], profile[FORCE + 1], profile[FORCE + 2]
    tx, ty, tz = profile[TORQUE], profile[TORQUE + 1], profile[TORQUE + 2]
    if kind == SINUSOID:
        s = math.sin(2.0 * math.pi * profile[FREQUENCY] * (t - profile[START]) + profile[PHASE])
        return ((profile[OFFSET_FORCE] + s * fx, profile[OFFSET_FORCE + 1] + s * fy,
                 profile[OFFSET_FORCE + 2] + s * fz),
                (profile[OFFSET_TORQUE] + s * tx, profile[OFFSET_TORQUE + 1] + s * ty,
                 profile[OFFSET_TORQUE + 2] + s * tz))
    return (fx, fy, fz), (tx, ty, tz)


@jit
def external_wrench(profiles, knots, t: float, rotation: Mat3) -> tuple:  # noqa: ANN001
    """Sum of all profiles at ``t`` [s]: ``(f_x, f_y, f_z)`` world NED [N], ``(tau_x, tau_y, tau_z)`` body FRD
    [N m] for the attitude rows ``rotation`` (``f_world = sum_world f + R sum_body f``,
    ``tau_body = R^T sum_world tau + sum_body tau``)."""
    fx = fy = fz = tx = ty = tz = 0.0
    for p in range(profiles.shape[0]):
        force, torque = profile_wrench(profiles[p], knots, t)
        if profiles[p, BODY_FRAME] != 0.0:
            force = mat_vec3(rotation, force)
        else:
            torque = mat_t_vec3(rotation, torque)
        fx, fy, fz = fx + force[0], fy + force[1], fz + force[2]
        tx, ty, tz = tx + torque[0], ty + torque[1], tz + torque[2]
    return (fx, fy, fz), (tx, ty, tz)
