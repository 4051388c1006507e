import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from fsr_sim.model import so3

RNG = np.random.default_rng(7)


def random_eta(n: int) -> np.ndarray:
    return np.column_stack((RNG.uniform(-1.2, 1.2, n), RNG.uniform(-1.2, 1.2, n), RNG.uniform(-3, 3, n)))


def test_skew_and_vee_are_inverse_and_give_cross_product():
    v, w = RNG.normal(size=3), RNG.normal(size=3)
    np.testing.assert_allclose(so3.skew(v) @ w, np.cross(v, w), atol=1e-15)
    np.testing.assert_allclose(so3.vee(so3.skew(v)), v)


def test_euler_zyx_matches_scipy_and_round_trips():
    eta = random_eta(50)
    rotations = so3.rotation_from_euler_zyx(eta)
    expected = Rotation.from_euler("ZYX", eta[:, ::-1]).as_matrix()
    np.testing.assert_allclose(rotations, expected, atol=1e-14)
    np.testing.assert_allclose(so3.euler_zyx_from_rotation(rotations), eta, atol=1e-12)


def test_quaternion_round_trip_and_scipy_order():
    for rotation in Rotation.random(20, random_state=3).as_matrix():
        q = so3.quaternion_from_rotation(rotation)
        assert q[3] >= 0.0
        np.testing.assert_allclose(so3.rotation_from_quaternion(q), rotation, atol=1e-14)
        np.testing.assert_allclose(Rotation.from_quat(q).as_matrix(), rotation, atol=1e-14)


def test_euler_rate_matrix_maps_euler_rates_to_body_angular_velocity():
    eta, eta_dot, h = np.array((0.3, -0.4, 1.1)), np.array((0.2, -0.5, 0.7)), 1e-6
    r = so3.rotation_from_euler_zyx(eta)
    r_dot = (so3.rotation_from_euler_zyx(eta + h * eta_dot) - so3.rotation_from_euler_zyx(eta - h * eta_dot)) / (2 * h)
    omega_body = so3.vee(r.T @ r_dot)
    np.testing.assert_allclose(so3.euler_rate_matrix(eta) @ eta_dot, omega_body, atol=1e-8)


def test_euler_rate_matrix_derivative_is_the_time_derivative():
    eta, eta_dot, h = np.array((0.3, -0.4, 1.1)), np.array((0.2, -0.5, 0.7)), 1e-6
    numeric = (so3.euler_rate_matrix(eta + h * eta_dot) - so3.euler_rate_matrix(eta - h * eta_dot)) / (2 * h)
    np.testing.assert_allclose(so3.euler_rate_matrix_derivative(eta, eta_dot), numeric, atol=1e-8)


def test_coriolis_matrix_satisfies_rotational_dynamics_in_euler_coordinates():
    # d/dt (M eta_dot) - C^T eta_dot ... the form used by the momentum observer: with no torque,
    # M eta_ddot + C eta_dot = 0 must reproduce Euler's equation I w_dot = -w x I w.
    inertia = np.diag((1.2, 0.9, 2.0))
    eta, eta_dot = np.array((0.2, 0.3, -0.5)), np.array((0.4, -0.3, 0.8))
    m = so3.euler_mass_matrix(eta, inertia)
    c = so3.euler_coriolis_matrix(eta, eta_dot, inertia)
    eta_ddot = np.linalg.solve(m, -c @ eta_dot)
    q = so3.euler_rate_matrix(eta)
    w = q @ eta_dot
    w_dot = so3.euler_rate_matrix_derivative(eta, eta_dot) @ eta_dot + q @ eta_ddot
    np.testing.assert_allclose(inertia @ w_dot, -np.cross(w, inertia @ w), atol=1e-12)


def test_vectorised_euler_functions_match_single_samples():
    eta, eta_dot = random_eta(5), RNG.normal(size=(5, 3))
    inertia = np.diag((1.0, 2.0, 3.0))
    stacked = so3.euler_coriolis_matrix(eta, eta_dot, inertia)
    for k in range(5):
        np.testing.assert_allclose(stacked[k], so3.euler_coriolis_matrix(eta[k], eta_dot[k], inertia))


@pytest.mark.parametrize("angle", [0.0, 1e-9, 0.7, np.pi - 1e-9, np.pi])
def test_exp_and_log_round_trip(angle):
    axis = np.array((1.0, -2.0, 0.5)) / np.linalg.norm((1.0, -2.0, 0.5))
    rotation = so3.rotation_exp(angle * axis)
    np.testing.assert_allclose(rotation, Rotation.from_rotvec(angle * axis).as_matrix(), atol=1e-12)
    log_axis, log_angle = so3.rotation_log(rotation)
    np.testing.assert_allclose(so3.rotation_exp(log_angle * log_axis), rotation, atol=1e-9)


def test_project_to_so3_gives_a_rotation():
    noisy = Rotation.random(random_state=1).as_matrix() + 1e-3 * RNG.normal(size=(3, 3))
    r = so3.project_to_so3(noisy)
    np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-14)
    assert np.linalg.det(r) == pytest.approx(1.0)


def test_shape_errors_name_expected_and_received():
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 3\), got array of shape \(4,\)"):
        so3.skew(np.zeros(4))


def test_rotations_from_quaternions_matches_the_single_sample_function():
    rng = np.random.default_rng(3)
    quaternions = rng.normal(size=(50, 4))  # not normalised: both functions normalise
    expected = np.stack([so3.rotation_from_quaternion(q) for q in quaternions])
    assert np.array_equal(so3.rotations_from_quaternions(quaternions), expected)
