"""Control authority from the model: the largest thrust, torques, angular accelerations and hover tilt the
rotors can give at hover with the other axes kept (docs/model.md §3.2, *Authority*).

Computed once per vehicle model at start-up, not per step (kept by :mod:`fsr_control.design.authority_cache`
for the planner's check and the designed gains; ``fsr-vehicle`` prints it): small linear programs
(:func:`scipy.optimize.linprog`, HiGHS) over the rotors' inputs ``x``, whose body wrench is linear,
``[f_b; tau_b] = M x`` (body FRD; rows ``f_x f_y f_z tau_x tau_y tau_z``; thrust ``u_T = -f_z`` [N]).
Each number is the largest ``s`` with

    M x = w_0 + s d,   x feasible                                                            (LP)

for a base wrench ``w_0`` and a direction ``d``:

* thrust range: ``w_0 = 0``, ``d = -e_fz`` (thrust along ``-z_b``), ``s`` maximised and minimised, every other
  row zero (no torque, and no lateral force on a fully actuated vehicle);
* torque about body axis ``k``: ``w_0 = [-m g e3; 0]`` (level hover: thrust ``m g``), ``d = e_tau_k``, the
  other rows kept at ``w_0`` (the other torques zero);
* angular acceleration about body axis ``k``: as the torque with ``d = [0; I_b e_k]`` (from rest the
  gyroscopic term vanishes, ``I_b omega_dot = tau_b``), so ``s`` [rad/s^2] is the largest ``omega_dot`` along
  ``e_k`` alone; for a diagonal inertia it is the torque over ``I_kk``.

A torque or an angular acceleration is solved for both signs of ``d`` and the smaller magnitude is reported
(a reference must be able to brake as well as accelerate).

The inputs ``x`` and their limits:

* fixed rotors: ``x_i = c_f u_w,i`` [N], the rotor's thrust, with ``c_f w_min^2 <= x_i <= c_f w_max^2`` (a box:
  the LP is exact); ``M`` is :func:`~fsr_sim.model.rotors.wrench_from_rotor_speed_sq` over ``c_f``.
* rotors on servos: ``x = [u_v1, u_l1, ...]`` [N] of the static allocation
  (:func:`~fsr_sim.model.rotors.static_tilting_allocation`), rotor ``i``'s thrust ``c_f u_w,i =
  |(u_v,i, u_l,i)|`` at tilt ``alpha_i = atan2(u_l,i, u_v,i)``. The feasible set per rotor is the annulus
  sector ``c_f w_min^2 <= |(u_v, u_l)| <= c_f w_max^2``, ``|alpha| <= tilt_angle_max``; the LP uses a convex
  polygon inside it, so every number is one the rotors can really give (an inner approximation):
  the disc ``|(u_v, u_l)| <= c_f w_max^2`` as the inscribed regular polygon of :data:`POLYGON_EDGES` edges
  with vertices at tilt 0 and 180 deg (at most ``1 - cos(pi / POLYGON_EDGES)`` = 0.12 % short of the disc);
  a servo limit below 180 deg as the sector ``|alpha| <= min(tilt_angle_max, 90 deg)`` (two half-planes
  through the origin; convex only up to 90 deg, so a limit between 90 and 180 deg is taken as 90 deg); a
  minimum speed ``w_min > 0`` as the half-plane ``u_v >= c_f w_min^2`` (the vertical thrust alone meets the
  minimum; the annulus itself is not convex).

Hover tilt (fully actuated vehicles only): the largest body tilt ``phi`` from level, about the body x or y
axis (either sign, the smallest of the four), up to which the vehicle can hover at that attitude with zero
torque: the body force ``f_b = -m g R^T e3`` with ``R = exp(phi S(a))``, ``a`` the tilt axis, must be
feasible for every angle from 0 to ``phi``. Found by a scan in :data:`TILT_SCAN_STEP` steps, then bisection
to :data:`TILT_TOLERANCE` (an angle between two feasible scan points is assumed feasible); 180 deg when
every attitude is.

Force set (fully actuated vehicles only): the body forces with zero torque the rotors can give, for a
reference that asks for a force in any body direction (a tilting vehicle accelerating sideways while level).
For each of :data:`FORCE_DIRECTIONS` unit body directions ``a_k`` (the six axes and a Fibonacci sphere) the
support ``b_k = max a_k . f_b`` over feasible inputs with zero torque (an LP); the set is kept as the
half-spaces ``a_k . f <= b_k`` (:class:`ForceSet`). That is an outer approximation, exact along each
``a_k``: between the directions it may admit a little more than the rotors give (the margin covers it).
Supporting planes, not the hull of points along rays, because the set of fixed canted rotors is a narrow cone
from the origin that rays in most directions miss.

The margin ``0 < margin <= 1`` (``trajectory.authority_margin`` of a scenario) shrinks every number towards
hover: torques, angular accelerations and the tilt are multiplied by it, the thrust range becomes
``m g + margin (T_max - m g)`` and ``m g - margin (m g - T_min)``. The feasible set is convex and contains
hover, so these smaller numbers are feasible too. The force set shrinks the same way, towards the level
hover force ``h = -m g e3``: ``h + margin (P - h)``.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from fsr_sim.model.frames import E3
from fsr_sim.model.rotors import (
    rotor_commands_from_static,
    static_tilting_allocation,
    wrench_from_rotor_speed_sq,
)
from fsr_sim.model.so3 import rotation_exp
from fsr_sim.model.vehicle import Vehicle

POLYGON_EDGES = 64  # inscribed polygon of a rotor's thrust disc (rotors on servos)
TILT_SCAN_STEP = np.deg2rad(5.0)  # rad: scan of the hover tilt
TILT_TOLERANCE = 1e-4  # rad: bisection of the hover tilt
AXES = ("roll", "pitch", "yaw")  # body FRD x, y, z
FORCE_DIRECTIONS = 6 + 96  # the body axes and a Fibonacci sphere (force set of a fully actuated vehicle)


@dataclass(frozen=True)
class Authority:
    """What the rotors give at hover, scaled by ``margin`` (module docstring for the equations).

    Attributes
    ----------
    margin : float
        The factor applied, in (0, 1]; 1 is the model's limits.
    hover_thrust : float
        ``m g`` [N].
    thrust_min, thrust_max : float
        [N], collective thrust ``u_T = -f_z`` along ``-z_b`` with zero torque (and zero lateral force).
    roll_torque, pitch_torque, yaw_torque : float
        [N m], >= 0: the smaller of the largest positive and negative torque about body x, y, z at hover
        thrust with the other torques zero.
    roll_acceleration, pitch_acceleration, yaw_acceleration : float
        [rad/s^2], >= 0: likewise the largest angular acceleration about body x, y, z alone, from rest.
    tilt_max : float or None
        [rad], fully actuated vehicles: the largest body roll or pitch at which the vehicle hovers; None for a
        vehicle that hovers only level (thrust along ``-z_b``).
    """

    margin: float
    hover_thrust: float
    thrust_min: float
    thrust_max: float
    roll_torque: float
    pitch_torque: float
    yaw_torque: float
    roll_acceleration: float
    pitch_acceleration: float
    yaw_acceleration: float
    tilt_max: float | None

    def scaled(self, margin: float) -> Authority:
        """These numbers (the model's: ``margin`` 1) shrunk by ``margin`` towards hover (module docstring)."""
        if self.margin != 1.0:
            raise ValueError(f"scaled: the authority is already scaled by a margin of {self.margin}")
        weight = self.hover_thrust
        return Authority(
            margin=margin,
            hover_thrust=weight,
            thrust_min=weight - margin * (weight - self.thrust_min),
            thrust_max=weight + margin * (self.thrust_max - weight),
            roll_torque=margin * self.roll_torque,
            pitch_torque=margin * self.pitch_torque,
            yaw_torque=margin * self.yaw_torque,
            roll_acceleration=margin * self.roll_acceleration,
            pitch_acceleration=margin * self.pitch_acceleration,
            yaw_acceleration=margin * self.yaw_acceleration,
            tilt_max=None if self.tilt_max is None else margin * self.tilt_max,
        )

    def as_dict(self) -> dict[str, float | None]:
        """The fields as plain Python numbers (JSON)."""
        return {field.name: getattr(self, field.name) for field in fields(self)}


@dataclass(frozen=True, eq=False)
class ForceSet:
    """The body forces [N] (FRD) with zero torque a fully actuated vehicle's rotors give: ``normals @ f <=
    offsets`` (module docstring, *Force set*: supporting planes); ``hover`` is the level hover force
    ``-m g e3``."""

    normals: np.ndarray  # (F, 3), unit
    offsets: np.ndarray  # (F,)
    hover: np.ndarray  # (3,)

    def shrunk_offsets(self, margin: float) -> np.ndarray:
        """The facets' offsets of ``h + margin (P - h)``: ``margin b + (1 - margin) a . h``."""
        return margin * self.offsets + (1.0 - margin) * (self.normals @ self.hover)

    def reach(self, directions: np.ndarray, margin: float = 1.0) -> np.ndarray:
        """The largest ``s >= 0`` with ``s u`` in the set shrunk by ``margin``, for each unit row ``u`` of
        ``directions`` (n, 3) [N] (0 when even a small force along ``u`` is outside it)."""
        offsets = self.shrunk_offsets(margin)
        along = np.atleast_2d(directions) @ self.normals.T  # (n, F): a_j . u
        with np.errstate(divide="ignore", invalid="ignore"):
            bound = np.where(along > 1e-12, offsets / along, np.inf)
        return np.maximum(bound.min(axis=1), 0.0)

    def contains(self, forces: np.ndarray, margin: float = 1.0) -> np.ndarray:
        """Whether each row of ``forces`` (n, 3) [N] lies in the set shrunk by ``margin``."""
        return np.all(np.atleast_2d(forces) @ self.normals.T <= self.shrunk_offsets(margin) + 1e-9, axis=1)

    def as_dict(self) -> dict[str, list]:
        return {"normals": self.normals.tolist(), "offsets": self.offsets.tolist(), "hover": self.hover.tolist()}

    @classmethod
    def from_dict(cls, values: dict[str, list]) -> ForceSet:
        return cls(*(np.array(values[key], dtype=float) for key in ("normals", "offsets", "hover")))


def force_directions(count: int = FORCE_DIRECTIONS) -> np.ndarray:
    """``count`` unit body directions (count, 3): the six axes, then a Fibonacci sphere of ``count - 6``."""
    n = count - 6
    z = 1.0 - (2.0 * np.arange(n) + 1.0) / n
    azimuth = np.pi * (3.0 - np.sqrt(5.0)) * np.arange(n)
    ring = np.sqrt(1.0 - z * z)
    sphere = np.column_stack((ring * np.cos(azimuth), ring * np.sin(azimuth), z))
    return np.vstack((np.eye(3), -np.eye(3), sphere))


def force_set(vehicle: Vehicle) -> ForceSet:
    """The :class:`ForceSet` of a fully actuated ``vehicle`` (module docstring)."""
    if not vehicle.fully_actuated:
        raise ValueError(f"vehicle '{vehicle.name}' is not fully actuated: its force is along -z_b only")
    from scipy.optimize import linprog

    inputs = rotor_inputs(vehicle)
    force, torque = inputs.matrix[:3], inputs.matrix[3:]
    directions = force_directions()
    supports = np.empty(len(directions))
    for k, direction in enumerate(directions):
        result = linprog(-(direction @ force), A_ub=inputs.inequality if len(inputs.bound) else None,
                         b_ub=inputs.bound if len(inputs.bound) else None, A_eq=torque, b_eq=np.zeros(3),
                         bounds=inputs.bounds, method="highs")
        if result.status != 0:
            raise RuntimeError(f"force set LP for '{vehicle.name}' failed: {result.message}")
        supports[k] = -result.fun
    return ForceSet(directions, supports, -vehicle.weight * E3)


@dataclass(frozen=True)
class RotorInputs:
    """The linear programs' inputs ``x`` of a vehicle: ``[f_b; tau_b] = matrix @ x`` (6 x m, N -> N and N m),
    ``inequality @ x <= bound`` (rows, may be empty) and per-input ``bounds`` (lower, upper) [N]."""

    vehicle: Vehicle
    matrix: np.ndarray
    inequality: np.ndarray
    bound: np.ndarray
    bounds: tuple[tuple[float, float], ...]

    def rotor_commands(self, inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """Squared rotor speeds ``u_w`` [(rad/s)^2] and tilts ``alpha`` [rad] (None for fixed rotors) of ``x``."""
        inputs = np.asarray(inputs, dtype=float)
        if self.vehicle.has_servos:
            return rotor_commands_from_static(self.vehicle, inputs)
        return inputs / self.vehicle.c_f, None


def rotor_inputs(vehicle: Vehicle) -> RotorInputs:
    """The inputs of :func:`largest_along` for ``vehicle``: rotor thrusts in a box (fixed rotors) or, on servos,
    ``[u_v1, u_l1, ...]`` in the convex polygons of the module docstring."""
    thrust_min = vehicle.c_f * vehicle.rotor_speed_min**2  # N per rotor
    thrust_max = vehicle.c_f * vehicle.rotor_speed_max**2
    n = vehicle.rotor_count
    if not vehicle.has_servos:
        matrix = wrench_from_rotor_speed_sq(vehicle) / vehicle.c_f
        return RotorInputs(vehicle, matrix, np.zeros((0, n)), np.zeros(0), ((thrust_min, thrust_max),) * n)
    # Per rotor, rows over (u_v, u_l): the polygon's edges (normals at pi/K + 2 pi j/K), then the limits.
    normals = np.pi / POLYGON_EDGES + 2.0 * np.pi * np.arange(POLYGON_EDGES) / POLYGON_EDGES
    rows = [np.column_stack((np.cos(normals), np.sin(normals)))]
    bounds = [np.full(POLYGON_EDGES, thrust_max * np.cos(np.pi / POLYGON_EDGES))]
    if vehicle.tilt_angle_max < np.pi:
        tilt = min(vehicle.tilt_angle_max, np.pi / 2.0)  # |u_l| <= tan(tilt) u_v
        rows.append(np.array(((-np.sin(tilt), np.cos(tilt)), (-np.sin(tilt), -np.cos(tilt)))))
        bounds.append(np.zeros(2))
    if thrust_min > 0.0:  # u_v >= c_f w_min^2
        rows.append(np.array(((-1.0, 0.0),)))
        bounds.append(np.array((-thrust_min,)))
    block, block_bound = np.vstack(rows), np.concatenate(bounds)
    inequality = np.kron(np.eye(n), block)  # rotor i's rows act on its (u_v,i, u_l,i)
    return RotorInputs(vehicle, static_tilting_allocation(vehicle), inequality, np.tile(block_bound, n),
                       ((-thrust_max, thrust_max),) * (2 * n))


def largest_along(inputs: RotorInputs, base_wrench: np.ndarray,
                  direction: np.ndarray | None) -> tuple[float, np.ndarray] | None:
    """The largest ``s`` with ``matrix @ x = base_wrench + s direction`` over feasible inputs ``x`` (LP).

    Parameters
    ----------
    inputs : RotorInputs
    base_wrench : array-like, shape (6,)
        ``[f_b; tau_b]`` [N, N m], body FRD.
    direction : array-like, shape (6,), or None
        ``d``; None: only whether ``base_wrench`` itself is feasible (``s = 0``).

    Returns
    -------
    (s, x) or None
        ``s`` [the unit of ``d``] and the inputs reaching it; None when no ``s`` is feasible.
    """
    from scipy.optimize import linprog  # here: scipy.optimize takes 0.4-0.8 s to import, and most starts hit the cache

    base = np.asarray(base_wrench, dtype=float).reshape(6)
    d = np.zeros(6) if direction is None else np.asarray(direction, dtype=float).reshape(6)
    m = inputs.matrix.shape[1]
    scale = np.max(np.abs(inputs.matrix))
    # A row the rotors cannot produce (f_x, f_y of coplanar rotors) asked for zero: 0 = 0, left out.
    keep = (np.max(np.abs(inputs.matrix), axis=1) > 1e-12 * scale) | (base != 0.0) | (d != 0.0)
    equality = np.hstack((inputs.matrix[keep], -d[keep, None]))
    objective = np.zeros(m + 1)
    objective[m] = -1.0 if direction is not None else 0.0
    extra = [(None, None) if direction is not None else (0.0, 0.0)]
    inequality = np.hstack((inputs.inequality, np.zeros((inputs.inequality.shape[0], 1))))
    result = linprog(objective, A_ub=inequality if len(inputs.bound) else None,
                     b_ub=inputs.bound if len(inputs.bound) else None, A_eq=equality, b_eq=base[keep],
                     bounds=[*inputs.bounds, *extra], method="highs")
    if result.status == 2:  # infeasible
        return None
    if result.status != 0:
        raise RuntimeError(f"authority LP for '{inputs.vehicle.name}' failed: {result.message}")
    return float(result.x[m]), result.x[:m]


def _smaller_of_both_signs(inputs: RotorInputs, base: np.ndarray, direction: np.ndarray) -> float:
    values = [largest_along(inputs, base, sign * direction) for sign in (1.0, -1.0)]
    if any(value is None for value in values):  # the caller has checked that hover is feasible
        raise RuntimeError(f"'{inputs.vehicle.name}': hover became infeasible in an authority LP")
    return max(0.0, min(value[0] for value in values))


def hover_tilt_limit(inputs: RotorInputs) -> float:
    """The largest body tilt [rad] about body x or y (either sign) at which the vehicle hovers with zero torque
    (module docstring); ``pi`` when it hovers at every attitude about these axes."""
    vehicle = inputs.vehicle

    def hovers(axis: np.ndarray, angle: float) -> bool:
        force_body = -vehicle.weight * rotation_exp(axis * angle).T @ E3
        return largest_along(inputs, np.concatenate((force_body, np.zeros(3))), None) is not None

    limits = []
    for axis in (np.array((1.0, 0.0, 0.0)), np.array((0.0, 1.0, 0.0))):
        for sign in (1.0, -1.0):
            feasible, limit = 0.0, np.pi
            for angle in np.append(np.arange(TILT_SCAN_STEP, np.pi, TILT_SCAN_STEP), np.pi):
                if not hovers(sign * axis, angle):
                    infeasible = angle
                    while infeasible - feasible > TILT_TOLERANCE:
                        middle = 0.5 * (feasible + infeasible)
                        feasible, infeasible = (middle, infeasible) if hovers(sign * axis, middle) else \
                            (feasible, middle)
                    limit = feasible
                    break
                feasible = angle
            limits.append(limit)
    return float(min(limits))


def authority(vehicle: Vehicle, margin: float = 1.0) -> Authority:
    """The vehicle's control authority at hover, shrunk by ``margin`` (module docstring: the LPs, the limits
    and how rotors on servos are approximated).

    Parameters
    ----------
    vehicle : Vehicle
    margin : float
        In (0, 1]: 1 gives the model's limits, 0.7 keeps 30 % in reserve.

    Returns
    -------
    Authority

    Raises
    ------
    ValueError
        ``margin`` outside (0, 1]; or the vehicle cannot hover (its weight ``m g`` outside the thrust its rotors
        give with zero torque), naming the vehicle, its weight and its thrust range.
    """
    margin = float(margin)
    if not 0.0 < margin <= 1.0:
        raise ValueError(f"margin: must be in (0, 1], got {margin}")
    inputs = rotor_inputs(vehicle)
    weight = vehicle.weight
    up = np.array((0.0, 0.0, -1.0, 0.0, 0.0, 0.0))  # thrust u_T = -f_z
    highest = largest_along(inputs, np.zeros(6), up)
    lowest = largest_along(inputs, np.zeros(6), -up)
    if highest is None or lowest is None:
        raise ValueError(f"vehicle '{vehicle.name}' cannot hover: its rotors cannot produce zero torque at any "
                         "thrust")
    thrust_max, thrust_min = highest[0], -lowest[0]
    if not thrust_min <= weight <= thrust_max:
        raise ValueError(f"vehicle '{vehicle.name}' cannot hover: its weight m g = {weight:.4g} N is outside the "
                         f"thrust its rotors give with zero torque, {thrust_min:.4g} .. {thrust_max:.4g} N")
    hover = np.concatenate((-weight * E3, np.zeros(3)))
    torques, accelerations = [], []
    for k in range(3):
        torques.append(_smaller_of_both_signs(inputs, hover, np.eye(6)[3 + k]))
        accelerations.append(_smaller_of_both_signs(inputs, hover, np.concatenate((np.zeros(3),
                                                                                   vehicle.inertia[:, k]))))
    tilt = hover_tilt_limit(inputs) if vehicle.fully_actuated else None
    model = Authority(1.0, weight, thrust_min, thrust_max, *torques, *accelerations, tilt)
    return model.scaled(margin)
