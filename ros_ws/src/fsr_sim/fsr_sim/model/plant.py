"""The true plant: rigid body + rotors (with ground/ceiling effect) + disturbances + ground contact.

Inputs are held constant over a step (zero-order hold) while the state-dependent parts (thrust ratios near
surfaces, time-varying disturbances) are evaluated at every RK4 stage. Two actuation modes (SPEC §3.1):

* ``rotors``: rotor speeds ``w_i`` [rad/s] (clamped to the vehicle's limits, saturation recorded) and, for
  a tilting vehicle, tilt angles ``alpha_i`` [rad] (clamped to +-tilt_angle_max), applied instantly;
  ``f_b = sum c_f r_i |w_i| w_i z_i``, ``tau_b = sum |w_i| w_i (c_f r_i p_i x z_i - k_i c_m z_i)`` with the
  thrust ratio ``r_i`` of :mod:`fsr_sim.model.environment` (drag torque is not scaled).
* ``wrench``: the commanded body wrench directly, ``f_b = -u_T e3`` and ``tau_b`` (the report's exercises 3
  and 4); surfaces then only act through contact.

Ground and ceiling are solid (contact geometry in :mod:`fsr_sim.model.environment`); an impact faster
than ``crash_speed`` is a divergence. ``ground_cap_steps`` / ``ceiling_cap_steps`` count the control steps
in which a rotor's thrust ratio was held at the surface's ``max_ratio`` (the effect model's validity ends
there).
"""

from __future__ import annotations

import math

import numpy as np

from fsr_sim.config.scenario import SimulationConfig
from fsr_sim.model.allocation import SaturationReport, clamp_rotor_speeds, rotor_axes, tilt_basis
from fsr_sim.model.disturbances import external_wrench_floats, total_external_wrench
from fsr_sim.model.environment import ThrustEffects
from fsr_sim.model.rigid_body import (
    ANGULAR_VELOCITY,
    POSITION,
    QUATERNION,
    VELOCITY,
    RigidBody,
    pack_state,
)
from fsr_sim.model.so3 import Mat3, Vec3, mat_vec3, rotation_from_quaternion

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
        self.max_ceiling_impact_speed = 0.0  # [m/s] upward speed at ceiling contact
        self.at_ceiling = False
        self.ground_cap_steps = 0
        self.ceiling_cap_steps = 0
        n = vehicle.rotor_count
        self.rotor_speeds = np.zeros(n)
        self.tilt_angles = np.zeros(n) if vehicle.is_tilting else None
        self.thrust = 0.0
        self.torque_command = np.zeros(3)
        self._speed_sq = np.zeros(n)
        # Constant per-rotor columns of the tilt basis (z_v, z_l): the axes are linear in (cos, sin) of the tilt.
        self._tilt_columns = [self._columns(axes) for axes in tilt_basis(vehicle)] if vehicle.is_tilting else None
        self._set_axes(self.tilt_angles)
        self._ratios = np.ones(n)
        self._update_body_wrench()

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
    def _columns(self, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(3, n) force, lever-arm torque and drag torque per squared speed for rotor axes (n, 3)."""
        v = self.vehicle
        return (v.c_f * axes).T, (v.c_f * np.cross(v.positions, axes)).T, (-(v.spins * v.c_m)[:, None] * axes).T

    def _set_axes(self, tilts: np.ndarray | None) -> None:
        if self._tilt_columns is None or tilts is None:
            # force (scaled by the thrust ratio), lever-arm torque (scaled too) and drag torque columns
            self._force_cols, self._lever_cols, self._drag_cols = self._columns(rotor_axes(self.vehicle, tilts))
            return
        # z_i = cos(alpha_i) z_v,i + sin(alpha_i) z_l,i, so each column is the same combination of the
        # constant columns of z_v and z_l (no np.cross / np.tile per command).
        c, s = np.cos(tilts), np.sin(tilts)
        (f_v, l_v, d_v), (f_l, l_l, d_l) = self._tilt_columns
        self._force_cols = f_v * c + f_l * s
        self._lever_cols = l_v * c + l_l * s
        self._drag_cols = d_v * c + d_l * s

    def _update_body_wrench(self) -> None:
        """Cache the actuator wrench as floats: constant over the period unless thrust ratios vary with pose."""
        if self.actuation == "wrench":
            self._body_wrench = (0.0, 0.0, -self.thrust, *self.torque_command.tolist())
        elif not self.effects.enabled:
            u = self._speed_sq
            self._body_wrench = (*(self._force_cols @ u).tolist(),
                                 *(self._lever_cols @ u + self._drag_cols @ u).tolist())
        else:
            # Per rotor: force and lever-arm torque at ratio 1 (scaled per stage by the ratio), and the
            # total drag torque (not scaled).
            u = self._speed_sq
            self._rotor_terms = list(zip((self._force_cols * u).T.tolist(), (self._lever_cols * u).T.tolist(),
                                         strict=True))
            self._drag_torque = (self._drag_cols @ u).tolist()

    def set_rotor_command(self, speeds: np.ndarray, tilts: np.ndarray | None = None) -> bool:
        """Apply rotor speeds [rad/s] (and tilts [rad]); returns True if anything saturated."""
        speeds = np.asarray(speeds, dtype=float)
        clamped, excess = clamp_rotor_speeds(self.vehicle, np.abs(speeds) * speeds)
        saturated = self.saturation.record(self.time, excess)
        self.rotor_speeds = clamped
        self._speed_sq = np.abs(clamped) * clamped
        if self.vehicle.is_tilting and tilts is not None:
            limit = self.vehicle.tilt_angle_max
            self.tilt_angles = np.minimum(np.maximum(np.asarray(tilts, dtype=float), -limit), limit)
            self._set_axes(self.tilt_angles)
        self._update_body_wrench()
        return saturated

    def set_wrench_command(self, thrust: float, torque_body: np.ndarray) -> None:
        """Apply ``u_T`` [N] along ``-z_b`` and ``tau_b`` [N m] (``actuation: wrench``)."""
        self.thrust = float(thrust)
        self.torque_command = np.array(torque_body, dtype=float)
        self._update_body_wrench()

    def cut_thrust(self) -> None:
        """Failsafe: all rotors stopped / zero wrench."""
        self.set_wrench_command(0.0, np.zeros(3))
        self.rotor_speeds = np.zeros(self.vehicle.rotor_count)
        self._speed_sq = np.zeros(self.vehicle.rotor_count)
        self._update_body_wrench()

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

    def _wrench(self, t: float, position: Vec3, rotation: Mat3) -> tuple[float, float, float, float, float, float]:
        """Force world (excluding gravity) [N] and torque body [N m] at an RK4 stage, on Python floats."""
        if self.actuation == "rotors" and self.effects.enabled:
            fx = fy = fz = 0.0
            tx, ty, tz = self._drag_torque
            for ratio, (force, lever) in zip(self.effects.ratios_floats(position[2], rotation[2]), self._rotor_terms,
                                             strict=True):
                fx, fy, fz = fx + ratio * force[0], fy + ratio * force[1], fz + ratio * force[2]
                tx, ty, tz = tx + ratio * lever[0], ty + ratio * lever[1], tz + ratio * lever[2]
        else:
            fx, fy, fz, tx, ty, tz = self._body_wrench
        fx, fy, fz = mat_vec3(rotation, (fx, fy, fz))
        disturbances = self.config.disturbances
        if disturbances:
            ex, ey, ez, ux, uy, uz = external_wrench_floats(disturbances, t, rotation)
            return fx + ex, fy + ey, fz + ez, tx + ux, ty + uy, tz + uz
        return fx, fy, fz, tx, ty, tz

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
        ceiling = self.config.environment.ceiling.enabled
        for sub in range(self.substeps):
            t = self.time + sub * self.dt
            self.state = self.body.step_floats(t, self.state, self.dt, self._wrench)
            self._apply_ground_contact()
            if ceiling:
                self._apply_ceiling_contact()
        effects = self.effects
        if effects.ground_capped or effects.ceiling_capped:
            self._count_capped_steps()
        self.step_index += 1

    def _count_capped_steps(self) -> None:
        effects = self.effects
        self.ground_cap_steps += effects.ground_capped
        self.ceiling_cap_steps += effects.ceiling_capped
        effects.ground_capped = effects.ceiling_capped = False

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

    def _apply_ceiling_contact(self) -> None:
        """The top of the vehicle (``top_height`` above the centre) stops at the ceiling, like the ground
        (called only when the ceiling is enabled)."""
        ceiling = self.config.environment.ceiling
        self.at_ceiling = False
        rest_z = ceiling.height + self.vehicle.top_height
        if self.state[2] > rest_z:
            return
        self.at_ceiling = True
        impact = -self.state[5]  # upward (negative NED z) speed
        if impact > self.max_ceiling_impact_speed:
            self.max_ceiling_impact_speed = float(impact)
        self.state[2] = rest_z
        self.state[VELOCITY] = 0.0  # held against the ceiling while the net force pushes up
        self.state[ANGULAR_VELOCITY] = 0.0

    def divergence(self) -> str | None:
        """Why the simulation cannot go on (NaN state, beyond physical bounds, crash), or None."""
        s = self.state.tolist()
        if not all(map(math.isfinite, s)):
            return "state is not finite (NaN or inf)"
        speed = math.sqrt(s[3] * s[3] + s[4] * s[4] + s[5] * s[5])
        if speed > MAX_SPEED:
            return f"speed {speed:.1f} m/s exceeds {MAX_SPEED} m/s"
        spin = math.sqrt(s[10] * s[10] + s[11] * s[11] + s[12] * s[12])
        if spin > MAX_SPIN:
            return f"angular speed {spin:.1f} rad/s exceeds {MAX_SPIN} rad/s"
        if self.max_impact_speed > self.crash_speed:
            return f"crashed into the ground at {self.max_impact_speed:.2f} m/s (limit {self.crash_speed} m/s)"
        if self.max_ceiling_impact_speed > self.crash_speed:
            return (f"crashed into the ceiling at {self.max_ceiling_impact_speed:.2f} m/s "
                    f"(limit {self.crash_speed} m/s)")
        return None
