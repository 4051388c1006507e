"""What a tuner varies: ``--param KEY=[log:]LO:HI`` and the candidate values it turns into.

A tuned key is a numeric scenario key (the dotted keys of ``fsr-fly --set``). A scalar key takes one range; a
list-valued key (a gain ``controller.gains.k_p``, three numbers) takes one range for each of its entries
(``k_p=log:1:50``: three parameters ``k_p.0``, ``k_p.1``, ``k_p.2`` in that range) or one item per entry
(``k_p=log:1:50,same,log:5:200``), each item a range, ``same`` (the entry takes the previous entry's value: x and y
of a symmetric vehicle tuned as one) or a number (held). ``log:`` draws the range on a log scale (``0 < LO``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from fsr_bringup.sweeps.axes import SweepError, _current_value

SAME = "same"


class TuneError(SweepError):
    """A tuning set-up refused (a bad range, key or metric); the message names it."""


@dataclass(frozen=True)
class Range:
    """One parameter of the optimiser: its name (the key, ``.i`` for an entry), bounds and scale."""

    name: str
    low: float
    high: float
    log: bool = False


@dataclass(frozen=True)
class TunedKey:
    """A tuned key: its entries (one for a scalar), each a :class:`Range`, ``SAME`` or a held number."""

    key: str
    entries: tuple[Range | str | float, ...]
    scalar: bool

    @property
    def ranges(self) -> list[Range]:
        return [entry for entry in self.entries if isinstance(entry, Range)]

    def value(self, params: dict[str, float]) -> float | list[float]:
        """The key's scenario value for the optimiser's ``params`` (name -> value)."""
        values: list[float] = []
        for entry in self.entries:
            if isinstance(entry, Range):
                values.append(float(params[entry.name]))
            elif entry == SAME:
                values.append(values[-1])
            else:
                values.append(float(entry))
        return values[0] if self.scalar else values


def parse_range(text: str, name: str) -> Range:
    """``[log:]LO:HI`` -> :class:`Range` named ``name`` (TuneError naming the key otherwise)."""
    parts = text.strip().split(":")
    log = parts[0].strip().lower() == "log"
    if log:
        parts = parts[1:]
    if len(parts) != 2:
        raise TuneError(f"--param {name}: expected [log:]LO:HI, got '{text}'")
    try:
        low, high = float(parts[0]), float(parts[1])
    except ValueError:
        raise TuneError(f"--param {name}: '{parts[0]}' and '{parts[1]}' must be numbers") from None
    if not (math.isfinite(low) and math.isfinite(high)) or not low < high:
        raise TuneError(f"--param {name}: needs finite LO < HI, got {low:g}:{high:g}")
    if log and low <= 0.0:
        raise TuneError(f"--param {name}: log needs 0 < LO, got {low:g}")
    return Range(name, low, high, log)


def parse_param(text: str) -> tuple[str, list[str]]:
    """``KEY=ITEM[,ITEM...]`` -> ``(key, items)`` (the items checked once the key's size is known)."""
    key, sep, spec = text.partition("=")
    key = key.strip()
    if not sep or not key or not spec.strip():
        raise TuneError(f"--param: expected KEY=[log:]LO:HI, got '{text}'")
    return key, [item.strip() for item in spec.split(",")]


def tuned_key(key: str, items: list[str], size: int | None) -> TunedKey:
    """The :class:`TunedKey` of ``key`` with the ``items`` of its ``--param`` (module docstring); ``size``: the
    number of entries of a list-valued key (None: a scalar)."""
    if size is None:
        if len(items) != 1:
            raise TuneError(f"--param {key}: a single number, give one range, got {len(items)} items")
        return TunedKey(key, (parse_range(items[0], key),), scalar=True)
    if len(items) == 1:
        items = items * size
    if len(items) != size:
        raise TuneError(f"--param {key}: {size} entries, give one range for all or one item per entry, got "
                        f"{len(items)}")
    entries: list[Range | str | float] = []
    for index, item in enumerate(items):
        name = f"{key}.{index}"
        if item.lower() == SAME:
            if index == 0:
                raise TuneError(f"--param {key}: the first entry cannot be '{SAME}'")
            entries.append(SAME)
            continue
        try:
            entries.append(float(item))
            continue
        except ValueError:
            entries.append(parse_range(item, name))
    if not any(isinstance(entry, Range) for entry in entries):
        raise TuneError(f"--param {key}: no entry has a range (nothing to tune)")
    return TunedKey(key, tuple(entries), scalar=False)


def key_size(data: dict[str, Any], key: str, accepts: Any) -> int | None:
    """The number of entries of ``key``'s value (None: a scalar): from the scenario mapping ``data`` if it holds
    the key, else from what its validation accepts (``accepts(value) -> bool``: a number, or three)."""
    found, value = _current_value(data, key)
    if found and isinstance(value, list):
        if any(isinstance(item, list) for item in value):
            raise TuneError(f"--param {key}: a matrix in the scenario; tune its diagonal as a list of 3")
        return len(value)
    if found and value is not None:
        return None
    if accepts(1.0):
        return None
    if accepts([1.0, 1.0, 1.0]):
        return 3
    raise TuneError(f"--param {key}: the scenario takes neither a number nor 3 numbers there")
