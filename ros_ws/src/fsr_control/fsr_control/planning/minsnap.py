"""Minimum-snap paths through points: a piecewise 7th-order polynomial at rest at both ends (docs/model.md §3.5).

Points ``q_0 .. q_M`` (world NED [m]; ``q_0`` the start) are joined by ``M`` segments of durations ``T_i`` [s].
Each axis is planned on its own: the path minimises the integral of the squared snap

    J = sum_i integral_0^{T_i} (d^4 p / dt^4)^2 dt

subject to ``p(t_i) = q_i`` at every point and rest at both ends (velocity, acceleration and jerk zero at
``q_0`` and ``q_M``). This is the quadratic program of Mellinger & Kumar (ICRA 2011), in the unconstrained
closed form of Richter, Bry & Roy (ISRR 2013): free derivatives at the inner points, fixed ones at the ends.
Its minimiser is known in closed form (de Boor, *A practical guide to splines*, the ``k = 4`` case of the
minimum-norm interpolating splines): in each segment ``d^8 p / dt^8 = 0`` (a polynomial of degree 7), and at
each inner point the derivatives 1..6 are continuous (only the 7th jumps). Here that is solved directly: per
segment, 8 coefficients ``c_ik`` in ``tau = (t - t_i) / T_i``; 8 equations per inner point (the position on
both sides, continuity of derivatives 1..6) and 4 at each end, one linear system of ``8 M`` unknowns for the
three axes at once. Continuity rows of derivative ``n`` are scaled by ``min(T_i, T_{i+1})^n`` so the system
stays well conditioned whatever the durations.

Segment times: given, or proportional to the distances between the points and scaled together so that the
path's peak speed is a given speed (scaling every duration by ``k`` keeps the shape and divides the n-th
derivative by ``k^n``, so one solve suffices); the peak speed is found exactly from the real roots of
``d |v|^2 / dtau`` in each segment.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.polynomial import polynomial

DEGREE = 7
COEFFICIENTS = DEGREE + 1
CONTINUOUS = 6  # derivatives continuous at an inner point (the 7th jumps)
REST = 3  # derivatives zero at both ends (velocity, acceleration, jerk)

# d^n/dtau^n of tau^k at tau = 1 is falling(k, n): row n, column k
_FALLING = np.array([[math.perm(k, n) for k in range(COEFFICIENTS)] for n in range(COEFFICIENTS)], dtype=float)


def minimum_snap(points: np.ndarray, durations: np.ndarray) -> np.ndarray:
    """The coefficients ``(M, 3, 8)`` of the minimum-snap path through ``points`` (M + 1, 3) with segment
    ``durations`` (M,) [s] > 0 (module docstring): segment ``i``, axis ``a``, ``p = sum_k c[i, a, k] tau^k``
    with ``tau = (t - t_i) / T_i``."""
    points = np.asarray(points, dtype=float)
    durations = np.asarray(durations, dtype=float)
    segments = len(durations)
    if points.shape != (segments + 1, 3):
        raise ValueError(f"need {segments + 1} points (3,) for {segments} segments, got {points.shape}")
    if not np.all(durations > 0.0):
        raise ValueError(f"segment durations must be > 0 s, got {durations.tolist()}")
    size = COEFFICIENTS * segments
    system = np.zeros((size, size))
    rhs = np.zeros((size, 3))
    row = 0

    def put(values: np.ndarray, segment: int, target: np.ndarray | float = 0.0) -> None:
        nonlocal row
        system[row, COEFFICIENTS * segment:COEFFICIENTS * (segment + 1)] += values
        rhs[row] = target
        row += 1

    start = np.zeros(COEFFICIENTS)
    for n in range(REST + 1):  # the start: position q_0, then at rest (c_n = 0)
        start[:] = 0.0
        start[n] = 1.0
        put(start, 0, points[0] if n == 0 else 0.0)
    for n in range(REST + 1):  # the end: position q_M, then at rest
        put(_FALLING[n], segments - 1, points[-1] if n == 0 else 0.0)
    for inner in range(1, segments):
        left, right = inner - 1, inner
        put(_FALLING[0], left, points[inner])
        start[:] = 0.0
        start[0] = 1.0
        put(start, right, points[inner])
        for n in range(1, CONTINUOUS + 1):  # d^n p / dt^n equal on both sides, scaled by min(T)^n
            scale = min(durations[left], durations[right]) ** n
            system[row, COEFFICIENTS * left:COEFFICIENTS * (left + 1)] = _FALLING[n] * scale / durations[left] ** n
            system[row, COEFFICIENTS * right + n] = -math.factorial(n) * scale / durations[right] ** n
            row += 1
    solution = np.linalg.solve(system, rhs)  # (8 M, 3)
    return np.ascontiguousarray(solution.reshape(segments, COEFFICIENTS, 3).transpose(0, 2, 1))


def peak_speed(coefficients: np.ndarray, durations: np.ndarray) -> float:
    """The largest speed [m/s] of a path of coefficients ``(M, 3, 8)`` (:func:`minimum_snap`): ``|v|^2`` at the
    real roots of its derivative in each segment and at the segment ends."""
    best = 0.0
    for segment, duration in zip(coefficients, durations, strict=True):
        velocity = [polynomial.polyder(axis) / duration for axis in segment]  # in tau, [m/s]
        speed_squared = sum(polynomial.polymul(axis, axis) for axis in velocity)
        roots = polynomial.polyroots(polynomial.polyder(speed_squared)) if len(speed_squared) > 1 else np.array([])
        candidates = [0.0, 1.0, *(root.real for root in np.atleast_1d(roots)
                                   if abs(root.imag) < 1e-9 and 0.0 < root.real < 1.0)]
        best = max(best, float(np.max(polynomial.polyval(np.array(candidates), speed_squared))))
    return math.sqrt(best)


def durations_for_speed(points: np.ndarray, speed: float) -> np.ndarray:
    """Segment durations [s] proportional to the distances between ``points`` (M + 1, 3) [m], scaled so that the
    minimum-snap path through them peaks at ``speed`` [m/s] (module docstring)."""
    distances = np.linalg.norm(np.diff(np.asarray(points, dtype=float), axis=0), axis=1)
    if not np.all(distances > 0.0):
        raise ValueError("consecutive points must differ")
    return distances * peak_speed(minimum_snap(points, distances), distances) / speed


def snap_cost(coefficients: np.ndarray, durations: np.ndarray) -> float:
    """``J`` of the module docstring [m^2/s^7] for coefficients ``(M, 3, 8)`` and ``durations`` (M,) [s]."""
    total = 0.0
    for segment, duration in zip(coefficients, durations, strict=True):
        for axis in segment:
            snap = polynomial.polyder(axis, 4)  # in tau: d^4 p / dtau^4
            integral = polynomial.polyint(polynomial.polymul(snap, snap))
            total += float(polynomial.polyval(1.0, integral)) / duration**7
    return total
