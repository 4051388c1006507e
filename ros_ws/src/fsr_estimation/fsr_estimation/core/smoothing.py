"""The smoothed settling time's low-pass (compiled core, :mod:`fsr_sim.core.jit`), written once: per sample in a
sweep's running measures (:mod:`fsr_bringup.core.flight_measures`) and over a whole log in the analysis
(:func:`fsr_estimation.estimator.metrics.low_pass`), so that both give the same numbers to the bit.

    y_0 = x_0,    y_k = g x_k + (1 - g) y_(k-1),    g = 1 - exp(-T_s / tau)

(``T_s`` the sample time, ``tau`` the filter's time constant, both in s; ``x`` in any unit, ``y`` in the same).
"""

from __future__ import annotations

import numpy as np

from fsr_sim.core.jit import jit, jit_inline


@jit_inline
def low_pass_step(gain: float, value: float, previous: float) -> float:
    """``g x_k + (1 - g) y_(k-1)``: the next output of the low-pass (module docstring)."""
    return gain * value + (1.0 - gain) * previous


@jit
def low_pass_columns(values: np.ndarray, gain: float, out: np.ndarray) -> None:
    """Every column of ``values`` (N, C) through the low-pass into ``out`` (N, C), from ``y_0 = x_0``."""
    for c in range(values.shape[1]):
        if values.shape[0]:
            out[0, c] = values[0, c]
        for k in range(1, values.shape[0]):
            out[k, c] = low_pass_step(gain, values[k, c], out[k - 1, c])
