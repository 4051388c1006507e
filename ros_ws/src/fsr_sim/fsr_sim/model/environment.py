"""Surfaces near the vehicle: ground and ceiling effect on rotor thrust, and ground contact (SPEC §3.3).

Surfaces are horizontal planes of the NED world given by their down-coordinate ``height`` [m] (the
ground at ``z = 0`` by default; a ceiling 3 m up is ``height: -3``). For rotor ``i`` at world position
``r_i = p + R p_i`` the distance to the ground is ``z = ground.height - r_i,z`` and to the ceiling
``z = r_i,z - ceiling.height``.

Thrust ratios at constant power, ``T / T_OGE``:

* ground (method of images, Cheeseman & Bennett): ``1 / (1 - (rho / (4 z))^2)``;
* ground, multirotor (Sanchez-Cuevas et al. 2017), generalised to ``n`` rotors: the denominator also
  loses ``sum_{j != i} (rho^2 z / 2) / (d_ij^2 + 4 z^2)^(3/2)`` for the other rotors at distance ``d_ij``
  and ``2 K_b rho^2 z / (b^2 + 4 z^2)^(3/2)`` for the body at distance ``b`` (the arm); for a quadrotor in
  X this is the paper's formula (two neighbours at ``d``, one at ``sqrt(2) d``);
* ceiling (empirical): ``1 / (1 - (1 / k1) (rho / (z + k2))^2)``.

Bound near the surface (all three are singular there): the ratio is ``1 / max(D, 1 / max_ratio)`` where
``D`` is the denominator, i.e. the formula is used down to the distance at which it reaches ``max_ratio``
(default 1.5; for the single-rotor ground formula that is ``z = 0.43 rho``) and held at ``max_ratio``
closer to the surface. Distances are also floored at 1 mm so that ``z <= 0`` (rotor at or through the
surface) gives the bounded value instead of a division by zero.

Contact: the ground stops the vehicle. The landing gear's feet are ``contact_height`` below the centre of
mass; when they would go below the ground the position is put back on it, the downward velocity is
removed and the vehicle is held (no sliding, no spin) while the net force pushes it into the ground.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsr_sim.config.validation import Section

MIN_DISTANCE = 1e-3  # m, floor for surface distances


@dataclass(frozen=True)
class Surface:
    enabled: bool
    height: float  # down-coordinate of the plane in world NED [m]
    effect: bool  # thrust change near it (ground / ceiling effect)
    max_ratio: float  # bound of T / T_OGE


@dataclass(frozen=True)
class Environment:
    ground: Surface
    ceiling: Surface
    ground_model: str = "single"  # "single" (one-rotor images) or "multirotor" (Sanchez-Cuevas 2017)
    body_factor: float = 2.0  # K_b of the multirotor model (their fitted value)
    ceiling_k1: float = 6.924  # empirical constants of the ceiling model (Hsiao & Chirarattananon 2019)
    ceiling_k2: float = 0.03782  # m

    @property
    def has_thrust_effects(self) -> bool:
        return (self.ground.enabled and self.ground.effect) or (self.ceiling.enabled and self.ceiling.effect)


def bounded_ratio(denominator: np.ndarray | float, max_ratio: float) -> np.ndarray:
    """``1 / max(D, 1 / max_ratio)``: the thrust ratio, continuous and at most ``max_ratio``."""
    return 1.0 / np.maximum(denominator, 1.0 / max_ratio)


def ground_effect_ratio(distance: np.ndarray | float, rotor_radius: float, max_ratio: float = 1.5) -> np.ndarray:
    """``T_IGE / T_OGE = 1 / (1 - (rho / (4 z))^2)`` for distances ``z`` [m] to the ground (bounded)."""
    z = np.maximum(distance, MIN_DISTANCE)
    return bounded_ratio(1.0 - (rotor_radius / (4.0 * z)) ** 2, max_ratio)


def multirotor_ground_effect_ratio(
    distance: np.ndarray,
    rotor_radius: float,
    rotor_separation: np.ndarray,
    arm_lengths: np.ndarray,
    body_factor: float = 2.0,
    max_ratio: float = 1.5,
) -> np.ndarray:
    """Per-rotor ground-effect ratio with the neighbouring rotors and the body (Sanchez-Cuevas 2017).

    distance: shape (n,), each rotor's distance to the ground [m]. rotor_separation: shape (n, n),
    ``d_ij`` [m] (diagonal ignored). arm_lengths: shape (n,), ``b_i`` [m].
    """
    z = np.maximum(distance, MIN_DISTANCE)
    rho2 = rotor_radius**2
    d2 = rotor_separation**2
    neighbours = (0.5 * rho2 * z[:, None]) / (d2 + 4.0 * z[:, None] ** 2) ** 1.5
    np.fill_diagonal(neighbours, 0.0)
    body = 2.0 * body_factor * rho2 * z / (arm_lengths**2 + 4.0 * z**2) ** 1.5
    denominator = 1.0 - (rotor_radius / (4.0 * z)) ** 2 - neighbours.sum(axis=1) - body
    return bounded_ratio(denominator, max_ratio)


def ceiling_effect_ratio(
    distance: np.ndarray | float, rotor_radius: float, k1: float, k2: float, max_ratio: float = 1.5
) -> np.ndarray:
    """``T_CE / T_OGE = 1 / (1 - (1/k1) (rho / (z + k2))^2)`` for distances ``z`` [m] to the ceiling."""
    z = np.maximum(distance, MIN_DISTANCE)
    return bounded_ratio(1.0 - (rotor_radius / (z + k2)) ** 2 / k1, max_ratio)


def environment_from_section(section: Section) -> Environment:
    """Parse the scenario's ``environment`` section (see module docstring); unknown keys are refused."""
    ground = section.section("ground")
    ground_surface = Surface(
        enabled=ground.boolean("enabled", True),
        height=ground.number("height", 0.0),
        effect=ground.boolean("effect", True),
        max_ratio=ground.number("max_ratio", 1.5, minimum=1.0),
    )
    ground_model = ground.string("model", "single", choices=("single", "multirotor"))
    body_factor = ground.number("body_factor", 2.0, minimum=0.0)
    ground.reject_unknown()
    ceiling = section.section("ceiling")
    ceiling_surface = Surface(
        enabled=ceiling.boolean("enabled", False),
        height=ceiling.number("height", -3.0),
        effect=ceiling.boolean("effect", True),
        max_ratio=ceiling.number("max_ratio", 1.5, minimum=1.0),
    )
    k1 = ceiling.number("k1", 6.924, strictly_positive=True)
    k2 = ceiling.number("k2", 0.03782, minimum=0.0)
    ceiling.reject_unknown()
    section.reject_unknown()
    if ground_surface.enabled and ceiling_surface.enabled and ceiling_surface.height >= ground_surface.height:
        raise section.error("ceiling.height", "the ceiling must be above the ground (smaller NED z)")
    return Environment(ground_surface, ceiling_surface, ground_model, body_factor, k1, k2)


class ThrustEffects:
    """Per-rotor thrust ratio for a vehicle's geometry in an environment (allocation-free per call)."""

    def __init__(self, environment: Environment, positions: np.ndarray, rotor_radius: float) -> None:
        self.environment = environment
        self.positions = positions
        self.rotor_radius = rotor_radius
        self.separation = np.linalg.norm(positions[:, None, :] - positions[None, :, :], axis=2)
        self.arm_lengths = np.linalg.norm(positions, axis=1)
        self.enabled = environment.has_thrust_effects

    def ratios(self, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """``T_i / T_OGE,i`` for each rotor (1 away from surfaces); ground and ceiling multiply."""
        rotor_down = position[2] + self.positions @ rotation[2]  # world z of each rotor
        env = self.environment
        ratio = np.ones(len(rotor_down))
        if env.ground.enabled and env.ground.effect:
            distance = env.ground.height - rotor_down
            if env.ground_model == "multirotor":
                ratio *= multirotor_ground_effect_ratio(
                    distance, self.rotor_radius, self.separation, self.arm_lengths,
                    env.body_factor, env.ground.max_ratio,
                )
            else:
                ratio *= ground_effect_ratio(distance, self.rotor_radius, env.ground.max_ratio)
        if env.ceiling.enabled and env.ceiling.effect:
            distance = rotor_down - env.ceiling.height
            ratio *= ceiling_effect_ratio(
                distance, self.rotor_radius, env.ceiling_k1, env.ceiling_k2, env.ceiling.max_ratio
            )
        return ratio
