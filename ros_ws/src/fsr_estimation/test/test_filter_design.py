import numpy as np
import pytest

from fsr_estimation.estimator.filter_design import (
    cascade_sections,
    check_filter_parameters,
    denominator_coefficients,
    gain_chain,
)


@pytest.mark.parametrize("c0", [1.0, 5.0, 10.0, 100.0])
@pytest.mark.parametrize("r", [1, 2, 3, 4, 5, 7])
def test_denominator_is_repeated_pole_and_gain_chain_multiplies_to_c0_power_r(c0, r):
    d = denominator_coefficients(c0, r)
    np.testing.assert_allclose(d[::-1], np.poly(np.full(r, -c0)), rtol=1e-12)
    gains = gain_chain(c0, r)
    assert gains.shape == (r,)
    assert np.prod(gains) == pytest.approx(c0**r, rel=1e-12)
    # K_j ... K_r = d_{j-1}: the integrator chain realises exactly (s + c0)^r
    for j in range(1, r + 1):
        assert np.prod(gains[j - 1:]) == pytest.approx(d[j - 1], rel=1e-12)


def test_first_order_gain_is_c0_and_second_order_matches_hand_values():
    assert gain_chain(10.0, 1).tolist() == [10.0]
    np.testing.assert_allclose(gain_chain(10.0, 2), [5.0, 20.0])  # K_2 = 2 c0, K_1 = c0^2 / K_2
    np.testing.assert_allclose(gain_chain(10.0, 3), [10.0 / 3.0, 10.0, 30.0])


def test_cascade_has_unit_dc_gain_per_sample_input():
    sections = cascade_sections(10.0, 3, 0.001)
    b, a = sections[:, :3].sum(axis=1), sections[:, 3:].sum(axis=1)
    # u = T_s w for a constant w: DC gain of H(z) times T_s is 1
    assert np.prod(b / a) * 0.001 == pytest.approx(1.0)


@pytest.mark.parametrize(
    ("c0", "r", "ts", "message"),
    [(0.0, 1, None, "c0"), (-1.0, 1, None, "c0"), (float("nan"), 1, None, "c0"), (1.0, 0, None, "r"),
     (1.0, 1.5, None, "r"), (1.0, True, None, "r"), (1.0, 1, 0.0, "sample_time"), (2000.0, 1, 0.001, "unstable")],
)
def test_bad_parameters_are_refused_by_name(c0, r, ts, message):
    with pytest.raises(ValueError, match=message):
        check_filter_parameters(c0, r, ts)
