"""Ground and ceiling effect: the core's per-rotor thrust ratios against the formulas, the bound, the geometry."""

import numpy as np
import pytest

from fsr_sim.core.surfaces import Surfaces
from fsr_sim.model.environment import Environment, Surface, pack_surfaces, thrust_ratio_log
from fsr_sim.model.vehicle import load_vehicle

RHO = 0.12
LEVEL = np.eye(3)


def surfaces(positions=((0.0, 0.0, 0.0),), *, ground=True, ceiling=False, multirotor=False, body_factor=2.0,
             max_ratio=1.5, k1=6.924, k2=0.03782, ceiling_height=-1.0) -> Surfaces:
    """Surfaces around rotors at ``positions`` (body = world: level), ground at z = 0."""
    positions = np.array(positions, dtype=float)
    separation = np.linalg.norm(positions[:, None] - positions[None], axis=2)
    arm = np.linalg.norm(positions, axis=1)
    return Surfaces(ground, 0.0, ground, 1.0 / max_ratio, multirotor, body_factor, ceiling, ceiling_height, ceiling,
                    1.0 / max_ratio, k1, k2, RHO, positions, separation**2, arm**2, 0.0, 0.0)


def ratio_at(z: np.ndarray, around: Surfaces) -> np.ndarray:
    """Ratios of the rotors with the centre ``z`` [m] above the ground (level), shape (len(z), n)."""
    z = np.atleast_1d(np.asarray(z, dtype=float))
    return thrust_ratio_log(around, -z, np.broadcast_to(LEVEL, (len(z), 3, 3)))


def test_ground_effect_matches_the_formula_at_rho_and_two_rho():
    single = surfaces()
    assert ratio_at(RHO, single)[0, 0] == pytest.approx(1.0 / (1.0 - 1.0 / 16.0), rel=1e-15)
    assert ratio_at(2 * RHO, single)[0, 0] == pytest.approx(1.0 / (1.0 - 1.0 / 64.0), rel=1e-15)


def test_ground_effect_is_bounded_and_continuous_near_the_surface():
    single = surfaces()
    ratio = ratio_at(np.linspace(-0.05, 3 * RHO, 2001), single)[:, 0]
    assert np.all(np.isfinite(ratio)) and ratio.max() == pytest.approx(1.5)
    assert np.all(np.diff(ratio) <= 1e-15)  # non-increasing with distance
    z_cap = RHO / (4.0 * np.sqrt(1.0 - 1.0 / 1.5))  # where the formula reaches the bound
    assert ratio_at(z_cap * 1.0001, single)[0, 0] < 1.5 < ratio_at(z_cap * 0.9999, single)[0, 0] + 1e-9
    assert ratio_at(0.0, single)[0, 0] == 1.5


def test_ceiling_effect_matches_the_formula_and_is_bounded():
    k1, k2, z = 6.924, 0.03782, 0.2
    ceiling = surfaces(ground=False, ceiling=True, ceiling_height=-1.0)
    below = ratio_at(1.0 - z, ceiling)[0, 0]  # the rotor z under the ceiling at -1 m
    assert below == pytest.approx(1.0 / (1.0 - (RHO / (z + k2)) ** 2 / k1), rel=1e-15)
    near = ratio_at(1.0 - np.linspace(-0.1, 0.05, 100), ceiling)[:, 0]
    assert np.all(np.isfinite(near)) and near.max() == pytest.approx(1.5)


def test_multirotor_ground_effect_reduces_to_single_rotor_far_from_others():
    far = ((0.0, 0.0, 0.0), (1e6, 0.0, 0.0))
    single = ratio_at([0.2, 0.3], surfaces(far))
    multi = ratio_at([0.2, 0.3], surfaces(far, multirotor=True, body_factor=0.0))
    np.testing.assert_allclose(multi[:, 0], single[:, 0], rtol=1e-12)


def test_multirotor_ground_effect_matches_sanchez_cuevas_quadrotor_formula():
    # X quadrotor: two neighbours at d, one at sqrt(2) d, body at b (Sanchez-Cuevas et al. 2017, eq. 8).
    d, b, kb, z = 0.3, 0.3 / np.sqrt(2.0), 2.0, 0.25
    pos = ((b, 0, 0), (0, b, 0), (-b, 0, 0), (0, -b, 0))
    expected = 1.0 / (
        1.0
        - (RHO / (4 * z)) ** 2
        - RHO**2 * z / np.sqrt((d**2 + 4 * z**2) ** 3)
        - (RHO**2 / 2) * z / np.sqrt((2 * d**2 + 4 * z**2) ** 3)
        - 2 * RHO**2 * z / np.sqrt((b**2 + 4 * z**2) ** 3) * kb
    )
    np.testing.assert_allclose(ratio_at(z, surfaces(pos, multirotor=True, body_factor=kb))[0], expected, rtol=1e-12)


def test_each_rotor_of_a_tilted_vehicle_sees_its_own_distances():
    """A tilted octocopter between ground and ceiling: rotor i at world down-coordinate ``p_z + (R p_i)_z`` gets
    the single-rotor ground formula times the ceiling formula at its own distances."""
    from scipy.spatial.transform import Rotation

    vehicle = load_vehicle("octocopter")
    env = Environment(Surface(True, 0.0, True, 1.5), Surface(True, -0.6, True, 1.4))
    packed = pack_surfaces(env, vehicle)
    rng = np.random.default_rng(5)
    rotations = Rotation.random(40, random_state=2).as_matrix()
    heights = rng.uniform(-0.5, -0.1, 40)
    rho, k1, k2 = vehicle.rotor_radius, env.ceiling_k1, env.ceiling_k2
    rotor_down = heights[:, None] + rotations[:, 2, :] @ vehicle.positions.T
    ground = 1.0 / np.maximum(1.0 - (rho / (4.0 * np.maximum(-rotor_down, 1e-3))) ** 2, 1.0 / 1.5)
    ceiling = 1.0 / np.maximum(1.0 - (rho / (np.maximum(rotor_down + 0.6, 1e-3) + k2)) ** 2 / k1, 1.0 / 1.4)
    np.testing.assert_allclose(thrust_ratio_log(packed, heights, rotations), ground * ceiling, rtol=1e-14)
