"""What a figure shows besides its data: the rules the figures follow, in one place (numpy only).

* **Zoom on a short start transient.** A panel's start transient lasts
  ``T = min {T : max y[t_0 + T, end] - min y[t_0 + T, end] <= q R}``, the max and min over all the panel's
  series from ``t_0 + T`` on, ``R`` their range over the whole axis and ``q =`` :data:`TRANSIENT_LEVEL`
  ``= 1/2``: after ``T`` the data fill at most half of the panel's height, so the excursion that sets the
  other half is over. The transient is *short* when ``T <`` :data:`SHORT_TRANSIENT` ``= 2 %`` of the time
  axis: it is a sliver at the axis' left edge (on ex3's 30 s axis the wrench estimator's settling from zero,
  ``T = 0.07 .. 0.34 s``, and the controller's first 0.1 s). A figure with a short transient in any panel
  gets a zoom on its first ``Z`` seconds beside every panel, ``Z`` the 1-2-5 ceiling (:func:`nice_ceil`) of
  ``max(2 max T, 1 % of the axis)`` over its short panels (ex3: 1 s for the estimate and the tracking
  errors, 0.5 s for the commanded wrench and the mass estimate). A panel flatter than its floor (rounding
  noise, drawn on a fixed axis) has no transient.
* **Limits drawn when near.** A limit of the drawn quantity (rotor speed, tilt angle) is drawn as a line
  when it lies within :data:`LIMIT_NEAR` ``= 10 %`` of the data's range from the data,
  ``lo - 0.1 (hi - lo) <= limit <= hi + 0.1 (hi - lo)``; otherwise the axis is scaled to the data alone.
* **Disturbance windows.** The intervals in which one of the scenario's disturbances acts and which do not
  cover the whole time axis (a step, a ramp table, a sinusoid that starts late:
  :meth:`fsr_sim.model.disturbances.DisturbanceProfile.acting_interval`) are shaded on the time axes,
  overlapping ones merged; a constant wrench or a turbulence field acts all the time and is not shaded.
* **No panel zero by construction.** A vehicle that is not fully actuated
  (:attr:`fsr_sim.model.vehicle.Vehicle.fully_actuated`) flies a controller that commands thrust along
  ``-z_b`` only: its commanded ``f_x`` and ``f_y`` are zero by construction and have no panel.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np

from fsr_sim.model.disturbances import DisturbanceProfile

TRANSIENT_LEVEL = 0.5  # q: a transient is over once a series stays within this share of the panel's range
SHORT_TRANSIENT = 0.02  # a transient shorter than this share of the time axis gets a zoom
ZOOM_FLOOR = 0.01  # the zoom spans at least this share of the time axis
LIMIT_NEAR = 0.1  # a limit within this share of the data's range from the data is drawn


def nice_ceil(value: float) -> float:
    """Smallest ``{1, 2, 5} x 10^k`` at or above ``value`` (> 0)."""
    decade = 10.0 ** math.floor(math.log10(value))
    for step in (1.0, 2.0, 5.0, 10.0):
        if step * decade >= value * (1.0 - 1e-12):
            return step * decade
    return 10.0 * decade


def _finite(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    ok = np.isfinite(y) & np.isfinite(t)
    return t[ok], y[ok]


def start_transient(series: Sequence[tuple[np.ndarray, np.ndarray]], floor: float = 0.0,
                    level: float = TRANSIENT_LEVEL) -> float | None:
    """``T`` [s] of the module docstring for a panel's series ``(t_i, y_i)`` (from the panel's first sample),
    evaluated at the samples of its longest series; None when the panel's range is below ``floor`` (or there
    is no data)."""
    finite = [_finite(np.asarray(t, dtype=float), np.asarray(y, dtype=float)) for t, y in series]
    finite = [(t, y) for t, y in finite if t.size]
    if not finite:
        return None
    span = max(float(y.max()) for _, y in finite) - min(float(y.min()) for _, y in finite)
    if span <= 0.0 or span < floor:
        return None
    t0 = min(float(t[0]) for t, _ in finite)
    grid = max((t for t, _ in finite), key=len)
    high, low = np.full(grid.shape, -np.inf), np.full(grid.shape, np.inf)
    for t, y in finite:  # max and min of every series from each grid time on
        index = np.searchsorted(t, grid)
        later = index < len(t)
        high[later] = np.maximum(high[later], np.maximum.accumulate(y[::-1])[::-1][index[later]])
        low[later] = np.minimum(low[later], np.minimum.accumulate(y[::-1])[::-1][index[later]])
    settled = high - low <= level * span
    return float(grid[np.argmax(settled)] - t0) if settled.any() else float(grid[-1] - t0)


def zoom_span(transients: Iterable[float | None], axis_span: float) -> float | None:
    """Length [s] of the zoom on the first seconds (module docstring), None when no transient is short."""
    short = [t for t in transients if t is not None and t < SHORT_TRANSIENT * axis_span]
    if not short or axis_span <= 0.0:
        return None
    return nice_ceil(max(2.0 * max(short), ZOOM_FLOOR * axis_span))


def limits_near(low: float, high: float, limits: Iterable[float], near: float = LIMIT_NEAR) -> list[float]:
    """The ``limits`` within ``near`` of the data's range ``high - low`` from ``[low, high]``."""
    margin = near * (high - low)
    return [limit for limit in limits if math.isfinite(limit) and low - margin <= limit <= high + margin]


def disturbance_windows(profiles: Iterable[DisturbanceProfile], t_start: float,
                        t_end: float) -> list[tuple[float, float]]:
    """The intervals (start, end) [s] within ``[t_start, t_end]`` in which a disturbance acts, merged where
    they overlap; an interval covering the whole axis is left out (module docstring)."""
    clipped = []
    for profile in profiles:
        interval = profile.acting_interval()
        if interval is None:
            continue
        start, end = max(interval[0], t_start), min(interval[1], t_end)
        if end <= start or (start <= t_start and end >= t_end):
            continue
        clipped.append((start, end))
    merged: list[tuple[float, float]] = []
    for start, end in sorted(clipped):
        if merged and start <= merged[-1][1]:
            merged[-1] = (merged[-1][0], max(merged[-1][1], end))
        else:
            merged.append((start, end))
    return merged
