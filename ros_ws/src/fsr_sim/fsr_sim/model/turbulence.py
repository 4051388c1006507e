"""Dryden turbulence (docs/model.md §3.4, *Turbulence*): the MIL-F-8785C / MIL-HDBK-1797 low-altitude model.

With the wind speed at 6 m ``W_6`` [m/s] (MIL's ``W_20``, 20 ft) and the altitude ``h`` (ft in the standard's
formulas, clipped to 10 .. 1000 ft; ``h_m`` the same in m):

    sigma_w = 0.1 W_6,   sigma_u = sigma_v = sigma_w / (0.177 + 0.000823 h)^0.4                 [m/s]
    L_w = h_m,   L_u = L_v = 0.3048 h / (0.177 + 0.000823 h)^1.2                                  [m]

and the one-sided power spectral densities over the angular frequency ``omega`` [rad/s] (Taylor's frozen
turbulence carried past at the airspeed ``V`` [m/s]), whose integrals over ``0 .. inf`` are ``sigma^2``:

    Phi_u(omega) = sigma_u^2 (2 L_u / (pi V)) / (1 + (L_u omega / V)^2)
    Phi_v,w(omega) = sigma^2 (L / (pi V)) (1 + 3 (L omega / V)^2) / (1 + (L omega / V)^2)^2

i.e. white noise of unit one-sided PSD through ``H_u(s) = sigma_u sqrt(2 L_u / (pi V)) / (1 + (L_u / V) s)`` and
``H_v,w(s) = sigma sqrt(L / (pi V)) (1 + sqrt(3) (L / V) s) / (1 + (L / V) s)^2``. fsr discretises each with the
zero-order hold at the RK4 step ``dt`` (:func:`scipy.signal.cont2discrete`: no direct feed-through, so the gust
is as smooth as the model and a law that differentiates the measured acceleration sees no white noise) and
drives it with white noise of variance ``pi / dt`` (a unit one-sided PSD up to the Nyquist frequency
``pi / dt``); the filters start in their
stationary state (:func:`scipy.linalg.solve_discrete_lyapunov`), so the gusts are stationary from ``t = 0``.
``u`` is along the horizontal mean wind (north without one), ``v`` to its right, ``w`` down. The wind pushes
through the vehicle's aerodynamics (:mod:`fsr_sim.core.aerodynamics`: the air velocity is the vehicle's minus
the wind).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from fsr_sim.core.turbulence import ORDER, TurbulenceParams
from fsr_sim.model.checks import InvalidValueError, finite_array

FEET = 0.3048  # m
ALTITUDE_RANGE_FT = (10.0, 1000.0)  # the low-altitude model's range


@dataclass(frozen=True)
class DrydenTurbulence:
    """One Dryden turbulence field (module docstring).

    Parameters
    ----------
    wind_speed : float
        ``W_6`` [m/s] >= 0, the mean wind speed at 6 m: it sets the intensity (``sigma_w = 0.1 W_6``; MIL's
        light / moderate / severe are 15 / 30 / 45 knots = 7.7 / 15.4 / 23.2 m/s).
    altitude : float
        ``h`` [m] > 0, above the ground (clipped to 3.05 .. 304.8 m, the model's range).
    airspeed : float or None
        ``V`` [m/s] > 0 that carries the frozen field past the vehicle; None: ``max(W_6, 1)``.
    mean : array-like, shape (3,)
        A steady wind [m/s], world NED, added to the gusts.
    seed : int
        ``0 .. 2^32 - 1``: the same seed gives the same gusts.
    """

    wind_speed: float
    altitude: float
    airspeed: float | None = None
    mean: np.ndarray = field(default_factory=lambda: np.zeros(3))
    seed: int = 0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.wind_speed) and self.wind_speed >= 0.0):
            raise InvalidValueError("wind_speed", f"must be >= 0 m/s, got {self.wind_speed}")
        if not (math.isfinite(self.altitude) and self.altitude > 0.0):
            raise InvalidValueError("altitude", f"must be > 0 m, got {self.altitude}")
        if self.airspeed is not None and not (math.isfinite(self.airspeed) and self.airspeed > 0.0):
            raise InvalidValueError("airspeed", f"must be > 0 m/s, got {self.airspeed}")
        if int(self.seed) != self.seed or not 0 <= self.seed < 2**32:
            raise InvalidValueError("seed", f"must be an integer in 0 .. 2^32 - 1, got {self.seed}")
        object.__setattr__(self, "mean", finite_array(self.mean, (3,), "mean"))
        object.__setattr__(self, "seed", int(self.seed))

    @property
    def speed(self) -> float:
        """``V`` [m/s]."""
        return self.airspeed if self.airspeed is not None else max(self.wind_speed, 1.0)

    @property
    def intensities(self) -> np.ndarray:
        """``(sigma_u, sigma_v, sigma_w)`` [m/s]."""
        h = float(np.clip(self.altitude / FEET, *ALTITUDE_RANGE_FT))
        sigma_w = 0.1 * self.wind_speed
        sigma_u = sigma_w / (0.177 + 0.000823 * h) ** 0.4
        return np.array((sigma_u, sigma_u, sigma_w))

    @property
    def scales(self) -> np.ndarray:
        """``(L_u, L_v, L_w)`` [m]."""
        h = float(np.clip(self.altitude / FEET, *ALTITUDE_RANGE_FT))
        length_u = FEET * h / (0.177 + 0.000823 * h) ** 1.2
        return np.array((length_u, length_u, FEET * h))

    def psd(self, omega: ArrayLike) -> np.ndarray:
        """The one-sided PSDs ``Phi_u, Phi_v, Phi_w`` [(m/s)^2 / (rad/s)] at ``omega`` [rad/s], shape (3, k)."""
        omega = np.asarray(omega, dtype=float)
        out = []
        for axis, (sigma, length) in enumerate(zip(self.intensities, self.scales, strict=True)):
            x = (length * omega / self.speed) ** 2
            if axis == 0:
                out.append(sigma**2 * 2.0 * length / (math.pi * self.speed) / (1.0 + x))
            else:
                out.append(sigma**2 * length / (math.pi * self.speed) * (1.0 + 3.0 * x) / (1.0 + x) ** 2)
        return np.array(out)

    def transfer_functions(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """``(numerator, denominator)`` in ``s`` of ``H_u, H_v, H_w`` (module docstring)."""
        out = []
        for axis, (sigma, length) in enumerate(zip(self.intensities, self.scales, strict=True)):
            tau = length / self.speed
            if axis == 0:
                out.append((np.array([sigma * math.sqrt(2.0 * tau / math.pi)]), np.array([tau, 1.0])))
            else:
                gain = sigma * math.sqrt(tau / math.pi)
                out.append((gain * np.array([math.sqrt(3.0) * tau, 1.0]), np.array([tau * tau, 2.0 * tau, 1.0])))
        return out


def pack_turbulence(entries: Sequence[DrydenTurbulence], dt: float) -> TurbulenceParams:
    """The core's :class:`~fsr_sim.core.turbulence.TurbulenceParams` of ``entries`` at the RK4 step ``dt`` [s],
    the filters' stationary start included."""
    if any(entry.wind_speed > 0.0 for entry in entries):  # only gusts need scipy (importing it takes ~1 s)
        from scipy.linalg import solve_discrete_lyapunov
        from scipy.signal import cont2discrete, tf2ss
    m = len(entries)
    a, b, c = np.zeros((m, 3, ORDER, ORDER)), np.zeros((m, 3, ORDER)), np.zeros((m, 3, ORDER))
    d, axes, mean = np.zeros((m, 3)), np.zeros((m, 3, 3)), np.zeros((m, 3))
    noise_std = np.full((m, 3), math.sqrt(math.pi / dt))
    states, gusts = np.zeros((m, 3, ORDER)), np.zeros((m, 3))
    for p, entry in enumerate(entries):
        horizontal = np.array((entry.mean[0], entry.mean[1], 0.0))
        u = horizontal / np.linalg.norm(horizontal) if np.linalg.norm(horizontal) > 0.0 else np.array((1.0, 0, 0))
        axes[p] = (u, np.cross((0.0, 0.0, 1.0), u), (0.0, 0.0, 1.0))  # u, v to its right, w down
        mean[p] = entry.mean
        rng = np.random.default_rng(entry.seed)
        gusts[p] = entry.mean  # a zero wind speed: no gusts, the filters stay at zero
        for j, (numerator, denominator) in enumerate(entry.transfer_functions() if entry.wind_speed > 0.0 else ()):
            a_j, b_j, c_j, d_j, _ = cont2discrete(tf2ss(numerator, denominator), dt, method="zoh")
            k = a_j.shape[0]
            a[p, j, :k, :k], b[p, j, :k], c[p, j, :k], d[p, j] = a_j, b_j[:, 0], c_j[0], d_j[0, 0]
            covariance = solve_discrete_lyapunov(a_j, (math.pi / dt) * (b_j @ b_j.T))
            eigenvalues, vectors = np.linalg.eigh(covariance)
            states[p, j, :k] = vectors @ (np.sqrt(np.clip(eigenvalues, 0.0, None)) * rng.standard_normal(k))
            gusts[p] += (c_j[0] @ states[p, j, :k]) * axes[p, j]  # the first step's gust (its noise term aside)
    return TurbulenceParams(
        seeds=np.array([entry.seed for entry in entries], dtype=np.int64), a=a, b=b, c=c, d=d,
        noise_std=noise_std, axes=axes, mean=mean, initial_states=states, initial_gusts=gusts)
