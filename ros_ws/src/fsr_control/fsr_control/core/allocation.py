"""From the law's body wrench to actuator commands per step (compiled core): allocation, desaturation and
the tilting rotors' null-space objective.

Three actuations (:class:`AllocationParams` ``mode``):

* ``WRENCH``: thrust ``u_T = -f_z`` and ``tau_b`` go to the plant as they are (``f_x``, ``f_y`` are a shortfall);
* ``FIXED``: ``u_w = G^+ [f; tau]`` (rows of the allocation the rotors can produce: the exact inverse for a
  quadrotor, the minimum-norm pseudo-inverse for the octocopter, all six for canted rotors), speeds
  ``sqrt(u_w)`` clamped; with ``priority`` (thrust-and-torque vehicles) a command beyond the limits is
  reallocated (:func:`fixed_desaturation`);
* ``TILTING``: ``u = G_s^+ [f; tau] (+ N z, the secondary objective)`` then eq. 5 of the report,
  ``u_w,i = |(u_v,i, u_l,i)| / c_f``, ``alpha_i = atan2(u_l,i, u_v,i)``; with ``priority`` a command beyond
  ``w_max`` is reallocated (:func:`tilting_desaturation`); the minimum speed and the tilt limit are clamped.

The priority rules (which axis gives way first, and why the closed forms hold) are documented in
:mod:`fsr_control.allocation`; the objective in
:mod:`fsr_control.nullspace`. Every saturated command is recorded (:mod:`fsr_sim.core.rotors`), never clipped
silently; the result's wrench is what the final command produces through the nominal allocation (what
``wrench_cmd`` carries) and the shortfall the demanded minus that wrench.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_sim.core.jit import jit, jit_inline
from fsr_sim.core.rotors import (
    clamped_speed,
    record_saturation,
    record_shortfall,
    rotor_command_from_static,
    static_from_rotor_command,
)

WRENCH, FIXED, TILTING = 0, 1, 2
FORCE_Z_ROW, TORQUE_X_ROW, TORQUE_Y_ROW, TORQUE_Z_ROW = 2, 3, 4, 5  # rows of the 6 x n allocation


class AllocationParams(NamedTuple):
    mode: int  # WRENCH, FIXED or TILTING
    priority: bool  # controller.allocation: priority (else clamp)
    air_mode: bool  # fixed rotors, priority: the thrust may rise for roll/pitch torque
    speed_min: float  # [rad/s]
    speed_max: float
    c_f: float  # thrust coefficient [N s^2]
    tilt_max: float  # [rad]
    allocation: np.ndarray  # (6, n) fixed rotors: wrench per u_w; (6, 2n) tilting: the static G_s
    inverse: np.ndarray  # (n, 6) fixed: G^+ (zero columns for rows the rotors cannot produce); (2n, 6): G_s^+
    thrust_ok: bool  # fixed rotors: step 3 of the priority allocation is well posed
    null_basis: np.ndarray  # (2n, k) orthonormal null space of G_s
    null_gram: np.ndarray  # (n, k * k) N_i^T N_i per rotor, flattened
    objective: bool  # tilting: the min_peak_speed secondary objective
    exponent: int  # its p (even, >= 4)
    iterations: int  # its Newton steps per command


class AllocationState(NamedTuple):
    saturation: np.ndarray  # rotor-speed saturation record
    tilt_saturation: np.ndarray  # tilt saturation record
    null_z: np.ndarray  # (k,) previous null-space solution [N] (warm start)
    null_hessian: np.ndarray  # (k, k) scratch
    null_terms: np.ndarray  # (n, k + 2) scratch: N_i^T t_i, then |t_i|^(p-2) and (p-2) |t_i|^(p-4)
    scratch: np.ndarray  # (8, 2n)


class Actuated(NamedTuple):
    """What the allocation gives: (produced force [N], torque [N m], body FRD), whether anything saturated;
    the speeds [rad/s], tilts [rad] and the shortfall (6,) are written into the caller's arrays."""

    force: tuple
    torque: tuple
    saturated: bool


@jit
def _produced(state: AllocationState, demanded: tuple, produced, shortfall, saturated: bool) -> Actuated:  # noqa: ANN001
    """The result of an allocation: the wrench its command produces (6,), the shortfall ``demanded - produced``
    written into ``shortfall`` and recorded when the command saturated."""
    for row in range(6):
        shortfall[row] = demanded[row] - produced[row]
    if saturated:
        record_shortfall(state.saturation, shortfall)
    return Actuated((produced[0], produced[1], produced[2]), (produced[3], produced[4], produced[5]), saturated)


# ----- fixed rotors -------------------------------------------------------------------------------------
@jit
def max_scale_in_box(base, direction, low: float, high: float) -> float:  # noqa: ANN001
    """Largest ``s in [0, 1]`` with ``low <= base + s direction <= high`` element-wise (``base`` assumed inside
    the box; rounding outside it gives ``s = 0``)."""
    scale = 1.0
    for i in range(base.shape[0]):
        a, d = base[i], direction[i]
        if d > 0.0:
            bound = (high - a) / d
        elif d < 0.0:
            bound = (low - a) / d
        else:
            continue
        if bound < scale:
            scale = bound
    return scale if scale > 0.0 else 0.0


@jit
def _inside(values, low: float, high: float) -> bool:  # noqa: ANN001
    for i in range(values.shape[0]):
        if not (low <= values[i] <= high):
            return False
    return True


@jit_inline
def _with_yaw(params: AllocationParams, base, tau_z: float, yaw, out) -> None:  # noqa: ANN001
    """The yaw step: ``out = base + s* v_yaw`` with the largest ``s* in [0, 1]`` that stays in the box."""
    for i in range(base.shape[0]):
        yaw[i] = tau_z * params.inverse[i, TORQUE_Z_ROW]
    low, high = params.speed_min * params.speed_min, params.speed_max * params.speed_max
    s = max_scale_in_box(base, yaw, low, high)
    for i in range(base.shape[0]):
        out[i] = base[i] + s * yaw[i]


@jit_inline
def fixed_desaturation(params: AllocationParams, thrust: float, torque: tuple, scratch, out) -> bool:  # noqa: ANN001
    """Squared speeds ``u_w`` (into ``out``) inside the box ``[w_min^2, w_max^2]`` for thrust ``u_T`` [N] and a body
    torque [N m], by priority (:mod:`fsr_control.allocation`): without air mode the thrust exact and the
    torque scaled first; else (or when the thrust alone does not fit) roll/pitch, then thrust, then yaw.
    False when step 3 does not apply and step 2 failed (the caller then clamps rotor by rotor)."""
    n = out.shape[0]
    inverse = params.inverse
    low, high = params.speed_min * params.speed_min, params.speed_max * params.speed_max
    g, roll_pitch, base, yaw = scratch[0, :n], scratch[1, :n], scratch[2, :n], scratch[3, :n]
    for i in range(n):
        g[i] = -inverse[i, FORCE_Z_ROW]  # d u_w / d u_T
        roll_pitch[i] = torque[0] * inverse[i, TORQUE_X_ROW] + torque[1] * inverse[i, TORQUE_Y_ROW]
    if not params.air_mode:  # the law's thrust exact, its torque scaled (if the thrust alone fits)
        for i in range(n):
            base[i] = thrust * g[i]
        if _inside(base, low, high):
            r = max_scale_in_box(base, roll_pitch, low, high)
            for i in range(n):
                base[i] = base[i] + r * roll_pitch[i]
            _with_yaw(params, base, torque[2], yaw, out)
            return True
    for i in range(n):
        base[i] = thrust * g[i] + roll_pitch[i]
    if not _inside(base, low, high):
        if not params.thrust_ok:
            return False
        # Step 3: roll/pitch scale r* (pairwise bound), then the reachable thrust closest to the command.
        scale = 1.0
        for i in range(n):
            a_i, k_i = low / g[i], roll_pitch[i] / g[i]
            for j in range(n):
                b_j, k_j = high / g[j], roll_pitch[j] / g[j]
                if k_j > k_i:
                    bound = (b_j - a_i) / (k_j - k_i)
                    if bound < scale:
                        scale = bound
        if scale < 0.0:
            scale = 0.0
        lowest, highest = -math.inf, math.inf
        for i in range(n):
            k_i = roll_pitch[i] / g[i]
            lowest = max(lowest, low / g[i] - scale * k_i)
            highest = min(highest, high / g[i] - scale * k_i)
        thrust = min(max(thrust, lowest), highest)
        for i in range(n):
            base[i] = thrust * g[i] + scale * roll_pitch[i]
    _with_yaw(params, base, torque[2], yaw, out)
    return True


@jit_inline
def allocate_fixed(params: AllocationParams, state: AllocationState, time: float, force: tuple, torque: tuple,
                   speeds, shortfall) -> Actuated:  # noqa: ANN001
    """Rotor speeds [rad/s] (into ``speeds``) for a body force [N] and torque [N m] (the rows the rotors cannot
    produce have zero columns in ``G^+``: coplanar rotors use only ``f_z = -u_T`` of the force)."""
    n = speeds.shape[0]
    inverse = params.inverse
    wrench = (force[0], force[1], force[2], torque[0], torque[1], torque[2])
    excess, speed_sq = state.scratch[4, :n], state.scratch[5, :n]
    for i in range(n):
        u = 0.0
        for row in range(6):
            u += inverse[i, row] * wrench[row]
        speeds[i], excess[i] = clamped_speed(u, params.speed_min, params.speed_max)
    saturated = record_saturation(state.saturation, time, excess)
    thrust = -force[2]
    if (saturated and params.priority and math.isfinite(thrust) and math.isfinite(torque[0])
            and math.isfinite(torque[1]) and math.isfinite(torque[2])):
        if fixed_desaturation(params, thrust, torque, state.scratch, speed_sq):
            for i in range(n):  # inside the box up to rounding: the clamp removes only that
                speeds[i] = clamped_speed(speed_sq[i], params.speed_min, params.speed_max)[0]
    allocation = params.allocation
    produced = state.scratch[6, :6]
    for row in range(6):
        total = 0.0
        for i in range(n):
            total += allocation[row, i] * (abs(speeds[i]) * speeds[i])
        produced[row] = total
    return _produced(state, (force[0], force[1], force[2], torque[0], torque[1], torque[2]), produced, shortfall,
                     saturated)


# ----- tilting rotors -----------------------------------------------------------------------------------
@jit
def max_scale_in_discs(base, direction, radius_sq: float) -> float:  # noqa: ANN001
    """Largest ``s in [0, 1]`` with ``|t_i + s d_i|^2 <= radius_sq`` for every interleaved pair ``t_i``, ``d_i``
    (``base`` assumed inside every disc): the larger root of a quadratic per pair, floored at 0."""
    scale = 1.0
    for i in range(0, base.shape[0], 2):
        tx, ty, dx, dy = base[i], base[i + 1], direction[i], direction[i + 1]
        dd = dx * dx + dy * dy
        if dd == 0.0:
            continue
        td = tx * dx + ty * dy
        root = (-td + math.sqrt(max(td * td - dd * (tx * tx + ty * ty - radius_sq), 0.0))) / dd
        if root < scale:
            scale = root
    return scale if scale > 0.0 else 0.0


@jit_inline
def tilting_desaturation(params: AllocationParams, wrench: tuple, scratch, out) -> None:  # noqa: ANN001
    """``u`` [N] (into ``out``, (2n,)) with every rotor's thrust vector ``|(u_v,i, u_l,i)| <= c_f w_max^2``: body
    force, then roll/pitch torque, then yaw torque, each added at the largest scale in ``[0, 1]`` that fits."""
    m = out.shape[0]
    inverse = params.inverse
    thrust_max = params.c_f * params.speed_max * params.speed_max
    radius_sq = thrust_max * thrust_max
    direction = scratch[0, :m]
    out[:] = 0.0
    for group in range(3):  # force, roll/pitch torque, yaw torque
        for i in range(m):
            if group == 0:
                direction[i] = inverse[i, 0] * wrench[0] + inverse[i, 1] * wrench[1] + inverse[i, 2] * wrench[2]
            elif group == 1:
                direction[i] = inverse[i, 3] * wrench[3] + inverse[i, 4] * wrench[4]
            else:
                direction[i] = wrench[5] * inverse[i, 5]
        s = max_scale_in_discs(out, direction, radius_sq)
        for i in range(m):
            out[i] = s * direction[i] if group == 0 else out[i] + s * direction[i]


@jit
def _solve_small(matrix, rhs, out) -> None:  # noqa: ANN001
    """``out = matrix^-1 rhs`` for the small symmetric positive-definite Hessian (closed form for 2 x 2,
    Gaussian elimination with partial pivoting otherwise; ``matrix`` and ``rhs`` are overwritten)."""
    k = rhs.shape[0]
    if k == 2:
        a, b, c, d = matrix[0, 0], matrix[0, 1], matrix[1, 0], matrix[1, 1]
        r0, r1 = rhs[0], rhs[1]
        det = a * d - b * c
        out[0], out[1] = (d * r0 - b * r1) / det, (a * r1 - c * r0) / det
        return
    for col in range(k):
        pivot = col
        for row in range(col + 1, k):
            if abs(matrix[row, col]) > abs(matrix[pivot, col]):
                pivot = row
        for j in range(k):
            matrix[col, j], matrix[pivot, j] = matrix[pivot, j], matrix[col, j]
        rhs[col], rhs[pivot] = rhs[pivot], rhs[col]
        for row in range(col + 1, k):
            factor = matrix[row, col] / matrix[col, col]
            for j in range(col, k):
                matrix[row, j] -= factor * matrix[col, j]
            rhs[row] -= factor * rhs[col]
    for row in range(k - 1, -1, -1):
        total = rhs[row]
        for j in range(row + 1, k):
            total -= matrix[row, j] * out[j]
        out[row] = total / matrix[row, row]


@jit_inline
def null_space_correction(params: AllocationParams, state: AllocationState, u) -> None:  # noqa: ANN001
    """Add ``N z`` to ``u`` (2n,) [N] with ``z`` minimising ``sum_i |t_i|^p`` (:mod:`fsr_control.nullspace`): a
    few Newton steps warm-started from the previous command's ``z``, on thrusts scaled by their mean."""
    basis, gram = params.null_basis, params.null_gram
    k = basis.shape[1]
    n = u.shape[0] // 2
    z = state.null_z
    if k == 0:
        return
    scale = 0.0
    for i in range(n):
        scale += math.sqrt(u[2 * i] * u[2 * i] + u[2 * i + 1] * u[2 * i + 1])
    scale = scale / n
    if not scale > 1e-9:
        z[:] = 0.0
        return
    half = params.exponent // 2
    t, hess, terms = state.scratch[5, :2 * n], state.null_hessian, state.null_terms
    grad, step = state.scratch[6, :k], state.scratch[7, :k]
    for c in range(k):
        z[c] = z[c] / scale
    for _ in range(params.iterations):
        for row in range(2 * n):
            total = 0.0
            for c in range(k):
                total += basis[row, c] * z[c]
            t[row] = u[row] / scale + total
        grad[:] = 0.0
        hess[:, :] = 0.0
        for i in range(n):
            sq = t[2 * i] * t[2 * i] + t[2 * i + 1] * t[2 * i + 1]  # |t_i|^2
            w1 = math.pow(sq, float(half - 1))  # |t_i|^(p-2)
            terms[i, k], terms[i, k + 1] = w1, (params.exponent - 2) * math.pow(sq, float(half - 2))
            for c in range(k):
                terms[i, c] = basis[2 * i, c] * t[2 * i] + basis[2 * i + 1, c] * t[2 * i + 1]  # N_i^T t_i
                grad[c] += w1 * terms[i, c]
            for c in range(k * k):
                hess[c // k, c % k] += w1 * gram[i, c]
        for c in range(k):
            for d in range(k):
                total = 0.0
                for i in range(n):
                    total += terms[i, c] * terms[i, k + 1] * terms[i, d]
                hess[c, d] += total
        _solve_small(hess, grad, step)
        for c in range(k):
            z[c] = z[c] - step[c]
    for c in range(k):
        z[c] = z[c] * scale
    for row in range(2 * n):
        total = 0.0
        for c in range(k):
            total += basis[row, c] * z[c]
        u[row] = u[row] + total


@jit_inline
def allocate_tilting(params: AllocationParams, state: AllocationState, time: float, force: tuple, torque: tuple,
                     speeds, tilts, shortfall) -> Actuated:  # noqa: ANN001
    """Rotor speeds [rad/s] and tilts [rad] (into ``speeds``, ``tilts``) for a body force [N] and torque [N m]."""
    n = speeds.shape[0]
    m = 2 * n
    inverse, c_f = params.inverse, params.c_f
    wrench = (force[0], force[1], force[2], torque[0], torque[1], torque[2])
    u = state.scratch[1, :m]
    for row in range(m):
        total = 0.0
        for col in range(6):
            total += inverse[row, col] * wrench[col]
        u[row] = total
    if params.objective:
        null_space_correction(params, state, u)
    excess, speed_sq = state.scratch[2, :n], state.scratch[3, :n]
    finite = True
    largest = 0.0
    for i in range(n):
        u_v, u_l = u[2 * i], u[2 * i + 1]
        finite = finite and math.isfinite(u_v) and math.isfinite(u_l)
        speed_sq[i], tilts[i] = rotor_command_from_static(u_v, u_l, c_f)
        speeds[i], excess[i] = clamped_speed(speed_sq[i], params.speed_min, params.speed_max)
        largest = speed_sq[i] if speed_sq[i] > largest or speed_sq[i] != speed_sq[i] else largest
    saturated = record_saturation(state.saturation, time, excess)
    if saturated and params.priority and largest > params.speed_max * params.speed_max and finite:
        tilting_desaturation(params, wrench, state.scratch, u)
        for i in range(n):
            speed_sq[i], tilts[i] = rotor_command_from_static(u[2 * i], u[2 * i + 1], c_f)
            speeds[i] = clamped_speed(speed_sq[i], params.speed_min, params.speed_max)[0]
    limit = params.tilt_max
    for i in range(n):  # the tilt limit, NaN kept
        tilt = tilts[i]
        clamped = -limit if tilt < -limit else (limit if tilt > limit else tilt)
        excess[i] = abs(tilt - clamped)
        tilts[i] = clamped
    saturated = record_saturation(state.tilt_saturation, time, excess) or saturated
    allocation = params.allocation
    produced = state.scratch[4, :6]
    for row in range(6):
        total = 0.0
        for i in range(n):
            u_v, u_l = static_from_rotor_command(speeds[i] * speeds[i], tilts[i], c_f)
            total += allocation[row, 2 * i] * u_v
            total += allocation[row, 2 * i + 1] * u_l
        produced[row] = total
    return _produced(state, wrench, produced, shortfall, saturated)


@jit_inline
def allocate(params: AllocationParams, state: AllocationState, time: float, force: tuple, torque: tuple, speeds,
             tilts, shortfall) -> Actuated:  # noqa: ANN001
    """The allocation of ``params.mode`` (module docstring)."""
    if params.mode == FIXED:
        return allocate_fixed(params, state, time, force, torque, speeds, shortfall)
    if params.mode == TILTING:
        return allocate_tilting(params, state, time, force, torque, speeds, tilts, shortfall)
    shortfall[:] = 0.0
    shortfall[0], shortfall[1] = force[0], force[1]
    return Actuated((0.0, 0.0, force[2]), torque, False)
