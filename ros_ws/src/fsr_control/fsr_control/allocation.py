"""From the controller's body wrench to actuator commands, through fsr_sim's allocation (SPEC §3.2).

Three actuations, one interface ``allocate(time, force_body, torque_body) -> Actuated``:

* :class:`WrenchActuation` (``actuation: wrench``): the plant takes ``u_T = -f_z`` and ``tau_b`` directly.
* :class:`FixedRotorActuation`: ``u_w = G^+ [f_z, tau]`` (fsr_sim's ``FixedRotorAllocator``: exact inverse
  for a quadrotor, minimum-norm pseudo-inverse for the octocopter).
* :class:`TiltingActuation`: ``u = G_static^+ wrench (+ N z, the secondary objective)``, then eq. 5:
  ``u_w,i = |(u_v,i, u_l,i)| / c_f``, ``alpha_i = atan2(u_l,i, u_v,i)``.

Rotor speeds ``w_i = sqrt(u_w,i)`` [rad/s] are clamped to the vehicle's ``[w_min, w_max]`` (tilts to
``+-tilt_angle_max``); every clamped command is recorded in a :class:`SaturationReport` (count, first
time, worst rotor) and flagged in the result, never clipped silently. ``force_body`` / ``torque_body`` of the
result are what the clamped command produces through the nominal allocation (what the plant applies,
ground effect aside): that is the ``wrench_cmd`` the controller publishes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fsr_control.nullspace import PeakThrustObjective
from fsr_sim.model.allocation import (
    FixedRotorAllocator,
    SaturationReport,
    clamp_rotor_speeds,
    rotor_commands_from_static,
    static_from_rotor_commands,
    static_tilting_allocation,
)
from fsr_sim.model.vehicle import Vehicle


@dataclass
class Actuated:
    """One allocated command: rotor speeds [rad/s] (None in wrench actuation), tilts [rad] (None for fixed
    rotors), the wrench it produces (body FRD, N / N m) and whether anything was clamped."""

    rotor_speeds: np.ndarray | None
    tilt_angles: np.ndarray | None
    force_body: np.ndarray
    torque_body: np.ndarray
    saturated: bool


class WrenchActuation:
    """``actuation: wrench``: thrust along ``-z_b`` and body torque go to the plant as they are."""

    def __init__(self) -> None:
        self.saturation = SaturationReport()
        self.tilt_saturation = SaturationReport()

    def allocate(self, time: float, force_body: np.ndarray, torque_body: np.ndarray) -> Actuated:
        return Actuated(None, None, np.array((0.0, 0.0, force_body[2])), np.array(torque_body, float), False)


class FixedRotorActuation:
    """Fixed rotors: pseudo-inverse of the 4 x n (coplanar) block, clamp, record saturation."""

    def __init__(self, vehicle: Vehicle) -> None:
        self.vehicle = vehicle
        self.allocator = FixedRotorAllocator(vehicle)
        self.allocation = self.allocator.allocation
        self.saturation = self.allocator.saturation
        self.tilt_saturation = SaturationReport()

    def allocate(self, time: float, force_body: np.ndarray, torque_body: np.ndarray) -> Actuated:
        speed_sq = self.allocator.rotor_speed_sq(-float(force_body[2]), torque_body)
        speeds, excess = clamp_rotor_speeds(self.vehicle, speed_sq)
        saturated = self.saturation.record(time, excess)
        wrench = self.allocation @ (np.abs(speeds) * speeds)
        return Actuated(speeds, None, wrench[:3], wrench[3:], saturated)


class TiltingActuation:
    """Tilting rotors: static allocation pseudo-inverse (+ optional null-space objective), eq. 5, clamp."""

    def __init__(self, vehicle: Vehicle, secondary: PeakThrustObjective | None = None) -> None:
        self.vehicle = vehicle
        self.allocation = static_tilting_allocation(vehicle)
        self.inverse = np.linalg.pinv(self.allocation)
        self.null_basis = scipy.linalg.null_space(self.allocation)
        self.secondary = secondary
        self.saturation = SaturationReport()
        self.tilt_saturation = SaturationReport()

    @classmethod
    def with_objective(cls, vehicle: Vehicle, objective: str, exponent: int = 8, iterations: int = 3
                       ) -> TiltingActuation:
        """``objective``: ``none`` (minimum-norm ``G^+``) or ``min_peak_speed`` (see fsr_control.nullspace)."""
        actuation = cls(vehicle)
        if objective == "min_peak_speed":
            actuation.secondary = PeakThrustObjective(actuation.null_basis, exponent, iterations)
        elif objective != "none":
            raise ValueError(f"unknown secondary objective '{objective}' (none, min_peak_speed)")
        return actuation

    def allocate(self, time: float, force_body: np.ndarray, torque_body: np.ndarray) -> Actuated:
        wrench = np.concatenate((force_body, torque_body))
        u = self.inverse @ wrench
        if self.secondary is not None:
            u = u + self.secondary.correction(u)
        speed_sq, tilts = rotor_commands_from_static(self.vehicle, u)
        speeds, excess = clamp_rotor_speeds(self.vehicle, speed_sq)
        saturated = self.saturation.record(time, excess)
        limit = self.vehicle.tilt_angle_max
        clamped_tilts = np.minimum(np.maximum(tilts, -limit), limit)  # np.clip without its Python overhead
        saturated |= self.tilt_saturation.record(time, np.abs(tilts - clamped_tilts))
        produced = self.allocation @ static_from_rotor_commands(self.vehicle, speeds * speeds, clamped_tilts)
        return Actuated(speeds, clamped_tilts, produced[:3], produced[3:], saturated)
