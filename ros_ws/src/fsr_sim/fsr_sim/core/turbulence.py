"""Dryden turbulence (compiled core).

Each turbulence entry ``p`` is three discrete filters (one per gust axis ``u, v, w``, order <= 2, state space
``x' = A x + B n``, ``y = C x + D n``: :mod:`fsr_sim.model.turbulence` designs them) driven by white noise
``n`` of standard deviation ``noise_std`` drawn from the counter-based generator of :mod:`fsr_sim.core.sensors`
(seed, RK4 step, channel): the same gusts in the node graph and in one process, compiled and under CPython.
The gust velocity of an entry, world NED [m/s], is ``mean + y_u a_u + y_v a_v + y_w a_w`` with the axes
``a`` (rows of ``axes``); it is held over each RK4 step and advanced after it (:func:`advance_gusts`).

The wind is the sum of the entries' gust velocities (:func:`wind_velocity`); it pushes on the vehicle through
the aerodynamics of :mod:`fsr_sim.core.aerodynamics` (the air velocity is the vehicle's minus the wind).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from fsr_sim.core.jit import jit, jit_inline
from fsr_sim.core.sensors import standard_normal

ORDER = 2  # filter states per axis (a first-order filter leaves its second state at zero)
CHANNELS_PER_ENTRY = 3  # noise channels u, v, w


class TurbulenceParams(NamedTuple):
    """The packed turbulence entries (``m`` of them; ``m = 0``: no turbulence, still air)."""

    seeds: np.ndarray  # (m,) int64, 0 .. 2^32 - 1
    a: np.ndarray  # (m, 3, 2, 2)
    b: np.ndarray  # (m, 3, 2)
    c: np.ndarray  # (m, 3, 2)
    d: np.ndarray  # (m, 3)
    noise_std: np.ndarray  # (m, 3) of the driving white noise
    axes: np.ndarray  # (m, 3, 3) rows: world NED directions of u, v, w
    mean: np.ndarray  # (m, 3) mean wind, world NED [m/s]
    initial_states: np.ndarray  # (m, 3, 2) the filters' (stationary) start
    initial_gusts: np.ndarray  # (m, 3) the gusts of the first step [m/s]


@jit
def advance_gusts(params: TurbulenceParams, states, gusts, step: int) -> None:  # noqa: ANN001
    """Every entry's filters one RK4 step on: ``states`` (m, 3, 2) from step ``step``'s noise, and the gust
    velocities ``gusts`` (m, 3) [m/s] world NED of the next step."""
    for p in range(states.shape[0]):
        seed = params.seeds[p]
        gx, gy, gz = params.mean[p, 0], params.mean[p, 1], params.mean[p, 2]
        for j in range(CHANNELS_PER_ENTRY):
            noise = params.noise_std[p, j] * standard_normal(seed, step, j)
            x0, x1 = states[p, j, 0], states[p, j, 1]
            a, b, c = params.a[p, j], params.b[p, j], params.c[p, j]
            y = c[0] * x0 + c[1] * x1 + params.d[p, j] * noise
            states[p, j, 0] = a[0, 0] * x0 + a[0, 1] * x1 + b[0] * noise
            states[p, j, 1] = a[1, 0] * x0 + a[1, 1] * x1 + b[1] * noise
            axis = params.axes[p, j]
            gx, gy, gz = gx + y * axis[0], gy + y * axis[1], gz + y * axis[2]
        gusts[p, 0], gusts[p, 1], gusts[p, 2] = gx, gy, gz


@jit_inline
def wind_velocity(gusts) -> tuple:  # noqa: ANN001
    """The wind [m/s], world NED: the sum of the entries' gust velocities ``gusts`` (m, 3) (zero without any)."""
    wx = wy = wz = 0.0
    for p in range(gusts.shape[0]):
        wx, wy, wz = wx + gusts[p, 0], wy + gusts[p, 1], wz + gusts[p, 2]
    return wx, wy, wz
