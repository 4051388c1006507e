import math

import numpy as np
import pytest

from fsr_estimation.estimator.metrics import (
    max_error_after,
    mean_absolute_error,
    settling_time,
    settling_time_report,
    settling_time_standard,
    sweep,
)
from fsr_estimation.estimator.observer import ObserverModel

TS = 0.01
TIME = np.arange(1001) * TS  # 10 s


def ramp_then_hold(level, t_reach, overshoot_until=None):
    x = np.minimum(TIME / t_reach, 1.0) * level
    if overshoot_until is not None:
        x = np.where((TIME >= t_reach) & (TIME < overshoot_until), 1.1 * level, x)
    return x


def test_standard_settling_is_the_entry_into_the_final_band():
    truth = np.array([1.0, 1.0])
    estimate = np.stack((ramp_then_hold(1.0, 2.5), ramp_then_hold(1.0, 2.5, overshoot_until=3.0)), axis=1)
    # |e| <= 0.03 from t >= 2.425 s on the ramp (first sample 2.43 s); the second overshoots by 10 % until 3 s
    np.testing.assert_allclose(settling_time_standard(TIME, estimate, truth), [2.43, 3.0])


def test_standard_settling_is_undefined_for_zero_truth_or_a_late_excursion():
    estimate = np.ones((len(TIME), 3))
    estimate[-1, 1] = 2.0
    result = settling_time_standard(TIME, estimate, np.array([0.0, 1.0, 1.0]))
    assert math.isnan(result[0]) and math.isnan(result[1]) and result[2] == 0.0


def test_report_settling_uses_signed_error_window_and_one_based_sample_times():
    truth = np.array([1.0])
    above = 1.0 + np.where(TIME < 1.0, 0.5, 0.0)[:, None]  # 50 % above the truth until 1 s
    # first k whose window [k - 2 s, k + 4 s] holds no sample above the band: k = 1 s + 2 s (index 300),
    # reported as (300 + 1) T_s
    assert settling_time_report(TIME, above, truth)[0] == pytest.approx(3.01)
    below = 1.0 - np.where(TIME < 1.0, 0.5, 0.0)[:, None]  # approaching from below counts as settled at once
    assert settling_time_report(TIME, below, truth)[0] == pytest.approx(TS)
    assert settling_time_standard(TIME, below, truth)[0] == pytest.approx(1.0)


def test_settling_rejects_an_unknown_definition():
    with pytest.raises(ValueError, match="standard, report"):
        settling_time(TIME, np.ones((len(TIME), 1)), np.ones(1), "fastest")


def test_mae_and_max_error_after():
    estimate = np.zeros((len(TIME), 2))
    estimate[:, 0] = np.where(TIME < 5.0, 1.0, 0.1)
    truth = np.array([0.0, -2.0])
    np.testing.assert_allclose(mean_absolute_error(estimate, truth), [(500 * 1.0 + 501 * 0.1) / 1001, 2.0])
    np.testing.assert_allclose(max_error_after(TIME, estimate, truth, 5.0), [0.1, 2.0])
    assert np.isnan(max_error_after(TIME, estimate, truth, 11.0)).all()


def test_sweep_gives_one_result_per_pair_and_refuses_bad_orders(synthetic):
    log, force = synthetic(n=3000)
    model = ObserverModel(1.5, np.diag([1.2416, 1.2416, 2.4832]))
    truth = np.concatenate((force, np.zeros(3)))
    results = sweep(log, model, [5.0, 20.0], [1, 2], truth)
    assert [(r.c0, r.r) for r in results] == [(5.0, 1), (5.0, 2), (20.0, 1), (20.0, 2)]
    # a faster filter settles sooner; a higher order later
    settle = {(r.c0, r.r): r.settling_time[0] for r in results}
    assert settle[(20.0, 1)] < settle[(5.0, 1)] and settle[(20.0, 1)] < settle[(20.0, 2)]
    with pytest.raises(ValueError, match="r: must be an integer"):
        sweep(log, model, [5.0], [0], truth)


def test_smoothed_settling_is_the_standard_one_through_the_low_pass_and_sees_through_noise():
    from fsr_estimation.estimator.metrics import low_pass, settling_time_smoothed, smoothing_gain

    gain = smoothing_gain(TS)
    values = np.random.default_rng(0).normal(size=(50, 2))
    expected = values.copy()
    for k in range(1, len(values)):  # the sweep's running filter
        expected[k] = gain * values[k] + (1.0 - gain) * expected[k - 1]
    np.testing.assert_array_equal(low_pass(values, gain), expected)
    level = np.array([1.0, 2.0])
    estimate = np.stack([ramp_then_hold(1.0, 2.0), ramp_then_hold(2.0, 2.0)], axis=1)
    noisy = estimate + 0.02 * level * np.random.default_rng(1).normal(size=estimate.shape)  # 3 % at 1.5 sigma
    assert not (settling_time_standard(TIME, noisy, level) < 9.0).any()  # NaN, or a last sample by chance
    smoothed = settling_time_smoothed(TIME, noisy, level)
    assert np.all((smoothed > 1.9) & (smoothed < 3.0)), smoothed  # the ramp's end, a few tenths later
    np.testing.assert_array_equal(settling_time(TIME, noisy, level, "smoothed"), smoothed)


def test_the_low_pass_takes_read_only_and_strided_logs_as_it_takes_their_copies():
    from fsr_estimation.estimator.metrics import low_pass

    values = np.random.default_rng(2).normal(size=(40, 4))
    expected = low_pass(values.copy(), 0.3)
    read_only = values.copy()
    read_only.flags.writeable = False
    np.testing.assert_array_equal(low_pass(read_only, 0.3), expected)
    np.testing.assert_array_equal(low_pass(np.asfortranarray(values), 0.3), expected)
    np.testing.assert_array_equal(low_pass(values[:, 1], 0.3), expected[:, 1])
