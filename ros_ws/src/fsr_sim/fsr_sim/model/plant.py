"""The true plant: rigid body + rotors (with ground/ceiling effect, and their lag) + disturbances + aerodynamics
(docs/model.md §3.4) + ground contact.

A checked shell around the compiled core (:mod:`fsr_sim.core.plant`): the constructor checks its arguments and
packs them once (:class:`~fsr_sim.core.plant.PlantParams`); every method calls the core. Commands are held
constant over a step (zero-order hold) while the state-dependent parts (rotor speeds and tilts lagging their
commands, thrust ratios near surfaces, aerodynamics, time-varying disturbances) are evaluated at every RK4
stage. Two actuation modes:

* ``rotors``: rotor speeds ``w_i`` [rad/s] (clamped to the vehicle's limits, saturation recorded) and, for
  a tilting vehicle, tilt angles ``alpha_i`` [rad] (clamped to +-tilt_angle_max), applied instantly, or through
  the vehicle's first-order lags (the speeds and tilts integrated within the RK4 stages, docs/model.md);
  ``f_b = sum c_f r_i |w_i| w_i z_i``, ``tau_b = sum |w_i| w_i (c_f r_i p_i x z_i - k_i c_m z_i)`` with the
  thrust ratio ``r_i`` of :mod:`fsr_sim.model.environment` (drag torque is not scaled).
* ``wrench``: the commanded body wrench ``f_b`` and ``tau_b`` directly (the report's exercises 3 and 4 use
  ``f_b = -u_T e3``) - or, with a rotor time constant, each component lagging its command by that first-order
  lag (the rotors' speed lag linearised about hover); surfaces then only act through contact.

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

from fsr_sim.contract import body_force_of_thrust, thrust_of
from fsr_sim.core import imu as core_imu
from fsr_sim.core import plant as core
from fsr_sim.core import rotors as core_rotors
from fsr_sim.core.aerodynamics import AeroParams
from fsr_sim.core.rigid_body import STATE_SIZE
from fsr_sim.core.sensors import new_sensor_memory
from fsr_sim.core.surfaces import has_thrust_effects
from fsr_sim.model.checks import InvalidValueError, finite_array
from fsr_sim.model.disturbances import DisturbanceProfile, pack_disturbances
from fsr_sim.model.environment import Environment, pack_surfaces, thrust_ratio_log
from fsr_sim.model.rigid_body import (
    ANGULAR_VELOCITY,
    POSITION,
    QUATERNION,
    VELOCITY,
    RigidBodyState,
    pack_state,
)
from fsr_sim.model.rotors import SaturationReport, rotor_axes, rotor_columns, tilt_basis
from fsr_sim.model.sensors import ImuModel, OdometryNoise, pack_sensors
from fsr_sim.model.so3 import rotation_from_euler_zyx, rotation_from_quaternion
from fsr_sim.model.turbulence import DrydenTurbulence, pack_turbulence
from fsr_sim.model.vehicle import ROTOR_AERODYNAMICS, Vehicle

MAX_SPEED = core.MAX_SPEED
MAX_SPIN = core.MAX_SPIN
DEFAULT_CRASH_SPEED = 3.0  # m/s downward at ground contact
ACTUATIONS = ("rotors", "wrench")


def pack_plant(vehicle: Vehicle, dt: float, substeps: int, actuation: str, environment: Environment,
               disturbances: Sequence[DisturbanceProfile], crash_speed: float,
               odometry_noise: OdometryNoise | None = None,
               turbulence: Sequence[DrydenTurbulence] = (), imu: ImuModel | None = None) -> core.PlantParams:
    """The core's :class:`~fsr_sim.core.plant.PlantParams` of a checked vehicle and environment."""
    n = vehicle.rotor_count
    if vehicle.has_servos:
        vertical, lateral = (rotor_columns(vehicle, axes) for axes in tilt_basis(vehicle))
    else:
        vertical, lateral = rotor_columns(vehicle, rotor_axes(vehicle)), np.zeros((n, core_rotors.COLUMN_WIDTH))
    table, knots = pack_disturbances(list(disturbances))
    mass, inertia, inertia_inv = pack_mass_properties(vehicle)
    return core.PlantParams(
        mass=mass, inertia=inertia, inertia_inv=inertia_inv, dt=float(dt),
        substeps=int(substeps), period=float(dt) * int(substeps), wrench_actuation=actuation == "wrench",
        speed_min=float(vehicle.rotor_speed_min), speed_max=float(vehicle.rotor_speed_max),
        tilting=vehicle.has_servos, tilt_max=float(vehicle.tilt_angle_max), vertical_columns=vertical,
        lateral_columns=lateral, surfaces=pack_surfaces(environment, vehicle), disturbances=table,
        disturbance_knots=knots, crash_speed=float(crash_speed),
        sensors=pack_sensors(odometry_noise, imu, float(dt) * int(substeps)),
        rotor_lag=actuator_lags(vehicle, actuation)[0],
        speed_decay=lag_decay(dt, vehicle.rotor_time_constant),
        speed_mean=lag_step_mean(dt, vehicle.rotor_time_constant),
        speed_stages=lag_stages(dt, vehicle.rotor_time_constant),
        wrench_lag=actuation == "wrench" and vehicle.rotor_time_constant > 0.0,
        tilt_lag=actuator_lags(vehicle, actuation)[1],
        tilt_decay=lag_decay(dt, vehicle.tilt_time_constant),
        tilt_step_max=float(vehicle.tilt_rate_max * dt),
        tilt_stages=np.column_stack((lag_stages(dt, vehicle.tilt_time_constant)[:, 0],
                                     STAGE_TIMES * dt * vehicle.tilt_rate_max if math.isfinite(vehicle.tilt_rate_max)
                                     else np.full(3, np.inf))),
        turbulence=pack_turbulence(turbulence, dt),
        aero=pack_aerodynamics(vehicle, actuation),
    )


def pack_mass_properties(vehicle: Vehicle) -> tuple[float, np.ndarray, np.ndarray]:
    """``(m, I, I^-1)`` of a vehicle as the core reads them: mass [kg], inertia and its inverse (3, 3) [kg m^2]."""
    inertia = np.ascontiguousarray(vehicle.inertia, dtype=float)
    return float(vehicle.mass), inertia, np.linalg.inv(inertia)


STAGE_TIMES = np.array((0.0, 0.5, 1.0))  # RK4's stage times in the step, in steps (the middle two share dt/2)


def lag_decay(span: float, time_constant: float) -> float:
    """``exp(-span / tau)`` of a first-order lag over ``span`` [s] (0 without a lag, ``tau = 0``)."""
    return math.exp(-span / time_constant) if time_constant > 0.0 else 0.0


def lag_step_mean(dt: float, time_constant: float) -> float:
    """``(tau / dt) (1 - exp(-dt / tau))``: the mean of ``exp(-s / tau)`` over an RK4 step (0 without a lag)."""
    return -math.expm1(-dt / time_constant) * time_constant / dt if time_constant > 0.0 else 0.0


def lag_stages(dt: float, time_constant: float) -> np.ndarray:
    """(3, 2): at RK4's stage times ``s = 0, dt/2, dt``, ``kappa(tau) exp(-s / tau)`` and ``kappa(tau / 2)
    exp(-2 s / tau)``, with ``kappa(tau)`` the exact mean of ``exp(-s / tau)`` over the step divided by its
    Simpson mean (:func:`fsr_sim.core.plant.actuators_at`; zeros without a lag)."""
    out = np.zeros((3, 2))
    if time_constant > 0.0:
        for column, tau in enumerate((time_constant, 0.5 * time_constant)):
            decay = np.exp(-STAGE_TIMES * dt / tau)
            simpson = (decay[0] + 4.0 * decay[1] + decay[2]) / 6.0
            out[:, column] = lag_step_mean(dt, tau) / simpson * decay
    return out


def pack_aerodynamics(vehicle: Vehicle, actuation: str) -> AeroParams:
    """The core's :class:`~fsr_sim.core.aerodynamics.AeroParams` of a vehicle; in wrench actuation the rotors are
    not modelled, so only the parasitic drag acts."""
    rotor_terms = [getattr(vehicle, name) for name in ROTOR_AERODYNAMICS]
    return AeroParams(
        parasitic=bool(np.any(vehicle.drag_coefficients > 0.0)),
        rotor=actuation == "rotors" and any(value > 0.0 for value in rotor_terms),
        drag=np.ascontiguousarray(vehicle.drag_coefficients, dtype=float), rotor_drag=float(rotor_terms[0]),
        inflow=float(rotor_terms[1]), lift=float(rotor_terms[2]), flapping=float(rotor_terms[3]),
        positions=np.ascontiguousarray(vehicle.positions, dtype=float), thrust_coefficient=float(vehicle.c_f))


def actuator_lags(vehicle: Vehicle, actuation: str) -> tuple[bool, bool]:
    """(the rotor speeds lag, the tilts lag) their commands: with rotor actuation, a rotor time constant; rotors
    on servos with a time constant or a rate limit."""
    rotors = actuation == "rotors"
    servo_lag = vehicle.tilt_time_constant > 0.0 or math.isfinite(vehicle.tilt_rate_max)
    return rotors and vehicle.rotor_time_constant > 0.0, rotors and vehicle.has_servos and servo_lag


def has_actuator_dynamics(params: core.PlantParams) -> bool:
    """Whether the rotors' speeds or tilts lag their commands (then ``rotor_state`` is published)."""
    return params.rotor_lag or params.tilt_lag


def new_plant_state(params: core.PlantParams, state_vector: np.ndarray) -> core.PlantState:
    """A :class:`~fsr_sim.core.plant.PlantState` at rest in ``state_vector`` (13,), no command yet."""
    n = params.vertical_columns.shape[0]
    state = core.PlantState(
        x=np.array(state_vector, dtype=float), speeds=np.zeros(n), speed_command=np.full(n, np.nan),
        tilt_command=np.full(n, np.nan), speed_sq=np.zeros(n), tilts=np.zeros(n),
        wrench_command=np.zeros(6), columns=params.vertical_columns.copy(),
        body_wrench=np.zeros(6), ratios=np.ones(n), actuator_start=np.zeros(max(2 * n, 6)),
        work=np.zeros((5, STATE_SIZE)),
        status=core.new_plant_status(), saturation=np.zeros(core_rotors.saturation_size(n)),
        gust_states=params.turbulence.initial_states.copy(), gusts=params.turbulence.initial_gusts.copy(),
        sensor_memory=new_sensor_memory(params.sensors),
    )
    core_rotors.reset_saturation(state.saturation)
    if params.tilting:
        core_rotors.tilted_columns(params.vertical_columns, params.lateral_columns, state.tilts, state.columns)
    core.update_actuator_wrench(params, state)
    return state


def divergence_reason(code: int, params: core.PlantParams, state: core.PlantState) -> str | None:
    """The message of a :func:`fsr_sim.core.plant.divergence` code (None: the flight goes on)."""
    status = state.status[0]
    if code == core.NOT_FINITE:
        return "state is not finite (NaN or inf)"
    if code == core.TOO_FAST:
        speed = math.sqrt(sum(v * v for v in state.x[VELOCITY].tolist()))
        return f"speed {speed:.1f} m/s exceeds {MAX_SPEED} m/s"
    if code == core.SPINNING:
        spin = math.sqrt(sum(w * w for w in state.x[ANGULAR_VELOCITY].tolist()))
        return f"angular speed {spin:.1f} rad/s exceeds {MAX_SPIN} rad/s"
    if code == core.GROUND_CRASH:
        return (f"crashed into the ground at {status.max_impact:.2f} m/s "
                f"(limit {params.crash_speed} m/s)")
    if code == core.CEILING_CRASH:
        return (f"crashed into the ceiling at {status.max_ceiling_impact:.2f} m/s "
                f"(limit {params.crash_speed} m/s)")
    return None


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
    odometry_noise : OdometryNoise, optional
        The sensor stage between the true state and the published ``odom`` (:mod:`fsr_sim.model.sensors`;
        default: none, ``odom`` is the true state).
    imu : ImuModel, optional
        An IMU (:mod:`fsr_sim.model.sensors`; default: none, ``imu`` is not published).

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
        odometry_noise: OdometryNoise | None = None,
        turbulence: Sequence[DrydenTurbulence] = (),
        imu: ImuModel | None = None,
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
        self.dt = float(dt)
        self.substeps = int(substeps)
        self.actuation = actuation
        self.environment = Environment() if environment is None else environment
        self.disturbances = list(disturbances)
        self.crash_speed = crash_speed
        self.odometry_noise = odometry_noise or OdometryNoise()
        self.turbulence = list(turbulence)
        self.imu = imu or ImuModel()
        self.params = pack_plant(vehicle, dt, substeps, actuation, self.environment, self.disturbances, crash_speed,
                                 self.odometry_noise, self.turbulence, self.imu)
        self.core_state = new_plant_state(self.params, pack_state(
            finite_array(position, (3,), "position"), rotation, finite_array(velocity, (3,), "velocity"),
            finite_array(angular_velocity, (3,), "angular_velocity"),
        ))
        self.saturation = SaturationReport(record=self.core_state.saturation)

    # ----- time -------------------------------------------------------------------------------------
    @property
    def period(self) -> float:
        return self.params.period

    @property
    def step_index(self) -> int:
        """Control periods stepped so far (the state's time is ``step_index * period``)."""
        return int(self.core_state.status[0].step_index)

    @step_index.setter
    def step_index(self, value: int) -> None:
        self.core_state.status[0].step_index = int(value)

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
    def state_vector(self) -> np.ndarray:
        """The 13 numbers of the state (:mod:`fsr_sim.model.rigid_body` layout; the core's array, not a copy)."""
        return self.core_state.x

    @property
    def state(self) -> RigidBodyState:
        """A snapshot of the current state: ``.position``, ``.velocity`` (world), ``.rotation``, ``.quaternion``,
        ``.angular_velocity`` (body), ``.vector`` (the 13 numbers)."""
        return RigidBodyState(self.core_state.x.copy())

    @property
    def position(self) -> np.ndarray:
        """Position [m], world NED (a view of the state vector)."""
        return self.core_state.x[POSITION]

    @property
    def velocity(self) -> np.ndarray:
        """Velocity [m/s], world NED (a view of the state vector)."""
        return self.core_state.x[VELOCITY]

    @property
    def rotation(self) -> np.ndarray:
        """``R`` body FRD -> world NED."""
        return rotation_from_quaternion(self.core_state.x[QUATERNION])

    @property
    def quaternion(self) -> np.ndarray:
        """Unit quaternion ``[x, y, z, w]`` body -> world (a view of the state vector)."""
        return self.core_state.x[QUATERNION]

    @property
    def angular_velocity(self) -> np.ndarray:
        """Angular velocity [rad/s], body FRD (a view of the state vector)."""
        return self.core_state.x[ANGULAR_VELOCITY]

    @property
    def rotor_speeds(self) -> np.ndarray:
        """The applied (clamped) rotor speeds [rad/s]."""
        return self.core_state.speeds.copy()

    @property
    def tilt_angles(self) -> np.ndarray | None:
        """The applied tilt angles [rad] (None for fixed rotors)."""
        return self.core_state.tilts.copy() if self.vehicle.has_servos else None

    @property
    def force_command(self) -> np.ndarray:
        """The commanded body force [N] (wrench actuation)."""
        return self.core_state.wrench_command[:3].copy()

    @property
    def torque_command(self) -> np.ndarray:
        """The commanded body torque [N m] (wrench actuation)."""
        return self.core_state.wrench_command[3:].copy()

    @property
    def applied_wrench(self) -> np.ndarray:
        """The body wrench the plant applies now, force [N] and torque [N m] FRD (wrench actuation): the command,
        or with a rotor time constant the wrench lagging it."""
        return self.core_state.body_wrench.copy()

    # ----- contact and surfaces ---------------------------------------------------------------------
    @property
    def _status(self) -> np.record:
        return self.core_state.status[0]

    @property
    def in_contact(self) -> bool:
        """Whether the ground held the vehicle at the end of the last RK4 step."""
        return bool(self._status.in_contact)

    @property
    def at_ceiling(self) -> bool:
        return bool(self._status.at_ceiling)

    @property
    def max_impact_speed(self) -> float:
        """Fastest downward speed at ground contact so far [m/s]."""
        return float(self._status.max_impact)

    @property
    def max_ceiling_impact_speed(self) -> float:
        """Fastest upward speed at ceiling contact so far [m/s]."""
        return float(self._status.max_ceiling_impact)

    @property
    def ground_cap_steps(self) -> int:
        """Control steps in which a rotor's ground-effect ratio was held at ``max_ratio``."""
        return int(self._status.ground_cap_steps)

    @property
    def ceiling_cap_steps(self) -> int:
        return int(self._status.ceiling_cap_steps)

    # ----- commands ---------------------------------------------------------------------------------
    def set_rotor_command(self, speeds: ArrayLike, tilts: ArrayLike | None = None) -> bool:
        """Command rotor speeds [rad/s], shape (n,) (and tilts [rad], shape (n,), for a tilting vehicle), held
        until the next command: the rotors take them at once, or follow them through the vehicle's first-order
        lags. Speeds are clamped to the vehicle's limits; returns True if anything saturated (recorded in
        :attr:`saturation`).

        Raises
        ------
        ValueError
            Speeds or tilts of another shape than (n,), or holding NaN or inf (tilts are ignored for a vehicle
            without servos).
        """
        n = self.vehicle.rotor_count
        speeds = np.ascontiguousarray(finite_array(speeds, (n,), "speeds"))
        with_tilts = tilts is not None
        tilt_array = np.ascontiguousarray(finite_array(tilts, (n,), "tilts")) if with_tilts else speeds
        return bool(core.set_rotor_command(self.params, self.core_state, speeds, tilt_array, with_tilts))

    def set_wrench(self, force_body: ArrayLike, torque_body: ArrayLike) -> None:
        """Command a body wrench (``actuation: wrench``): force [N] and torque [N m], body FRD, held until the
        next command; it acts at once, or lagging by the rotor time constant (module docstring). The report's
        thrust ``u_T`` is ``force_body = [0, 0, -u_T]``."""
        if self.actuation != "wrench":
            raise RuntimeError("set_wrench needs actuation='wrench' (this plant takes rotor speeds)")
        wrench = np.concatenate((finite_array(force_body, (3,), "force_body"),
                                 finite_array(torque_body, (3,), "torque_body")))
        core.set_wrench_command(self.params, self.core_state, wrench)

    def set_wrench_command(self, thrust: float, torque_body: ArrayLike) -> None:
        """Apply ``u_T`` [N] along ``-z_b`` and ``tau_b`` [N m]: :meth:`set_wrench` with ``f_b = -u_T e3``."""
        self.set_wrench(body_force_of_thrust(thrust), torque_body)

    @property
    def thrust(self) -> float:
        """``u_T = -f_z`` [N] of the commanded body wrench (``actuation: wrench``)."""
        return thrust_of(float(self.core_state.wrench_command[2]))

    def cut_thrust(self) -> None:
        """Failsafe: all rotors commanded to stop / zero wrench (with a rotor lag they spin down)."""
        core.cut_thrust(self.params, self.core_state)

    # ----- dynamics ---------------------------------------------------------------------------------
    def external_wrench(self) -> tuple[np.ndarray, np.ndarray]:
        """True external wrench now: (force world NED [N], torque body FRD [N m]): everything beyond the rotors'
        ``c_f w^2``, ``c_m w^2`` - the disturbances and the aerodynamics (``wrench_truth``)."""
        force, torque = core.plant_external_wrench(self.params, self.core_state)
        return np.array(force), np.array(torque)

    def specific_force(self) -> np.ndarray:
        """What an IMU at the centre of mass senses now: ``R^T (p_ddot - g e3)`` [m/s^2], body FRD, with every
        force acting on the current state (:mod:`fsr_sim.core.imu`)."""
        return np.array(core_imu.true_specific_force(self.params, self.core_state))

    def thrust_ratios(self) -> np.ndarray:
        """Ground/ceiling thrust ratio of each rotor at the current pose (1 away from surfaces)."""
        if not has_thrust_effects(self.params.surfaces):
            return np.ones(self.vehicle.rotor_count)
        return thrust_ratio_log(self.params.surfaces, self.position[2:3], self.rotation[None])[0]

    def step(self) -> None:
        """Advance one period: ``physics_substeps`` RK4 steps of ``physics_dt``, with ground contact."""
        core.plant_step(self.params, self.core_state)

    def divergence(self) -> str | None:
        """Why the simulation cannot go on (NaN state, beyond physical bounds, crash), or None."""
        return divergence_reason(core.divergence(self.params, self.core_state), self.params, self.core_state)
