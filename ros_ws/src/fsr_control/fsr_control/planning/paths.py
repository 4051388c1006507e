"""Paths at speed (``trajectory.kind`` minsnap, circle, lissajous): their shape as rows of the core's table.

Each kind is a path specification that gives, for the vehicle's start position and a time scale ``k``
(:meth:`PathSpec.shape`; ``k > 1`` flies the same path slower, as the feasibility check stretches it), the
rows the compiled sampler evaluates (:mod:`fsr_control.core.reference`, docs/model.md §3.5):

* ``minsnap``: the minimum-snap polynomial through the points (:mod:`fsr_control.planning.minsnap`), one
  polynomial row per segment, from the start position, at rest at both ends; segment times given per point or
  from the path's peak speed; every duration times ``k``;
* ``circle``: ``p = c + R (cos(w s) e_1 + sin(w s) e_2)`` in the plane normal to ``n``, ``e_1`` towards the
  start position (the circle starts at its point nearest to it), ``e_2 = n x e_1`` (counterclockwise seen
  from the side ``n`` points to; clockwise: ``-n x e_1``), ``w = speed / R`` or ``2 pi / period``; written as one
  sinusoid per world axis (``A cos x + B sin x = sqrt(A^2 + B^2) sin(x + atan2(A, B))``), a periodic row;
* ``lissajous``: ``p_k = c_k + A_k sin(2 pi f_k s + phi_k)`` per world axis, a periodic row.

A periodic path runs on the ramped clock ``s(t)`` (:func:`fsr_control.core.reference.ramp_clock`): its path time
``s_total = laps x period`` (or ``duration - ramp``) takes ``duration = s_total + ramp``; ``k`` divides every
frequency and multiplies the ramp and the duration. The yaw (:class:`YawSpec`) is the trajectory's to add.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
from numpy.polynomial import polynomial

from fsr_control.core import reference as core
from fsr_control.planning.minsnap import DEGREE, durations_for_speed, minimum_snap, peak_speed

PATH_KINDS = ("waypoints", "minsnap", "circle", "lissajous")  # trajectory.kind
YAW_MODES = ("fixed", "velocity", "rate")  # trajectory.yaw.mode
CIRCLE_NORMALS = {"xy": (0.0, 0.0, -1.0), "xz": (0.0, 1.0, 0.0), "yz": (1.0, 0.0, 0.0)}  # seen from up, east, north
DIRECTIONS = ("counterclockwise", "clockwise")
MINSNAP_RAMP_S = 1.0  # default ramp of a minsnap path's yaw: at most this, and at most a quarter of the path
APPROACH_MIN_S = 2.0  # default approach: at least this
APPROACH_SPEED_SHARE = 0.5  # default approach: its peak speed is this share of the path's
SEPTIC_PEAK_SPEED = 35.0 / 16.0  # a rest-to-rest septic's peak speed, times its distance over its duration
PERIOD_DENOMINATOR = 1000  # lissajous laps: frequencies as fractions with denominators up to this (to 1e-9)


class PathError(ValueError):
    """A path that cannot be planned as written; ``key``: the ``trajectory`` key to change."""

    def __init__(self, key: str, message: str) -> None:
        super().__init__(message)
        self.key = key


@dataclass(frozen=True)
class YawSpec:
    """``trajectory.yaw``: ``fixed`` (at ``yaw`` [rad], default the heading at the path's start), ``velocity``
    (the heading of the horizontal direction of motion) or ``rate`` (``rate`` [rad/s], ramped with the path)."""

    mode: str = "fixed"
    yaw: float | None = None
    rate: float = 0.0


@dataclass(frozen=True)
class PathShape:
    """A path's rows at one time scale (module docstring): ``kind`` (``core.KIND_*``), the clock ``duration``
    [s] (ramps included) and ``ramp`` [s]; per row its duration [s], position coefficients (rows, 3, 8) in its
    ``tau`` (zero for a periodic row) and direction of motion ``heading`` (rows, 3, 2, 8) (the core's layout);
    the sinusoids (``core.PERIODIC_*`` rows, (4, 3); zero for a polynomial path) and the end position [m]."""

    kind: float
    duration: float
    ramp: float
    row_durations: np.ndarray
    coefficients: np.ndarray
    heading: np.ndarray
    periodic: np.ndarray
    end: np.ndarray


class PathSpec:
    """What every path kind gives the trajectory (module docstring)."""

    kind: str
    yaw: YawSpec
    approach_duration: float | None  # [s] of the leg to the path's start pose (None: from the distance)

    def start_point(self, start: np.ndarray) -> np.ndarray:
        """Where the path starts [m], from the vehicle's start position ``start``."""
        raise NotImplementedError

    def shape(self, start: np.ndarray, factor: float = 1.0) -> PathShape:
        """The rows from the start position ``start``, flown ``factor`` (>= 1) times slower."""
        raise NotImplementedError

    def peak_speed(self, start: np.ndarray) -> float:
        """The path's peak speed [m/s] as written."""
        raise NotImplementedError

    def approach_time(self, distance: float, start: np.ndarray) -> float:
        """The approach leg's duration [s] over ``distance`` [m]: ``approach_duration``, or at least
        :data:`APPROACH_MIN_S` with a peak speed :data:`APPROACH_SPEED_SHARE` of the path's."""
        if self.approach_duration is not None:
            return self.approach_duration
        speed = APPROACH_SPEED_SHARE * self.peak_speed(start)
        return max(APPROACH_MIN_S, SEPTIC_PEAK_SPEED * distance / speed if speed > 0.0 else 0.0)


def _heading_rows(tau_coefficients: np.ndarray, duration: float, first: bool, last: bool) -> np.ndarray:
    """(3, 2, 8): the direction of motion of a polynomial row, ``dp/dtau`` (x, y) divided by ``tau^3`` at a rest
    start and by ``(1 - tau)^3`` at a rest end (positive factors: the same heading, defined at rest), and its 1st
    and 2nd time derivatives, in powers of ``tau`` (:func:`fsr_control.core.reference.direction_heading`)."""
    out = np.zeros((core.HEADING_DERIVATIVES, 2, DEGREE + 1))
    for c in range(2):
        direction = polynomial.polyder(tau_coefficients[c])
        if first:
            direction = direction[3:] if len(direction) > 3 else np.zeros(1)
        if last:
            direction = polynomial.polydiv(direction, (1.0, -3.0, 3.0, -1.0))[0]  # (1 - tau)^3
        for n in range(core.HEADING_DERIVATIVES):
            values = polynomial.polyder(direction, n) / duration**n if len(direction) > n else np.zeros(1)
            out[n, c, :len(values)] = values
    return out


@dataclass(frozen=True, kw_only=True, eq=False)
class MinSnapPath(PathSpec):
    """``kind: minsnap``: through ``points`` (M, 3) [m] after the start position, segment ``durations`` (M,) [s]
    or the peak ``speed`` [m/s]; ``ramp`` [s] blends the yaw at both ends (None: :data:`MINSNAP_RAMP_S`, at most a
    quarter of the path)."""

    points: np.ndarray
    durations: np.ndarray | None
    speed: float | None
    yaw: YawSpec = YawSpec()
    ramp: float | None = None
    approach_duration: float | None = None
    kind: str = "minsnap"

    def start_point(self, start: np.ndarray) -> np.ndarray:
        return np.asarray(start, dtype=float)

    def _solved(self, start: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        points = np.vstack((np.asarray(start, dtype=float), self.points))
        durations = self.durations if self.durations is not None else durations_for_speed(points, self.speed)
        return points, np.asarray(durations, dtype=float), minimum_snap(points, durations)

    def shape(self, start: np.ndarray, factor: float = 1.0) -> PathShape:
        points, durations, coefficients = self._solved(start)
        total = float(durations.sum())
        ramp = min(MINSNAP_RAMP_S, 0.25 * total) if self.ramp is None else self.ramp
        if ramp > 0.5 * total:
            raise PathError("ramp", f"must be at most half the path's duration ({0.5 * total:.3g} s), got {ramp:g}")
        durations = durations * factor
        rows = len(durations)
        heading = np.array([_heading_rows(coefficients[i], durations[i], i == 0, i == rows - 1) for i in range(rows)])
        return PathShape(core.KIND_POLYNOMIAL, total * factor, ramp * factor, durations, coefficients, heading,
                         np.zeros((4, 3)), points[-1].copy())

    def peak_speed(self, start: np.ndarray) -> float:
        _, durations, coefficients = self._solved(start)
        return peak_speed(coefficients, durations)


@dataclass(frozen=True, kw_only=True, eq=False)
class PeriodicPath(PathSpec):
    """A path of one sinusoid per world axis (circle, lissajous; module docstring): the clock ``duration`` [s] and
    ``ramp`` [s] as written."""

    duration: float
    ramp: float

    def sinusoids(self, start: np.ndarray) -> np.ndarray:
        """(4, 3): centre [m], amplitude [m], angular frequency [rad/s], phase [rad] per world axis."""
        raise NotImplementedError

    def start_point(self, start: np.ndarray) -> np.ndarray:
        waves = self.sinusoids(start)
        return waves[core.PERIODIC_CENTRE] + waves[core.PERIODIC_AMPLITUDE] * np.sin(waves[core.PERIODIC_PHASE])

    def shape(self, start: np.ndarray, factor: float = 1.0) -> PathShape:
        waves = self.sinusoids(start)
        waves[core.PERIODIC_FREQUENCY] /= factor
        duration, ramp = self.duration * factor, self.ramp * factor
        path_time = duration - ramp
        end = waves[core.PERIODIC_CENTRE] + waves[core.PERIODIC_AMPLITUDE] * np.sin(
            waves[core.PERIODIC_FREQUENCY] * path_time + waves[core.PERIODIC_PHASE])
        return PathShape(core.KIND_PERIODIC, duration, ramp, np.array([duration]), np.zeros((1, 3, DEGREE + 1)),
                         np.zeros((1, core.HEADING_DERIVATIVES, 2, DEGREE + 1)), waves, end)

    def peak_speed(self, start: np.ndarray) -> float:
        waves = self.sinusoids(start)
        frequency = waves[core.PERIODIC_FREQUENCY]
        longest = 2.0 * math.pi / frequency[frequency > 0.0].min() if np.any(frequency > 0.0) else 1.0
        s = np.linspace(0.0, longest, 4097)[:, None]
        velocity = waves[core.PERIODIC_AMPLITUDE] * frequency * np.cos(frequency * s + waves[core.PERIODIC_PHASE])
        return float(np.linalg.norm(velocity, axis=1).max())


def _unit(vector: np.ndarray) -> np.ndarray:
    return vector / np.linalg.norm(vector)


@dataclass(frozen=True, kw_only=True, eq=False)
class CirclePath(PeriodicPath):
    """``kind: circle`` of ``centre`` [m] and ``radius`` [m] in the plane normal to ``normal`` (unit, NED), at the
    angular rate ``rate`` [rad/s], ``direction`` counterclockwise or clockwise seen from the normal's side."""

    centre: np.ndarray
    radius: float
    normal: np.ndarray
    rate: float
    direction: str = "counterclockwise"
    yaw: YawSpec = YawSpec()
    approach_duration: float | None = None
    kind: str = "circle"

    def axes(self, start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(e_1, e_2)``: towards the start position in the plane (else north, else east), and along the motion."""
        normal = _unit(np.asarray(self.normal, dtype=float))
        for towards in (np.asarray(start, dtype=float) - self.centre, np.array((1.0, 0.0, 0.0)),
                        np.array((0.0, 1.0, 0.0))):
            in_plane = towards - normal * float(normal @ towards)
            if np.linalg.norm(in_plane) > 1e-9 * max(1.0, self.radius):
                first = _unit(in_plane)
                break
        second = np.cross(normal, first)
        return first, (second if self.direction == "counterclockwise" else -second)

    def sinusoids(self, start: np.ndarray) -> np.ndarray:
        first, second = self.axes(start)
        cosine, sine = self.radius * first, self.radius * second  # p = c + cos(w s) R e_1 + sin(w s) R e_2
        return np.array((np.asarray(self.centre, dtype=float), np.hypot(cosine, sine), np.full(3, self.rate),
                         np.arctan2(cosine, sine)))


@dataclass(frozen=True, kw_only=True, eq=False)
class LissajousPath(PeriodicPath):
    """``kind: lissajous``: ``centre`` [m], ``amplitude`` [m], ``frequency`` [rad/s] and ``phase`` [rad] per world
    axis."""

    centre: np.ndarray
    amplitude: np.ndarray
    frequency: np.ndarray
    phase: np.ndarray
    yaw: YawSpec = YawSpec()
    approach_duration: float | None = None
    kind: str = "lissajous"

    def sinusoids(self, start: np.ndarray) -> np.ndarray:
        return np.array((self.centre, self.amplitude, self.frequency, self.phase), dtype=float)


def common_period(frequencies_hz: np.ndarray) -> float | None:
    """The period [s] after which sinusoids of ``frequencies_hz`` (> 0) all repeat (``1 / gcd``), or None when
    they have none (a frequency not a fraction of denominator up to :data:`PERIOD_DENOMINATOR`)."""
    fractions = []
    for value in frequencies_hz:
        fraction = Fraction(float(value)).limit_denominator(PERIOD_DENOMINATOR)
        if abs(float(fraction) - value) > 1e-9 * value:
            return None
        fractions.append(fraction)
    numerator = math.gcd(*(f.numerator for f in fractions))
    denominator = math.lcm(*(f.denominator for f in fractions))
    return float(Fraction(denominator, numerator))
