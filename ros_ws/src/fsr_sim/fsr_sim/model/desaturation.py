"""Allocation with priorities: what gives way when the rotors cannot produce the commanded wrench.

Clamping each rotor on its own (``controller.allocation: clamp``) also cuts collective thrust and roll/pitch
torque when only the yaw torque is out of reach. The priority allocation (``controller.allocation:
priority``, the default) instead keeps the axes that hold the vehicle in the air and lets the others give
way, in a fixed order, like PX4's sequential desaturation. It exploits that the wrench is linear in the
squared rotor speeds ``u_w,i = w_i^2`` [(rad/s)^2], so the speed limits are box constraints on ``u_w``:
along any straight line ``u_w(s) = a + s d`` the feasible ``s`` form an interval with a closed form.

Fixed rotors (any count ``n``; rows ``f_z, tau_x, tau_y, tau_z`` of the allocation ``G``, ``P = G^+``,
``g = -P e_fz`` the squared-speed change per newton of thrust ``u_T = -f_z``, ``v_rp = P [0, tau_x, tau_y, 0]``,
``v_yaw = P [0, 0, 0, tau_z]``, box ``B = [w_min^2, w_max^2]^n``). Priority, highest first: roll/pitch
torque (the thrust direction, i.e. the attitude), then collective thrust ``u_T``, then yaw torque:

1. ``u_w = P w`` in ``B``: returned as it is (the clamp path, bit-identical).
2. ``u_T g + v_rp`` in ``B`` (thrust and roll/pitch reachable without yaw): yaw gives way,
   ``u_w = u_T g + v_rp + s* v_yaw`` with ``s* = max {s in [0, 1] : u_w(s) in B}``; thrust and roll/pitch
   torque are exact.
3. Otherwise yaw is dropped and, for a roll/pitch scale ``r`` and a thrust ``T``, rotor ``i`` needs
   ``T in [(lo_i - r v_rp,i)/g_i, (hi_i - r v_rp,i)/g_i]``. The largest ``r in [0, 1]`` for which these
   intervals intersect is the minimum over rotor pairs of ``(b_j - a_i)/(k_j - k_i)`` (``a = lo/g``,
   ``b = hi/g``, ``k = v_rp/g``, pairs with ``k_j > k_i``): roll/pitch torque keeps its direction and is
   scaled by ``r*`` only if it cannot be met at any thrust. Then ``T*`` is the commanded thrust clipped to
   the intersection (the closest reachable thrust: it may rise above the command to make room for the
   torque, as PX4's air mode does, or fall), and the yaw step of 2 adds back what yaw still fits.

Without air mode (``controller.air_mode: false``) the thrust comes first instead: ``u_w = u_T g + r* v_rp +
s* v_yaw`` with ``r* = max {r in [0, 1] : u_T g + r v_rp in B}`` (roll/pitch scaled, same direction), then the
yaw step; the commanded thrust is kept exactly (steps 2-3 only if ``u_T g`` alone is outside ``B``).

Step 3 needs ``g_i > 0`` (more thrust asks every rotor for more; true for every multirotor layout) and a
uniform thrust inside ``B`` (true for ``w_min < w_max``); otherwise the command is clamped rotor by rotor.
The result of steps 2 and 3 is inside ``B`` up to rounding (a final clamp removes that).

Tilting rotors (static allocation ``G_s``, ``u = [u_v1, u_l1, ...]`` [N], ``P_s = G_s^+``): rotor ``i``'s thrust
vector ``t_i = (u_v,i, u_l,i)`` must satisfy ``|t_i| <= c_f w_max^2``, a disc (convex). Priority, highest first:
body force, then roll/pitch torque, then yaw torque. Starting from ``u = 0`` each group in turn is added at
the largest scale in ``[0, 1]`` that keeps every ``t_i`` in its disc (the root of a quadratic per rotor):
``u = s_F P_s [f; 0] + s_rp P_s [0; tau_x; tau_y; 0] + s_y P_s [0; 0; 0; tau_z]``. So yaw gives way first,
then roll/pitch, then force, each keeping its direction. The minimum speed and the tilt limit (not convex
sets) are then enforced by the clamp, as without priorities.

Everything here runs on plain Python floats: a handful of rotors per 1 kHz step, where numpy's per-call
overhead would dominate.
"""

from __future__ import annotations

import math

import numpy as np

FORCE_Z_ROW, TORQUE_X_ROW, TORQUE_Y_ROW, TORQUE_Z_ROW = 2, 3, 4, 5  # rows of the 6 x n allocation


def max_scale_in_box(base: list[float], direction: list[float], low: list[float], high: list[float]) -> float:
    """Largest ``s in [0, 1]`` with ``low <= base + s direction <= high`` (element-wise).

    Parameters
    ----------
    base, direction, low, high : list of float, length n
        A point (assumed inside the box; rounding outside it gives ``s = 0``), a direction and the box.

    Returns
    -------
    float
        ``min(1, min_i bound_i)`` with ``bound_i = (high_i - base_i) / d_i`` for ``d_i > 0`` and
        ``(low_i - base_i) / d_i`` for ``d_i < 0``, floored at 0.
    """
    scale = 1.0
    for a, d, lo, hi in zip(base, direction, low, high, strict=True):
        if d > 0.0:
            bound = (hi - a) / d
        elif d < 0.0:
            bound = (lo - a) / d
        else:
            continue
        if bound < scale:
            scale = bound
    return scale if scale > 0.0 else 0.0


def max_scale_in_discs(base: list[float], direction: list[float], radius_sq: float) -> float:
    """Largest ``s in [0, 1]`` with ``|t_i + s d_i|^2 <= radius_sq`` for every pair ``t_i``, ``d_i``.

    Parameters
    ----------
    base, direction : list of float, length 2n
        Interleaved pairs ``(x_1, y_1, x_2, y_2, ...)``: the start (assumed inside every disc) and the
        direction.
    radius_sq : float
        Squared disc radius (for thrust vectors [N]: ``(c_f w_max^2)^2``).

    Returns
    -------
    float
        ``min(1, min_i s_i)`` with ``s_i`` the larger root of ``|d_i|^2 s^2 + 2 (t_i . d_i) s + |t_i|^2 - R^2``,
        floored at 0.
    """
    scale = 1.0
    for i in range(0, len(base), 2):
        tx, ty, dx, dy = base[i], base[i + 1], direction[i], direction[i + 1]
        dd = dx * dx + dy * dy
        if dd == 0.0:
            continue
        td = tx * dx + ty * dy
        root = (-td + math.sqrt(max(td * td - dd * (tx * tx + ty * ty - radius_sq), 0.0))) / dd
        if root < scale:
            scale = root
    return scale if scale > 0.0 else 0.0


class FixedRotorDesaturation:
    """Priority allocation of fixed rotors (module docstring, steps 2 and 3) over ``u_w`` [(rad/s)^2].

    Parameters
    ----------
    inverse : ndarray, shape (n, m)
        ``P``: pseudo-inverse of the allocation rows ``rows`` (``FixedRotorAllocator.inverse``).
    rows : ndarray of int, shape (m,)
        Which rows of the 6 x n allocation ``P`` inverts; must contain ``f_z`` (2). Missing torque rows
        (e.g. ``c_m = 0`` leaves no yaw row) contribute nothing.
    speed_min, speed_max : float
        Rotor speed limits [rad/s]; the box is ``[speed_min^2, speed_max^2]``.
    """

    def __init__(self, inverse: np.ndarray, rows: np.ndarray, speed_min: float, speed_max: float) -> None:
        rows = [int(r) for r in rows]
        if FORCE_Z_ROW not in rows:
            raise ValueError(f"the allocation rows {rows} have no f_z row: fixed rotors without thrust")
        n = inverse.shape[0]

        def column(row: int) -> list[float]:
            return inverse[:, rows.index(row)].tolist() if row in rows else [0.0] * n

        self.thrust_column = [-v for v in column(FORCE_Z_ROW)]  # g: d u_w / d u_T
        self.roll_column, self.pitch_column, self.yaw_column = (column(r) for r in (TORQUE_X_ROW, TORQUE_Y_ROW,
                                                                                    TORQUE_Z_ROW))
        self.low = [speed_min * speed_min] * n
        self.high = [speed_max * speed_max] * n
        # Step 3 is well posed when every rotor's u_w grows with thrust and a uniform thrust fits in the box.
        g = self.thrust_column
        self.thrust_ok = all(v > 0.0 for v in g) and max(lo / gi for lo, gi in zip(self.low, g, strict=True)) <= min(
            hi / gi for hi, gi in zip(self.high, g, strict=True))

    def allocate_keeping_thrust(self, thrust: float, torque_body: tuple[float, float, float]) -> list[float] | None:
        """Squared rotor speeds ``u_w`` [(rad/s)^2] with the thrust ``u_T`` [N] exact and the torque [N m] (FRD)
        scaled to fit (``controller.air_mode: false``, PX4 without air mode): thrust, then roll/pitch torque,
        then yaw, ``u_w = u_T g + r* v_rp + s* v_yaw`` with ``r* = max {r in [0, 1] : u_T g + r v_rp in B}``
        and ``s*`` the yaw step of :meth:`allocate`.

        Returns None when the thrust alone does not fit (``u_T g`` outside the box): the caller then uses the
        priority allocation.
        """
        low, high = self.low, self.high
        base = [thrust * gi for gi in self.thrust_column]
        if not all(lo <= u <= hi for u, lo, hi in zip(base, low, high, strict=True)):
            return None
        roll_pitch = self._roll_pitch_direction(torque_body)
        r = max_scale_in_box(base, roll_pitch, low, high)
        return self._with_yaw([u + r * v for u, v in zip(base, roll_pitch, strict=True)], torque_body[2])

    def _roll_pitch_direction(self, torque_body: tuple[float, float, float]) -> list[float]:
        """``v_rp = tau_x a + tau_y b``: the squared speeds of the roll/pitch torque alone."""
        tau_x, tau_y = torque_body[0], torque_body[1]
        return [tau_x * a + tau_y * b for a, b in zip(self.roll_column, self.pitch_column, strict=True)]

    def _with_yaw(self, base: list[float], tau_z: float) -> list[float]:
        """The yaw step: ``base + s* v_yaw`` with the largest ``s* in [0, 1]`` that stays in the box."""
        yaw = [tau_z * c for c in self.yaw_column]
        s = max_scale_in_box(base, yaw, self.low, self.high)
        return [u + s * y for u, y in zip(base, yaw, strict=True)]

    def allocate(self, thrust: float, torque_body: tuple[float, float, float]) -> list[float] | None:
        """Squared rotor speeds ``u_w`` [(rad/s)^2] inside the box for thrust ``u_T`` [N] along ``-z_b`` and body
        torque [N m] (FRD), by steps 2 and 3 of the module docstring.

        Returns None when step 3 does not apply (see ``thrust_ok``) and step 2 did not succeed: the caller
        then clamps rotor by rotor.
        """
        g, low, high = self.thrust_column, self.low, self.high
        roll_pitch = self._roll_pitch_direction(torque_body)
        base = [thrust * gi + v for gi, v in zip(g, roll_pitch, strict=True)]
        if not all(lo <= u <= hi for u, lo, hi in zip(base, low, high, strict=True)):
            if not self.thrust_ok:
                return None
            # Step 3: roll/pitch scale r* (pairwise bound), then the reachable thrust closest to the command.
            a = [lo / gi for lo, gi in zip(low, g, strict=True)]
            b = [hi / gi for hi, gi in zip(high, g, strict=True)]
            k = [v / gi for v, gi in zip(roll_pitch, g, strict=True)]
            scale = 1.0
            for a_i, k_i in zip(a, k, strict=True):
                for b_j, k_j in zip(b, k, strict=True):
                    if k_j > k_i:
                        bound = (b_j - a_i) / (k_j - k_i)
                        if bound < scale:
                            scale = bound
            scale = max(scale, 0.0)
            lowest = max(a_i - scale * k_i for a_i, k_i in zip(a, k, strict=True))
            highest = min(b_i - scale * k_i for b_i, k_i in zip(b, k, strict=True))
            thrust = min(max(thrust, lowest), highest)
            base = [thrust * gi + scale * v for gi, v in zip(g, roll_pitch, strict=True)]
        return self._with_yaw(base, torque_body[2])


class TiltingDesaturation:
    """Priority allocation of tilting rotors (module docstring): force, then roll/pitch, then yaw torque.

    Parameters
    ----------
    inverse : ndarray, shape (2n, 6)
        ``P_s``: pseudo-inverse of the static 6 x 2n allocation (``u = [u_v1, u_l1, ...]`` [N]).
    max_thrust : float
        Largest rotor thrust ``c_f w_max^2`` [N]: the radius of each rotor's disc of thrust vectors.
    """

    def __init__(self, inverse: np.ndarray, max_thrust: float) -> None:
        self.force_columns = inverse[:, 0:3]
        self.roll_pitch_columns = inverse[:, 3:5]
        self.yaw_column = inverse[:, 5].tolist()
        self.radius_sq = max_thrust * max_thrust

    def allocate(self, force_body: np.ndarray, torque_body: np.ndarray) -> np.ndarray:
        """``u`` [N], shape (2n,), with every ``|(u_v,i, u_l,i)| <= c_f w_max^2``, for a body force [N] and torque
        [N m] (FRD), each wrench group scaled in priority order (module docstring)."""
        force = (self.force_columns @ force_body).tolist()
        zero = [0.0] * len(force)
        s_force = max_scale_in_discs(zero, force, self.radius_sq)
        base = [s_force * f for f in force]
        roll_pitch = (self.roll_pitch_columns @ torque_body[0:2]).tolist()
        s_roll_pitch = max_scale_in_discs(base, roll_pitch, self.radius_sq)
        base = [u + s_roll_pitch * v for u, v in zip(base, roll_pitch, strict=True)]
        tau_z = float(torque_body[2])
        yaw = [tau_z * c for c in self.yaw_column]
        s_yaw = max_scale_in_discs(base, yaw, self.radius_sq)
        return np.array([u + s_yaw * y for u, y in zip(base, yaw, strict=True)])
