import numpy as np
import pytest

from fsr_estimation.estimator.metrics import mass_change
from fsr_estimation.estimator.momentum import model_momentum_rate
from fsr_estimation.estimator.observer import (
    MomentumObserver,
    ObserverModel,
    body_frame_wrench,
    estimate_log,
)
from fsr_sim.model.so3 import euler_coriolis_matrix, euler_rate_matrix, euler_rate_matrix_derivative

MASS = 1.5
INERTIA = np.diag([1.2416, 1.2416, 2.4832])
MODEL = ObserverModel(MASS, INERTIA)


def arrays(log):
    return log.velocity_world, log.eta, log.eta_dot, log.force_body, log.torque_body


def run_online(log, c0, r, count=None, body_every=1):
    """Observer outputs for the first ``count`` samples and the body-frame wrench every ``body_every``."""
    observer = MomentumObserver(MASS, [1.2416, 1.2416, 2.4832], c0, r, log.sample_time)
    count = len(log) if count is None else count
    out = np.empty((count, 6))
    body = np.full((count, 6), np.nan)
    v, eta, eta_dot, force, torque = arrays(log)
    for k in range(count):
        out[k] = observer.update(v[k], eta[k], eta_dot[k], force[k], torque[k])
        if k % body_every == 0:
            body[k] = np.concatenate(observer.wrench_body())
    return observer, out, body


def test_online_recursion_equals_whole_log_filter_on_the_report_log(report_log):
    observer, online, body = run_online(report_log, 10.0, 3, body_every=97)
    offline = estimate_log(*arrays(report_log), model=MODEL, c0=10.0, r=3, sample_time=report_log.sample_time)
    assert np.abs(online - offline).max() < 1e-9
    checked = ~np.isnan(body[:, 0])
    assert np.abs(body[checked] - body_frame_wrench(offline, report_log.eta)[checked]).max() < 1e-9
    assert observer.mass_estimate == pytest.approx(MASS + offline[-1, 2] / 9.81, abs=1e-12)


@pytest.mark.parametrize(("c0", "r"), [(1.0, 1), (10.0, 5), (100.0, 2)])
def test_online_equals_whole_log_on_a_rotating_segment(report_log, c0, r):
    count = 3000  # the start of the report log: the vehicle rolls, pitches and yaws
    _, online, _ = run_online(report_log, c0, r, count)
    offline = estimate_log(*(a[:count] for a in arrays(report_log)), model=MODEL, c0=c0, r=r,
                           sample_time=report_log.sample_time)
    assert np.abs(online - offline).max() < 1e-9


def test_report_mass_estimate_is_minus_a_quarter_kilogram_ned(report_log):
    w = estimate_log(*arrays(report_log), model=MODEL, c0=10.0, r=1, sample_time=report_log.sample_time)
    assert mass_change(w, 9.81) == pytest.approx(-0.25, abs=5e-4)
    assert w[-1, 2] < 0.0  # NED: the lighter vehicle's residual force points up


@pytest.mark.parametrize("r", [1, 2, 4])
def test_constant_external_force_is_recovered_exactly_in_steady_state(r, synthetic):
    log, force_world = synthetic()
    w = estimate_log(*arrays(log), model=MODEL, c0=20.0, r=r, sample_time=log.sample_time)
    np.testing.assert_allclose(w[-1, :3], force_world, atol=1e-9)
    np.testing.assert_allclose(w[-1, 3:], 0.0, atol=1e-9)
    assert np.all(w[0] == 0.0)


def test_mass_estimate_of_a_lighter_plant_is_lower(synthetic):
    # The plant weighs 1.2 kg but the model says 1.5 kg: the data look like an upward force of 0.3 g.
    log, _ = synthetic(mass=1.2, force_world=np.zeros(3))
    observer = MomentumObserver(MASS, INERTIA, 20.0, 1, log.sample_time)
    for k in range(len(log)):
        observer.update(*(a[k] for a in arrays(log)))
    assert observer.mass_estimate == pytest.approx(1.2, abs=1e-4)  # thrust noise passes through (m - m_model) a


def test_reset_restarts_from_zero_and_reproduces_the_sequence(report_log):
    observer = MomentumObserver(MASS, INERTIA, 10.0, 2, report_log.sample_time)
    first = [observer.update(*(a[k] for a in arrays(report_log))).copy() for k in range(200)]
    observer.reset()
    again = [observer.update(*(a[k] for a in arrays(report_log))).copy() for k in range(200)]
    assert np.all(again[0] == 0.0) and np.any(first[-1] != 0.0)
    np.testing.assert_array_equal(np.array(first), np.array(again))


def test_lean_coriolis_term_matches_the_so3_matrix():
    rng = np.random.default_rng(3)
    eta = rng.uniform(-1.2, 1.2, (50, 3))
    eta_dot = rng.normal(size=(50, 3))
    omega = np.einsum("kij,kj->ki", euler_rate_matrix(eta), eta_dot)
    lean = np.einsum("kji,kj->ki", euler_rate_matrix_derivative(eta, eta_dot), omega @ INERTIA.T)
    full = np.einsum("kji,kj->ki", euler_coriolis_matrix(eta, eta_dot, INERTIA), eta_dot)
    np.testing.assert_allclose(lean, full, atol=1e-12)


def test_general_body_force_reduces_to_the_reports_thrust_form():
    rng = np.random.default_rng(4)
    eta = rng.uniform(-0.5, 0.5, (20, 3))
    thrust = rng.uniform(5, 15, 20)
    force = np.zeros((20, 3))
    force[:, 2] = -thrust
    b = model_momentum_rate(MASS, INERTIA, eta, np.zeros((20, 3)), force, np.zeros((20, 3)))
    from fsr_sim.model.so3 import rotation_from_euler_zyx

    report = MASS * 9.81 * np.array([0, 0, 1.0]) - thrust[:, None] * rotation_from_euler_zyx(eta)[:, :, 2]
    np.testing.assert_allclose(b[:, :3], report, atol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"mass": 0.0}, "mass"), ({"inertia": [1, 1]}, "inertia"), ({"inertia": [[1, 2, 0], [0, 1, 0], [0, 0, 1]]},
     "symmetric"), ({"inertia": [1, -1, 1]}, "positive definite"), ({"c0": -1.0}, "c0"), ({"r": 0}, "r")],
)
def test_bad_observer_parameters_are_refused(kwargs, message):
    args = {"mass": MASS, "inertia": INERTIA, "c0": 10.0, "r": 1, "sample_time": 0.001} | kwargs
    with pytest.raises(ValueError, match=message):
        MomentumObserver(**args)
