"""Surfaces near the vehicle: ground and ceiling effect on rotor thrust, and ground contact (docs/model.md §3.3).

Surfaces are horizontal planes of the NED world given by their down-coordinate ``height`` [m] (the
ground at ``z = 0`` by default; a ceiling 3 m up is ``height: -3``). For rotor ``i`` at world position
``r_i = p + R p_i`` the distance to the ground is ``z = ground.height - r_i,z`` and to the ceiling
``z = r_i,z - ceiling.height``.

The thrust ratios and the contact rule are computed per step by the compiled core,
:mod:`fsr_sim.core.surfaces` (its docstring has the formulas: single-rotor and multirotor ground effect,
ceiling effect, the bound near a surface); :func:`pack_surfaces` packs an :class:`Environment` and a
vehicle's geometry for it once, and :func:`thrust_ratio_log` evaluates it over a whole log.

Contact: the ground and the ceiling are solid. The landing gear's feet are the vehicle's ``contact_height``
below the centre of mass, its top (rotor guards, frame) ``top_height`` above it (vehicle YAML, default
``contact_height``); the contact points are taken along world down (attitude ignored, as for the ground).
When the feet would go below the ground (``p_z > ground.height - contact_height``) or the top above the
ceiling (``p_z < ceiling.height + top_height``) the position is put back on the surface, the velocity
and angular velocity are removed and the vehicle is held (no sliding, no spin) while the net force
pushes it into the surface. An impact faster than the plant's crash speed (3 m/s) ends the flight
("crashed into the ground" / "crashed into the ceiling").
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsr_sim.core import surfaces as core_surfaces
from fsr_sim.core.surfaces import Surfaces
from fsr_sim.model.vehicle import Vehicle

GROUND_MODELS = ("single", "multirotor")


@dataclass(frozen=True)
class Surface:
    """A horizontal plane: ``height`` its down-coordinate in world NED [m]; ``effect`` the thrust change near
    it (ground / ceiling effect) bounded by ``max_ratio`` (``T / T_OGE``, >= 1)."""

    enabled: bool = True
    height: float = 0.0
    effect: bool = True
    max_ratio: float = 1.5

    def __post_init__(self) -> None:
        if not self.max_ratio >= 1.0:
            raise ValueError(f"max_ratio must be >= 1, got {self.max_ratio}")


@dataclass(frozen=True)
class Environment:
    """The surfaces around the vehicle. ``Environment()``: the ground at ``z = 0`` with ground effect (single-
    rotor model), no ceiling. ``Environment(ground=Surface(enabled=False))``: free space."""

    ground: Surface = field(default_factory=Surface)
    ceiling: Surface = field(default_factory=lambda: Surface(enabled=False, height=-3.0))
    ground_model: str = "single"  # "single" (one-rotor images) or "multirotor" (Sanchez-Cuevas 2017)
    body_factor: float = 2.0  # K_b of the multirotor model (their fitted value)
    ceiling_k1: float = 6.924  # empirical constants of the ceiling model (Hsiao & Chirarattananon 2019)
    ceiling_k2: float = 0.03782  # m

    def __post_init__(self) -> None:
        if self.ground_model not in GROUND_MODELS:
            raise ValueError(f"ground_model must be one of {', '.join(GROUND_MODELS)}, got '{self.ground_model}'")
        if self.ground.enabled and self.ceiling.enabled and self.ceiling.height >= self.ground.height:
            raise ValueError("the ceiling must be above the ground (smaller NED z)")

    @property
    def has_thrust_effects(self) -> bool:
        return (self.ground.enabled and self.ground.effect) or (self.ceiling.enabled and self.ceiling.effect)


def pack_surfaces(environment: Environment, vehicle: Vehicle) -> Surfaces:
    """The core's :class:`~fsr_sim.core.surfaces.Surfaces` of ``environment`` around ``vehicle``."""
    positions = np.ascontiguousarray(vehicle.positions, dtype=float)
    separation = np.linalg.norm(positions[:, None, :] - positions[None, :, :], axis=2)
    arm = np.linalg.norm(positions, axis=1)
    ground, ceiling = environment.ground, environment.ceiling
    return Surfaces(
        ground=bool(ground.enabled), ground_height=float(ground.height), ground_effect=bool(ground.effect),
        ground_floor=1.0 / ground.max_ratio, multirotor=environment.ground_model == "multirotor",
        body_factor=float(environment.body_factor), ceiling=bool(ceiling.enabled),
        ceiling_height=float(ceiling.height), ceiling_effect=bool(ceiling.effect),
        ceiling_floor=1.0 / ceiling.max_ratio, ceiling_k1=float(environment.ceiling_k1),
        ceiling_k2=float(environment.ceiling_k2), rotor_radius=float(vehicle.rotor_radius),
        rotor_positions=positions, separation_sq=separation * separation, arm_sq=arm * arm,
        contact_height=float(vehicle.contact_height), top_height=float(vehicle.top_height),
    )


def thrust_ratio_log(surfaces: Surfaces, position_down: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """``T_i / T_OGE,i`` of every rotor along a log, shape (N, n): the plant's own per-stage function
    (:func:`fsr_sim.core.surfaces.thrust_ratios`) at each pose (``position_down`` (N,) [m], ``rotation`` (N, 3, 3)
    body -> world)."""
    z = np.ascontiguousarray(position_down, dtype=float).reshape(-1)
    row2 = np.ascontiguousarray(np.asarray(rotation, dtype=float)[:, 2, :])
    out = np.ones((len(z), len(surfaces.rotor_positions)))
    if core_surfaces.has_thrust_effects(surfaces):
        core_surfaces.thrust_ratio_log(surfaces, z, row2, out)
    return out


def contact_mask(surfaces: Surfaces, position_down: np.ndarray) -> np.ndarray:
    """The contact rule (:func:`fsr_sim.core.surfaces.in_contact`) at every sample of a log, (N,) bool."""
    z = np.ascontiguousarray(position_down, dtype=float).reshape(-1)
    out = np.zeros(len(z), dtype=bool)
    core_surfaces.contact_log(surfaces, z, out)
    return out
