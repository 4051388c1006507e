"""The sensor stage (fsr_sim.core.sensors): its generator is the same compiled and under CPython, it is
standard normal, and an off stage leaves odom the true state."""

from __future__ import annotations

import numpy as np
import pytest

from fsr_sim.core import sensors
from fsr_sim.core.odometry import PUBLISHED_SIZE
from fsr_sim.model.checks import InvalidValueError
from fsr_sim.model.sensors import OdometryNoise


def test_the_generator_is_the_same_compiled_and_under_cpython():
    for seed, step, channel in [(0, 0, 0), (7, 123456, 11), (2**32 - 1, 10**7, 5), (42, 2**33 + 5, 3)]:
        assert sensors.mix32(seed + step) == sensors.mix32.py_func(seed + step)
        assert sensors.standard_normal(seed, step, channel) == sensors.standard_normal.py_func(seed, step, channel)


def test_the_generator_is_standard_normal_and_its_channels_independent():
    samples = np.array([[sensors.standard_normal(3, k, c) for c in range(2)] for k in range(100_000)])
    assert np.all(np.abs(samples.mean(axis=0)) < 0.01) and np.all(np.abs(samples.std(axis=0) - 1.0) < 0.01)
    assert abs(np.corrcoef(samples.T)[0, 1]) < 0.01
    assert abs(np.mean(samples[:, 0] ** 4) - 3.0) < 0.05  # Gaussian kurtosis
    other_seed = np.array([sensors.standard_normal(4, k, 0) for k in range(1000)])
    assert not np.allclose(other_seed, samples[:1000, 0])


def test_an_off_stage_leaves_the_row_as_it_is_and_an_on_stage_keeps_a_unit_quaternion():
    row = np.arange(PUBLISHED_SIZE, dtype=float)
    row[3:7] = (0.0, 0.6, 0.0, 0.8)
    kept = row.copy()
    sensors.sense(OdometryNoise().pack(0.001), 5, row, np.zeros(12))
    assert np.array_equal(row, kept)
    noisy = OdometryNoise(0.1, 0.05, 0.1, 0.1, seed=9).pack(0.001)
    sensors.sense(noisy, 5, row, np.zeros(12))
    assert abs(np.linalg.norm(row[3:7]) - 1.0) < 1e-15 and row[6] >= 0.0
    assert np.array_equal(row[13:], kept[13:])  # wrench_truth is never noisy
    again = kept.copy()
    sensors.sense(noisy, 5, again, np.zeros(12))
    assert np.array_equal(row, again)  # determined by (seed, step) alone


@pytest.mark.parametrize("kwargs, name", [({"position_std": -1.0}, "position_std"), ({"seed": -1}, "seed"),
                                          ({"attitude_std": float("nan")}, "attitude_std"), ({"seed": 2**32}, "seed")])
def test_invalid_noise_is_refused_naming_the_field(kwargs, name):
    with pytest.raises(InvalidValueError) as error:
        OdometryNoise(**kwargs)
    assert error.value.name == name
