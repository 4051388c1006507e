"""The rotors' physics from their geometry (docs/model.md §3.2): the body wrench of rotor commands (the allocation
matrices, never hand-typed), the speed limits and the record of their saturation. The inverse, the controller's
allocation of a wrench to rotor commands, is :mod:`fsr_control.allocation` (docs/architecture.md, *Layers*).

Per rotor ``i`` with position ``p_i`` (body FRD), spin ``k_i``, axis ``z_i = Rot(a_i, alpha_i) z_0,i`` (``z_0,i`` its
fixed thrust axis, ``-e3`` unless canted)
and signed squared speed ``u_w,i = |w_i| w_i`` [(rad/s)^2]:

    f_b   = sum_i c_f u_w,i z_i                                   [N, body FRD]
    tau_b = sum_i u_w,i (c_f p_i x z_i - k_i c_m z_i)             [N m, body FRD]

so ``[f_b; tau_b] = wrench_from_rotor_speed_sq(...) @ u_w`` with a 6 x n matrix (rows
``f_x f_y f_z tau_x tau_y tau_z``).

Tilting rotors (tilt axis ``a_i`` normal to ``z_0,i``): ``z_i = cos(alpha_i) z_v,i + sin(alpha_i) z_l,i``
with ``z_v,i = z_0,i`` and ``z_l,i = a_i x z_0,i`` (``e3 x a_i`` for an uncanted rotor). With
``u_v,i = c_f u_w,i cos alpha_i`` and ``u_l,i = c_f u_w,i sin alpha_i`` [N] the wrench is linear in
``u = [u_v1, u_l1, ..., u_vn, u_ln]`` through the static 6 x 2n matrix of :func:`static_tilting_allocation`,
and eq. 5 of the report inverts the substitution: ``u_w,i = sqrt(u_v,i^2 + u_l,i^2) / c_f``,
``alpha_i = atan2(u_l,i, u_v,i)``.
"""

from __future__ import annotations

import numpy as np

from fsr_sim.core import rotors as core_rotors
from fsr_sim.model.vehicle import Vehicle


def rotor_axes(vehicle: Vehicle, tilt_angles: np.ndarray | None = None) -> np.ndarray:
    """Thrust directions ``z_i = cos(alpha_i) z_0,i + sin(alpha_i) a_i x z_0,i`` (body FRD, unit), shape (..., n, 3),
    for tilt angles ``alpha_i`` [rad] of shape (..., n) (many samples at once); the fixed axes ``z_0,i`` (n, 3)
    without servos or tilts."""
    if vehicle.tilt_axes is None or tilt_angles is None:
        return np.array(vehicle.thrust_axes)
    alpha = np.asarray(tilt_angles, dtype=float).reshape(*np.shape(tilt_angles)[:-1], vehicle.rotor_count, 1)
    z_v, z_l = tilt_basis(vehicle)
    return np.cos(alpha) * z_v + np.sin(alpha) * z_l


def tilt_basis(vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
    """``z_v,i = z_0,i`` and ``z_l,i = a_i x z_0,i``: the rotor axis at tilt 0 and at tilt +pi/2."""
    z_v = np.array(vehicle.thrust_axes)
    return z_v, np.cross(vehicle.tilt_axes, z_v)


def actuation_matrix(vehicle: Vehicle) -> np.ndarray:
    """What the rotors can produce: the 6 x n allocation of fixed rotors, or the 6 x 2n static allocation of rotors
    on servos; rank 6 means :attr:`~fsr_sim.model.vehicle.Vehicle.fully_actuated`."""
    return static_tilting_allocation(vehicle) if vehicle.has_servos else wrench_from_rotor_speed_sq(vehicle)


def wrench_columns(vehicle: Vehicle, axes: np.ndarray, thrust: float, drag: float) -> np.ndarray:
    """6 x n columns ``[t z_i; t p_i x z_i - k_i d z_i]`` per unit input (thrust ``t``, drag torque ``d``)."""
    torque = thrust * np.cross(vehicle.positions, axes) - (vehicle.spins * drag)[:, None] * axes
    return np.vstack((thrust * axes.T, torque.T))


def wrench_from_rotor_speed_sq(vehicle: Vehicle, tilt_angles: np.ndarray | None = None) -> np.ndarray:
    """The 6 x n allocation matrix: body wrench ``[f; tau]`` from signed squared rotor speeds ``u_w``."""
    return wrench_columns(vehicle, rotor_axes(vehicle, tilt_angles), vehicle.c_f, vehicle.c_m)


def octocopter_allocation_4x8(vehicle: Vehicle) -> np.ndarray:
    """The report's ``G_q`` (rows ``f_z, tau_x, tau_y, tau_z``) of a coplanar vehicle: rows 2..5 of the
    6 x n allocation (``f_x``, ``f_y`` are identically zero without tilt)."""
    if vehicle.has_servos or np.any(vehicle.thrust_axes[:, :2] != 0.0):
        raise ValueError(f"G_q is defined for coplanar fixed rotors; '{vehicle.name}' has tilting or canted rotors")
    return wrench_from_rotor_speed_sq(vehicle)[2:]


def static_tilting_allocation(vehicle: Vehicle) -> np.ndarray:
    """The 6 x 2n static map from ``u = [u_v1, u_l1, ..., u_vn, u_ln]`` [N] to the body wrench."""
    if vehicle.tilt_axes is None:
        raise ValueError(f"vehicle '{vehicle.name}' has no tilting rotors")
    z_v, z_l = tilt_basis(vehicle)
    drag_per_newton = vehicle.c_m / vehicle.c_f
    vertical = wrench_columns(vehicle, z_v, 1.0, drag_per_newton)
    lateral = wrench_columns(vehicle, z_l, 1.0, drag_per_newton)
    matrix = np.empty((6, 2 * vehicle.rotor_count))
    matrix[:, 0::2] = vertical
    matrix[:, 1::2] = lateral
    return matrix


def rotor_commands_from_static(vehicle: Vehicle, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 5: ``u = [u_v1, u_l1, ...]`` [N] -> (squared speeds ``u_w`` [(rad/s)^2], tilts ``alpha`` [rad]), by the
    compiled core's :func:`fsr_sim.core.rotors.rotor_command_from_static`."""
    values = np.asarray(u, dtype=float).ravel().tolist()
    if len(values) != 2 * vehicle.rotor_count:
        raise ValueError(f"u needs 2 x {vehicle.rotor_count} values, got {len(values)}")
    pairs = [core_rotors.rotor_command_from_static(u_v, u_l, vehicle.c_f)
             for u_v, u_l in zip(values[0::2], values[1::2], strict=True)]
    return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])


def static_from_rotor_commands(vehicle: Vehicle, speed_sq: np.ndarray, tilt: np.ndarray) -> np.ndarray:
    """Inverse of :func:`rotor_commands_from_static`: ``u_v = c_f u_w cos(alpha)``, ``u_l = c_f u_w sin(alpha)``."""
    return np.array([value for u_w, alpha in zip(np.asarray(speed_sq, dtype=float).tolist(),
                                                np.asarray(tilt, dtype=float).tolist(), strict=True)
                     for value in core_rotors.static_from_rotor_command(u_w, alpha, vehicle.c_f)])


WRENCH_AXES = ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")  # body FRD
SHORTFALL_TOLERANCE = core_rotors.SHORTFALL_TOLERANCE


def rotor_columns(vehicle: Vehicle, axes: np.ndarray) -> np.ndarray:
    """The core's rotor columns (n, 9) for rotor axes (n, 3): force ``c_f z_i``, lever torque ``c_f p_i x z_i``,
    drag torque ``-k_i c_m z_i`` per unit squared speed (:mod:`fsr_sim.core.rotors`)."""
    force_and_lever = wrench_columns(vehicle, axes, vehicle.c_f, 0.0)
    drag = wrench_columns(vehicle, axes, 0.0, vehicle.c_m)[3:]
    return np.ascontiguousarray(np.hstack((force_and_lever[:3].T, force_and_lever[3:].T, drag.T)))


class SaturationReport:
    """Running record of rotor-speed (and tilt) saturation: how often, since when, which rotor, and which
    wrench axis gave way (:meth:`record_shortfall`) by how much. A view of the core's record array
    (:mod:`fsr_sim.core.rotors`), which the compiled code fills; ``SaturationReport(n)`` makes a new one."""

    def __init__(self, rotor_count: int = 0, record: np.ndarray | None = None) -> None:
        if record is None:
            record = np.zeros(core_rotors.saturation_size(rotor_count))
            core_rotors.reset_saturation(record)
        self.array = record

    @property
    def count(self) -> int:
        return int(self.array[core_rotors.SATURATED_COUNT])

    @property
    def first_time(self) -> float | None:
        value = float(self.array[core_rotors.FIRST_TIME])
        return None if value != value else value

    @property
    def last_time(self) -> float | None:
        value = float(self.array[core_rotors.LAST_TIME])
        return None if value != value else value

    @property
    def worst_rotor(self) -> int | None:
        """1-based rotor index of the largest excess (None: never saturated)."""
        return int(self.array[core_rotors.WORST_ROTOR]) or None

    @property
    def worst_excess(self) -> float:
        """rad/s beyond the limit."""
        return float(self.array[core_rotors.WORST_EXCESS])

    @property
    def per_rotor(self) -> dict[int, int]:
        counts = self.array[core_rotors.PER_ROTOR:]
        return {i + 1: int(c) for i, c in enumerate(counts.tolist()) if c}

    @property
    def axis_steps(self) -> list[int]:
        """Steps each wrench axis gave way (``WRENCH_AXES`` order)."""
        return [int(v) for v in self.array[core_rotors.AXIS_STEPS:core_rotors.AXIS_STEPS + 6].tolist()]

    @property
    def axis_max_shortfall(self) -> list[float]:
        """Largest shortfall of each wrench axis [N / N m]."""
        return self.array[core_rotors.AXIS_MAX_SHORTFALL:core_rotors.AXIS_MAX_SHORTFALL + 6].tolist()

    def record(self, time: float, excess: np.ndarray) -> bool:
        """Record one command; ``excess`` per rotor [rad/s] (0 where within limits). True if it saturated."""
        excess = np.ascontiguousarray(excess, dtype=float).reshape(-1)
        missing = core_rotors.saturation_size(len(excess)) - len(self.array)
        if missing > 0:  # made without a rotor count
            self.array = np.concatenate((self.array, np.zeros(missing)))
        return bool(core_rotors.record_saturation(self.array, float(time), excess))

    def record_shortfall(self, shortfall: np.ndarray) -> None:
        """Record one saturated step's ``commanded - achieved`` body wrench ``[f; tau]`` (shape (6,), N and N m):
        every axis with ``|shortfall| > SHORTFALL_TOLERANCE`` gave way on this step."""
        core_rotors.record_shortfall(self.array, np.ascontiguousarray(shortfall, dtype=float))

    def as_dict(self) -> dict:
        return {
            "count": self.count,
            "first_time": self.first_time,
            "last_time": self.last_time,
            "worst_rotor": self.worst_rotor,
            "worst_excess_rad_s": self.worst_excess,
            "per_rotor": {str(k): v for k, v in sorted(self.per_rotor.items())},
            "gave_way": {
                axis: {"steps": steps, "max_shortfall": largest}
                for axis, steps, largest in zip(WRENCH_AXES, self.axis_steps, self.axis_max_shortfall, strict=True)
            },
        }


def clamp_rotor_speeds(vehicle: Vehicle, speed_sq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotor speeds [rad/s] from squared speeds (any shape), clamped to ``[w_min, w_max]``; also the excess per
    rotor (:func:`fsr_sim.core.rotors.clamped_speed`: a negative ``u_w`` counts as an excess below ``w_min``)."""
    speed_sq = np.asarray(speed_sq, dtype=float)
    flat = np.ascontiguousarray(speed_sq).reshape(-1)
    speeds, excess = np.empty_like(flat), np.empty_like(flat)
    core_rotors.clamped_speeds(flat, vehicle.rotor_speed_min, vehicle.rotor_speed_max, speeds, excess)
    return speeds.reshape(speed_sq.shape), excess.reshape(speed_sq.shape)
