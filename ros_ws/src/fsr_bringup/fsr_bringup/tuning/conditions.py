"""The seeded conditions a candidate is flown under: condition ``c`` of a study seeded ``seed`` sets every random
source of the scenario from ``(seed, c)`` - the sensor stage's noise seeds and each Dryden turbulence's seed -
and draws each ``--sample``d key (a mass error, a motor lag) from ``numpy.random.default_rng((seed, c))``, so the
same condition is the same flight for every candidate (common random numbers: candidates are compared on the
same gusts and the same noise). Conditions ``0 .. N-1`` train; the held-out conditions the tuner never sees are
``N .. N+H-1``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fsr_bringup.runner.scenario_check import check_scenario
from fsr_bringup.sweeps.axes import SampledKey, _current_value, flight_scenario
from fsr_sim.config.scenario import Scenario
from fsr_sim.config.validation import ConfigError

# Seed keys of the sensor stages (each also set where its stage is off: it then changes nothing).
SENSOR_SEED_KEYS = ("sensors.odometry.seed", "sensors.imu.seed")
MAX_SEED = 2**32 - 1


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
    """:func:`seed_keys` of scenario ``base``, a sensor stage's key where its validation takes a seed (1) there."""

    def valid(key: str) -> bool:
        try:
            check_scenario(flight_scenario(base, {key: 1}))
        except ConfigError:
            return False
        return True

    return seed_keys(base.data, valid)


def condition_seed(seed: int, condition: int) -> int:
    """The seed [0, 2^32) of condition ``condition`` of a study seeded ``seed`` (every seed key gets it)."""
    return int(np.random.SeedSequence((seed, condition)).generate_state(1)[0])


def condition_values(seed: int, condition: int, keys: list[str], sample: list[SampledKey]) -> dict[str, Any]:
    """The ``set`` values of one condition (module docstring)."""
    values: dict[str, Any] = dict.fromkeys(keys, condition_seed(seed, condition))
    rng = np.random.default_rng((seed, condition))
    for item in sample:
        values[item.key] = item.draw(rng)
    return values
