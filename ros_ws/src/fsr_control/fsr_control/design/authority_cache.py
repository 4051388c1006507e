"""A vehicle's authority (:mod:`fsr_control.design.authority`) and, if fully actuated, its force set, computed once per
vehicle model and kept on disk.

The planner checks every leg against the authority at each start (every node, every in-process flight, every
flight of a sweep), but the linear programs behind it take 0.05 s for a quadrotor and 0.6 s for a vehicle on
servos (1 s with its force set), after an import of scipy.optimize of about half a second. So the model's
numbers (margin 1) are
kept in memory and in ``<cache>/<key>.json``: ``<cache>`` is ``$FSR_AUTHORITY_CACHE`` if set, else
``$XDG_CACHE_HOME/fsr/authority`` (``~/.cache/fsr/authority``); ``<key>`` hashes every field of the
vehicle and the sources of the modules that compute the numbers, so a changed vehicle or a changed
computation can never be served stale numbers. An unwritable cache folder only costs the computation.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import tempfile
from pathlib import Path

import numpy as np

from fsr_control.design import authority as authority_module
from fsr_control.design.authority import Authority, ForceSet, authority, force_set
from fsr_sim.core.jit import fsr_cache
from fsr_sim.model import rotors
from fsr_sim.model.vehicle import Vehicle

_MEMORY: dict[str, tuple[Authority, ForceSet | None]] = {}


def cache_folder() -> Path:
    """Where the numbers are kept (module docstring)."""
    folder = os.environ.get("FSR_AUTHORITY_CACHE")
    return Path(folder) if folder else fsr_cache("authority")


def vehicle_key(vehicle: Vehicle) -> str:
    """Hash of every field of ``vehicle`` and of the sources of the authority and of the rotors' wrench it uses."""
    digest = hashlib.sha256()
    for module in (authority_module, rotors):
        digest.update(Path(module.__file__).read_bytes())
    for field in dataclasses.fields(vehicle):
        value = getattr(vehicle, field.name)
        digest.update(field.name.encode())
        digest.update(value.tobytes() if isinstance(value, np.ndarray) else repr(value).encode())
    return digest.hexdigest()[:24]


def model_authority(vehicle: Vehicle) -> Authority:
    """The model's :class:`~fsr_control.design.authority.Authority` of ``vehicle`` (margin 1): from memory, the
    disk cache, or computed (and then kept in both)."""
    return _entry(vehicle)[0]


def model_force_set(vehicle: Vehicle) -> ForceSet | None:
    """The :class:`~fsr_control.design.authority.ForceSet` of ``vehicle`` if it is fully actuated (else None), kept
    like :func:`model_authority`."""
    return _entry(vehicle)[1]


def _entry(vehicle: Vehicle) -> tuple[Authority, ForceSet | None]:
    key = vehicle_key(vehicle)
    if key in _MEMORY:
        return _MEMORY[key]
    path = cache_folder() / f"{key}.json"
    try:
        stored = json.loads(path.read_text(encoding="utf-8"))
        forces = stored["force_set"]
        result = (Authority(**stored["authority"]), None if forces is None else ForceSet.from_dict(forces))
    except (OSError, ValueError, TypeError, KeyError):
        result = (authority(vehicle, margin=1.0), force_set(vehicle) if vehicle.fully_actuated else None)
        _write(path, json.dumps({"authority": result[0].as_dict(),
                                 "force_set": None if result[1] is None else result[1].as_dict()}))
    _MEMORY[key] = result
    return result


def _write(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (a reader sees the whole file or none); nothing if unwritable."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile("w", dir=path.parent, suffix=".tmp", delete=False, encoding="utf-8") as f:
            f.write(text)
        os.replace(f.name, path)
    except OSError:
        pass
