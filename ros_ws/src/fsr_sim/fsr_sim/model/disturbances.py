"""External wrench profiles (SPEC §3.4): constant, step, sinusoid and piecewise-linear table.

Each profile gives a force [N] and a torque [N m], both in its ``frame`` (``world`` NED, the default, or
``body`` FRD), as a function of simulated time ``t`` [s]. Several profiles add up. The plant applies the
force in the world frame and the torque in the body frame, so with ``R`` the attitude (body -> world):

* ``frame: world``: ``f_world = f``, ``tau_body = R^T tau`` (a torque fixed in space, e.g. about world down);
* ``frame: body``: ``f_world = R f``, ``tau_body = tau`` (a torque that turns with the vehicle).

For the exercise-3 yaw torque ``[0, 0, -0.4]`` the two agree while the vehicle stays level.

From Python: :func:`constant`, :func:`step`, :func:`sinusoid`, :func:`table`. Scenario syntax (a list under
``disturbances``, parsed by :mod:`fsr_sim.config.plant_sections`)::

    - {kind: constant, force: [1, 1, 0], torque: [0, 0, -0.4]}          # frame: world (default)
    - {kind: step, start: 10.0, force: [2, 0, 0]}                         # zero before start
    - {kind: sinusoid, force: [0.5, 0, 0], frequency_hz: 0.5, phase_deg: 0, offset_force: [0, 0, 0]}
    - {kind: table, time: [0, 5, 6], force: [[0,0,0], [0,0,0], [1,0,0]]}  # linear, held at the ends
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from fsr_sim.model.checks import InvalidValueError, finite_array
from fsr_sim.model.so3 import Mat3, mat_t_vec3, mat_vec3

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
        if self.kind == "table":
            return (
                np.array([np.interp(t, self.times, self.force[:, i]) for i in range(3)]),
                np.array([np.interp(t, self.times, self.torque[:, i]) for i in range(3)]),
            )
        if t < self.start or t >= self.end:
            return ZERO3, ZERO3
        if self.kind == "sinusoid":
            s = np.sin(2.0 * np.pi * self.frequency_hz * (t - self.start) + self.phase)
            return self.offset_force + s * self.force, self.offset_torque + s * self.torque
        return self.force, self.torque


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


def total_external_wrench(
    profiles: list[DisturbanceProfile], t: float, rotation: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Sum of all profiles at ``t``: (force world NED [N], torque body FRD [N m]).

    ``f_world = sum_world f + R sum_body f`` and ``tau_body = R^T sum_world tau + sum_body tau`` with ``R``
    (shape (3, 3)) the attitude body FRD -> world NED.
    """
    total = external_wrench_floats(profiles, t, np.asarray(rotation, dtype=float).tolist())
    return np.array(total[:3]), np.array(total[3:])


def external_wrench_floats(
    profiles: list[DisturbanceProfile], t: float, rotation: Mat3
) -> tuple[float, float, float, float, float, float]:
    """:func:`total_external_wrench` on Python floats (rows of ``R``): ``(f_x, f_y, f_z)`` world [N] and
    ``(tau_x, tau_y, tau_z)`` body [N m] (the plant evaluates it at every RK4 stage)."""
    fx = fy = fz = tx = ty = tz = 0.0
    for profile in profiles:
        force, torque = profile.wrench(t)
        force = force.tolist()
        torque = torque.tolist()
        if profile.frame == "body":
            force = mat_vec3(rotation, force)
        else:
            torque = mat_t_vec3(rotation, torque)
        fx, fy, fz = fx + force[0], fy + force[1], fz + force[2]
        tx, ty, tz = tx + torque[0], ty + torque[1], tz + torque[2]
    return fx, fy, fz, tx, ty, tz
