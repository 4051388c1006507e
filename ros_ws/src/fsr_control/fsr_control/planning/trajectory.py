"""Waypoint trajectories: rest-to-rest 7th-order segments with holds, and goals received at run time.

Frames and units: positions world NED [m]; ``rotation`` ``R_d`` maps the desired body frame (FRD) to the
world; ``angular_velocity`` / ``angular_acceleration`` are ``omega_d`` / ``omega_dot_d`` in the desired body
frame [rad/s, rad/s^2] (the quantities of docs/model.md §3.6-3.7).

Each segment moves the position and one angle ``theta`` with the polynomial of :mod:`polynomial`, and the
attitude about a fixed axis ``a`` (docs/model.md §3.5):

    R_d(t) = R_0 exp(theta(t) S(a)),   omega_d = a theta_dot,   omega_dot_d = a theta_ddot.

* ``full_attitude=False`` (quadrotor, octocopter): ``R_0 = Rz(psi_0)``, ``a = e3`` and ``theta`` the yaw
  change wrapped to (-pi, pi], so ``R_d = Rz(psi_d)`` with ``psi_d = psi_0 + theta`` (roll = pitch = 0).
* ``full_attitude=True`` (tilting rotors): ``a, theta_f`` are the axis and angle of ``R_0^T R_f``.

Waypoints are flown in order, each starting when the previous one has arrived and held for its ``hold``;
after the last the reference holds the final pose. :meth:`Trajectory.replan` drops whatever is left and
plans from the current reference to a new goal: the position and ``theta`` keep the reference's velocity,
acceleration and jerk (smooth even mid-motion); the start's angular rate is projected on the new axis
(exact for yaw-only references; for a tilting vehicle replanned mid-rotation the rate about other axes
restarts from zero).

With ``limits`` (:class:`~fsr_control.planning.feasibility.ReferenceLimits`) every leg, and every goal
replanned to, is first checked against the vehicle's authority (:mod:`fsr_control.planning.feasibility`):
``feasibility`` ``stretch`` flies an infeasible leg with its angle shaped (the angle's polynomial lengthened,
the position on time) or the whole leg stretched to the shortest feasible duration, ``warn`` flies it as
written, ``refuse`` raises :class:`~fsr_control.planning.feasibility.InfeasibleReferenceError`. Each infeasible
leg is listed in :attr:`Trajectory.adjustments`. A feasible leg is exactly the leg without a check.

Construction and replanning are Python (they run once, or once per goal); sampling the reference at a time is
the compiled core's (:mod:`fsr_control.core.reference`) on the table :meth:`Trajectory.table` packs.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

from fsr_control.core import reference as core
from fsr_control.planning.feasibility import (
    DEFAULT_FEASIBILITY,
    InfeasibleReferenceError,
    LegAdjustment,
    ReferenceLimits,
    plan_leg,
)
from fsr_control.planning.polynomial import SepticSegment
from fsr_sim.model.frames import E3
from fsr_sim.model.so3 import rotation_exp, rotation_log, skew


def yaw_rotation(yaw_rad: float) -> np.ndarray:
    """``Rz(psi)`` (body FRD -> world NED)."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array(((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0)))


def wrap_angle(angle_rad: float) -> float:
    """Angle wrapped to (-pi, pi]."""
    wrapped = math.remainder(angle_rad, 2.0 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped


@dataclass(frozen=True)
class Waypoint:
    """A target pose: position world NED [m], rotation body->world (None: keep the previous attitude),
    travel time [s] > 0 and hold after arrival [s] >= 0."""

    position: np.ndarray
    rotation: np.ndarray | None
    duration: float
    hold: float = 0.0


@dataclass(frozen=True)
class Reference:
    """The desired state at ``time`` [s] (see the module docstring for frames).

    ``jerk`` and ``snap`` are the 3rd and 4th derivatives of the position (world, m/s^3, m/s^4), used for
    the flatness-based angular feed-forward of the geometric controller. ``yaw`` [rad] is the heading of
    ``R_d``'s x axis; ``yaw_rate`` and ``yaw_acceleration`` are the world-z components of ``R_d omega_d`` and
    ``R_d omega_dot_d`` (for a yaw-only reference: ``psi_dot``, ``psi_ddot``).
    """

    time: float
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray
    snap: np.ndarray
    rotation: np.ndarray
    angular_velocity: np.ndarray
    angular_acceleration: np.ndarray
    yaw: float
    yaw_rate: float
    yaw_acceleration: float

    @classmethod
    def from_sample(cls, t: float, sample: core.ReferenceSample) -> Reference:
        """The :class:`Reference` at ``t`` [s] of the core's :class:`~fsr_control.core.reference.ReferenceSample`."""
        return cls(t, *(np.array(value) for value in sample[:8]), float(sample.yaw), float(sample.yaw_rate),
                   float(sample.yaw_acceleration))


class _Segment:
    """Position + angle polynomial and the fixed-axis attitude of one leg."""

    def __init__(
        self,
        start_time: float,
        duration: float | np.ndarray,
        position: tuple[np.ndarray, np.ndarray],
        rotation_start: np.ndarray,
        axis: np.ndarray,
        angle: float,
        yaw_start: float | None,
        start_rates: np.ndarray | None = None,
    ) -> None:
        start = np.append(position[0], 0.0)
        goal = np.append(position[1], angle)
        self.poly = SepticSegment(start_time, duration, start, goal, start_rates)
        self.rotation_start = np.array(rotation_start, dtype=float)
        self.axis = np.array(axis, dtype=float)
        # Rodrigues with a fixed unit axis: R_0 exp(theta S(a)) = R_0 + sin(theta) R_0 S + (1 - cos(theta)) R_0 S^2
        s = skew(self.axis)
        self._r0_s = self.rotation_start @ s
        self._r0_s2 = self._r0_s @ s
        self.yaw_start = yaw_start  # set for yaw-only (fixed-rotor) references
        self.start_time = start_time
        self.end_time = self.poly.end_time


def _pack(segments: list[_Segment]) -> core.TrajectoryTable:
    """The core's table of ``segments``."""
    return core.TrajectoryTable(
        start_time=np.array([s.start_time for s in segments]),
        duration=np.ascontiguousarray([s.poly.durations for s in segments]),
        coefficients=np.ascontiguousarray([s.poly.table for s in segments]),
        goal=np.ascontiguousarray([s.poly.goal for s in segments]),
        rotation_start=np.ascontiguousarray([s.rotation_start for s in segments]),
        r0_s=np.ascontiguousarray([s._r0_s for s in segments]),
        r0_s2=np.ascontiguousarray([s._r0_s2 for s in segments]),
        axis=np.ascontiguousarray([s.axis for s in segments]),
        yaw_start=np.array([np.nan if s.yaw_start is None else s.yaw_start for s in segments]),
    )

class Trajectory:
    """Waypoints flown from a start pose; ``evaluate(t)`` gives the :class:`Reference` at ``t`` [s]."""

    def __init__(
        self,
        waypoints: list[Waypoint],
        start_position: np.ndarray,
        start_rotation: np.ndarray,
        full_attitude: bool,
        start_time: float = 0.0,
        limits: ReferenceLimits | None = None,
        feasibility: str = DEFAULT_FEASIBILITY,
    ) -> None:
        self.full_attitude = full_attitude
        self.limits = limits
        self.feasibility = feasibility
        self.adjustments: list[LegAdjustment] = []  # the infeasible legs and goals, in order
        position = np.array(start_position, dtype=float)
        if full_attitude:
            rotation = np.array(start_rotation, dtype=float)
            yaw = None
        else:
            yaw = math.atan2(start_rotation[1][0], start_rotation[0][0])
            rotation = yaw_rotation(yaw)
        self._segments: list[_Segment] = []
        self._starts: list[float] = []
        t = float(start_time)
        # A zero-length rest segment so that the reference is defined from the start time on.
        self._append(_Segment(t, 1.0, (position, position), rotation, E3, 0.0, yaw))
        self._segments[0].end_time = t
        for index, waypoint in enumerate(waypoints, start=1):
            goal_rotation = rotation if waypoint.rotation is None else np.asarray(waypoint.rotation, dtype=float)
            try:
                segment = self._checked_leg(f"leg {index}", waypoint.duration, t, position, rotation, yaw,
                                            waypoint.position, goal_rotation)
            except InfeasibleReferenceError as error:
                raise InfeasibleReferenceError(str(error), waypoint=index - 1) from None
            self._append(segment)
            position = np.array(waypoint.position, dtype=float)
            rotation, yaw = self._end_attitude(segment)
            t += segment.poly.duration + waypoint.hold
        self._table: core.TrajectoryTable | None = None

    @property
    def end_time(self) -> float:
        """Arrival time [s] at the last goal (the reference holds it afterwards)."""
        return self._segments[-1].end_time

    def _append(self, segment: _Segment) -> None:
        self._table = None
        self._segments.append(segment)
        self._starts.append(segment.start_time)

    def _end_attitude(self, segment: _Segment) -> tuple[np.ndarray, float | None]:
        angle = segment.poly.goal[3]
        if segment.yaw_start is not None:
            yaw = segment.yaw_start + angle
            return yaw_rotation(yaw), yaw
        return segment.rotation_start @ rotation_exp(segment.axis * angle), None

    def _leg(
        self,
        t0: float,
        duration: float | np.ndarray,
        position: np.ndarray,
        rotation: np.ndarray,
        yaw: float | None,
        goal_position: np.ndarray,
        goal_rotation: np.ndarray,
        start_rates: np.ndarray | None = None,
        start_axis: np.ndarray | None = None,
    ) -> _Segment:
        """A segment from a pose to a goal pose over ``duration`` [s] (one, or (4,): per channel);
        ``start_rates`` (3, 4) carry the current motion."""
        if yaw is not None:
            goal_yaw = math.atan2(goal_rotation[1][0], goal_rotation[0][0])
            axis, angle = E3, wrap_angle(goal_yaw - yaw)
        else:
            axis, angle = rotation_log(np.asarray(rotation).T @ goal_rotation)
            if angle == 0.0 and start_axis is not None:
                axis = start_axis
        if start_rates is not None and start_axis is not None:
            start_rates = start_rates.copy()
            start_rates[:, 3] *= float(axis @ start_axis)  # keep the rate component about the new axis
        return _Segment(t0, duration, (position, np.asarray(goal_position, dtype=float)), rotation, axis, angle,
                        yaw, start_rates)

    def _checked_leg(self, label: str, duration: float, *leg: object) -> _Segment:
        """:meth:`_leg` (arguments after the duration) through the feasibility check (module docstring)."""
        def build(position_duration: float, angle_duration: float) -> tuple[_Segment, core.TrajectoryTable]:
            durations = position_duration if angle_duration == position_duration else \
                np.array((position_duration,) * 3 + (angle_duration,))
            segment = self._leg(leg[0], durations, *leg[1:])
            return segment, _pack([segment])

        segment, adjustment = plan_leg(build, duration, label, self.limits, self.feasibility)
        if adjustment is not None:
            self.adjustments.append(adjustment)
        return segment

    def table(self) -> core.TrajectoryTable:
        """The segments as the core's :class:`~fsr_control.core.reference.TrajectoryTable` (packed once per plan)."""
        if self._table is None:
            self._table = _pack(self._segments)
        return self._table

    def _sample(self, t: float) -> tuple[int, np.ndarray, core.ReferenceSample]:
        """(active segment, its channel derivatives (5, 4), the reference) at ``t`` [s]."""
        table = self.table()
        segment = core.active_segment(table, t)
        derivatives = np.empty((core.DERIVATIVES, core.CHANNELS))
        core.channel_derivatives(table, segment, t, derivatives)
        return segment, derivatives, core.reference_from_derivatives(table, segment, derivatives)

    def evaluate(self, t: float) -> Reference:
        """The desired state at ``t`` [s]."""
        t = float(t)
        return Reference.from_sample(t, self._sample(t)[2])

    def replan(self, goal_position: np.ndarray, goal_rotation: np.ndarray, now: float, duration: float) -> None:
        """Plan from the reference at ``now`` [s] to a new goal pose over ``duration`` [s] (then hold).

        Waypoints not yet reached are dropped. For a yaw-only trajectory only the goal's yaw is used. The goal
        is checked like a leg (module docstring; ``refuse`` raises before anything is changed).
        """
        index, derivatives, sample = self._sample(float(now))
        active = self._segments[index]
        reference = Reference.from_sample(now, sample)
        start_rates = derivatives[1:4]
        if self.full_attitude:
            yaw = None
            rotation = reference.rotation
        else:
            yaw = active.yaw_start + derivatives[0, 3]
            rotation = yaw_rotation(yaw)
        segment = self._checked_leg(f"goal at t = {now:.3f} s", duration, now, reference.position, rotation, yaw,
                                    goal_position, goal_rotation, start_rates, active.axis)
        keep = bisect.bisect_left(self._starts, now)
        del self._segments[keep:]
        del self._starts[keep:]
        self._append(segment)
