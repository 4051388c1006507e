"""The seeded conditions a candidate is flown under: condition ``c`` of a study seeded ``seed`` sets every random
source of the scenario from ``(seed, c)`` - the sensor stage's noise seeds and each Dryden turbulence's seed - and
gives each ``--sample``d key (a mass error, a motor lag) a value, so the same condition is the same flight for every
candidate (common random numbers: candidates are compared on the same gusts and the same noise). Conditions
``0 .. N-1`` train; the held-out conditions the tuner never sees are ``N .. N+H-1``.

The held-out conditions draw each sampled key from ``numpy.random.default_rng((seed, c))``: independent draws of its
distribution, the test of the tuned values. The ``N`` training conditions spread each sampled key over its
distribution instead (:func:`spread_quantile`): the quantiles ``0, 1/(N-1), .., 1`` - a bounded distribution's
bounds included - or ``(i + 1/2) / N`` of a normal, in an order shuffled per key. Ten random draws leave a
uniform's outer tenth on one side unseen about one study in three (``0.9^10``), and an optimiser pushes its
candidates to the edge of what flies on the conditions it sees: gains tuned that way lose the flights beyond it
(docs/tuning.md's walk-through: the lightest masses of its +-20 %, where the roll and pitch torque runs out first).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from fsr_bringup.runner.scenario_check import check_scenario
from fsr_bringup.sweeps.axes import SampledKey, _current_value, flight_scenario
from fsr_sim.config.scenario import Scenario
from fsr_sim.config.validation import ConfigError

# Seed keys of the sensor stages: the odometry's also set where its noise is off (it then changes nothing), the
# IMU's only where the scenario has an IMU (set alone, the key would add one, ideal, that the laws then fly on).
ODOMETRY_SEED_KEY, IMU_SEED_KEY = "sensors.odometry.seed", "sensors.imu.seed"
SENSOR_SEED_KEYS = (ODOMETRY_SEED_KEY, IMU_SEED_KEY)
MAX_SEED = 2**32 - 1
SPREAD_STREAM = 0x5BEAD  # the first entropy word of the training spread's shuffles (a condition's is the seed)


def seed_keys(data: dict[str, Any], valid: Any) -> list[str]:
    """The seed keys of the scenario mapping ``data``: the sensor stages' that its validation accepts
    (``valid(key) -> bool``), and ``disturbances.i.seed`` of each Dryden turbulence entry."""
    keys = [key for key in SENSOR_SEED_KEYS if valid(key)]
    found, disturbances = _current_value(data, "disturbances")
    if found and isinstance(disturbances, list):
        keys += [f"disturbances.{i}.seed" for i, entry in enumerate(disturbances)
                 if isinstance(entry, dict) and entry.get("kind") == "dryden"]
    return keys


def scenario_seed_keys(base: Scenario) -> list[str]:
    """:func:`seed_keys` of scenario ``base``: a sensor stage's key where its validation takes a seed (1) there,
    the IMU's only where ``base`` has an IMU."""
    has_imu = check_scenario(base).simulation.imu.enabled

    def valid(key: str) -> bool:
        if key == IMU_SEED_KEY and not has_imu:
            return False
        try:
            check_scenario(flight_scenario(base, {key: 1}))
        except ConfigError:
            return False
        return True

    return seed_keys(base.data, valid)


def condition_seed(seed: int, condition: int) -> int:
    """The seed [0, 2^32) of condition ``condition`` of a study seeded ``seed`` (every seed key gets it)."""
    return int(np.random.SeedSequence((seed, condition)).generate_state(1)[0])


@functools.lru_cache(maxsize=64)
def _spread_order(seed: int, training: int, index: int) -> tuple[int, ...]:
    """The ranks of the training conditions for the ``index``-th sampled key (kept: every trial asks them)."""
    return tuple(int(rank) for rank in np.random.default_rng((SPREAD_STREAM, seed, training, index)).permutation(
        training))


def spread_quantile(seed: int, condition: int, training: int, index: int, bounded: bool) -> float:
    """The quantile of training condition ``condition`` (``< training``) of the ``index``-th sampled key (module
    docstring): its rank in an order of the ``training`` conditions shuffled by ``(seed, index)``, as ``rank /
    (training - 1)`` (``bounded``: the distribution's bounds are its quantiles 0 and 1) or ``(rank + 1/2) /
    training`` (a normal); 1/2 for a single condition."""
    rank = _spread_order(seed, training, index)[condition]
    if bounded and training > 1:
        return rank / (training - 1)
    return (rank + 0.5) / training


def condition_values(seed: int, condition: int, keys: list[str], sample: list[SampledKey],
                     training: int = 0) -> dict[str, Any]:
    """The ``set`` values of one condition (module docstring): a training one (``condition < training``) spreads
    the sampled keys, any other draws them."""
    values: dict[str, Any] = dict.fromkeys(keys, condition_seed(seed, condition))
    rng = np.random.default_rng((seed, condition))
    for index, item in enumerate(sample):
        values[item.key] = (item.quantile(spread_quantile(seed, condition, training, index, item.bounded))
                            if condition < training else item.draw(rng))
    return values
