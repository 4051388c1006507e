"""A candidate's objective: a statistic over its seeded flights of one sweep metric (both minimised).

``METRIC[:STAT]`` with ``METRIC`` a numeric column of the sweep's table (:data:`fsr_bringup.sweeps.metrics.
RANKABLE_METRICS`, e.g. ``position_error_rms_m``) and ``STAT`` ``mean`` (default), ``median``, ``q90`` (the 90 %
quantile, linear interpolation) or ``max``. A flight that did not finish (it diverged, or its values were refused)
or whose metric is not finite (inf: never settled) counts as a penalty in the metric's unit, so a candidate that
loses the vehicle on one seed in ten is worse than one that flies them all, and the optimiser never sees NaN:
``penalty`` for a finished flight without a finite value, ``penalty * (2 - flown_s / duration)`` for a lost one
(between ``penalty`` and twice it: a flight lost later counts less, so that among candidates that lose every
flight - where a search starts, far from gains that fly - the optimiser still sees which way is better; a
flight refused before its first step counts ``2 * penalty``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fsr_bringup.sweeps.metrics import RANKABLE_METRICS
from fsr_bringup.tuning.space import TuneError
from fsr_sim.contract import FINISHED

STATISTICS = ("mean", "median", "q90", "max")
DEFAULT_PENALTY = 10.0  # in the metric's unit: what a diverged flight (or one with no finite value) costs


@dataclass(frozen=True)
class Objective:
    metric: str
    statistic: str = "mean"
    penalty: float = DEFAULT_PENALTY

    @property
    def label(self) -> str:
        return f"{self.metric}:{self.statistic}"

    def flight_value(self, row: dict[str, Any], duration: float) -> float:
        """One flight's contribution (module docstring); ``duration`` [s]: the flight's, as planned."""
        if row.get("end_reason") != FINISHED:
            flown = row.get("flown_s", 0.0)
            flown = flown if isinstance(flown, float) and math.isfinite(flown) else 0.0
            return self.penalty * (2.0 - min(max(flown / duration, 0.0), 1.0))
        value = row.get(self.metric, math.nan)
        return float(value) if math.isfinite(value) else self.penalty

    def of(self, rows: Sequence[dict[str, Any]], duration: float) -> float:
        """The statistic over the flights' values (``duration`` [s]: the flights', as planned)."""
        values = np.array([self.flight_value(row, duration) for row in rows], dtype=float)
        if self.statistic == "mean":
            return float(np.mean(values))
        if self.statistic == "median":
            return float(np.median(values))
        if self.statistic == "q90":
            return float(np.quantile(values, 0.9))
        return float(np.max(values))


def lost(rows: Sequence[dict[str, Any]]) -> int:
    """The flights that did not finish."""
    return sum(row.get("end_reason") != FINISHED for row in rows)


def parse_objective(text: str, penalty: float = DEFAULT_PENALTY) -> Objective:
    """``METRIC[:STAT]`` -> :class:`Objective` (TuneError naming what is wrong)."""
    metric, _, statistic = text.strip().partition(":")
    statistic = statistic.strip().lower() or "mean"
    if metric not in RANKABLE_METRICS:
        raise TuneError(f"--objective: unknown metric '{metric}' (one of {', '.join(RANKABLE_METRICS)})")
    if statistic not in STATISTICS:
        raise TuneError(f"--objective: unknown statistic '{statistic}' (one of {', '.join(STATISTICS)})")
    if not (math.isfinite(penalty) and penalty > 0.0):
        raise TuneError(f"--penalty: must be a finite number > 0, got {penalty:g}")
    return Objective(metric, statistic, float(penalty))
