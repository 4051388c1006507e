"""Can the vehicle fly a leg? Its demands from the flat outputs against the authority at hover, and the
shortest durations it can fly (docs/model.md §3.5, *Feasible references*).

A leg's reference (position ``p(t)`` world NED, an angle ``theta(t)`` about a fixed axis ``a``:
:mod:`fsr_control.planning.trajectory`) asks, for perfect tracking, of a vehicle of mass ``m`` and inertia
``I`` (body FRD, gravity ``g`` along the world's ``+z``):

* thrust along ``-z_b`` (quadrotor, octocopter): the thrust vector ``n = g e3 - p''`` (per unit mass), the
  thrust ``u_T = m |n|`` and the attitude ``R_d`` that points ``-z_b`` along ``n`` with the reference's heading,
  with its rates ``omega_d``, ``omega_dot_d`` from ``n' = -p'''``, ``n'' = -p''''`` and the heading's rate and
  acceleration (:func:`fsr_control.core.flatness.attitude_from_thrust_vector`, the geometric law's own);
* full attitude (fully actuated): the reference's ``R_d``, ``omega_d = a theta'``, ``omega_dot_d = a theta''``,
  the body force ``f_b = m R_d^T (p'' - g e3)``, its magnitude ``|f_b|`` (the thrust) and its tilt from
  ``-z_b``, ``acos(-f_z / |f_b|)``; ``f_b`` must lie in the vehicle's force set (the forces with zero torque
  its rotors give in each body direction, :class:`fsr_control.design.authority.ForceSet`): a tilting vehicle
  gives less force sideways than along ``-z_b``;

and in both the body torque ``tau = I omega_dot_d + omega_d x I omega_d`` (with thrust along ``-z_b`` its yaw
part holds the heading's ``I_zz psi''`` and the yaw rate the attitude picks up while tilted about two axes at
once: 0.23 N m on quadrotor_ex4 for 6.2 m in 4 s, beyond its 0.155 N m). The leg is sampled at
:data:`SAMPLES` times over each channel's duration; its peaks must lie within the authority scaled by the
margin (:mod:`fsr_control.design.authority`): the thrust within ``[thrust_min, thrust_max]`` (fully actuated: the
body force within the force set), ``|tau_k|`` within the torque about body axis ``k``, and (fully actuated) the
tilt within ``tilt_max``. Each axis is compared with
what the rotors give about it alone at hover thrust, so a leg that asks for several axes at once near their
limits can pass with little to spare; the margin is that reserve. The peak body rates are reported, not
limited (no rotor limit bounds a rate).

The shortest duration: a leg that starts at rest asks ``d^n/dt^n`` of ``1 / T^n`` of its shape, so its
demands fall as it lengthens; the smallest factor ``k >= 1`` on the durations that makes the leg feasible is
found by doubling and bisection (relative tolerance :data:`FACTOR_TOLERANCE`) and the duration rounded up to
:data:`DURATION_STEP`. ``trajectory.feasibility: stretch`` lengthens the angle alone (*shaped*: the angle's
polynomial takes longer, the position keeps its duration) when that suffices; otherwise (*stretched*) the
position gets the shortest duration it can fly with the angle at its slowest (:data:`MAX_FACTOR`), and the
angle the shortest it can fly beside that position (the same or longer).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from fsr_control.core import reference as core
from fsr_control.core.flatness import ATTITUDE_OK, attitude_from_thrust_vector
from fsr_control.design.authority import Authority, ForceSet
from fsr_control.design.authority_cache import model_authority, model_force_set
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.vehicle import Vehicle

FEASIBILITY_MODES = ("stretch", "warn", "refuse")  # trajectory.feasibility
DEFAULT_FEASIBILITY = "stretch"
SAMPLES = 257  # per leg (both ends included), per path segment, per ramp of a periodic path
CRUISE_SAMPLES = 64  # per period of a periodic path's fastest axis, between its ramps
CRUISE_SAMPLES_MAX = 4096
FACTOR_TOLERANCE = 1e-3  # relative, on the shortest duration
DURATION_STEP = 0.01  # s: shortest durations are rounded up to it
MAX_FACTOR = 1024.0  # beyond it a leg is called infeasible at any duration
AXES = ("roll", "pitch", "yaw")


class InfeasibleReferenceError(ValueError):
    """A leg (or a goal, or a path) the vehicle cannot fly, refused (``trajectory.feasibility: refuse``);
    ``waypoint`` is the index of the scenario's waypoint (None for a goal or a path), ``part`` ``approach`` or
    ``path`` for a path's approach leg or the path itself."""

    def __init__(self, message: str, waypoint: int | None = None, part: str | None = None) -> None:
        super().__init__(message)
        self.waypoint = waypoint
        self.part = part


@dataclass(frozen=True)
class ReferenceLimits:
    """What references may ask of a vehicle: its mass [kg], inertia (3, 3) [kg m^2], whether it flies a full
    attitude, its authority at hover, the model's (``model``) and scaled by the margin (``allowed``), and
    (fully actuated) its force set (``forces``, unscaled: ``allowed.margin`` applies)."""

    mass: float
    inertia: np.ndarray
    full_attitude: bool
    model: Authority
    allowed: Authority
    forces: ForceSet | None = None


def reference_limits(vehicle: Vehicle, margin: float) -> ReferenceLimits:
    """The :class:`ReferenceLimits` of ``vehicle`` (its authority from the cache) with ``margin`` in (0, 1]."""
    model = model_authority(vehicle)
    return ReferenceLimits(vehicle.mass, np.array(vehicle.inertia, dtype=float), vehicle.fully_actuated, model,
                           model.scaled(margin), model_force_set(vehicle))


@dataclass(frozen=True)
class Shortfall:
    """One quantity a leg asks for beyond the allowed: ``needed``, what the rotors give (``model``, ``where``:
    at hover, or along the force's direction) and what the margin allows (``allowed``), in ``unit``."""

    quantity: str
    unit: str
    needed: float
    model: float
    allowed: float
    where: str = "at hover"

    def text(self, margin: float) -> str:
        return (f"needs {self.needed:.3g} {self.unit} of {self.quantity}, the rotors give {self.model:.3g} "
                f"{self.unit} {self.where} ({self.allowed:.3g} with the margin {margin:g})")


@dataclass(frozen=True)
class LegDemand:
    """The peaks of a leg (module docstring): thrust [N], torque magnitude per body axis [N m], tilt [rad]
    (full attitude: of the force from ``-z_b``; thrust along ``-z_b``: of ``-z_b`` from the vertical) and body
    rate magnitude per axis [rad/s]; with a force set, the body force [N] (FRD) that uses the largest share of
    the force the margin allows along it, and that share (``force_share`` <= 1: within the set)."""

    thrust_max: float
    thrust_min: float
    torque: np.ndarray
    tilt: float
    rate: np.ndarray
    force: np.ndarray | None = None
    force_share: float = 0.0

    def shortfalls(self, limits: ReferenceLimits) -> list[Shortfall]:
        """What the leg asks for beyond ``limits.allowed`` (empty: feasible)."""
        model, allowed = limits.model, limits.allowed
        out = []
        if self.force is not None:
            if self.force_share > 1.0:
                magnitude = float(np.linalg.norm(self.force))
                direction = self.force / magnitude
                along = ", ".join(f"{value:.2f}" for value in direction)
                out.append(Shortfall(f"body force along [{along}] (body FRD)", "N", magnitude,
                                     float(limits.forces.reach(direction)[0]),
                                     float(limits.forces.reach(direction, allowed.margin)[0]), "along it"))
        elif self.thrust_max > allowed.thrust_max:
            out.append(Shortfall("thrust", "N", self.thrust_max, model.thrust_max, allowed.thrust_max))
        if self.force is None and self.thrust_min < allowed.thrust_min:
            out.append(Shortfall("minimum thrust (it asks for less)", "N", self.thrust_min, model.thrust_min,
                                 allowed.thrust_min))
        for k, axis in enumerate(AXES):
            limit = getattr(allowed, f"{axis}_torque")
            if self.torque[k] > limit:
                out.append(Shortfall(f"{axis} torque", "N m", float(self.torque[k]),
                                     getattr(model, f"{axis}_torque"), limit))
        if limits.full_attitude and allowed.tilt_max is not None and self.tilt > allowed.tilt_max:
            out.append(Shortfall("tilt", "deg", math.degrees(self.tilt), math.degrees(model.tilt_max),
                                 math.degrees(allowed.tilt_max)))
        return out


def _leg_times(table: core.TrajectoryTable, segment: int) -> np.ndarray:
    """:data:`SAMPLES` times [s] over each distinct channel duration of a leg (the position's motion stays densely
    sampled beside a long angle), from its start to its end."""
    return table.start_time[segment] + np.unique(np.concatenate(
        [np.linspace(0.0, duration, SAMPLES) for duration in np.unique(table.duration[segment])]))


def path_samples(table: core.TrajectoryTable) -> tuple[np.ndarray, np.ndarray]:
    """(rows, times [s]) sampling a path's table, every row over its own span: a polynomial row :data:`SAMPLES`
    times up to the next row's start (its end for the last); a periodic row :data:`SAMPLES` times over each ramp
    and :data:`CRUISE_SAMPLES` per period of its fastest axis between them (at most :data:`CRUISE_SAMPLES_MAX`)."""
    rows, times = [], []
    count = len(table.start_time)
    for row in range(count):
        path = table.path[row]
        if path[core.PATH_KIND] == core.KIND_PERIODIC:
            start, end, ramp = path[core.PATH_START], path[core.PATH_END], path[core.PATH_RAMP]
            frequency = table.periodic[row, core.PERIODIC_FREQUENCY].max()
            cruise = end - start - 2.0 * ramp
            periods = cruise * frequency / (2.0 * math.pi) if frequency > 0.0 else 1.0
            middle = min(CRUISE_SAMPLES_MAX, max(2, math.ceil(CRUISE_SAMPLES * periods)))
            sampled = np.unique(np.concatenate((np.linspace(start, start + ramp, SAMPLES),
                                                np.linspace(start + ramp, end - ramp, middle),
                                                np.linspace(end - ramp, end, SAMPLES))))
        else:
            duration = table.duration[row, 0]
            sampled = table.start_time[row] + np.linspace(0.0, duration, SAMPLES)
            if row < count - 1:
                sampled = sampled[:-1]  # the next row from its start on
        rows.append(np.full(len(sampled), row))
        times.append(sampled)
    return np.concatenate(rows), np.concatenate(times)


def leg_demand(table: core.TrajectoryTable, segment: int, limits: ReferenceLimits) -> LegDemand:
    """The :class:`LegDemand` of row ``segment`` of ``table``, sampled from its start to its end with the
    core's own reference (the samples the control law would get)."""
    times = _leg_times(table, segment)
    return _demand(table, np.full(len(times), segment), times, limits)


def path_demand(table: core.TrajectoryTable, limits: ReferenceLimits) -> LegDemand:
    """The :class:`LegDemand` of a path's whole table (:func:`path_samples`)."""
    return _demand(table, *path_samples(table), limits)


def _demand(table: core.TrajectoryTable, rows: np.ndarray, times: np.ndarray, limits: ReferenceLimits) -> LegDemand:
    """The peaks of the reference of row ``rows[i]`` at ``times[i]`` [s] (:class:`LegDemand`), sampled by the core
    in one call (:func:`fsr_control.core.reference.sample_references`)."""
    samples = np.empty((len(times), core.SAMPLE_WIDTH))
    core.sample_references(table, np.ascontiguousarray(rows, dtype=np.int64), np.ascontiguousarray(times, float),
                           np.empty((core.DERIVATIVES, core.CHANNELS)), samples)
    acceleration = samples[:, core.SAMPLE_ACCELERATION:core.SAMPLE_ACCELERATION + 3]
    rotation = samples[:, core.SAMPLE_ROTATION:core.SAMPLE_ROTATION + 9].reshape(-1, 3, 3)
    thrust = np.empty(len(times))
    tilt = np.empty(len(times))
    omega = samples[:, core.SAMPLE_ANGULAR_VELOCITY:core.SAMPLE_ANGULAR_VELOCITY + 3].copy()
    omega_dot = samples[:, core.SAMPLE_ANGULAR_ACCELERATION:core.SAMPLE_ANGULAR_ACCELERATION + 3].copy()
    forces = np.zeros((len(times), 3))  # body force (full attitude)
    for i, row in enumerate(samples.tolist()):
        if limits.full_attitude:
            force_body = forces[i] = limits.mass * rotation[i].T @ (acceleration[i] - (0.0, 0.0, GRAVITY))
            thrust[i] = np.linalg.norm(force_body)
            tilt[i] = math.acos(max(-1.0, min(1.0, -force_body[2] / thrust[i]))) if thrust[i] > 0.0 else 0.0
            continue
        a, jerk, snap = row[core.SAMPLE_ACCELERATION:], row[core.SAMPLE_JERK:], row[core.SAMPLE_SNAP:]
        n = (-a[0], -a[1], GRAVITY - a[2])
        status, _, rate, rate_dot = attitude_from_thrust_vector(
            n, (-jerk[0], -jerk[1], -jerk[2]), (-snap[0], -snap[1], -snap[2]), row[core.SAMPLE_YAW],
            row[core.SAMPLE_YAW_RATE], row[core.SAMPLE_YAW_ACCELERATION])
        norm = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
        thrust[i] = limits.mass * norm
        if status != ATTITUDE_OK:  # free fall or a horizontal thrust axis: no torque is defined there
            tilt[i], omega[i], omega_dot[i] = math.pi / 2.0, 0.0, 0.0
            continue
        tilt[i] = math.acos(max(-1.0, min(1.0, n[2] / norm)))
        omega[i], omega_dot[i] = rate, rate_dot
    inertia = limits.inertia
    torque = omega_dot @ inertia.T + np.cross(omega, omega @ inertia.T)
    force, share = None, 0.0
    if limits.full_attitude and limits.forces is not None:
        magnitude = np.linalg.norm(forces, axis=1)
        moving = magnitude > 0.0
        shares = np.zeros(len(times))
        with np.errstate(divide="ignore"):  # no force at all along a direction: an infinite share
            shares[moving] = magnitude[moving] / limits.forces.reach(forces[moving] / magnitude[moving, None],
                                                                     limits.allowed.margin)
        peak = int(np.argmax(shares))
        force, share = forces[peak], float(shares[peak])
    return LegDemand(float(thrust.max()), float(thrust.min()), np.abs(torque).max(axis=0), float(tilt.max()),
                     np.abs(omega).max(axis=0), force, share)


def smallest_factor(feasible: Callable[[float], bool], low: float = 1.0) -> float | None:
    """The smallest ``k`` in ``(low, MAX_FACTOR]`` with ``feasible(k)`` (``feasible(low)`` is known false), to
    :data:`FACTOR_TOLERANCE`; None if even ``MAX_FACTOR`` is not."""
    high = 2.0 * low
    while not feasible(high):
        low, high = high, 2.0 * high
        if high > MAX_FACTOR:
            return None
    while high - low > FACTOR_TOLERANCE * low:
        middle = 0.5 * (low + high)
        low, high = (low, middle) if feasible(middle) else (middle, high)
    return high


def rounded_up(duration: float) -> float:
    """``duration`` [s] rounded up to :data:`DURATION_STEP`."""
    return math.ceil(duration / DURATION_STEP - 1e-9) * DURATION_STEP


@dataclass(frozen=True)
class LegAdjustment:
    """An infeasible leg and what the planner did with it.

    ``label`` names it (``leg 2``, ``goal at t = 5.000 s``); ``duration`` is the written one [s];
    ``position_duration`` / ``angle_duration`` [s] the shortest feasible ones (None: none up to
    :data:`MAX_FACTOR`); ``action``: ``shaped`` (the angle lengthened), ``stretched`` (the whole leg),
    ``flown as written`` (``warn``), ``within the limits`` (as written: beyond the margin, within the rotors'
    limits) or ``refused``; ``without_margin``: no duration keeps the margin, the durations are those within
    the rotors' own limits (margin 1).
    """

    label: str
    duration: float
    shortfalls: tuple[Shortfall, ...]
    margin: float
    position_duration: float | None
    angle_duration: float | None
    action: str
    without_margin: bool = False

    def text(self) -> str:
        """One line: what the leg needs, what the rotors give, the shortest duration and what was done."""
        needs = "; ".join(item.text(self.margin) for item in self.shortfalls)
        if self.position_duration is None:
            shortest = f"no duration up to {MAX_FACTOR:g} times as long makes it feasible: change its position or " \
                       "attitude"
        elif self.position_duration == self.duration:
            shortest = f"its angle needs at least {self.angle_duration:.2f} s"
        else:
            shortest = f"it needs at least {self.position_duration:.2f} s" + (
                f" and its angle {self.angle_duration:.2f} s" if self.angle_duration != self.position_duration else "")
        if self.action == "shaped":
            done = f"angle shaped to {self.angle_duration:.2f} s (the position keeps {self.duration:.4g} s)"
        elif self.action == "stretched":
            done = f"stretched to {self.position_duration:.2f} s" + (
                f", its angle shaped to {self.angle_duration:.2f} s"
                if self.angle_duration != self.position_duration else "")
        elif self.action == "within the limits":
            done = "flown as written"
        else:
            done = {"flown as written": "flown as written (trajectory.feasibility: warn)",
                    "refused": "refused (trajectory.feasibility: refuse)"}[self.action]
        if self.without_margin:
            reserve = f"no duration keeps the margin {self.margin:g} (what it holds at rest needs more); "
            shortest = reserve + ("it is within the rotors' limits as written" if self.action == "within the limits"
                                  else f"within the rotors' limits {shortest}")
        return f"{self.label} ({self.duration:.4g} s) {needs}: {shortest}; {done}"

    def as_dict(self) -> dict[str, object]:
        """Plain values (JSON): the label, durations, action and each shortfall."""
        return {"label": self.label, "duration_s": self.duration, "action": self.action,
                "position_duration_s": self.position_duration, "angle_duration_s": self.angle_duration,
                "shortfalls": [vars(item) for item in self.shortfalls]}


def plan_leg(
    build: Callable[[float, float], tuple[object, core.TrajectoryTable]],
    duration: float,
    label: str,
    limits: ReferenceLimits | None,
    mode: str,
    path: bool = False,
) -> tuple[object, LegAdjustment | None]:
    """A leg the vehicle can fly, by ``mode`` (:data:`FEASIBILITY_MODES`), and what was done if it was not.

    ``build(position_duration, angle_duration)`` makes the leg and a one-row table of it; ``duration`` [s] is
    the written one. A feasible leg (or no ``limits``) is built with ``duration`` exactly, as without a check.
    Otherwise ``stretch`` builds it with the shortest durations (module docstring; the angle shaped alone only if
    the leg moves it), ``warn`` as written, ``refuse`` raises. ``path``: ``build`` makes a whole path (its table
    checked by :func:`path_demand`, its angle never shaped apart: ``build`` stretches the path in time).

    Raises
    ------
    InfeasibleReferenceError
        ``refuse``; or ``stretch`` when no duration up to :data:`MAX_FACTOR` times the written one is feasible,
        not even within the rotors' own limits.
    """
    segment, table = build(duration, duration)
    if limits is None:
        return segment, None

    def demand(table: core.TrajectoryTable, limits: ReferenceLimits) -> LegDemand:
        return path_demand(table, limits) if path else leg_demand(table, 0, limits)

    shortfalls = demand(table, limits).shortfalls(limits)
    if not shortfalls:
        return segment, None
    # the leg moves its angle: only then can shaping it help
    turns = not path and table.goal[0, core.CHANNELS - 1] != 0.0
    position, angle, action = _shortest(build, duration, limits, turns, demand)
    without_margin = False
    if position is None and limits.allowed.margin < 1.0:
        # Not even at MAX_FACTOR: what the leg asks for at rest (a tilted pose held) is beyond the margin. Within
        # the rotors' own limits it can still be flown: the shortest durations there.
        model_limits = replace(limits, allowed=limits.model)
        if not demand(table, model_limits).shortfalls(model_limits):
            position, angle, action = duration, duration, "within the limits"
        else:
            position, angle, action = _shortest(build, duration, model_limits, turns, demand)
        without_margin = position is not None
    if mode == "warn":
        action = "flown as written"
    elif mode == "refuse" or position is None:
        action = "refused"
    adjustment = LegAdjustment(label, duration, tuple(shortfalls), limits.allowed.margin, position, angle, action,
                               without_margin)
    if action == "refused":
        raise InfeasibleReferenceError(adjustment.text())
    if action in ("flown as written", "within the limits"):
        return segment, adjustment
    return build(position, angle)[0], adjustment


def _shortest(build: Callable[[float, float], tuple[object, core.TrajectoryTable]], duration: float,
              limits: ReferenceLimits, turns: bool,
              demand: Callable[[core.TrajectoryTable, ReferenceLimits], LegDemand],
              ) -> tuple[float | None, float | None, str]:
    """(position duration, angle duration, ``shaped`` or ``stretched``) of the shortest feasible leg (module
    docstring); durations None when none up to :data:`MAX_FACTOR` is."""

    def feasible(position_duration: float, angle_duration: float) -> bool:
        return not demand(build(position_duration, angle_duration)[1], limits).shortfalls(limits)

    slowest_angle = MAX_FACTOR * duration
    if turns and feasible(duration, slowest_angle):
        return duration, rounded_up(smallest_factor(lambda k: feasible(duration, k * duration)) * duration), "shaped"
    factor = smallest_factor(lambda k: feasible(k * duration, slowest_angle))
    if factor is None:
        return None, None, "stretched"
    position = angle = rounded_up(factor * duration)
    if not feasible(position, position):
        angle = rounded_up(smallest_factor(lambda k: feasible(position, k * duration), position / duration)
                           * duration)
    return position, angle, "stretched"
