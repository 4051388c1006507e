"""From the controller's body wrench to actuator commands, through fsr_sim's allocation (SPEC §3.2).

Three actuations, one interface ``allocate(time, force_body, torque_body) -> Actuated``:

* :class:`WrenchActuation` (``actuation: wrench``): the plant takes ``u_T = -f_z`` and ``tau_b`` directly.
* :class:`FixedRotorActuation`: ``u_w = G^+ [f_z, tau]`` (fsr_sim's ``FixedRotorAllocator``: exact inverse
  for a quadrotor, minimum-norm pseudo-inverse for the octocopter).
* :class:`TiltingActuation`: ``u = G_static^+ wrench (+ N z, the secondary objective)``, then eq. 5:
  ``u_w,i = |(u_v,i, u_l,i)| / c_f``, ``alpha_i = atan2(u_l,i, u_v,i)``.

Saturation (``controller.allocation``): with ``clamp`` rotor speeds ``w_i = sqrt(u_w,i)`` [rad/s] are clamped
to the vehicle's ``[w_min, w_max]`` one by one (tilts to ``+-tilt_angle_max``). With ``priority`` (default) a
command beyond the speed limits is first reallocated by :mod:`fsr_sim.model.desaturation`: fixed rotors keep
roll/pitch torque, then thrust, and yaw torque gives way first; tilting rotors keep force, then roll/pitch,
then yaw. A command within the limits is the same with either strategy (bit for bit). Every saturated
command is recorded in a :class:`SaturationReport` (count, first time, worst rotor, and per wrench axis the
steps it gave way and the largest shortfall) and flagged in the result, never clipped silently.
``force_body`` / ``torque_body`` of the result are what the final command produces through the nominal
allocation (what the plant applies, ground effect aside): that is the ``wrench_cmd`` the controller
publishes; ``shortfall`` is the demanded minus that wrench (``wrench_shortfall``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsr_control.nullspace import PeakThrustObjective
from fsr_sim.model.allocation import (
    FixedRotorAllocator,
    SaturationReport,
    clamp_rotor_speeds,
    rotor_commands_from_static,
    static_from_rotor_commands,
    static_tilting_allocation,
)
from fsr_sim.model.desaturation import FixedRotorDesaturation, TiltingDesaturation
from fsr_sim.model.vehicle import Vehicle

ALLOCATION_STRATEGIES = ("clamp", "priority")


@dataclass
class Actuated:
    """One allocated command: rotor speeds [rad/s] (None in wrench actuation), tilts [rad] (None for fixed
    rotors), the wrench it produces (body FRD, N / N m), whether anything saturated, and the shortfall
    ``[f; tau]_demanded - [f; tau]_produced`` (shape (6,), body FRD, N / N m)."""

    rotor_speeds: np.ndarray | None
    tilt_angles: np.ndarray | None
    force_body: np.ndarray
    torque_body: np.ndarray
    saturated: bool
    shortfall: np.ndarray


class WrenchActuation:
    """``actuation: wrench``: thrust along ``-z_b`` and body torque go to the plant as they are."""

    def __init__(self) -> None:
        self.saturation = SaturationReport()
        self.tilt_saturation = SaturationReport()

    def allocate(self, time: float, force_body: np.ndarray, torque_body: np.ndarray) -> Actuated:
        """Pass ``u_T = -f_z`` [N] and ``tau_b`` [N m] through; ``f_x``, ``f_y`` cannot be applied (shortfall)."""
        return Actuated(None, None, np.array((0.0, 0.0, force_body[2])), np.array(torque_body, float), False,
                        np.array((force_body[0], force_body[1], 0.0, 0.0, 0.0, 0.0)))


def _checked_strategy(strategy: str) -> str:
    if strategy not in ALLOCATION_STRATEGIES:
        raise ValueError(f"unknown allocation strategy '{strategy}' ({', '.join(ALLOCATION_STRATEGIES)})")
    return strategy


class FixedRotorActuation:
    """Fixed rotors: pseudo-inverse of the 4 x n (coplanar) block; beyond the limits either clamp rotor by
    rotor (``strategy='clamp'``) or reallocate with priorities (``'priority'``, fsr_sim.model.desaturation)."""

    def __init__(self, vehicle: Vehicle, strategy: str = "priority") -> None:
        self.vehicle = vehicle
        self.strategy = _checked_strategy(strategy)
        self.allocator = FixedRotorAllocator(vehicle)
        self.allocation = self.allocator.allocation
        self.saturation = self.allocator.saturation
        self.tilt_saturation = SaturationReport()
        self.desaturation = (
            FixedRotorDesaturation(self.allocator.inverse, self.allocator.rows, vehicle.rotor_speed_min,
                                   vehicle.rotor_speed_max)
            if strategy == "priority" else None
        )

    def allocate(self, time: float, force_body: np.ndarray, torque_body: np.ndarray) -> Actuated:
        """Rotor speeds [rad/s] for a body force (only ``f_z = -u_T`` [N] is used) and torque [N m], FRD."""
        thrust = -float(force_body[2])
        speed_sq = self.allocator.rotor_speed_sq(thrust, torque_body)
        speeds, excess = clamp_rotor_speeds(self.vehicle, speed_sq)
        saturated = self.saturation.record(time, excess)
        if saturated and self.desaturation is not None:
            torque = (float(torque_body[0]), float(torque_body[1]), float(torque_body[2]))
            if math.isfinite(thrust) and all(math.isfinite(t) for t in torque):
                desaturated = self.desaturation.allocate(thrust, torque)
                if desaturated is not None:  # inside the box up to rounding: the clamp removes only that
                    speeds = clamp_rotor_speeds(self.vehicle, np.array(desaturated))[0]
        wrench = self.allocation @ (np.abs(speeds) * speeds)
        shortfall = np.concatenate((force_body, torque_body)) - wrench
        if saturated:
            self.saturation.record_shortfall(shortfall)
        return Actuated(speeds, None, wrench[:3], wrench[3:], saturated, shortfall)


class TiltingActuation:
    """Tilting rotors: static allocation pseudo-inverse (+ optional null-space objective), eq. 5, clamp."""

    def __init__(self, vehicle: Vehicle, secondary: PeakThrustObjective | None = None,
                 strategy: str = "priority") -> None:
        self.vehicle = vehicle
        self.strategy = _checked_strategy(strategy)
        self.allocation = static_tilting_allocation(vehicle)
        self.inverse = np.linalg.pinv(self.allocation)
        import scipy.linalg  # lazily: only a tilting vehicle needs it (~0.3 s of imports)

        self.null_basis = scipy.linalg.null_space(self.allocation)
        self.secondary = secondary
        self.saturation = SaturationReport()
        self.tilt_saturation = SaturationReport()
        self.max_speed_sq = vehicle.rotor_speed_max * vehicle.rotor_speed_max
        self.desaturation = (
            TiltingDesaturation(self.inverse, vehicle.c_f * self.max_speed_sq) if strategy == "priority" else None
        )

    @classmethod
    def with_objective(cls, vehicle: Vehicle, objective: str, exponent: int = 8, iterations: int = 3,
                       strategy: str = "priority") -> TiltingActuation:
        """``objective``: ``none`` (minimum-norm ``G^+``) or ``min_peak_speed`` (see fsr_control.nullspace);
        ``strategy``: ``clamp`` or ``priority`` (module docstring)."""
        actuation = cls(vehicle, strategy=strategy)
        if objective == "min_peak_speed":
            actuation.secondary = PeakThrustObjective(actuation.null_basis, exponent, iterations)
        elif objective != "none":
            raise ValueError(f"unknown secondary objective '{objective}' (none, min_peak_speed)")
        return actuation

    def allocate(self, time: float, force_body: np.ndarray, torque_body: np.ndarray) -> Actuated:
        """Rotor speeds [rad/s] and tilts [rad] for a body force [N] and torque [N m] (FRD).

        With ``priority``, a command beyond ``w_max`` is replaced by the priority allocation (force, then
        roll/pitch, then yaw; without the secondary objective on that step); the minimum speed and the tilt
        limit are clamped as with ``clamp``.
        """
        wrench = np.concatenate((force_body, torque_body))
        u = self.inverse @ wrench
        if self.secondary is not None:
            u = u + self.secondary.correction(u)
        speed_sq, tilts = rotor_commands_from_static(self.vehicle, u)
        speeds, excess = clamp_rotor_speeds(self.vehicle, speed_sq)
        saturated = self.saturation.record(time, excess)
        if (saturated and self.desaturation is not None and speed_sq.max() > self.max_speed_sq
                and np.isfinite(u).all()):
            speed_sq, tilts = rotor_commands_from_static(self.vehicle,
                                                         self.desaturation.allocate(force_body, torque_body))
            speeds = clamp_rotor_speeds(self.vehicle, speed_sq)[0]
        limit = self.vehicle.tilt_angle_max
        clamped_tilts = np.minimum(np.maximum(tilts, -limit), limit)  # np.clip without its Python overhead
        saturated |= self.tilt_saturation.record(time, np.abs(tilts - clamped_tilts))
        produced = self.allocation @ static_from_rotor_commands(self.vehicle, speeds * speeds, clamped_tilts)
        shortfall = wrench - produced
        if saturated:
            self.saturation.record_shortfall(shortfall)
        return Actuated(speeds, clamped_tilts, produced[:3], produced[3:], saturated, shortfall)
