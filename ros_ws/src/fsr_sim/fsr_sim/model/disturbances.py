"""External wrench profiles (SPEC §3.4): constant, step, sinusoid and piecewise-linear table.

Each profile gives a force [N] and a torque [N m], both in its ``frame`` (``world`` NED, the default, or
``body`` FRD), as a function of simulated time ``t`` [s]. Several profiles add up. The plant applies the
force in the world frame and the torque in the body frame, so with ``R`` the attitude (body -> world):

* ``frame: world``: ``f_world = f``, ``tau_body = R^T tau`` (a torque fixed in space, e.g. about world down);
* ``frame: body``: ``f_world = R f``, ``tau_body = tau`` (a torque that turns with the vehicle).

For the exercise-3 yaw torque ``[0, 0, -0.4]`` the two agree while the vehicle stays level.

Scenario syntax (a list under ``disturbances``)::

    - {kind: constant, force: [1, 1, 0], torque: [0, 0, -0.4]}          # frame: world (default)
    - {kind: step, start: 10.0, force: [2, 0, 0]}                         # zero before start
    - {kind: sinusoid, force: [0.5, 0, 0], frequency_hz: 0.5, phase_deg: 0, offset_force: [0, 0, 0]}
    - {kind: table, time: [0, 5, 6], force: [[0,0,0], [0,0,0], [1,0,0]]}  # linear, held at the ends
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fsr_sim.config.validation import Section, checked_array
from fsr_sim.model.so3 import Mat3, mat_t_vec3, mat_vec3

ZERO3 = np.zeros(3)


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


def disturbance_from_section(section: Section) -> DisturbanceProfile:
    """Parse one entry of the scenario's ``disturbances`` list (unknown keys refused)."""
    kind = section.string("kind", choices=("constant", "step", "sinusoid", "table"))
    frame = section.string("frame", "world", choices=("world", "body"))
    if kind == "table":
        times = section.raw("time")
        if not isinstance(times, list) or len(times) < 1:
            raise section.error("time", "must be a non-empty list of times [s]")
        times_array = checked_array(times, (len(times),), section.key("time"), section.source)
        if np.any(np.diff(times_array) <= 0.0):
            raise section.error("time", "must be strictly increasing")
        shape = (len(times), 3)
        zeros = np.zeros(shape).tolist()
        force = checked_array(section.raw("force", zeros), shape, section.key("force"), section.source)
        torque = checked_array(section.raw("torque", zeros), shape, section.key("torque"), section.source)
        section.reject_unknown()
        return DisturbanceProfile(kind, frame, force, torque, times=times_array)
    force = section.vector("force", 3, [0.0, 0.0, 0.0])
    torque = section.vector("torque", 3, [0.0, 0.0, 0.0])
    start = section.number("start", 0.0, minimum=0.0) if kind != "constant" else 0.0
    end = section.number("end") if kind != "constant" and section.has("end") else float("inf")
    if end <= start:
        raise section.error("end", f"must be after start ({start}), got {end}")
    frequency = phase = 0.0
    offset_force = offset_torque = ZERO3
    if kind == "sinusoid":
        frequency = section.number("frequency_hz", strictly_positive=True)
        phase = np.deg2rad(section.number("phase_deg", 0.0))
        offset_force = section.vector("offset_force", 3, [0.0, 0.0, 0.0])
        offset_torque = section.vector("offset_torque", 3, [0.0, 0.0, 0.0])
    section.reject_unknown()
    return DisturbanceProfile(
        kind, frame, force, torque, start, end, frequency, phase, offset_force, offset_torque
    )


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
