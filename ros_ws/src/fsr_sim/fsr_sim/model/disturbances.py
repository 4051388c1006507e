"""External wrench profiles (docs/model.md §3.4): constant, step, sinusoid and piecewise-linear table.

Each profile gives a force [N] and a torque [N m], both in its ``frame`` (``world`` NED, the default, or
``body`` FRD), as a function of simulated time ``t`` [s]. Several profiles add up. The plant applies the
force in the world frame and the torque in the body frame, so with ``R`` the attitude (body -> world):

* ``frame: world``: ``f_world = f``, ``tau_body = R^T tau`` (a torque fixed in space, e.g. about world down);
* ``frame: body``: ``f_world = R f``, ``tau_body = tau`` (a torque that turns with the vehicle).

For the exercise-3 yaw torque ``[0, 0, -0.4]`` the two agree while the vehicle stays level.

From Python: :func:`constant`, :func:`step`, :func:`sinusoid`, :func:`table`. The plant evaluates them per step in
the compiled core (:mod:`fsr_sim.core.disturbances`) from one table packed by :func:`pack_disturbances`.
Scenario syntax (a list under ``disturbances``, parsed by :mod:`fsr_sim.config.plant_sections`)::

    - {kind: constant, force: [1, 1, 0], torque: [0, 0, -0.4]}          # frame: world (default)
    - {kind: step, start: 10.0, force: [2, 0, 0]}                         # zero before start
    - {kind: sinusoid, force: [0.5, 0, 0], frequency_hz: 0.5, phase_deg: 0, offset_force: [0, 0, 0]}
    - {kind: table, time: [0, 5, 6], force: [[0,0,0], [0,0,0], [1,0,0]]}  # linear, held at the ends
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from fsr_sim.core import disturbances as core
from fsr_sim.core.so3 import matrix_rows
from fsr_sim.model.checks import InvalidValueError, finite_array

ZERO3 = np.zeros(3)
FRAMES = ("world", "body")


@dataclass(frozen=True)
class DisturbanceProfile:
    kind: str
    frame: str  # frame of the force and the torque: "world" or "body"
    force: np.ndarray  # (3,) amplitude / value, or (k, 3) table
    torque: np.ndarray  # (3,) or (k, 3), in ``frame``
    start: float = 0.0
    end: float = float("inf")
    frequency_hz: float = 0.0
    phase: float = 0.0
    offset_force: np.ndarray = field(default_factory=lambda: ZERO3)
    offset_torque: np.ndarray = field(default_factory=lambda: ZERO3)
    times: np.ndarray | None = None

    def wrench(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(force in ``frame`` [N], torque in ``frame`` [N m]) at time ``t`` [s]."""
        table, knots = pack_disturbances([self])
        force, torque = core.profile_wrench(table[0], knots, float(t))
        return np.array(force), np.array(torque)

    def acting_interval(self) -> tuple[float, float] | None:
        """``(start, end)`` [s] outside which the profile is zero (``-inf``/``inf`` where it never stops), or
        None when it is zero all the time. Constant: ``[0, inf)``; step and sinusoid: ``[start, end)`` (a
        sinusoid's sine is zero at instants only, so it counts as acting throughout); table: from the knot
        before the first non-zero knot to the knot after the last one (values are held beyond the ends)."""
        if self.kind != "table":
            values = np.concatenate((self.force, self.torque, self.offset_force, self.offset_torque))
            return (self.start, self.end) if np.any(values != 0.0) else None
        nonzero = np.flatnonzero(np.any(np.hstack((self.force, self.torque)) != 0.0, axis=1))
        if nonzero.size == 0:
            return None
        first, last = int(nonzero[0]), int(nonzero[-1])
        start = -np.inf if first == 0 else float(self.times[first - 1])
        end = np.inf if last == len(self.times) - 1 else float(self.times[last + 1])
        return start, end


def constant(force: ArrayLike = ZERO3, torque: ArrayLike = ZERO3, frame: str = "world") -> DisturbanceProfile:
    """A wrench that acts all the time: ``force`` [N] and ``torque`` [N m] in ``frame`` (``world`` or ``body``)."""
    return _profile("constant", frame, force, torque)


def step(start: float, force: ArrayLike = ZERO3, torque: ArrayLike = ZERO3, end: float = float("inf"),
         frame: str = "world") -> DisturbanceProfile:
    """A wrench acting for ``start <= t < end`` [s] (zero outside)."""
    return _profile("step", frame, force, torque, start=start, end=end)


def sinusoid(frequency_hz: float, force: ArrayLike = ZERO3, torque: ArrayLike = ZERO3, phase_deg: float = 0.0,
             offset_force: ArrayLike = ZERO3, offset_torque: ArrayLike = ZERO3, start: float = 0.0,
             end: float = float("inf"), frame: str = "world") -> DisturbanceProfile:
    """``offset + amplitude sin(2 pi f (t - start) + phase)`` for ``start <= t < end`` [s]."""
    if not frequency_hz > 0.0:
        raise InvalidValueError("frequency_hz", f"must be > 0, got {frequency_hz}")
    return _profile("sinusoid", frame, force, torque, start=start, end=end, frequency_hz=float(frequency_hz),
                    phase=float(np.deg2rad(phase_deg)), offset_force=finite_array(offset_force, (3,), "offset_force"),
                    offset_torque=finite_array(offset_torque, (3,), "offset_torque"))


def table(times: ArrayLike, force: ArrayLike | None = None, torque: ArrayLike | None = None,
          frame: str = "world") -> DisturbanceProfile:
    """Piecewise-linear in time: ``force``/``torque`` shape (k, 3) at the ``k`` strictly increasing ``times`` [s],
    held at the ends."""
    times = np.atleast_1d(np.asarray(times, dtype=float))
    if times.ndim != 1 or len(times) < 1 or np.any(np.diff(times) <= 0.0) or not np.all(np.isfinite(times)):
        raise InvalidValueError("time", f"must be non-empty and strictly increasing [s], got {times.tolist()}")
    shape = (len(times), 3)
    force = finite_array(np.zeros(shape) if force is None else force, shape, "force")
    torque = finite_array(np.zeros(shape) if torque is None else torque, shape, "torque")
    if frame not in FRAMES:
        raise InvalidValueError("frame", f"must be one of {', '.join(FRAMES)}, got '{frame}'")
    return DisturbanceProfile("table", frame, force, torque, times=times)


def _profile(kind: str, frame: str, force: ArrayLike, torque: ArrayLike, **fields: float) -> DisturbanceProfile:
    if frame not in FRAMES:
        raise InvalidValueError("frame", f"must be one of {', '.join(FRAMES)}, got '{frame}'")
    start, end = fields.get("start", 0.0), fields.get("end", float("inf"))
    if not end > start:
        raise InvalidValueError("end", f"must be after start ({start}), got {end}")
    return DisturbanceProfile(kind, frame, finite_array(force, (3,), "force"), finite_array(torque, (3,), "torque"),
                              **fields)


KINDS = {"constant": core.CONSTANT, "step": core.STEP, "sinusoid": core.SINUSOID, "table": core.TABLE}


def pack_disturbances(profiles: list[DisturbanceProfile]) -> tuple[np.ndarray, np.ndarray]:
    """The profiles as the core's table (m, ``WIDTH``) and knot rows (k, ``KNOT_WIDTH``)
    (:mod:`fsr_sim.core.disturbances`)."""
    table = np.zeros((len(profiles), core.WIDTH))
    knots = []
    for row, profile in zip(table, profiles, strict=True):
        row[core.KIND] = KINDS[profile.kind]
        row[core.BODY_FRAME] = profile.frame == "body"
        row[core.START], row[core.END] = profile.start, profile.end
        row[core.FREQUENCY], row[core.PHASE] = profile.frequency_hz, profile.phase
        if profile.kind == "table":
            row[core.KNOT_START], row[core.KNOT_COUNT] = len(knots), len(profile.times)
            knots += np.column_stack((profile.times, profile.force, profile.torque)).tolist()
            continue
        row[core.FORCE:core.FORCE + 3] = profile.force
        row[core.TORQUE:core.TORQUE + 3] = profile.torque
        row[core.OFFSET_FORCE:core.OFFSET_FORCE + 3] = profile.offset_force
        row[core.OFFSET_TORQUE:core.OFFSET_TORQUE + 3] = profile.offset_torque
    return table, np.array(knots, dtype=float).reshape(len(knots), core.KNOT_WIDTH)


def total_external_wrench(
    profiles: list[DisturbanceProfile], t: float, rotation: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Sum of all profiles at ``t``: (force world NED [N], torque body FRD [N m]).

    ``f_world = sum_world f + R sum_body f`` and ``tau_body = R^T sum_world tau + sum_body tau`` with ``R``
    (shape (3, 3)) the attitude body FRD -> world NED.
    """
    table, knots = pack_disturbances(profiles)
    rows = matrix_rows(np.ascontiguousarray(rotation, dtype=float))
    force, torque = core.external_wrench(table, knots, float(t), rows)
    return np.array(force), np.array(torque)
