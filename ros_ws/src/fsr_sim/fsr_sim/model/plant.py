"""The true plant: rigid body + rotors (with ground/ceiling effect) + disturbances + ground contact.

Inputs are held constant over a step (zero-order hold) while the state-dependent parts (thrust ratios near
surfaces, time-varying disturbances) are evaluated at every RK4 stage. Two actuation modes (SPEC §3.1):

* ``rotors``: rotor speeds ``w_i`` [rad/s] (clamped to the vehicle's limits, saturation recorded) and, for
  a tilting vehicle, tilt angles ``alpha_i`` [rad] (clamped to +-tilt_angle_max), applied instantly;
  ``f_b = sum c_f r_i |w_i| w_i z_i``, ``tau_b = sum |w_i| w_i (c_f r_i p_i x z_i - k_i c_m z_i)`` with the
  thrust ratio ``r_i`` of :mod:`fsr_sim.model.environment` (drag torque is not scaled).
* ``wrench``: the commanded body wrench directly, ``f_b = -u_T e3`` and ``tau_b`` (the report's exercises 3
  and 4); surfaces then only act through contact.
"""

from __future__ import annotations

import math

import numpy as np

from fsr_sim.config.scenario import SimulationConfig
from fsr_sim.model.allocation import SaturationReport, clamp_rotor_speeds, rotor_axes
from fsr_sim.model.disturbances import total_external_wrench
from fsr_sim.model.environment import ThrustEffects
from fsr_sim.model.rigid_body import (
    ANGULAR_VELOCITY,
    POSITION,
    QUATERNION,
    VELOCITY,
    RigidBody,
    pack_state,
)
from fsr_sim.model.so3 import rotation_from_quaternion

MAX_SPEED = 100.0  # m/s: beyond this the simulation is considered diverged
MAX_SPIN = 200.0  # rad/s
DEFAULT_CRASH_SPEED = 3.0  # m/s downward at ground contact


class Plant:
    """Simulated vehicle; ``step()`` advances one lockstep period (``physics_substeps`` RK4 steps)."""

    def __init__(self, config: SimulationConfig, crash_speed: float = DEFAULT_CRASH_SPEED) -> None:
        vehicle = config.plant_vehicle
        self.config = config
        self.vehicle = vehicle
        self.body = RigidBody(vehicle.mass, vehicle.inertia)
        init = config.initial
        self.state = pack_state(init.position, init.rotation, init.velocity, init.angular_velocity)
        self.step_index = 0
        self.dt = config.physics_dt
        self.substeps = config.physics_substeps
        self.actuation = config.actuation
        self.effects = ThrustEffects(config.environment, vehicle.positions, vehicle.rotor_radius)
        self.saturation = SaturationReport()
        self.crash_speed = crash_speed
        self.max_impact_speed = 0.0
        self.in_contact = False
        n = vehicle.rotor_count
        self.rotor_speeds = np.zeros(n)
        self.tilt_angles = np.zeros(n) if vehicle.is_tilting else None
        self.thrust = 0.0
        self.torque_command = np.zeros(3)
        self._speed_sq = np.zeros(n)
        self._set_axes(self.tilt_angles)
        self._ratios = np.ones(n)

    # ----- time -------------------------------------------------------------------------------------
    @property
    def period(self) -> float:
        return self.dt * self.substeps

    @property
    def time(self) -> float:
        """Simulated time [s] of the current state."""
        return self.step_index * self.period

    @property
    def stamp_ns(self) -> int:
        """Simulated time of the current state in integer nanoseconds (exact step multiples)."""
        return self.step_index * int(round(self.period * 1e9))

    # ----- state ------------------------------------------------------------------------------------
    @property
    def position(self) -> np.ndarray:
        return self.state[POSITION]

    @property
    def velocity(self) -> np.ndarray:
        return self.state[VELOCITY]

    @property
    def rotation(self) -> np.ndarray:
        return rotation_from_quaternion(self.state[QUATERNION])

    @property
    def quaternion(self) -> np.ndarray:
        return self.state[QUATERNION]

    @property
    def angular_velocity(self) -> np.ndarray:
        return self.state[ANGULAR_VELOCITY]

    # ----- commands ---------------------------------------------------------------------------------
    def _set_axes(self, tilts: np.ndarray | None) -> None:
        v = self.vehicle
        axes = rotor_axes(v, tilts)
        self._force_cols = (v.c_f * axes).T  # (3, n) per squared speed, scaled by the thrust ratio
        self._lever_cols = (v.c_f * np.cross(v.positions, axes)).T
        self._drag_cols = (-(v.spins * v.c_m)[:, None] * axes).T

    def set_rotor_command(self, speeds: np.ndarray, tilts: np.ndarray | None = None) -> bool:
        """Apply rotor speeds [rad/s] (and tilts [rad]); returns True if anything saturated."""
        speeds = np.asarray(speeds, dtype=float)
        clamped, excess = clamp_rotor_speeds(self.vehicle, np.abs(speeds) * speeds)
        saturated = self.saturation.record(self.time, excess)
        self.rotor_speeds = clamped
        self._speed_sq = np.abs(clamped) * clamped
        if self.vehicle.is_tilting and tilts is not None:
            limit = self.vehicle.tilt_angle_max
            self.tilt_angles = np.clip(np.asarray(tilts, dtype=float), -limit, limit)
            self._set_axes(self.tilt_angles)
        return saturated

    def set_wrench_command(self, thrust: float, torque_body: np.ndarray) -> None:
        """Apply ``u_T`` [N] along ``-z_b`` and ``tau_b`` [N m] (``actuation: wrench``)."""
        self.thrust = float(thrust)
        self.torque_command = np.array(torque_body, dtype=float)

    def cut_thrust(self) -> None:
        """Failsafe: all rotors stopped / zero wrench."""
        self.set_wrench_command(0.0, np.zeros(3))
        self.rotor_speeds = np.zeros(self.vehicle.rotor_count)
        self._speed_sq = np.zeros(self.vehicle.rotor_count)

    # ----- dynamics ---------------------------------------------------------------------------------
    def body_wrench(self, position: np.ndarray, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Actuator wrench (force body [N], torque body [N m]) at the given pose."""
        if self.actuation == "wrench":
            return np.array((0.0, 0.0, -self.thrust)), self.torque_command
        u = self._speed_sq
        if self.effects.enabled:
            self._ratios = self.effects.ratios(position, rotation)
            scaled = self._ratios * u
        else:
            scaled = u
        return self._force_cols @ scaled, self._lever_cols @ scaled + self._drag_cols @ u

    def _wrench(self, t: float, position: np.ndarray, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        force_body, torque_body = self.body_wrench(position, rotation)
        force_world = rotation @ force_body
        if self.config.disturbances:
            f_ext, tau_ext = total_external_wrench(self.config.disturbances, t, rotation)
            return force_world + f_ext, torque_body + tau_ext
        return force_world, torque_body

    def external_wrench(self) -> tuple[np.ndarray, np.ndarray]:
        """True external wrench now: (force world NED [N], torque body FRD [N m])."""
        return total_external_wrench(self.config.disturbances, self.time, self.rotation)

    def thrust_ratios(self) -> np.ndarray:
        """Ground/ceiling thrust ratio of each rotor at the current pose (1 away from surfaces)."""
        if not self.effects.enabled:
            return np.ones(self.vehicle.rotor_count)
        return self.effects.ratios(self.position, self.rotation)

    def step(self) -> None:
        """Advance one period: ``physics_substeps`` RK4 steps of ``physics_dt``, with ground contact."""
        for sub in range(self.substeps):
            t = self.time + sub * self.dt
            self.state = self.body.step(t, self.state, self.dt, self._wrench)
            self._apply_ground_contact()
        self.step_index += 1

    def _apply_ground_contact(self) -> None:
        ground = self.config.environment.ground
        self.in_contact = False
        if not ground.enabled:
            return
        rest_z = ground.height - self.vehicle.contact_height
        if self.state[2] < rest_z:
            return
        self.in_contact = True
        impact = self.state[5]
        if impact > self.max_impact_speed:
            self.max_impact_speed = float(impact)
        self.state[2] = rest_z
        self.state[VELOCITY] = 0.0  # held by the ground (no bounce, no sliding)
        self.state[ANGULAR_VELOCITY] = 0.0

    def divergence(self) -> str | None:
        """Why the simulation cannot go on (NaN state, beyond physical bounds, crash), or None."""
        if not np.all(np.isfinite(self.state)):
            return "state is not finite (NaN or inf)"
        speed = math.sqrt(self.state[3:6] @ self.state[3:6])
        if speed > MAX_SPEED:
            return f"speed {speed:.1f} m/s exceeds {MAX_SPEED} m/s"
        spin = math.sqrt(self.state[10:13] @ self.state[10:13])
        if spin > MAX_SPIN:
            return f"angular speed {spin:.1f} rad/s exceeds {MAX_SPIN} rad/s"
        if self.max_impact_speed > self.crash_speed:
            return f"crashed into the ground at {self.max_impact_speed:.2f} m/s (limit {self.crash_speed} m/s)"
        return None
