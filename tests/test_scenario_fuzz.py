"""Fuzz: mutated scenario files either fly (in process, a few steps) or are refused with a ConfigError.

Mutations: a key deleted, a key misspelt, a value replaced by a value of another kind or an out-of-range
number, a list shortened, the YAML text cut or corrupted. A refusal must be a ConfigError whose message
names the file; anything else (a traceback from deep inside numpy, a hang) fails the test.
"""

from __future__ import annotations

import copy
import math
import random
from pathlib import Path
from typing import Any

import pytest
import yaml

from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_bringup.runner.scenario_check import check_scenario
from fsr_sim.config.scenario import load_scenario
from fsr_sim.config.validation import ConfigError, builtin_config_dir

BASES = ("ex3_estimation", "ex4_geometric", "ex5_voliro", "octo_ground_effect", "ceiling_approach", "step_disturbance")
MUTANTS_PER_BASE = 50
FLY_STEPS = 20
REPLACEMENTS: tuple[Any, ...] = (
    None, 0, -1, -1e-9, 1e12, math.nan, math.inf, "fast", "", True, [], [1.0], [1.0, 2.0], [[1, 2], [3, 4]],
    {"a": 1}, 0.5, 3, [0, 0, 0], [-1, 2, 3], [1, 2, 3, 4, 5, 6],
)


def paths(node: Any, prefix: tuple = ()) -> list[tuple]:
    """Every dotted path (as a tuple of keys / indices) in a nested mapping."""
    found = []
    if isinstance(node, dict):
        for key, value in node.items():
            found.append((*prefix, key))
            found += paths(value, (*prefix, key))
    elif isinstance(node, list):
        for index, value in enumerate(node):
            found.append((*prefix, index))
            found += paths(value, (*prefix, index))
    return found


def parent_of(data: Any, path: tuple) -> Any:
    for part in path[:-1]:
        data = data[part]
    return data


def mutate(data: dict, rng: random.Random) -> str:
    """Mutate ``data`` in place (or return broken YAML text); returns the YAML text to write."""
    target = rng.choice(paths(data))
    parent, last = parent_of(data, target), target[-1]
    operation = rng.choice(("delete", "typo", "replace", "replace", "replace", "shorten", "text"))
    if operation == "delete":
        del parent[last]
    elif operation == "typo" and isinstance(last, str) and len(last) > 2:
        position = rng.randrange(len(last))
        parent[last[:position] + last[position + 1:]] = parent.pop(last)
    elif operation == "shorten" and isinstance(parent[last], list) and parent[last]:
        parent[last] = parent[last][:-1]
    elif operation == "text":
        text = yaml.safe_dump(data, sort_keys=False)
        cut = rng.randrange(1, len(text))
        return rng.choice((text[:cut], text[:cut] + ": [\n", text.replace(":", "", 1), "\t" + text))
    else:
        parent[last] = copy.deepcopy(rng.choice(REPLACEMENTS))
    return yaml.safe_dump(data, sort_keys=False)


def mutants() -> list[tuple[str, int]]:
    return [(base, seed) for base in BASES for seed in range(MUTANTS_PER_BASE)]


@pytest.mark.parametrize(("base", "seed"), mutants())
def test_mutated_scenario_flies_or_is_refused_cleanly(tmp_path: Path, base: str, seed: int):
    rng = random.Random(f"{base}-{seed}")
    data = yaml.safe_load((builtin_config_dir("scenarios") / f"{base}.yaml").read_text())
    path = tmp_path / f"{base}_{seed}.yaml"
    path.write_text(mutate(data, rng))
    try:
        checked = check_scenario(load_scenario(path))
    except ConfigError as error:
        assert str(path) in str(error), f"the message does not name the file: {error}"
        return
    # Valid: fly a few steps (a mutated duration could be hours long).
    period = checked.simulation.control_period
    short = check_scenario(load_scenario(path, [f"duration={FLY_STEPS * period!r}"]))
    result = fly_in_process(short.scenario)
    assert result.end_reason in ("finished", "diverged"), result.end_reason
