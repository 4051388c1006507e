"""Reading and checking configuration values: one error type that names the file, the key and the reason."""

from __future__ import annotations

import copy
import difflib
import math
import re
from collections.abc import Iterable, Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from fsr_sim.model.checks import InvalidValueError, finite_array, symmetric_positive_definite


class ConfigError(ValueError):
    """A configuration value (YAML file, ROS parameter or command-line override) was refused.

    The message reads ``<source>: <key>: <reason>``, e.g.
    ``scenarios/ex4.yaml: vehicle.mass: must be > 0, got -1.0``.
    """

    def __init__(self, key: str, reason: str, source: str = "") -> None:
        self.key = key
        self.reason = reason
        self.source = source
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{key}: {reason}" if key else f"{where}{reason}")


class YamlLoader(yaml.SafeLoader):
    """PyYAML's safe loader, with YAML 1.2's numbers: ``1e-4`` and ``2E5`` are floats (YAML 1.1, PyYAML's, reads a
    float only with a dot, ``1.0e-4``, and ``1e-4`` as text)."""


YamlLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


def yaml_value(text: str) -> Any:
    """The YAML value of ``text`` (a file's or a ``--set``'s) with :class:`YamlLoader`."""
    return yaml.load(text, Loader=YamlLoader)  # noqa: S506 - a SafeLoader


def load_yaml_file(path: str | Path) -> dict[str, Any]:
    """Read a YAML mapping from ``path``; syntax errors and non-mapping documents raise :class:`ConfigError`."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise ConfigError("", f"cannot read file ({error.strerror})", str(path)) from None
    return parse_yaml_mapping(text, str(path))


def parse_yaml_mapping(text: str, source: str) -> dict[str, Any]:
    """Parse YAML text that must hold a mapping at the top level (a text parsed before in this process is
    not parsed again: the same scenario and vehicle files are read several times while a run is set up)."""
    cached = _PARSED.get(text)
    if cached is None:
        if len(_PARSED) >= 64:
            _PARSED.clear()
        cached = _PARSED[text] = _parse_yaml_mapping(text, source)
    return copy.deepcopy(cached)


_PARSED: dict[str, dict[str, Any]] = {}


def _parse_yaml_mapping(text: str, source: str) -> dict[str, Any]:
    try:
        data = yaml_value(text)
    except yaml.YAMLError as error:
        raise ConfigError("", f"YAML syntax error{yaml_error_text(error)}", source) from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError("", f"expected a mapping at the top level, got {type(data).__name__}", source)
    return data


def yaml_error_text(error: yaml.YAMLError, single_line: bool = False) -> str:
    """PyYAML's multi-line error as one line: `` at line L, column C: <problem>`` (line omitted if
    ``single_line``, e.g. for a one-line ``--set`` value)."""
    mark = getattr(error, "problem_mark", None)
    if mark is None:
        where = ""
    elif single_line:
        where = f" at column {mark.column + 1}"
    else:
        where = f" at line {mark.line + 1}, column {mark.column + 1}"
    problem = getattr(error, "problem", None) or " ".join(str(error).split())
    return f"{where}: {problem}"


def builtin_config_dir(kind: str) -> Path:
    """Folder of the built-in ``vehicles`` or ``scenarios`` YAML files shipped as package data."""
    return Path(str(resources.files("fsr_sim.config").joinpath(kind)))


def builtin_names(kind: str) -> list[str]:
    """Names (file stems) of the built-in configuration files of ``kind``."""
    return sorted(p.stem for p in builtin_config_dir(kind).glob("*.yaml"))


def resolve_config_path(name_or_path: str, kind: str) -> Path:
    """A built-in name (``quadrotor_ex4``) or a path to a YAML file -> the file's path.

    A file of that name wins over the built-in one; a folder of that name (a sweep's ``--out``) does not."""
    candidate = Path(name_or_path)
    builtin = builtin_config_dir(kind) / f"{name_or_path}.yaml"
    if candidate.suffix in (".yaml", ".yml") or candidate.is_file():
        if not candidate.is_file():
            raise ConfigError("", f"no such {kind[:-1]} file", str(candidate))
        return candidate
    if candidate.exists() and not builtin.is_file():  # a folder named like the file, e.g. a sweep's --out
        raise ConfigError("", f"is a folder, not a {kind[:-1]} file", str(candidate))
    if not builtin.is_file():
        names = builtin_names(kind)
        raise ConfigError("", f"unknown {kind[:-1]} '{name_or_path}' {did_you_mean(name_or_path, names)}"
                              f"(built-in: {', '.join(names)})")
    return builtin


def did_you_mean(word: str, names: Iterable[str]) -> str:
    """``"(did you mean 'k_p'?) "`` for the closest of ``names`` to ``word`` (case-insensitive), or ``""``."""
    lowered = {name.lower(): name for name in names}
    close = difflib.get_close_matches(word.lower(), list(lowered), n=1, cutoff=0.5)
    return f"(did you mean '{lowered[close[0]]}'?) " if close else ""


class Section:
    """Typed, checked access to one mapping of a configuration file.

    Every read records the key; :meth:`reject_unknown` then refuses any key that was not read, so a typo
    (``duraton``) is an error instead of a silently ignored value.
    """

    def __init__(self, data: Mapping[str, Any] | None, prefix: str, source: str) -> None:
        if data is None:
            data = {}
        if not isinstance(data, Mapping):
            raise ConfigError(prefix, f"expected a mapping, got {type(data).__name__}", source)
        self.data = data
        self.prefix = prefix
        self.source = source
        self._read: set[str] = set()

    def key(self, name: str) -> str:
        return f"{self.prefix}.{name}" if self.prefix else name

    def error(self, name: str, reason: str) -> ConfigError:
        return ConfigError(self.key(name), reason, self.source)

    def required(self, name: str, default: Any = None) -> Any:
        """The raw value of ``name`` (``default`` where it is absent); none: 'is required', pointing at a likely typo
        among the keys that are not known here."""
        value = self.raw(name, default)
        if value is None:
            typos = difflib.get_close_matches(name, [str(k) for k in self.data if k not in self._read], n=1)
            hint = f" (found unknown key '{typos[0]}': a typo?)" if typos else ""
            raise self.error(name, f"is required{hint}")
        return value

    def has(self, name: str) -> bool:
        self._read.add(name)
        return name in self.data and self.data[name] is not None

    def raw(self, name: str, default: Any = None) -> Any:
        self._read.add(name)
        value = self.data.get(name, default)
        return default if value is None else value

    def section(self, name: str) -> Section:
        return Section(self.raw(name, {}), self.key(name), self.source)

    def number(
        self,
        name: str,
        default: float | None = None,
        *,
        minimum: float | None = None,
        maximum: float | None = None,
        strictly_positive: bool = False,
    ) -> float:
        value = self.required(name, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(name, f"must be a number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            raise self.error(name, f"must be finite, got {value}")
        if strictly_positive and value <= 0.0:
            raise self.error(name, f"must be > 0, got {value}")
        if minimum is not None and value < minimum:
            raise self.error(name, f"must be >= {minimum}, got {value}")
        if maximum is not None and value > maximum:
            raise self.error(name, f"must be <= {maximum}, got {value}")
        return value

    def integer(self, name: str, default: int | None = None, *, minimum: int | None = None,
                maximum: int | None = None) -> int:
        value = self.required(name, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(name, f"must be an integer, got {value!r}")
        if minimum is not None and value < minimum:
            raise self.error(name, f"must be >= {minimum}, got {value}")
        if maximum is not None and value > maximum:
            raise self.error(name, f"must be <= {maximum}, got {value}")
        return int(value)

    def boolean(self, name: str, default: bool | None = None) -> bool:
        value = self.raw(name, default)
        if not isinstance(value, bool):
            raise self.error(name, f"must be true or false, got {value!r}")
        return value

    def string(self, name: str, default: str | None = None, *, choices: tuple[str, ...] | None = None) -> str:
        value = self.required(name, default)
        if not isinstance(value, str):
            raise self.error(name, f"must be a string, got {value!r}")
        if choices is not None and value not in choices:
            raise self.error(name, f"must be one of {', '.join(choices)}; got '{value}'")
        return value

    def vector(self, name: str, size: int, default: Any = None) -> np.ndarray:
        value = self.required(name, default)
        return checked_array(value, (size,), self.key(name), self.source)

    def reject_unknown(self, known: Iterable[str] | None = None) -> None:
        """Refuse the first key not in ``known`` (default: the keys read so far), naming the closest known
        key (``k_P`` -> ``k_p``, case-insensitive) as a likely typo."""
        names = sorted(self._read if known is None else known)
        unknown = sorted(str(k) for k in self.data if k not in names)
        if not unknown:
            return
        raise self.error(unknown[0], f"unknown key {did_you_mean(unknown[0], names)}(known here: {', '.join(names)})")


def checked_array(value: Any, shape: tuple[int, ...], key: str, source: str = "") -> np.ndarray:
    """``value`` as a finite float array of ``shape``, or :class:`ConfigError` naming ``key``."""
    try:
        return finite_array(value, shape, key)
    except InvalidValueError as error:
        raise ConfigError(key, error.reason, source) from None


def checked_spd(value: Any, key: str, source: str = "", semidefinite: bool = False) -> np.ndarray:
    """3 numbers (the diagonal) or a 3x3 matrix, symmetric positive definite (an inertia, a gain; with
    ``semidefinite``, zero eigenvalues are allowed: an optional gain) -> (3, 3).

    The check is :func:`fsr_sim.model.checks.symmetric_positive_definite`; this adds the file and the key.
    """
    if value is None:
        raise ConfigError(key, "is required", source)
    try:
        return symmetric_positive_definite(value, key, semidefinite)
    except InvalidValueError as error:
        raise ConfigError(key, error.reason, source) from None
