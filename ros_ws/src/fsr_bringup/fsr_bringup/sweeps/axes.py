"""What a sweep varies: grid axes (a key and its values) and sampled keys (a key and a distribution), and the
flights they make.

Keys are the dotted keys of ``fsr-fly --set`` (``plant.mass``, ``controller.gains.k_p``, ``estimator.c0``,
``trajectory.waypoints.0.position``, ``disturbances.0.force``). Only numbers can be swept: a grid value is a
number or a list of numbers (a YAML flow value on the command line: ``[7,7,40]``), a sampled key must be a
single number (``controller.gains.k_p.2`` samples one item of a list). A sample of a key the scenario holds as an
integer (``estimator.r``) is rounded to the nearest integer.

Flights: the product of the grid's axes (the first axis varies slowest), each with ``n`` draws of the sampled
keys (``numpy.random.default_rng(seed)``, the keys drawn in the order given, flight after flight), so the same
axes, ``n`` and seed give the same flights on every machine.
"""

from __future__ import annotations

import itertools
import math
import statistics
from dataclasses import dataclass
from typing import Any

import numpy as np
import yaml

from fsr_sim.config.scenario import Scenario, scenario_from_mapping
from fsr_sim.config.validation import yaml_value

DISTRIBUTIONS = ("uniform", "normal", "loguniform")


@dataclass(frozen=True)
class GridAxis:
    key: str
    values: tuple[Any, ...]  # numbers or lists of numbers


@dataclass(frozen=True)
class SampledKey:
    key: str
    distribution: str  # one of DISTRIBUTIONS
    first: float  # uniform/loguniform: low; normal: mean
    second: float  # uniform/loguniform: high; normal: standard deviation
    integer: bool = False  # the scenario holds an integer: draws are rounded

    def draw(self, rng: np.random.Generator) -> float | int:
        if self.distribution == "uniform":
            value = rng.uniform(self.first, self.second)
        elif self.distribution == "normal":
            value = rng.normal(self.first, self.second)
        else:
            value = math.exp(rng.uniform(math.log(self.first), math.log(self.second)))
        return int(round(value)) if self.integer else float(value)

    def quantile(self, q: float) -> float | int:
        """The distribution's value at cumulative probability ``q`` (in [0, 1] for a uniform or loguniform, whose
        0 and 1 are the bounds; in (0, 1) for a normal)."""
        if self.distribution == "uniform":
            value = self.first + q * (self.second - self.first)
        elif self.distribution == "normal":
            value = statistics.NormalDist(self.first, self.second).inv_cdf(q) if self.second > 0.0 else self.first
        else:
            value = math.exp(math.log(self.first) + q * (math.log(self.second) - math.log(self.first)))
        return int(round(value)) if self.integer else float(value)

    @property
    def bounded(self) -> bool:
        """Whether the distribution has finite bounds (its quantiles 0 and 1)."""
        return self.distribution != "normal"


class SweepError(ValueError):
    """A grid or sample the sweep refuses; the message names the key."""


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _numeric(value: Any) -> bool:
    """A number, or a (nested) list of numbers."""
    if isinstance(value, list):
        return bool(value) and all(_numeric(item) for item in value)
    return _is_number(value)


def parse_grid(text: str) -> GridAxis:
    """``KEY=V1,V2,...`` with YAML flow values (``k_p=[7,7,40],[12,12,55]``) -> :class:`GridAxis`."""
    key, sep, values = text.partition("=")
    key = key.strip()
    if not sep or not key or not values.strip():
        raise SweepError(f"--grid: expected KEY=V1,V2,..., got '{text}'")
    try:
        parsed = yaml_value(f"[{values}]")
    except yaml.YAMLError:
        raise SweepError(f"--grid {key}: the values '{values}' are not YAML flow values (numbers or [lists])") from None
    return grid_axis(key, parsed)


def grid_axis(key: str, values: Any) -> GridAxis:
    """A grid axis of the Python API (``{key: [values]}``), checked."""
    if not isinstance(values, (list, tuple)) or not values:
        raise SweepError(f"grid {key}: give a non-empty list of values, got {values!r}")
    values = [list(v) if isinstance(v, tuple) else (v.tolist() if isinstance(v, np.ndarray) else v) for v in values]
    values = [v.item() if isinstance(v, np.generic) else v for v in values]
    for value in values:
        if not _numeric(value):
            raise SweepError(f"grid {key}: {value!r} is not a number (or a list of numbers); only numbers can be swept")
    return GridAxis(key, tuple(values))


def parse_sample(text: str) -> SampledKey:
    """``KEY=uniform:LO:HI`` | ``normal:MEAN:STD`` | ``loguniform:LO:HI`` -> :class:`SampledKey`."""
    key, sep, spec = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise SweepError(f"--sample: expected KEY=DISTRIBUTION:A:B, got '{text}'")
    return sampled_key(key, spec)


def sampled_key(key: str, spec: Any) -> SampledKey:
    """A sampled key of the Python API: ``"uniform:1.0:1.5"`` or ``("uniform", 1.0, 1.5)``, checked."""
    parts = spec.split(":") if isinstance(spec, str) else list(spec) if isinstance(spec, (list, tuple)) else None
    if parts is None or len(parts) != 3:
        raise SweepError(f"sample {key}: expected DISTRIBUTION:A:B ({', '.join(DISTRIBUTIONS)}), got {spec!r}")
    name = str(parts[0]).strip().lower()
    if name not in DISTRIBUTIONS:
        raise SweepError(f"sample {key}: unknown distribution '{parts[0]}' (one of {', '.join(DISTRIBUTIONS)})")
    try:
        first, second = float(parts[1]), float(parts[2])
    except (TypeError, ValueError):
        raise SweepError(f"sample {key}: {parts[1]!r} and {parts[2]!r} must be numbers") from None
    if not (math.isfinite(first) and math.isfinite(second)):
        raise SweepError(f"sample {key}: the bounds must be finite, got {first:g} and {second:g}")
    if name == "normal" and second < 0.0:
        raise SweepError(f"sample {key}: the standard deviation must be >= 0, got {second:g}")
    if name != "normal" and first > second:
        raise SweepError(f"sample {key}: LO > HI ({first:g} > {second:g})")
    if name == "loguniform" and first <= 0.0:
        raise SweepError(f"sample {key}: loguniform needs 0 < LO, got {first:g}")
    return SampledKey(key, name, first, second)


def _current_value(data: dict[str, Any], key: str) -> tuple[bool, Any]:
    """``(found, value)`` of the dotted ``key`` in a scenario mapping."""
    node: Any = data
    for part in key.split("."):
        if isinstance(node, dict) and part in node:
            node = node[part]
        elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        else:
            return False, None
    return True, node


def check_axes(scenario: Scenario, grid: list[GridAxis], sample: list[SampledKey]) -> list[SampledKey]:
    """Refuse keys that are not numeric leaves of ``scenario`` (naming the key) and keys given twice; returns the
    sampled keys with ``integer`` set where the scenario holds an integer. Unknown keys are refused by the
    scenario's own validation when the first flight is checked (with a "did you mean")."""
    keys = [axis.key for axis in grid] + [item.key for item in sample]
    for key in keys:
        if keys.count(key) > 1:
            raise SweepError(f"{key}: swept twice (give each key once, as a grid axis or as a sampled key)")
    checked = []
    for item in [*grid, *sample]:
        found, value = _current_value(scenario.data, item.key)
        if found and value is not None and not _numeric(value):
            raise SweepError(f"{item.key}: not a numeric leaf (the scenario has {value!r}); only numbers can be swept")
        if isinstance(item, SampledKey):
            if found and isinstance(value, list):
                raise SweepError(f"{item.key}: a list of {len(value)} in the scenario; a distribution draws one "
                                 "number: "
                                 f"sample an item ({item.key}.0) or give a grid of lists")
            checked.append(SampledKey(item.key, item.distribution, item.first, item.second,
                                      found and isinstance(value, int) and not isinstance(value, bool)))
    return checked


def plan_flights(grid: list[GridAxis], sample: list[SampledKey], n: int | None, seed: int) -> list[dict[str, Any]]:
    """The ``set`` values of every flight (module docstring), in order."""
    if sample and (n is None or n < 1):
        raise SweepError(f"a sample needs n >= 1 flights (--n), got {n}")
    if not sample and n is not None and not grid:
        raise SweepError("n without a sample: give --sample KEY=DISTRIBUTION:A:B (or a --grid)")
    points = [dict(zip([axis.key for axis in grid], combo, strict=True))
              for combo in itertools.product(*(axis.values for axis in grid))] if grid else [{}]
    if not sample:
        return points
    rng = np.random.default_rng(seed)
    draws = [{item.key: item.draw(rng) for item in sample} for _ in range(int(n))]
    return [{**point, **draw} for point in points for draw in draws]


def flight_scenario(base: Scenario, values: dict[str, Any]) -> Scenario:
    """The scenario of one flight: the sweep's (its fixed values applied) with the flight's ``values``."""
    return scenario_from_mapping(base.data, base.source, base.base_dir, values=values)


# The unit of a swept key by its last named part (list items and indices are skipped): what a figure's axis says.
KEY_UNITS = {
    "mass": "kg", "inertia": "kg m^2", "c0": "rad/s", "r": "-", "duration": "s", "hold": "s", "start": "s",
    "end": "s", "physics_dt": "s", "rotor_time_constant": "s", "tilt_time_constant": "s",
    "tilt_rate_max_deg_s": "deg/s", "drag_coefficients": "N s^2/m^2", "force": "N", "torque": "N m",
    "position": "m", "velocity": "m/s", "angular_velocity": "rad/s", "attitude_rpy_deg": "deg",
    "acceleration_filter_hz": "Hz", "frequency_hz": "Hz", "phase_deg": "deg", "wind_speed": "m/s",
    "altitude": "m", "airspeed": "m/s", "mean": "m/s", "k_p": "N/m", "k_v": "N s/m", "k_r": "N m/rad",
    "k_w": "N m s/rad", "k_d": "m/s^2 per m/s", "position_std": "m", "attitude_std_deg": "deg",
    "velocity_std": "m/s", "angular_velocity_std": "rad/s", "rate_hz": "Hz", "delay_s": "s", "delay": "s",
    "authority_margin": "-", "crash_speed": "m/s", "height": "m", "max_ratio": "-",
}


def key_label(key: str) -> str:
    """An axis label of a swept key with its unit (``plant.mass`` -> ``plant.mass [kg]``; unknown: the key)."""
    named = [part for part in key.split(".") if not part.isdigit()]
    unit = KEY_UNITS.get(named[-1]) if named else None
    return f"{key} [{unit}]" if unit else key

