"""Ground and ceiling: the thrust change near them and the contact rule (compiled core).

Surfaces are horizontal planes of the NED world given by their down-coordinate ``height`` [m]. For rotor
``i`` at world position ``r_i = p + R p_i`` the distance to the ground is ``z = ground_height - r_i,z`` and to
the ceiling ``z = r_i,z - ceiling_height``. Thrust ratios at constant power, ``T / T_OGE``:

* ground (method of images, Cheeseman & Bennett): ``1 / (1 - (rho / (4 z))^2)``;
* ground, multirotor (Sanchez-Cuevas et al. 2017), generalised to ``n`` rotors: the denominator also loses
  ``sum_{j != i} (rho^2 z / 2) / (d_ij^2 + 4 z^2)^(3/2)`` for the other rotors at distance ``d_ij`` and
  ``2 K_b rho^2 z / (b^2 + 4 z^2)^(3/2)`` for the body at distance ``b`` (the arm);
* ceiling (empirical): ``1 / (1 - (1 / k1) (rho / (z + k2))^2)``.

Ground and ceiling multiply. Bound near the surface (all three are singular there): the ratio is
``1 / max(D, 1 / max_ratio)`` with ``D`` the denominator, and distances are floored at ``MIN_DISTANCE``
(1 mm) so that a rotor at or through the surface gets the bounded value. A ratio held at ``max_ratio`` means
the vehicle is closer than the model is valid for: :func:`thrust_ratios` reports it.

Contact (:func:`in_contact`, :func:`surface_contact`): the landing gear's feet are ``contact_height`` below the
centre of mass and the top ``top_height`` above it, along world down.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_sim.core.jit import jit, jit_inline
from fsr_sim.core.so3 import Vec3

MIN_DISTANCE = 1e-3  # m, floor for surface distances
CONTACT_TOLERANCE = 0.002  # m: feet (or top) this close to a surface count as touching it


class Surfaces(NamedTuple):
    """The surfaces around one vehicle and its geometry (packed once by :func:`fsr_sim.model.environment.
    pack_surfaces`). Heights are world NED down-coordinates [m]; a ``floor`` is ``1 / max_ratio``."""

    ground: bool  # enabled (solid)
    ground_height: float
    ground_effect: bool
    ground_floor: float
    multirotor: bool  # the multirotor ground model
    body_factor: float  # K_b
    ceiling: bool
    ceiling_height: float
    ceiling_effect: bool
    ceiling_floor: float
    ceiling_k1: float
    ceiling_k2: float  # [m]
    rotor_radius: float  # rho [m]
    rotor_positions: np.ndarray  # (n, 3) body FRD [m]
    separation_sq: np.ndarray  # (n, n) d_ij^2 [m^2]
    arm_sq: np.ndarray  # (n,) b_i^2 [m^2]
    contact_height: float  # [m] feet below the centre of mass
    top_height: float  # [m] top above the centre of mass


@jit_inline
def has_thrust_effects(surfaces: Surfaces) -> bool:
    """Whether any surface changes the rotors' thrust."""
    return (surfaces.ground and surfaces.ground_effect) or (surfaces.ceiling and surfaces.ceiling_effect)


@jit
def _three_halves(x: float) -> float:
    """``x^(3/2)`` as ``x sqrt(x)`` (exact operations: the same bits compiled and under CPython)."""
    return x * math.sqrt(x)


@jit_inline
def thrust_ratios(surfaces: Surfaces, position_down: float, rotation_row2: Vec3, out) -> tuple[bool, bool]:  # noqa: ANN001
    """``T_i / T_OGE,i`` of every rotor into ``out`` (n,) for the centre's down-coordinate ``p_z`` [m] and the
    third row of ``R``; returns whether a ground / a ceiling ratio was held at its ``max_ratio``.

    ``a if not a < b else b`` is ``max(a, b)`` that keeps NaN (a NaN state stays NaN)."""
    rho = surfaces.rotor_radius
    rho2 = rho * rho
    ground = surfaces.ground and surfaces.ground_effect
    ceiling = surfaces.ceiling and surfaces.ceiling_effect
    positions, separation_sq = surfaces.rotor_positions, surfaces.separation_sq
    r0, r1, r2 = rotation_row2
    ground_capped = ceiling_capped = False
    n = positions.shape[0]
    for i in range(n):
        rotor_down = position_down + (positions[i, 0] * r0 + positions[i, 1] * r1 + positions[i, 2] * r2)
        ratio = 1.0
        if ground:
            z = surfaces.ground_height - rotor_down
            z = z if not z < MIN_DISTANCE else MIN_DISTANCE
            image = rho / (4.0 * z)
            denominator = 1.0 - image * image
            if surfaces.multirotor:
                c, q = 0.5 * rho2 * z, 4.0 * (z * z)  # a neighbour at d takes c / (d^2 + q)^(3/2)
                neighbours = 0.0
                for j in range(n):
                    if j != i:
                        neighbours = neighbours + c / _three_halves(separation_sq[i, j] + q)
                body = 2.0 * surfaces.body_factor * rho2 * z / _three_halves(surfaces.arm_sq[i] + q)
                denominator = denominator - neighbours - body
            if denominator < surfaces.ground_floor:
                denominator = surfaces.ground_floor
                ground_capped = True
            ratio = 1.0 / denominator
        if ceiling:
            z = rotor_down - surfaces.ceiling_height
            z = z if not z < MIN_DISTANCE else MIN_DISTANCE
            image = rho / (z + surfaces.ceiling_k2)
            denominator = 1.0 - image * image / surfaces.ceiling_k1
            if denominator < surfaces.ceiling_floor:
                denominator = surfaces.ceiling_floor
                ceiling_capped = True
            ratio = ratio * (1.0 / denominator)
        out[i] = ratio
    return ground_capped, ceiling_capped


@jit_inline
def ground_rest_z(surfaces: Surfaces) -> float:
    """The centre's down-coordinate [m] with the feet on the ground."""
    return surfaces.ground_height - surfaces.contact_height


@jit_inline
def ceiling_rest_z(surfaces: Surfaces) -> float:
    """The centre's down-coordinate [m] with the top at the ceiling."""
    return surfaces.ceiling_height + surfaces.top_height


@jit_inline
def in_contact(surfaces: Surfaces, z: float) -> bool:
    """The contact rule: the centre's down-coordinate ``z`` [m] puts the feet within ``CONTACT_TOLERANCE`` of
    the ground, or the top within it of the ceiling (enabled surfaces only)."""
    if surfaces.ground and z >= ground_rest_z(surfaces) - CONTACT_TOLERANCE:
        return True
    return surfaces.ceiling and z <= ceiling_rest_z(surfaces) + CONTACT_TOLERANCE


@jit
def thrust_ratio_log(surfaces: Surfaces, position_down, rotation_row2, out) -> None:  # noqa: ANN001
    """:func:`thrust_ratios` at every pose of a log: ``position_down`` (N,) [m], ``rotation_row2`` (N, 3) the
    third rows of ``R``, ``out`` (N, n)."""
    for k in range(position_down.shape[0]):
        row = (rotation_row2[k, 0], rotation_row2[k, 1], rotation_row2[k, 2])
        thrust_ratios(surfaces, position_down[k], row, out[k])


@jit
def contact_log(surfaces: Surfaces, position_down, out) -> None:  # noqa: ANN001
    """:func:`in_contact` at every sample of a log: ``position_down`` (N,) [m] into ``out`` (N,) bool."""
    for k in range(position_down.shape[0]):
        out[k] = in_contact(surfaces, position_down[k])
