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

Reaching the cap means the vehicle is closer to the surface than the model is valid for; :class:`ThrustEffects`
raises ``ground_capped`` / ``ceiling_capped`` when a rotor is evaluated at the cap (the plant counts the steps
and clears them).

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

from fsr_sim.model.so3 import Vec3

MIN_DISTANCE = 1e-3  # m, floor for surface distances
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


def bounded_ratio(denominator: np.ndarray | float, max_ratio: float) -> np.ndarray:
    """``1 / max(D, 1 / max_ratio)``: the thrust ratio, continuous and at most ``max_ratio``."""
    return 1.0 / np.maximum(denominator, 1.0 / max_ratio)


# The formulas, written with arithmetic operators only so that they serve both the vectorised functions
# (arrays, whole logs) and the plant's per-rotor path on Python floats (every RK4 stage): one definition.
def _ground_denominator(z: np.ndarray | float, rotor_radius: float) -> np.ndarray | float:
    """``1 - (rho / (4 z))^2`` (single-rotor images), ``z`` floored."""
    return 1.0 - (rotor_radius / (4.0 * z)) ** 2


def _neighbour_scale(z: np.ndarray | float, rho2: float) -> tuple[np.ndarray | float, np.ndarray | float]:
    """``(c, q) = (rho^2 z / 2, 4 z^2)``: a neighbour at distance ``d`` takes ``c / (d^2 + q)^(3/2)`` off the
    denominator (both paths evaluate exactly that expression with these two numbers)."""
    return 0.5 * rho2 * z, 4.0 * z**2


def _body_term(z: np.ndarray | float, arm_sq: np.ndarray | float, rho2: float, body_factor: float
               ) -> np.ndarray | float:
    """``2 K_b rho^2 z / (b^2 + 4 z^2)^(3/2)``: the body's share of the denominator."""
    return 2.0 * body_factor * rho2 * z / (arm_sq + 4.0 * z**2) ** 1.5


def _ceiling_denominator(z: np.ndarray | float, rotor_radius: float, k1: float, k2: float) -> np.ndarray | float:
    """``1 - (1/k1) (rho / (z + k2))^2``, ``z`` floored."""
    return 1.0 - (rotor_radius / (z + k2)) ** 2 / k1


def ground_effect_ratio(distance: np.ndarray | float, rotor_radius: float, max_ratio: float = 1.5) -> np.ndarray:
    """``T_IGE / T_OGE = 1 / (1 - (rho / (4 z))^2)`` for distances ``z`` [m] to the ground (bounded)."""
    z = np.maximum(distance, MIN_DISTANCE)
    return bounded_ratio(_ground_denominator(z, rotor_radius), max_ratio)


def multirotor_ground_effect_ratio(
    distance: np.ndarray,
    rotor_radius: float,
    rotor_separation: np.ndarray,
    arm_lengths: np.ndarray,
    body_factor: float = 2.0,
    max_ratio: float = 1.5,
) -> np.ndarray:
    """Per-rotor ground-effect ratio with the neighbouring rotors and the body (Sanchez-Cuevas 2017).

    distance: shape (n,), each rotor's distance to the ground [m], or (..., n) for many poses at once (a
    whole log). rotor_separation: shape (n, n), ``d_ij`` [m] (diagonal ignored). arm_lengths: shape (n,),
    ``b_i`` [m].
    """
    z = np.maximum(distance, MIN_DISTANCE)
    rho2 = rotor_radius**2
    c, q = _neighbour_scale(z[..., :, None], rho2)
    separation = np.asarray(rotor_separation)
    others = 1.0 - np.eye(len(separation))  # rotor i's own term is left out
    neighbours = others * (c / (separation**2 + q) ** 1.5)
    body = _body_term(z, np.asarray(arm_lengths) ** 2, rho2, body_factor)
    denominator = _ground_denominator(z, rotor_radius) - neighbours.sum(axis=-1) - body
    return bounded_ratio(denominator, max_ratio)


def ceiling_effect_ratio(
    distance: np.ndarray | float, rotor_radius: float, k1: float, k2: float, max_ratio: float = 1.5
) -> np.ndarray:
    """``T_CE / T_OGE = 1 / (1 - (1/k1) (rho / (z + k2))^2)`` for distances ``z`` [m] to the ceiling."""
    z = np.maximum(distance, MIN_DISTANCE)
    return bounded_ratio(_ceiling_denominator(z, rotor_radius, k1, k2), max_ratio)


class ThrustEffects:
    """Per-rotor thrust ratio for a vehicle's geometry in an environment (allocation-free per call)."""

    def __init__(self, environment: Environment, positions: np.ndarray, rotor_radius: float) -> None:
        self.environment = environment
        self.positions = positions
        self.rotor_radius = rotor_radius
        self.separation = np.linalg.norm(positions[:, None, :] - positions[None, :, :], axis=2)
        self.arm_lengths = np.linalg.norm(positions, axis=1)
        self.enabled = environment.has_thrust_effects
        # Constants of the per-rotor float path (ratios_floats() runs at every RK4 stage).
        self._rotor_positions = [tuple(row) for row in positions.tolist()]
        separations = self.separation.tolist()
        self._others_sq = [[d * d for j, d in enumerate(row) if j != i] for i, row in enumerate(separations)]
        self._arm_sq = [b * b for b in self.arm_lengths.tolist()]
        ground, ceiling = environment.ground, environment.ceiling
        self._ground = ground.enabled and ground.effect
        self._ceiling = ceiling.enabled and ceiling.effect
        self._multirotor = environment.ground_model == "multirotor"
        self.ground_capped = False  # set by ratios_floats when a rotor's ground ratio is at max_ratio
        self.ceiling_capped = False  # likewise for the ceiling (the plant counts and clears both)

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

    def ratios_floats(self, position_down: float, rotation_row2: Vec3) -> list[float]:
        """:meth:`ratios` on Python floats: ``position_down`` = p_z [m], ``rotation_row2`` = third row of ``R``.

        ``a if not a < b else b`` is ``max(a, b)`` that propagates NaN like ``np.maximum`` (so does the
        explicit ``if denominator < floor``). Sets ``ground_capped`` / ``ceiling_capped`` when a ratio is held
        at its ``max_ratio``.
        """
        env = self.environment
        rho = self.rotor_radius
        rho2 = rho * rho
        ground, ceiling, multirotor = self._ground, self._ceiling, self._multirotor
        ground_height, ceiling_height = env.ground.height, env.ceiling.height
        ground_floor, ceiling_floor = 1.0 / env.ground.max_ratio, 1.0 / env.ceiling.max_ratio
        body_factor, k1, k2 = env.body_factor, env.ceiling_k1, env.ceiling_k2
        r0, r1, r2 = rotation_row2
        out = []
        for (px, py, pz), others_sq, arm_sq in zip(self._rotor_positions, self._others_sq, self._arm_sq, strict=True):
            rotor_down = position_down + (px * r0 + py * r1 + pz * r2)  # world z of the rotor
            ratio = 1.0
            if ground:
                z = ground_height - rotor_down
                z = z if not z < MIN_DISTANCE else MIN_DISTANCE
                denominator = _ground_denominator(z, rho)
                if multirotor:
                    c, q = _neighbour_scale(z, rho2)
                    neighbours = sum([c / (d2 + q) ** 1.5 for d2 in others_sq])
                    denominator = denominator - neighbours - _body_term(z, arm_sq, rho2, body_factor)
                if denominator < ground_floor:
                    denominator = ground_floor
                    self.ground_capped = True
                ratio = 1.0 / denominator
            if ceiling:
                z = rotor_down - ceiling_height
                z = z if not z < MIN_DISTANCE else MIN_DISTANCE
                denominator = _ceiling_denominator(z, rho, k1, k2)
                if denominator < ceiling_floor:
                    denominator = ceiling_floor
                    self.ceiling_capped = True
                ratio = ratio * (1.0 / denominator)
            out.append(ratio)
        return out
