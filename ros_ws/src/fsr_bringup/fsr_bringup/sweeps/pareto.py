"""The Pareto front of a sweep over two metrics, both to be made small (e.g. estimate settling time against the
estimate's steady-state noise): a finished flight is on the front when no other finished flight is at least as
good in both metrics and strictly better in one. Flights with a NaN or infinite value in either metric are
never on it (they do not settle, or the metric does not apply).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fsr_bringup.sweeps.axes import SweepError
from fsr_sim.contract import FINISHED


def parse_pareto(text: str, metrics: list[str] | tuple[str, ...]) -> tuple[str, str]:
    """``"X,Y"`` -> ``("X", "Y")``: two different names from ``metrics``, else :class:`SweepError` naming them."""
    names = [name.strip() for name in text.split(",")]
    if len(names) != 2 or not all(names):
        raise SweepError(f"--pareto: expected two metrics X,Y, got '{text}'")
    unknown = [name for name in names if name not in metrics]
    if unknown:
        raise SweepError(f"--pareto: unknown metric {', '.join(map(repr, unknown))} (one of {', '.join(metrics)})")
    if names[0] == names[1]:
        raise SweepError(f"--pareto: the two metrics must differ, got '{text}'")
    return names[0], names[1]


def non_dominated(points: np.ndarray) -> np.ndarray:
    """Mask of the rows of ``points`` (n x 2, to minimise) that no other row dominates.

    Sorted by the first column (ties by the second), a row is on the front when its second value is below every
    earlier row's; equal points are all kept.
    """
    order = np.lexsort((points[:, 1], points[:, 0]))
    mask = np.zeros(len(points), dtype=bool)
    best_x, best_y = np.inf, np.inf
    for index in order:
        x, y = points[index]
        if y < best_y or (y == best_y and x == best_x):
            mask[index] = True
            best_x, best_y = x, y
    return mask


def pareto_front(table: Any, x: str, y: str) -> Any:
    """A boolean Series over ``table``'s rows: the finished flights on the front of ``x`` and ``y`` (both minimised)."""
    finite = np.isfinite(table[x].to_numpy(dtype=float)) & np.isfinite(table[y].to_numpy(dtype=float))
    candidates = finite & (table["end_reason"] == FINISHED).to_numpy()
    mask = np.zeros(len(table), dtype=bool)
    if candidates.any():
        points = table.loc[candidates, [x, y]].to_numpy(dtype=float)
        mask[np.flatnonzero(candidates)] = non_dominated(points)
    import pandas as pd  # here: fsr-sweep --help does not pay for pandas

    return pd.Series(mask, index=table.index, name="pareto")
