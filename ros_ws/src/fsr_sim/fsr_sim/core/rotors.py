"""Rotors per step (compiled core): their wrench columns, speed limits and the saturation record.

Per rotor ``i`` with position ``p_i`` (body FRD), spin ``k_i``, axis ``z_i`` and signed squared speed
``u_w,i = |w_i| w_i`` [(rad/s)^2]: ``f_b = sum c_f u_w,i z_i`` and ``tau_b = sum u_w,i (c_f p_i x z_i -
k_i c_m z_i)``. A rotor's *columns* are the three 3-vectors ``c_f z_i`` (force), ``c_f p_i x z_i`` (lever-arm
torque) and ``-k_i c_m z_i`` (drag torque) per unit ``u_w`` (a row of 9 numbers, :data:`COLUMN_WIDTH`); only the
first two scale with a surface's thrust ratio. A tilting rotor's axis is ``z_i = cos(alpha_i) z_v,i +
sin(alpha_i) z_l,i``, so its columns are the same combination of the columns of ``z_v`` and ``z_l``.

The saturation record is one float64 array (:func:`saturation_size`): how many commands saturated, the first
and last time (NaN: never), the worst rotor (1-based; 0: none) and its excess [rad/s], per wrench axis the
steps it gave way and the largest shortfall, and per rotor the commands in which it was beyond a limit.
"""

from __future__ import annotations

import math

from fsr_sim.core.jit import jit

FORCE_COLUMN, LEVER_COLUMN, DRAG_COLUMN = 0, 3, 6  # first of 3 entries each in a rotor's column row
COLUMN_WIDTH = 9

# The saturation record's layout.
SATURATED_COUNT, FIRST_TIME, LAST_TIME, WORST_ROTOR, WORST_EXCESS = 0, 1, 2, 3, 4
AXIS_STEPS = 5  # 6 entries: force xyz, torque xyz
AXIS_MAX_SHORTFALL = 11  # 6 entries
PER_ROTOR = 17  # n entries
SHORTFALL_TOLERANCE = 1e-9  # N or N m: a larger |commanded - achieved| on an axis means that axis gave way


def saturation_size(rotor_count: int) -> int:
    """Length of a saturation record for ``rotor_count`` rotors."""
    return PER_ROTOR + rotor_count


@jit
def reset_saturation(record) -> None:  # noqa: ANN001
    record[:] = 0.0
    record[FIRST_TIME] = record[LAST_TIME] = math.nan


@jit
def clamped_speed(speed_sq: float, low: float, high: float) -> tuple[float, float]:
    """(speed [rad/s] of a signed squared speed, clamped to ``[low, high]``; its excess beyond the limit).
    A negative ``u_w`` (reverse thrust, not available) counts as an excess below ``low``; NaN stays NaN."""
    speed = math.copysign(math.sqrt(abs(speed_sq)), speed_sq) if speed_sq != 0.0 else 0.0
    clamped = speed
    if speed < low:
        clamped = low
    elif speed > high:
        clamped = high
    return clamped, abs(speed - clamped)


@jit
def record_saturation(record, time: float, excess) -> bool:  # noqa: ANN001
    """Record one command with ``excess`` (n,) [rad/s] per rotor (0 within the limits); True if it saturated.
    A NaN excess does not count (as ``numpy.max`` propagating NaN into ``not > 0``)."""
    worst = 0
    largest = 0.0
    for i in range(excess.shape[0]):
        value = excess[i]
        if value != value:
            return False
        if value > largest:
            largest, worst = value, i
    if not largest > 0.0:
        return False
    record[SATURATED_COUNT] += 1.0
    if record[FIRST_TIME] != record[FIRST_TIME]:
        record[FIRST_TIME] = time
    record[LAST_TIME] = time
    for i in range(min(excess.shape[0], record.shape[0] - PER_ROTOR)):
        if excess[i] > 0.0:
            record[PER_ROTOR + i] += 1.0
    if largest > record[WORST_EXCESS]:
        record[WORST_EXCESS] = largest
        record[WORST_ROTOR] = worst + 1.0
    return True


@jit
def record_shortfall(record, shortfall) -> None:  # noqa: ANN001
    """Record one saturated step's ``commanded - achieved`` body wrench (6,) [N, N m]: every axis with
    ``|shortfall| > SHORTFALL_TOLERANCE`` gave way on this step."""
    for axis in range(6):
        magnitude = abs(shortfall[axis])
        if magnitude > SHORTFALL_TOLERANCE:
            record[AXIS_STEPS + axis] += 1.0
            if magnitude > record[AXIS_MAX_SHORTFALL + axis]:
                record[AXIS_MAX_SHORTFALL + axis] = magnitude


@jit
def tilted_columns(vertical, lateral, tilts, out) -> None:  # noqa: ANN001
    """Columns (n, 9) of rotors tilted by ``tilts`` (n,) [rad]: ``vertical cos(alpha) + lateral sin(alpha)``."""
    for i in range(out.shape[0]):
        c, s = math.cos(tilts[i]), math.sin(tilts[i])
        for j in range(COLUMN_WIDTH):
            out[i, j] = vertical[i, j] * c + lateral[i, j] * s


@jit
def scaled_rotor_wrench(columns, speed_sq, ratios) -> tuple:  # noqa: ANN001
    """Body (force [N], torque [N m]) of squared speeds (n,) through rotor columns (n, 9) with each rotor's
    thrust ratio (n,) near a surface: force and lever-arm torque scale with the ratio, the drag torque does
    not."""
    fx = fy = fz = 0.0
    tx = ty = tz = 0.0
    n = columns.shape[0]
    for i in range(n):  # the drag torque first (the lever terms are added to it)
        u = speed_sq[i]
        tx += columns[i, DRAG_COLUMN] * u
        ty += columns[i, DRAG_COLUMN + 1] * u
        tz += columns[i, DRAG_COLUMN + 2] * u
    for i in range(n):
        u, ratio = speed_sq[i], ratios[i]
        fx, fy, fz = (fx + ratio * (columns[i, FORCE_COLUMN] * u), fy + ratio * (columns[i, FORCE_COLUMN + 1] * u),
                      fz + ratio * (columns[i, FORCE_COLUMN + 2] * u))
        tx, ty, tz = (tx + ratio * (columns[i, LEVER_COLUMN] * u), ty + ratio * (columns[i, LEVER_COLUMN + 1] * u),
                      tz + ratio * (columns[i, LEVER_COLUMN + 2] * u))
    return (fx, fy, fz), (tx, ty, tz)


@jit
def rotor_wrench(columns, speed_sq, out) -> None:  # noqa: ANN001
    """Body wrench (6,) of squared speeds (n,) through rotor columns (n, 9): force, then lever + drag torque."""
    for j in range(3):
        force = lever = drag = 0.0
        for i in range(columns.shape[0]):
            force += columns[i, FORCE_COLUMN + j] * speed_sq[i]
            lever += columns[i, LEVER_COLUMN + j] * speed_sq[i]
            drag += columns[i, DRAG_COLUMN + j] * speed_sq[i]
        out[j] = force
        out[3 + j] = lever + drag


@jit
def clamped_speeds(speed_sq, low: float, high: float, speeds, excess) -> None:  # noqa: ANN001
    """:func:`clamped_speed` of every element of ``speed_sq`` (1-D) into ``speeds`` and ``excess``."""
    for i in range(speed_sq.shape[0]):
        speeds[i], excess[i] = clamped_speed(speed_sq[i], low, high)


@jit
def rotor_command_from_static(u_v: float, u_l: float, c_f: float) -> tuple[float, float]:
    """The report's eq. 5 for one tilting rotor: (``u_w = |(u_v, u_l)| / c_f`` [(rad/s)^2], ``alpha = atan2(u_l, u_v)``
    [rad]) of its vertical and lateral thrust [N]."""
    return math.sqrt(u_v * u_v + u_l * u_l) / c_f, math.atan2(u_l, u_v)


@jit
def static_from_rotor_command(speed_sq: float, tilt: float, c_f: float) -> tuple[float, float]:
    """The inverse of :func:`rotor_command_from_static`: ``(c_f u_w cos(alpha), c_f u_w sin(alpha))`` [N]."""
    thrust = c_f * speed_sq
    return thrust * math.cos(tilt), thrust * math.sin(tilt)



@jit
def _measured_row(allocation, c_f: float, tilting: bool, speeds, tilts, row: int) -> float:  # noqa: ANN001
    total = 0.0
    for i in range(speeds.shape[0]):
        if tilting:
            u_v, u_l = static_from_rotor_command(speeds[i] * speeds[i], tilts[i], c_f)
            total += allocation[row, 2 * i] * u_v
            total += allocation[row, 2 * i + 1] * u_l
        else:
            total += allocation[row, i] * (abs(speeds[i]) * speeds[i])
    return total


@jit
def measured_rotor_wrench(allocation, c_f: float, tilting: bool, speeds, tilts) -> tuple:  # noqa: ANN001
    """Body (force [N], torque [N m]) that rotors at ``speeds`` (n,) [rad/s] and ``tilts`` (n,) [rad] produce
    through the nominal allocation: fixed rotors ``allocation`` (6, n) on ``u_w,i = |w_i| w_i``, rotors on servos
    the static ``allocation`` (6, 2n) on ``(c_f u_w cos(alpha), c_f u_w sin(alpha))``: the allocation's own
    arithmetic for the wrench of its command (:mod:`fsr_control.core.allocation`), here on the rotors' measured
    state (``rotor_state``)."""
    return ((_measured_row(allocation, c_f, tilting, speeds, tilts, 0),
             _measured_row(allocation, c_f, tilting, speeds, tilts, 1),
             _measured_row(allocation, c_f, tilting, speeds, tilts, 2)),
            (_measured_row(allocation, c_f, tilting, speeds, tilts, 3),
             _measured_row(allocation, c_f, tilting, speeds, tilts, 4),
             _measured_row(allocation, c_f, tilting, speeds, tilts, 5)))
