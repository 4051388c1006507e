"""Quality of a wrench estimate against a constant true wrench (docs/model.md §5), vectorised over channels.

Channels are the 6 components of ``w_hat`` (``fx fy fz tx ty tz``) in whatever frame the truth is given
in; the report compares the world force and the eta-coordinate torque with ``[1, 1, 0, 0, 0, -0.4]``.

Three settling-time definitions (tolerance 3 % of ``|truth|``):

* ``standard`` (default): the time after which ``|error|`` stays within the band to the end of the log,
  ``t[k] - t[0]`` of the first sample of that final stretch (0 if it never leaves the band).
* ``report``: the first sample ``k`` at which the moving maximum of the *signed* error
  ``w_hat - truth`` over the window from 2 s before to 4 s after ``k`` is within the band, reported as
  ``k * T_s`` with ``k`` counted from 1. This reproduces the report's Table 3 (and inherits its flaws: the
  look-back adds 2 s and an estimate below the truth counts as settled).
* ``smoothed``: ``standard`` on the estimate and the truth after a first-order low-pass of time constant
  :data:`SMOOTHING_TIME_CONSTANT_S` (0.1 s), ``y_k = g x_k + (1 - g) y_(k-1)``, ``g = 1 - exp(-T_s / 0.1)``,
  ``y_0 = x_0``: with sensor noise (or a lagging actuator in the truth) the raw error never stays within 3 % of
  the truth, the filtered one does; the filter delays a settling by up to a few tenths of a second (causal, so
  a sweep computes it as it flies).

Undefined values (a zero true value has no 3 % band; a log that ends outside the band) are NaN.

The truth is a constant (C,) (the report's injected wrench) or a series (N, C) sampled with the estimate
(the effective truth of ``fsr-analyze``, which changes along a flight); the band is then taken per sample
and a channel has a settling time when its final true value is not zero.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from fsr_estimation.core.smoothing import low_pass_columns
from fsr_estimation.estimator.filter_design import check_filter_parameters
from fsr_estimation.estimator.momentum import observer_input
from fsr_estimation.estimator.observer import ObserverModel, filter_observer_input

CHANNELS = ("fx", "fy", "fz", "tx", "ty", "tz")
SETTLING_DEFINITIONS = ("standard", "report", "smoothed")
TOLERANCE = 0.03
REPORT_LOOK_BACK = 2.0  # s
REPORT_LOOK_AHEAD = 4.0  # s
SMOOTHING_TIME_CONSTANT_S = 0.1  # s: the low-pass of the smoothed settling time
DEFAULT_LAST_SECONDS = 5.0  # s: max error over the end of the log (the report: after 25 s of 30 s)


class FlightLogLike(Protocol):
    time: np.ndarray
    velocity_world: np.ndarray
    eta: np.ndarray
    eta_dot: np.ndarray
    force_body: np.ndarray
    torque_body: np.ndarray


def sample_times(time: ArrayLike, definition: str = "standard") -> np.ndarray:
    """Time of each sample [s] under a settling ``definition``: ``t - t[0]`` or the report's ``k T_s``
    (k from 1, ``T_s`` the mean sample time)."""
    t = np.asarray(time, dtype=float)
    if definition == "report":
        sample_time = (t[-1] - t[0]) / (len(t) - 1)
        return np.arange(1, len(t) + 1) * sample_time
    if definition in ("standard", "smoothed"):
        return t - t[0]
    raise ValueError(f"settling definition must be one of {', '.join(SETTLING_DEFINITIONS)}; got '{definition}'")


def settling_time_standard(time: ArrayLike, estimate: ArrayLike, truth: ArrayLike,
                           tolerance: float = TOLERANCE) -> np.ndarray:
    """Time [s] after which ``|w_hat - truth| <= tolerance |truth|`` holds to the end, per channel, shape (C,).

    time (N,) [s]; estimate (N, C); truth (C,) or (N, C). NaN for a zero (final) truth or an error outside the
    band at the end.
    """
    t = sample_times(time, "standard")
    e = np.abs(np.asarray(estimate, dtype=float) - np.asarray(truth, dtype=float))
    band = tolerance * np.abs(np.broadcast_to(np.asarray(truth, dtype=float), e.shape))
    outside = e > band
    n = len(t)
    # Index of the last sample outside the band (-1 when none), found from the end of the log.
    last_outside = np.where(outside.any(axis=0), n - 1 - np.argmax(outside[::-1], axis=0), -1)
    result = np.where(last_outside < n - 1, t[np.minimum(last_outside + 1, n - 1)], np.nan)
    return np.where(band[-1] > 0.0, result, np.nan)


def settling_time_report(time: ArrayLike, estimate: ArrayLike, truth: ArrayLike, tolerance: float = TOLERANCE,
                         look_back: float = REPORT_LOOK_BACK, look_ahead: float = REPORT_LOOK_AHEAD) -> np.ndarray:
    """The report's convergence time [s] per channel, shape (C,) (see the module docstring).

    ``max(w_hat[j] - truth, j in [k - look_back/T_s, k + look_ahead/T_s]) <= tolerance |truth|`` at the
    first such k, reported as ``(k + 1) T_s`` (k from 0 here). NaN for a zero truth or never.
    """
    t = np.asarray(time, dtype=float)
    sample_time = (t[-1] - t[0]) / (len(t) - 1)
    back = int(round(look_back / sample_time))
    ahead = int(round(look_ahead / sample_time))
    signed_error = np.asarray(estimate, dtype=float) - np.asarray(truth, dtype=float)
    size = back + ahead + 1
    # A window [k - back, k + ahead] is a centred window of `size` shifted by origin (scipy's sign).
    from scipy.ndimage import maximum_filter1d  # lazily (scipy imports take ~0.5 s)

    moving_max = maximum_filter1d(signed_error, size, axis=0, mode="constant", cval=-np.inf,
                                  origin=size // 2 - ahead)
    band = tolerance * np.abs(np.broadcast_to(np.asarray(truth, dtype=float), signed_error.shape))
    inside = moving_max <= band
    first = np.argmax(inside, axis=0)
    times = sample_times(t, "report")
    result = np.where(inside.any(axis=0), times[first], np.nan)
    return np.where(band[-1] > 0.0, result, np.nan)


def smoothing_gain(sample_time: float, time_constant: float = SMOOTHING_TIME_CONSTANT_S) -> float:
    """``g = 1 - exp(-T_s / tau)`` of the smoothed settling time's low-pass (sample time and tau in s)."""
    return -math.expm1(-sample_time / time_constant)


def low_pass(values: np.ndarray, gain: float) -> np.ndarray:
    """``y_0 = x_0``, ``y_k = g x_k + (1 - g) y_(k-1)`` along axis 0: the sweep's running filter, the same compiled
    function (:mod:`fsr_estimation.core.smoothing`), so both agree to the bit."""
    values = np.asarray(values, dtype=float)
    # contiguous and writable: the one signature compiled ahead (a read-only view, e.g. of shared memory, is copied)
    columns = np.require(values.reshape(len(values), -1), requirements=("C", "W"))
    out = np.empty_like(columns)
    low_pass_columns(columns, float(gain), out)
    return out.reshape(values.shape)


def settling_time_smoothed(time: ArrayLike, estimate: ArrayLike, truth: ArrayLike,
                           tolerance: float = TOLERANCE) -> np.ndarray:
    """:func:`settling_time_standard` on the estimate and the truth through the ``smoothed`` low-pass (module
    docstring; a constant truth is left as it is), per channel, shape (C,)."""
    t = np.asarray(time, dtype=float)
    estimate = np.asarray(estimate, dtype=float)
    if len(t) < 2 or not t[-1] > t[0]:
        return settling_time_standard(t, estimate, truth, tolerance)
    gain = smoothing_gain((t[-1] - t[0]) / (len(t) - 1))
    truth = np.asarray(truth, dtype=float)
    return settling_time_standard(t, low_pass(estimate, gain), low_pass(truth, gain) if truth.ndim == 2 else truth,
                                  tolerance)


def settling_time(time: ArrayLike, estimate: ArrayLike, truth: ArrayLike, definition: str = "standard",
                  tolerance: float = TOLERANCE) -> np.ndarray:
    """Settling time [s] per channel under ``definition`` (``standard``, ``report`` or ``smoothed``)."""
    if definition == "standard":
        return settling_time_standard(time, estimate, truth, tolerance)
    if definition == "report":
        return settling_time_report(time, estimate, truth, tolerance)
    if definition == "smoothed":
        return settling_time_smoothed(time, estimate, truth, tolerance)
    raise ValueError(f"settling definition must be one of {', '.join(SETTLING_DEFINITIONS)}; got '{definition}'")


def mean_absolute_error(estimate: ArrayLike, truth: ArrayLike) -> np.ndarray:
    """``mean_k |w_hat[k] - truth|`` over the whole log, per channel, shape (C,); truth (C,) or (N, C)."""
    return np.mean(np.abs(np.asarray(estimate, dtype=float) - np.asarray(truth, dtype=float)), axis=0)


def max_error_after(time: ArrayLike, estimate: ArrayLike, truth: ArrayLike, after: float,
                    definition: str = "standard") -> np.ndarray:
    """``max |w_hat - truth|`` over the samples at time >= ``after`` [s] (the time of ``definition``), (C,).

    truth (C,) or (N, C). NaN when no sample is that late.
    """
    times = sample_times(time, definition)
    late = times >= after - 1e-9 * max(1.0, abs(after))  # the sample at exactly `after` counts
    e = np.abs(np.asarray(estimate, dtype=float) - np.asarray(truth, dtype=float))
    if not late.any():
        return np.full(e.shape[1], np.nan)
    return e[late].max(axis=0)


def mass_change(estimate: ArrayLike, gravity: float) -> float:
    """``dm = f_e,z(end) / g`` [kg] (NED: negative when the vehicle is lighter than the model)."""
    return float(np.asarray(estimate, dtype=float)[-1, 2]) / gravity


@dataclass
class SweepResult:
    """Metrics of one (c0, r) run; arrays are per channel (``CHANNELS``), NaN where undefined."""

    c0: float
    r: int
    dm: float  # kg
    m_real: float  # kg
    settling_time: np.ndarray  # s
    mae: np.ndarray
    max_error: np.ndarray
    estimate: np.ndarray | None = None  # (N, 6) w_hat, kept when asked for (plots)


def sweep(log: FlightLogLike, model: ObserverModel, c0_values: list[float], r_values: list[int],
          truth: ArrayLike, *, settling: str = "standard", after: float | None = None,
          keep_estimates: bool = False) -> list[SweepResult]:
    """Run the observer over one log for every (c0, r) and measure it; one result per pair, c0-major.

    log: a :class:`fsr_estimation.io.flight_log.FlightLog` (or anything with its attributes ``time`` (N,)
    and ``velocity_world``, ``eta``, ``eta_dot``, ``force_body``, ``torque_body`` (N, 3)). truth (6,) in the
    frame of ``w_hat``. The momentum residual is computed once; each pair is then one ``sosfilt`` over the
    whole log. ``after`` [s] (default: the last 5 s of the log) bounds the max error.
    """
    t = np.asarray(log.time, dtype=float)
    truth = np.asarray(truth, dtype=float)
    if truth.shape != (6,):
        raise ValueError(f"truth: expected 6 numbers (fx fy fz tx ty tz), got shape {truth.shape}")
    sample_time = (t[-1] - t[0]) / (len(t) - 1)
    for c0 in c0_values:
        for r in r_values:
            check_filter_parameters(c0, r, sample_time)
    if after is None:
        after = max(0.0, (t[-1] - t[0]) - DEFAULT_LAST_SECONDS)
    u = observer_input(model.mass, model.inertia, log.velocity_world, log.eta, log.eta_dot, log.force_body,
                       log.torque_body, sample_time, model.gravity)
    results = []
    for c0 in c0_values:
        for r in r_values:
            w = filter_observer_input(u, c0, r, sample_time)
            dm = mass_change(w, model.gravity)
            results.append(SweepResult(
                c0=float(c0), r=int(r), dm=dm, m_real=model.mass + dm,
                settling_time=settling_time(t, w, truth, settling),
                mae=mean_absolute_error(w, truth),
                max_error=max_error_after(t, w, truth, after, settling),
                estimate=w if keep_estimates else None,
            ))
    return results
