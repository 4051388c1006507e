"""Fuzz: mutated scenario files, each with the outcome its kind of mutation calls for.

Mutations and what each must do (decided from the mutation, never from the outcome):

* a key misspelt -> refused: a ConfigError that names the file and the misspelt key (every section
  rejects unknown keys);
* the YAML text broken (an unclosed ``[``, the first ``:`` removed, a leading tab) -> refused: a
  ConfigError naming the file;
* a key deleted, a list shortened, a value replaced by a value of another kind or an out-of-range number
  -> refused with a ConfigError naming the file and the mutated key, or accepted and flown (in process, a
  few steps) to the end: ``finished``. Only a replacement by a huge finite number (``1e12``: a speed, a
  position or a gain nobody flies) may also end ``diverged``;
* the YAML text cut short -> refused naming the file, or (cut at a line boundary: a shorter, valid
  scenario) flown to the end.

Anything else (a traceback from deep inside numpy, a hang, a divergence of a sane scenario, a refusal that
does not say which key) fails the test.
"""

from __future__ import annotations

import copy
import math
import random
from dataclasses import dataclass
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


HUGE = 1e12  # the one replacement that may make a valid scenario diverge


@dataclass(frozen=True)
class Mutation:
    text: str  # the YAML text to write
    kind: str  # typo | broken_text | cut_text | delete | shorten | replace
    key: str = ""  # the key a refusal must name: the misspelt key, or the nearest key on the mutated path
    value: Any = None  # the replacement


def nearest_key(path: tuple) -> str:
    """The last mapping key on a path (``("trajectory", "waypoints", 0, "position", 1)`` -> ``position``)."""
    return next(str(part) for part in reversed(path) if isinstance(part, str))


def mutate(data: dict, rng: random.Random) -> Mutation:
    """Mutate ``data`` in place (or break its YAML text); returns the text to write and what was done."""
    target = rng.choice(paths(data))
    parent, last = parent_of(data, target), target[-1]
    operation = rng.choice(("delete", "typo", "replace", "replace", "replace", "shorten", "text"))
    if operation == "delete":
        del parent[last]
        return Mutation(yaml.safe_dump(data, sort_keys=False), "delete", nearest_key(target))
    if operation == "typo" and isinstance(last, str) and len(last) > 2:
        position = rng.randrange(len(last))
        misspelt = last[:position] + last[position + 1:]
        parent[misspelt] = parent.pop(last)
        return Mutation(yaml.safe_dump(data, sort_keys=False), "typo", misspelt)
    if operation == "shorten" and isinstance(parent[last], list) and parent[last]:
        parent[last] = parent[last][:-1]
        return Mutation(yaml.safe_dump(data, sort_keys=False), "shorten", nearest_key(target))
    if operation == "text":
        text = yaml.safe_dump(data, sort_keys=False)
        cut = rng.randrange(1, len(text))
        broken = rng.choice((None, text[:cut] + ": [\n", text.replace(":", "", 1), "\t" + text))
        return Mutation(text[:cut], "cut_text") if broken is None else Mutation(broken, "broken_text")
    value = copy.deepcopy(rng.choice(REPLACEMENTS))
    parent[last] = value
    return Mutation(yaml.safe_dump(data, sort_keys=False), "replace", nearest_key(target), value)


def mutants() -> list[tuple[str, int]]:
    return [(base, seed) for base in BASES for seed in range(MUTANTS_PER_BASE)]


@pytest.mark.parametrize(("base", "seed"), mutants())
def test_mutated_scenario_does_what_its_mutation_calls_for(tmp_path: Path, base: str, seed: int):
    rng = random.Random(f"{base}-{seed}")
    data = yaml.safe_load((builtin_config_dir("scenarios") / f"{base}.yaml").read_text())
    path = tmp_path / f"{base}_{seed}.yaml"
    mutation = mutate(data, rng)
    path.write_text(mutation.text)
    try:
        checked = check_scenario(load_scenario(path))
    except ConfigError as error:
        assert str(path) in str(error), f"the message does not name the file: {error}"
        if mutation.key:
            assert mutation.key in str(error), f"{mutation}: the message does not name '{mutation.key}': {error}"
        return
    assert mutation.kind not in ("typo", "broken_text"), f"{mutation}: accepted, must be refused"
    # Valid: fly a few steps (a mutated duration could be hours long).
    period = checked.simulation.control_period
    short = check_scenario(load_scenario(path, [f"duration={FLY_STEPS * period!r}"]))
    result = fly_in_process(short.scenario)
    may_diverge = mutation.kind == "replace" and mutation.value == HUGE
    expected = ("finished", "diverged") if may_diverge else ("finished",)
    assert result.end_reason in expected, f"{mutation}: {result.end_reason} ({result.reason})"
    assert len(result.time) == FLY_STEPS + 1 or result.end_reason == "diverged"


def test_mutation_kinds_are_all_exercised():
    """The fixed seeds cover every kind of mutation (so each expectation above is checked)."""
    kinds = set()
    for base, seed in mutants():
        data = yaml.safe_load((builtin_config_dir("scenarios") / f"{base}.yaml").read_text())
        kinds.add(mutate(data, random.Random(f"{base}-{seed}")).kind)
    assert kinds == {"typo", "broken_text", "cut_text", "delete", "shorten", "replace"}
