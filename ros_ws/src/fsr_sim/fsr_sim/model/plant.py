"""The true plant: rigid body + rotors (with ground/ceiling effect) + disturbances + ground contact.

Inputs are held constant over a step (zero-order hold) while the state-dependent parts (thrust ratios near
surfaces, time-varying disturbances) are evaluated at every RK4 stage. Two actuation modes (SPEC §3.1):

* ``rotors``: rotor speeds ``w_i`` [rad/s] (clamped to the vehicle's limits, saturation recorded) and, for
  a tilting vehicle, tilt angles ``alpha_i`` [rad] (clamped to +-tilt_angle_max), applied instantly;
  ``f_b = sum c_f r_i |w_i| w_i z_i``, ``tau_b = sum |w_i| w_i (c_f r_i p_i x z_i - k_i c_m z_i)`` with the
  thrust ratio ``r_i`` of :mod:`fsr_sim.model.environment` (drag torque is not scaled).
* ``wrench``: the commanded body wrench directly, ``f_b`` and ``tau_b`` (the report's exercises 3 and 4 use
  ``f_b = -u_T e3``); surfaces then only act through contact.

Built from plain Python values::

    plant = Plant(load_vehicle("quadrotor_ex4"), dt=0.001, actuation="wrench", position=[0, 0, -1])
    plant.set_wrench(force_body=[0, 0, -11.772], torque_body=[0, 0, 0])
    plant.step()
    plant.state.position, plant.state.rotation

A scenario's plant section gives the same object through :func:`fsr_sim.config.scenario.plant_from_config`.

Ground and ceiling are solid (contact geometry in :mod:`fsr_sim.model.environment`); an impact faster
than ``crash_speed`` is a divergence. ``ground_cap_steps`` / ``ceiling_cap_steps`` count the control steps
in which a rotor's thrust ratio was held at the surface's ``max_ratio`` (the effect model's validity ends
there).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from fsr_sim.model.allocation import SaturationReport, clamp_rotor_speeds, rotor_axes, tilt_basis, wrench_columns
from fsr_sim.model.checks import InvalidValueError, finite_array
from fsr_sim.model.disturbances import DisturbanceProfile, external_wrench_floats, total_external_wrench
from fsr_sim.model.environment import Environment, ThrustEffects
from fsr_sim.model.rigid_body import (
    ANGULAR_VELOCITY,
    POSITION,
    QUATERNION,
    VELOCITY,
    RigidBody,
    RigidBodyState,
    pack_state,
)
from fsr_sim.model.so3 import Mat3, Vec3, mat_vec3, rotation_from_euler_zyx, rotation_from_quaternion
from fsr_sim.model.vehicle import Vehicle

MAX_SPEED = 100.0  # m/s: beyond this the simulation is considered diverged
MAX_SPIN = 200.0  # rad/s
DEFAULT_CRASH_SPEED = 3.0  # m/s downward at ground contact
ACTUATIONS = ("rotors", "wrench")


class Plant:
    """Simulated vehicle; :meth:`step` advances one period (``substeps`` RK4 steps of ``dt``).

    Parameters
    ----------
    vehicle : Vehicle
        The true plant (its mass and inertia are what the dynamics use).
    dt : float
        RK4 step [s], > 0.
    actuation : {"rotors", "wrench"}
        Rotor speeds (:meth:`set_rotor_command`) or a body wrench (:meth:`set_wrench`).
    position, velocity : array-like, shape (3,)
        Initial position [m] and velocity [m/s], world NED.
    rotation : array-like, shape (3, 3), optional
        Initial attitude, body FRD -> world NED (default: level, heading north).
    attitude_rpy_deg : array-like, shape (3,), optional
        The initial attitude as ZYX Euler angles [deg] instead of ``rotation``.
    angular_velocity : array-like, shape (3,)
        Initial angular velocity [rad/s], body FRD.
    environment : Environment, optional
        Surfaces (default ``Environment()``: ground at ``z = 0`` with ground effect, no ceiling).
    disturbances : sequence of DisturbanceProfile
        External wrenches (:mod:`fsr_sim.model.disturbances`), summed.
    substeps : int
        RK4 steps per :meth:`step` (the control period is ``dt * substeps``).
    crash_speed : float
        Downward speed at ground contact [m/s] beyond which :meth:`divergence` reports a crash.

    Raises
    ------
    ValueError
        Naming the argument, for any invalid value.
    """

    def __init__(
        self,
        vehicle: Vehicle,
        dt: float = 0.001,
        actuation: str = "rotors",
        position: ArrayLike = (0.0, 0.0, 0.0),
        rotation: ArrayLike | None = None,
        velocity: ArrayLike = (0.0, 0.0, 0.0),
        angular_velocity: ArrayLike = (0.0, 0.0, 0.0),
        environment: Environment | None = None,
        disturbances: Sequence[DisturbanceProfile] = (),
        substeps: int = 1,
        crash_speed: float = DEFAULT_CRASH_SPEED,
        attitude_rpy_deg: ArrayLike | None = None,
    ) -> None:
        if actuation not in ACTUATIONS:
            raise InvalidValueError("actuation", f"must be one of {', '.join(ACTUATIONS)}, got '{actuation}'")
        if not dt > 0.0:
            raise InvalidValueError("dt", f"must be > 0 s, got {dt}")
        if int(substeps) != substeps or substeps < 1:
            raise InvalidValueError("substeps", f"must be an integer >= 1, got {substeps}")
        if rotation is not None and attitude_rpy_deg is not None:
            raise InvalidValueError("rotation", "give rotation or attitude_rpy_deg, not both")
        if attitude_rpy_deg is not None:
            rotation = rotation_from_euler_zyx(np.deg2rad(finite_array(attitude_rpy_deg, (3,), "attitude_rpy_deg")))
        rotation = np.eye(3) if rotation is None else finite_array(rotation, (3, 3), "rotation")
        self.vehicle = vehicle
        self.body = RigidBody(vehicle.mass, vehicle.inertia)
        self.state_vector = pack_state(
            finite_array(position, (3,), "position"), rotation, finite_array(velocity, (3,), "velocity"),
            finite_array(angular_velocity, (3,), "angular_velocity"),
        )
        self.step_index = 0
        self.dt = float(dt)
        self.substeps = int(substeps)
        self.actuation = actuation
        self.environment = Environment() if environment is None else environment
        self.disturbances = list(disturbances)
        self.effects = ThrustEffects(self.environment, vehicle.positions, vehicle.rotor_radius)
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
        self.force_command = np.zeros(3)
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
    def state(self) -> RigidBodyState:
        """A snapshot of the current state: ``.position``, ``.velocity`` (world), ``.rotation``, ``.quaternion``,
        ``.angular_velocity`` (body), ``.vector`` (the 13 numbers)."""
        return RigidBodyState(self.state_vector.copy())

    @property
    def position(self) -> np.ndarray:
        """Position [m], world NED (a view of the state vector)."""
        return self.state_vector[POSITION]

    @property
    def velocity(self) -> np.ndarray:
        """Velocity [m/s], world NED (a view of the state vector)."""
        return self.state_vector[VELOCITY]

    @property
    def rotation(self) -> np.ndarray:
        """``R`` body FRD -> world NED."""
        return rotation_from_quaternion(self.state_vector[QUATERNION])

    @property
    def quaternion(self) -> np.ndarray:
        """Unit quaternion ``[x, y, z, w]`` body -> world (a view of the state vector)."""
        return self.state_vector[QUATERNION]

    @property
    def angular_velocity(self) -> np.ndarray:
        """Angular velocity [rad/s], body FRD (a view of the state vector)."""
        return self.state_vector[ANGULAR_VELOCITY]

    # ----- commands ---------------------------------------------------------------------------------
    def _columns(self, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(3, n) force, lever-arm torque and drag torque per squared speed for rotor axes (n, 3): the three
        parts of :func:`fsr_sim.model.allocation.wrench_columns` (kept apart: only the first two scale with
        the surface-effect ratio)."""
        v = self.vehicle
        force_and_lever = wrench_columns(v, axes, v.c_f, 0.0)
        return force_and_lever[:3], force_and_lever[3:], wrench_columns(v, axes, 0.0, v.c_m)[3:]

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
            self._body_wrench = (*self.force_command.tolist(), *self.torque_command.tolist())
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

    def set_rotor_command(self, speeds: ArrayLike, tilts: ArrayLike | None = None) -> bool:
        """Apply rotor speeds [rad/s], shape (n,) (and tilts [rad], shape (n,), for a tilting vehicle), held
        until the next command; speeds are clamped to the vehicle's limits. Returns True if anything
        saturated (recorded in :attr:`saturation`)."""
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

    def set_wrench(self, force_body: ArrayLike, torque_body: ArrayLike) -> None:
        """Apply a body wrench (``actuation: wrench``): force [N] and torque [N m], body FRD, held until the
        next command. The report's thrust ``u_T`` is ``force_body = [0, 0, -u_T]``."""
        if self.actuation != "wrench":
            raise RuntimeError("set_wrench needs actuation='wrench' (this plant takes rotor speeds)")
        self.force_command = np.array(force_body, dtype=float).reshape(3)
        self.torque_command = np.array(torque_body, dtype=float).reshape(3)
        self._update_body_wrench()

    def set_wrench_command(self, thrust: float, torque_body: ArrayLike) -> None:
        """Apply ``u_T`` [N] along ``-z_b`` and ``tau_b`` [N m]: :meth:`set_wrench` with ``f_b = -u_T e3``."""
        self.set_wrench((0.0, 0.0, -float(thrust)), torque_body)

    @property
    def thrust(self) -> float:
        """``u_T = -f_z`` [N] of the commanded body wrench (``actuation: wrench``)."""
        return -float(self.force_command[2])

    def cut_thrust(self) -> None:
        """Failsafe: all rotors stopped / zero wrench."""
        self.force_command = np.zeros(3)
        self.torque_command = np.zeros(3)
        self.rotor_speeds = np.zeros(self.vehicle.rotor_count)
        self._speed_sq = np.zeros(self.vehicle.rotor_count)
        self._update_body_wrench()

    # ----- dynamics ---------------------------------------------------------------------------------
    def body_wrench(self, position: np.ndarray, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Actuator wrench (force body [N], torque body [N m]) at the given pose."""
        if self.actuation == "wrench":
            return self.force_command.copy(), self.torque_command.copy()
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
        disturbances = self.disturbances
        if disturbances:
            ex, ey, ez, ux, uy, uz = external_wrench_floats(disturbances, t, rotation)
            return fx + ex, fy + ey, fz + ez, tx + ux, ty + uy, tz + uz
        return fx, fy, fz, tx, ty, tz

    def external_wrench(self) -> tuple[np.ndarray, np.ndarray]:
        """True external wrench now: (force world NED [N], torque body FRD [N m])."""
        return total_external_wrench(self.disturbances, self.time, self.rotation)

    def thrust_ratios(self) -> np.ndarray:
        """Ground/ceiling thrust ratio of each rotor at the current pose (1 away from surfaces)."""
        if not self.effects.enabled:
            return np.ones(self.vehicle.rotor_count)
        return self.effects.ratios(self.position, self.rotation)

    def step(self) -> None:
        """Advance one period: ``physics_substeps`` RK4 steps of ``physics_dt``, with ground contact."""
        ceiling = self.environment.ceiling.enabled
        for sub in range(self.substeps):
            t = self.time + sub * self.dt
            self.state_vector = self.body.step_floats(t, self.state_vector, self.dt, self._wrench)
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
        ground = self.environment.ground
        self.in_contact = False
        if not ground.enabled:
            return
        rest_z = ground.height - self.vehicle.contact_height
        state = self.state_vector
        if state[2] < rest_z:
            return
        self.in_contact = True
        impact = state[5]
        if impact > self.max_impact_speed:
            self.max_impact_speed = float(impact)
        state[2] = rest_z
        state[VELOCITY] = 0.0  # held by the ground (no bounce, no sliding)
        state[ANGULAR_VELOCITY] = 0.0

    def _apply_ceiling_contact(self) -> None:
        """The top of the vehicle (``top_height`` above the centre) stops at the ceiling, like the ground
        (called only when the ceiling is enabled)."""
        ceiling = self.environment.ceiling
        self.at_ceiling = False
        rest_z = ceiling.height + self.vehicle.top_height
        state = self.state_vector
        if state[2] > rest_z:
            return
        self.at_ceiling = True
        impact = -state[5]  # upward (negative NED z) speed
        if impact > self.max_ceiling_impact_speed:
            self.max_ceiling_impact_speed = float(impact)
        state[2] = rest_z
        state[VELOCITY] = 0.0  # held against the ceiling while the net force pushes up
        state[ANGULAR_VELOCITY] = 0.0

    def divergence(self) -> str | None:
        """Why the simulation cannot go on (NaN state, beyond physical bounds, crash), or None."""
        s = self.state_vector.tolist()
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
