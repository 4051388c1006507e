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
    path_samples,
    plan_leg,
)
from fsr_control.planning.paths import PathError, PathShape, PathSpec
from fsr_control.planning.polynomial import SepticSegment
from fsr_sim.contract import FINISHED
from fsr_sim.model.frames import E3
from fsr_sim.model.so3 import rotation_exp, rotation_log, skew

APPROACH_TOLERANCE = 1e-9  # m, rad: a path starting this close to the start pose needs no approach leg
BLEND_TURN_MAX = 0.9 * math.pi  # rad: yaw velocity: the most the motion may turn within a ramp (the blend's wrap)
HEADING_FLIP = 0.5 * math.pi  # rad: yaw velocity: a turn of the motion between two of its samples beyond this is a
# vertical passage (the heading flips), not a turn


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
    """Position + angle polynomial and the fixed-axis attitude of one leg (or one row of a path: :meth:`of_path`)."""

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
        self._set(SepticSegment(start_time, duration, start, goal, start_rates), rotation_start, axis, yaw_start)

    def _set(self, poly: SepticSegment, rotation_start: np.ndarray, axis: np.ndarray, yaw_start: float | None,
             path: np.ndarray | None = None, periodic: np.ndarray | None = None,
             heading: np.ndarray | None = None) -> None:
        self.poly = poly
        self.rotation_start = np.array(rotation_start, dtype=float)
        self.axis = np.array(axis, dtype=float)
        # Rodrigues with a fixed unit axis: R_0 exp(theta S(a)) = R_0 + sin(theta) R_0 S + (1 - cos(theta)) R_0 S^2
        s = skew(self.axis)
        self._r0_s = self.rotation_start @ s
        self._r0_s2 = self._r0_s @ s
        self.yaw_start = yaw_start  # set for yaw-only (fixed-rotor) references
        self.start_time = poly.start_time
        self.end_time = poly.end_time
        self.path = np.zeros(core.PATH_WIDTH) if path is None else path  # a leg: KIND_POLYNOMIAL, YAW_CHANNEL
        self.periodic = np.zeros((4, 3)) if periodic is None else periodic
        self.heading = np.zeros((core.HEADING_DERIVATIVES, 2, core.DEGREE + 1)) if heading is None else heading

    @classmethod
    def of_path(cls, poly: SepticSegment, rotation_start: np.ndarray, axis: np.ndarray, yaw_start: float | None,
                path: np.ndarray, periodic: np.ndarray, heading: np.ndarray, end_time: float) -> _Segment:
        """A path's row (:mod:`fsr_control.core.reference`): its position polynomial ``poly`` (zero for a periodic
        row), ``path`` columns, sinusoids and direction of motion, ending at ``end_time`` [s]."""
        segment = cls.__new__(cls)
        segment._set(poly, rotation_start, axis, yaw_start, path, periodic, heading)
        segment.end_time = end_time
        return segment


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
        path=np.ascontiguousarray([s.path for s in segments]),
        periodic=np.ascontiguousarray([s.periodic for s in segments]),
        heading=np.ascontiguousarray([s.heading for s in segments]),
    )


def mid_path(end_reason: str, end_time: float, plan_end_time: float | None) -> bool:
    """A flight that ``finished`` (``end_reason``, :data:`fsr_sim.contract.FINISHED`) at ``end_time`` [s] before its
    plan came to rest at ``plan_end_time`` [s]: it ended mid-path."""
    return end_reason == FINISHED and plan_end_time is not None and end_time < plan_end_time - 1e-9


def mid_path_note(end_time: float, plan_end_time: float) -> str:
    """The line that tells a flight ended mid-path (:func:`mid_path`)."""
    return (f"the flight ended mid-path: it finished at {end_time:.3f} s (the scenario's duration) and its plan comes "
            f"to rest at {plan_end_time:.3f} s; raise duration to at least {math.ceil(plan_end_time * 100) / 100:g} s")


def heading_of(rotation: np.ndarray) -> float:
    """The heading [rad] of a rotation's x axis (body FRD -> world NED)."""
    return math.atan2(rotation[1][0], rotation[0][0])


class Trajectory:
    """Waypoints (or a path) flown from a start pose; ``evaluate(t)`` gives the :class:`Reference` at ``t`` [s]."""

    def __init__(
        self,
        waypoints: list[Waypoint],
        start_position: np.ndarray,
        start_rotation: np.ndarray,
        full_attitude: bool,
        start_time: float = 0.0,
        limits: ReferenceLimits | None = None,
        feasibility: str = DEFAULT_FEASIBILITY,
        path: PathSpec | None = None,
    ) -> None:
        if path is not None and waypoints:
            raise ValueError("a trajectory flies either waypoints or a path, not both")
        self.full_attitude = full_attitude
        self.limits = limits
        self.feasibility = feasibility
        self.adjustments: list[LegAdjustment] = []  # the infeasible legs and goals, in order
        position = np.array(start_position, dtype=float)
        if full_attitude:
            rotation = np.array(start_rotation, dtype=float)
            yaw = None
        else:
            yaw = heading_of(start_rotation)
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
        if path is not None:
            self._plan_path(path, t, position, rotation, yaw)
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

    def _plan_path(self, path: PathSpec, t: float, position: np.ndarray, rotation: np.ndarray,
                   yaw: float | None) -> None:
        """The approach leg to the path's start pose (if it is not the current one), then the path's rows, each
        through the feasibility check (:func:`~fsr_control.planning.feasibility.plan_leg`; the path as a whole,
        stretched in time)."""
        heading = yaw if yaw is not None else heading_of(rotation)
        start_point = path.start_point(position)
        shape = path.shape(start_point)
        probe = _pack(self._path_segments(shape, t, rotation, yaw, np.zeros(core.PATH_WIDTH), 0.0))
        target = {"fixed": heading if path.yaw.yaw is None else path.yaw.yaw, "rate": heading,
                  "velocity": core.direction_heading(probe, 0, t)[0]}[path.yaw.mode]
        target = heading + wrap_angle(target - heading)  # the shorter turn
        distance = float(np.linalg.norm(start_point - position))
        if distance > APPROACH_TOLERANCE or abs(target - heading) > APPROACH_TOLERANCE:
            goal = yaw_rotation(target) if yaw is not None else yaw_rotation(target - heading) @ rotation
            try:
                segment = self._checked_leg("approach", path.approach_time(distance, position), t, position,
                                            rotation, yaw, start_point, goal)
            except InfeasibleReferenceError as error:
                raise InfeasibleReferenceError(str(error), part="approach") from None
            self._append(segment)
            rotation, yaw = self._end_attitude(segment)
            t = segment.end_time
        columns = self._yaw_columns(path, probe, shape, t, rotation, yaw)
        final_angle = {"fixed": 0.0, "rate": path.yaw.rate * (shape.duration - shape.ramp),
                       "velocity": columns[core.PATH_HEADING_END] - columns[core.PATH_YAW_ORIGIN]}[path.yaw.mode]

        def build(duration: float, _angle_duration: float) -> tuple[list[_Segment], core.TrajectoryTable]:
            factor = duration / shape.duration
            scaled = path.shape(start_point, factor)
            stretched = columns.copy()
            stretched[core.PATH_YAW_RATE] /= factor  # the same turn, as much slower as the path
            segments = self._path_segments(scaled, t, rotation, yaw, stretched, final_angle)
            return segments, _pack(segments)

        try:
            segments, adjustment = plan_leg(build, shape.duration, f"{path.kind} path", self.limits,
                                            self.feasibility, path=True)
        except InfeasibleReferenceError as error:
            raise InfeasibleReferenceError(str(error), part="path") from None
        if adjustment is not None:
            self.adjustments.append(adjustment)
        for segment in segments:
            self._append(segment)

    def _yaw_columns(self, path: PathSpec, probe: core.TrajectoryTable, shape: PathShape, t: float,
                     rotation: np.ndarray, yaw: float | None) -> np.ndarray:
        """The path columns of the yaw (``core.PATH_YAW*``, ``PATH_HEADING_*``) for a path starting at ``t`` [s]
        with the attitude ``rotation`` / ``yaw`` (after the approach). ``velocity``: the heading of the motion is
        checked along the path (defined everywhere, turning less than :data:`BLEND_TURN_MAX` within a ramp, so that
        the blend of module :mod:`fsr_control.core.reference` is continuous); :class:`PathError` otherwise."""
        columns = np.zeros(core.PATH_WIDTH)
        heading = yaw if yaw is not None else heading_of(rotation)
        columns[core.PATH_YAW_ORIGIN] = heading
        columns[core.PATH_HEADING_START] = heading
        if path.yaw.mode == "fixed":
            return columns
        if path.yaw.mode == "rate":
            columns[core.PATH_YAW], columns[core.PATH_YAW_RATE] = core.YAW_RATE, path.yaw.rate
            return columns
        columns[core.PATH_YAW] = core.YAW_VELOCITY
        origin = probe.start_time[0]  # the probe's rows start where the path would without an approach
        rows, times = path_samples(probe)
        headings = np.array([core.direction_heading(probe, row, time) for row, time in zip(rows, times, strict=True)])
        # Undefined, or flipping between two samples: the motion is vertical there (or turns back on itself)
        flips = np.abs([wrap_angle(float(step)) for step in np.diff(headings[:, 0])]) > HEADING_FLIP
        undefined = ~np.all(np.isfinite(headings), axis=1) | np.append(flips, False)
        if undefined.any():
            when = times[int(np.argmax(undefined))] - origin
            raise PathError("yaw", f"mode velocity: the path has no horizontal direction of motion {when:.3g} s "
                                   "into it (it moves vertically there, or turns back on itself): use mode fixed "
                                   "or rate")
        arrival = heading + wrap_angle(float(headings[-1, 0]) - heading)
        columns[core.PATH_HEADING_END] = arrival
        for anchor, inside, where in ((heading, times - origin <= shape.ramp, "first"),
                                      (arrival, times - origin >= shape.duration - shape.ramp, "last")):
            turn = np.abs([wrap_angle(float(h) - anchor) for h in headings[inside, 0]])
            if turn.size and turn.max() > BLEND_TURN_MAX:
                raise PathError("ramp", f"yaw mode velocity: the direction of motion turns by "
                                        f"{math.degrees(turn.max()):.0f} deg within the {where} ramp "
                                        f"({shape.ramp:g} s; the yaw blends into it there, at most "
                                        f"{math.degrees(BLEND_TURN_MAX):.0f} deg): shorten trajectory.ramp")
        return columns

    def _path_segments(self, shape: PathShape, t0: float, rotation: np.ndarray, yaw: float | None,
                       columns: np.ndarray, final_angle: float) -> list[_Segment]:
        """The rows of ``shape`` from ``t0`` [s] with the yaw ``columns`` (their kind and clock set here) and the
        angle ``final_angle`` [rad] at the end; the attitude turns about the world's vertical from ``rotation``
        (``R_0 exp(theta S(R_0^T e3)) = Rz(theta) R_0``), or is ``Rz(yaw + theta)``."""
        if yaw is not None:
            rotation_start, axis = yaw_rotation(yaw), E3
        else:
            rotation_start, axis = np.asarray(rotation, dtype=float), np.asarray(rotation, dtype=float)[2]
        columns = columns.copy()
        columns[core.PATH_KIND] = shape.kind
        columns[core.PATH_START], columns[core.PATH_END] = t0, t0 + shape.duration
        columns[core.PATH_RAMP] = shape.ramp
        segments = []
        start = t0
        rows = len(shape.row_durations)
        for row, duration in enumerate(shape.row_durations):
            coefficients = np.vstack((shape.coefficients[row], np.zeros(core.DEGREE + 1)))  # theta: the columns'
            end = shape.end if row == rows - 1 else coefficients[:3].sum(axis=1)
            poly = SepticSegment.from_coefficients(start, duration, coefficients, np.append(end, final_angle))
            segments.append(_Segment.of_path(poly, rotation_start, axis, yaw, columns, shape.periodic.copy(),
                                             shape.heading[row], start + duration))
            start += duration
        segments[-1].end_time = t0 + shape.duration
        return segments

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
