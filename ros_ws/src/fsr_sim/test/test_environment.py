import numpy as np
import pytest

from fsr_sim.model.environment import (
    ceiling_effect_ratio,
    ground_effect_ratio,
    multirotor_ground_effect_ratio,
)

RHO = 0.12


def test_ground_effect_matches_the_formula_at_rho_and_two_rho():
    assert ground_effect_ratio(RHO, RHO) == pytest.approx(1.0 / (1.0 - 1.0 / 16.0), rel=1e-15)
    assert ground_effect_ratio(2 * RHO, RHO) == pytest.approx(1.0 / (1.0 - 1.0 / 64.0), rel=1e-15)


def test_ground_effect_is_bounded_and_continuous_near_the_surface():
    z = np.linspace(-0.05, 3 * RHO, 2001)
    ratio = ground_effect_ratio(z, RHO, max_ratio=1.5)
    assert np.all(np.isfinite(ratio)) and ratio.max() == pytest.approx(1.5)
    assert np.all(np.diff(ratio) <= 1e-15)  # non-increasing with distance
    z_cap = RHO / (4.0 * np.sqrt(1.0 - 1.0 / 1.5))  # where the formula reaches the bound
    assert ground_effect_ratio(z_cap * 1.0001, RHO) < 1.5 < ground_effect_ratio(z_cap * 0.9999, RHO) + 1e-9
    assert ground_effect_ratio(0.0, RHO) == 1.5


def test_ceiling_effect_matches_the_formula_and_is_bounded():
    k1, k2, z = 6.924, 0.03782, 0.2
    expected = 1.0 / (1.0 - (RHO / (z + k2)) ** 2 / k1)
    assert ceiling_effect_ratio(z, RHO, k1, k2) == pytest.approx(expected, rel=1e-15)
    assert ceiling_effect_ratio(RHO, RHO, k1, k2) == pytest.approx(1.0 / (1.0 - (RHO / (RHO + k2)) ** 2 / k1))
    near = ceiling_effect_ratio(np.linspace(-0.1, 0.05, 100), RHO, k1, k2, max_ratio=1.5)
    assert np.all(np.isfinite(near)) and near.max() == pytest.approx(1.5)


def test_multirotor_ground_effect_reduces_to_single_rotor_far_from_others():
    z = np.array((0.2, 0.3))
    far = np.array(((0.0, 1e6), (1e6, 0.0)))
    single = ground_effect_ratio(z, RHO)
    multi = multirotor_ground_effect_ratio(z, RHO, far, np.array((1e6, 1e6)), body_factor=0.0)
    np.testing.assert_allclose(multi, single, rtol=1e-12)


def test_multirotor_ground_effect_matches_sanchez_cuevas_quadrotor_formula():
    # X quadrotor: two neighbours at d, one at sqrt(2) d, body at b (Sanchez-Cuevas et al. 2017, eq. 8).
    d, b, kb, z = 0.3, 0.3 / np.sqrt(2.0), 2.0, 0.25
    pos = np.array(((b, 0), (0, b), (-b, 0), (0, -b)), dtype=float)
    sep = np.linalg.norm(pos[:, None] - pos[None], axis=2)
    expected = 1.0 / (
        1.0
        - (RHO / (4 * z)) ** 2
        - RHO**2 * z / np.sqrt((d**2 + 4 * z**2) ** 3)
        - (RHO**2 / 2) * z / np.sqrt((2 * d**2 + 4 * z**2) ** 3)
        - 2 * RHO**2 * z / np.sqrt((b**2 + 4 * z**2) ** 3) * kb
    )
    ratio = multirotor_ground_effect_ratio(np.full(4, z), RHO, sep, np.full(4, b), body_factor=kb)
    np.testing.assert_allclose(ratio, expected, rtol=1e-12)


@pytest.mark.parametrize("model", ["single", "multirotor"])
def test_per_rotor_float_path_equals_the_vectorised_ratios(model):
    """The plant's per-stage path (ratios_floats) and ratios() / thrust_ratios() are the same formulas."""
    from scipy.spatial.transform import Rotation

    from fsr_sim.model.environment import Environment, Surface, ThrustEffects
    from fsr_sim.model.vehicle import load_vehicle

    vehicle = load_vehicle("octocopter")
    env = Environment(Surface(True, 0.0, True, 1.5), Surface(True, -0.6, True, 1.4), ground_model=model)
    effects = ThrustEffects(env, vehicle.positions, vehicle.rotor_radius)
    rng = np.random.default_rng(5)
    for rotation, height in zip(Rotation.random(40, random_state=2).as_matrix(), rng.uniform(-0.7, 0.1, 40),
                                strict=True):
        position = np.array((0.3, -0.2, height))
        expected = effects.ratios(position, rotation)
        assert np.any(expected != 1.0)
        np.testing.assert_allclose(effects.ratios_floats(height, tuple(rotation[2])), expected, rtol=1e-14)
