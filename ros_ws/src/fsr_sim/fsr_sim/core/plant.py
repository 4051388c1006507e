"""The true plant per step (compiled core): rigid body + rotors (with ground/ceiling effect) + disturbances +
aerodynamics (:mod:`fsr_sim.core.aerodynamics`, in the wind of :mod:`fsr_sim.core.turbulence`) + contact.

Commands are held over a control period (zero-order hold) while everything that moves within it (the actuators
lagging their commands, thrust ratios near surfaces, time-varying disturbances, the aerodynamics) is evaluated
at every RK4 stage. Two actuations:

* rotors: speeds ``w_i`` [rad/s] clamped to the vehicle's limits (saturation recorded) and, for a tilting
  vehicle, tilts ``alpha_i`` [rad] clamped to ``+-tilt_max``, applied at once - or, with actuator dynamics
  (:func:`actuators_at`), approached by a first-order lag; ``f_b = sum c_f r_i u_w,i z_i``,
  ``tau_b = sum u_w,i (c_f r_i p_i x z_i - k_i c_m z_i)`` with the thrust ratio ``r_i`` of
  :mod:`fsr_sim.core.surfaces` (drag torque is not scaled);
* wrench: the commanded body wrench directly - or, with a rotor time constant, the wrench lagging it by the same
  first-order lag per component (the rotors' speed lag linearised about hover has that time constant); surfaces
  then only act through contact.

Ground and ceiling are solid: after each RK4 step a vehicle whose feet are below the ground (top above the
ceiling) is put back on it with zero velocity and angular velocity (held: no bounce, no sliding); the fastest
impact is kept, and one faster than ``crash_speed`` is a divergence (:func:`divergence`).

:class:`PlantParams` is packed once from the checked ``Vehicle``/scenario objects
(:class:`fsr_sim.model.plant.Plant`); :class:`PlantState` holds everything that changes.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_sim.core.aerodynamics import AeroParams, aerodynamic_wrench, has_aerodynamics
from fsr_sim.core.disturbances import external_wrench
from fsr_sim.core.jit import jit, jit_inline, zeroed_record
from fsr_sim.core.rigid_body import (
    ANGULAR_VELOCITY_X,
    ANGULAR_VELOCITY_Y,
    ANGULAR_VELOCITY_Z,
    POSITION_Z,
    VELOCITY_X,
    VELOCITY_Y,
    VELOCITY_Z,
    rigid_body_rates,
    rk4_combine,
    stage_state,
    state_angular_velocity,
    state_rotation,
    state_velocity,
)
from fsr_sim.core.rotors import clamped_speed, record_saturation, rotor_wrench, scaled_rotor_wrench, tilted_columns
from fsr_sim.core.sensors import SensorParams
from fsr_sim.core.so3 import Mat3, mat_t_vec3, mat_vec3
from fsr_sim.core.surfaces import Surfaces, ceiling_rest_z, ground_rest_z, has_thrust_effects, thrust_ratios
from fsr_sim.core.turbulence import TurbulenceParams, advance_gusts, wind_velocity

MAX_SPEED = 100.0  # m/s: beyond this the simulation is considered diverged
MAX_SPIN = 200.0  # rad/s

# divergence() codes (the message is made by fsr_sim.model.plant.divergence_reason)
RUNNING, NOT_FINITE, TOO_FAST, SPINNING, GROUND_CRASH, CEILING_CRASH = 0, 1, 2, 3, 4, 5

PLANT_STATUS = np.dtype([
    ("step_index", np.int64),  # control periods stepped so far (the state's time is step_index * period)
    ("in_contact", np.bool_),  # the ground held the vehicle at the end of the last RK4 step
    ("at_ceiling", np.bool_),  # the ceiling held it then
    ("max_impact", np.float64),  # fastest downward speed at ground contact so far [m/s]
    ("max_ceiling_impact", np.float64),  # fastest upward speed at ceiling contact so far [m/s]
    ("ground_cap_steps", np.int64),  # control periods in which a ground-effect ratio was held at max_ratio
    ("ceiling_cap_steps", np.int64),  # the same for the ceiling effect
    ("ground_capped", np.bool_),  # a ground-effect ratio was held at max_ratio in the current period
    ("ceiling_capped", np.bool_),
    ("wrench_commanded", np.bool_),  # a wrench command came (the lagging wrench starts at the first one)
], align=True)
"""The fields of ``PlantState.status``, a record read and written in place as ``status[0].step_index``."""


def new_plant_status() -> np.ndarray:
    """A zeroed :data:`PLANT_STATUS` record (a 1-element record array: ``status[0].field`` reads and writes the
    fields compiled and under CPython alike)."""
    return zeroed_record(PLANT_STATUS)


class PlantParams(NamedTuple):
    """Everything about the true plant that does not change during a flight (SI units, frames as above)."""

    mass: float
    inertia: np.ndarray  # (3, 3)
    inertia_inv: np.ndarray  # (3, 3)
    dt: float  # RK4 step [s]
    substeps: int  # RK4 steps per control period
    period: float  # dt * substeps [s]
    wrench_actuation: bool
    speed_min: float  # [rad/s]
    speed_max: float
    tilting: bool
    tilt_max: float  # [rad]
    vertical_columns: np.ndarray  # (n, 9) rotor columns at tilt 0 (fixed rotors: their only columns)
    lateral_columns: np.ndarray  # (n, 9) rotor columns at tilt +pi/2 (zeros for fixed rotors)
    surfaces: Surfaces
    disturbances: np.ndarray  # (m, WIDTH) rows of fsr_sim.core.disturbances
    disturbance_knots: np.ndarray  # (k, KNOT_WIDTH)
    crash_speed: float  # [m/s]
    sensors: SensorParams  # the stage between the true state and odom (fsr_sim.core.sensors)
    rotor_lag: bool  # rotor actuation: speeds follow their command through a first-order lag (actuators_at)
    speed_decay: float  # exp(-dt / tau_w) of the rotor time constant tau_w
    speed_mean: float  # (tau_w / dt) (1 - exp(-dt / tau_w)): a step's mean of exp(-s / tau_w)
    speed_stages: np.ndarray  # (3, 2) at the RK4 stages s = 0, dt/2, dt: the lag's factors (actuators_at)
    wrench_lag: bool  # wrench actuation: the applied wrench follows its command through that lag
    tilt_lag: bool  # rotor actuation, on servos: tilts follow their command through a lag and/or a rate limit
    tilt_decay: float  # exp(-dt / tau_alpha) (0: no lag)
    tilt_step_max: float  # [rad] per RK4 step: tilt_rate_max dt (inf: no rate limit)
    tilt_stages: np.ndarray  # (3, 2) at the RK4 stages: the lag's factor and the rate limit (actuators_at)
    turbulence: TurbulenceParams  # Dryden gusts: the wind (fsr_sim.core.turbulence)
    aero: AeroParams  # parasitic drag and the rotors' aerodynamics (fsr_sim.core.aerodynamics)


class PlantState(NamedTuple):
    """What changes (float64 arrays, modified in place)."""

    x: np.ndarray  # (13,) rigid-body state, fsr_sim.core.rigid_body layout
    speeds: np.ndarray  # (n,) applied rotor speeds [rad/s] (clamped): the rotors' actual speeds (of the RK4 stage)
    speed_command: np.ndarray  # (n,) commanded speeds, clamped [rad/s] (NaN until the first command)
    tilt_command: np.ndarray  # (n,) commanded tilts, clamped [rad] (NaN until the first command)
    speed_sq: np.ndarray  # (n,) |w| w [(rad/s)^2]
    tilts: np.ndarray  # (n,) applied tilt angles [rad] (of the RK4 stage)
    wrench_command: np.ndarray  # (6,) commanded body force [N] and torque [N m] (wrench actuation)
    columns: np.ndarray  # (n, 9) the rotors' columns at the applied tilts
    body_wrench: np.ndarray  # (6,) actuator wrench away from surfaces (wrench actuation: the applied wrench)
    ratios: np.ndarray  # (n,) scratch: thrust ratios of the current stage
    actuator_start: np.ndarray  # (max(2n, 6),) scratch: speeds and tilts (or the wrench) at the RK4 step's start
    work: np.ndarray  # (5, 13) scratch: RK4 rates k1..k4 and the stage state
    status: np.ndarray  # (1,) PLANT_STATUS record: step index, contact, impacts, surface-cap counts
    saturation: np.ndarray  # rotor-speed saturation record (fsr_sim.core.rotors)
    gust_states: np.ndarray  # (m, 3, 2) turbulence filter states
    gusts: np.ndarray  # (m, 3) gust velocities [m/s] world NED, held over the RK4 step
    sensor_memory: np.ndarray  # the sensor stage's bias, held measurement and delay line (fsr_sim.core.sensors)


@jit_inline
def plant_time(params: PlantParams, state: PlantState) -> float:
    """Simulated time [s] of the current state."""
    return state.status[0].step_index * params.period


@jit_inline
def update_actuator_wrench(params: PlantParams, state: PlantState) -> None:
    """Cache the actuator wrench of the held command away from surfaces (constant over an RK4 step); a lagging
    wrench (``wrench_lag``) is the plant's state, moved by the RK4 steps only (:func:`actuators_at`)."""
    if params.wrench_actuation:
        if params.wrench_lag:
            return
        for i in range(6):  # element by element: an array copy would need numba's allocator (core/jit.py)
            state.body_wrench[i] = state.wrench_command[i]
    else:
        rotor_wrench(state.columns, state.speed_sq, state.body_wrench)


@jit_inline
def set_rotor_command(params: PlantParams, state: PlantState, speeds, tilts, with_tilts: bool) -> bool:  # noqa: ANN001
    """Hold rotor speeds (n,) [rad/s] (and, ``with_tilts`` on a tilting vehicle, tilts (n,) [rad]) until the
    next command; speeds are clamped to the limits. True if anything saturated (recorded).

    With actuator dynamics the command is what the rotors (servos) approach (:func:`actuators_at`); the
    first command is also their state at the start (the flight starts with the rotors spun up)."""
    n = speeds.shape[0]
    excess = state.ratios  # scratch until the next stage
    first = not state.speed_command[0] == state.speed_command[0]  # NaN: never commanded
    for i in range(n):
        clamped, excess[i] = clamped_speed(abs(speeds[i]) * speeds[i], params.speed_min, params.speed_max)
        state.speed_command[i] = clamped
        if first or not params.rotor_lag:
            state.speeds[i] = clamped
            state.speed_sq[i] = abs(clamped) * clamped
    saturated = record_saturation(state.saturation, plant_time(params, state), excess)
    if params.tilting and with_tilts:
        first_tilt = not state.tilt_command[0] == state.tilt_command[0]
        limit = params.tilt_max
        for i in range(n):
            tilt = tilts[i]
            if tilt < -limit:
                tilt = -limit
            elif tilt > limit:
                tilt = limit
            state.tilt_command[i] = tilt
            if first_tilt or not params.tilt_lag:
                state.tilts[i] = tilt
        tilted_columns(params.vertical_columns, params.lateral_columns, state.tilts, state.columns)
    update_actuator_wrench(params, state)
    return saturated


@jit_inline
def lagged(value: float, target: float, decay: float) -> float:
    """A first-order lag towards a held ``target`` after a time ``s``: ``target + (value - target) decay``
    (``decay = exp(-s / tau)``)."""
    return target + (value - target) * decay


@jit_inline
def period_mean_lagged(value: float, target: float, decay: float, mean: float, steps: int) -> float:
    """Mean over a control period of ``steps`` RK4 steps of a lagging input, from ``value`` at the period's start
    towards the held ``target``: each step applies ``target + (value - target) mean`` (``mean = (tau / dt)
    (1 - exp(-dt / tau))``, the exact mean of the exponential: :func:`actuators_at`), then moves it by
    ``decay = exp(-dt / tau)``."""
    total = 0.0
    for _ in range(steps):
        total += lagged(value, target, mean)
        value = lagged(value, target, decay)
    return total / steps


@jit_inline
def hold_actuator_start(params: PlantParams, state: PlantState) -> None:
    """Keep the lagging actuators' state at the start of an RK4 step (``actuator_start``): the applied wrench
    (wrench actuation), else the rotor speeds then the tilts."""
    start = state.actuator_start
    if params.wrench_lag:
        for i in range(6):
            start[i] = state.body_wrench[i]
        return
    n = state.speeds.shape[0]
    for i in range(n):
        start[i] = state.speeds[i]
        start[n + i] = state.tilts[i]


@jit_inline
def _tilts_from_start(params: PlantParams, state: PlantState, decay: float, step_max: float) -> None:
    """Tilts moved from their start towards the command by the lag (``decay``) and at most ``step_max`` [rad]."""
    if not state.tilt_command[0] == state.tilt_command[0]:  # never commanded: they stay
        return
    n = state.tilts.shape[0]
    start = state.actuator_start
    for i in range(n):
        current = start[n + i]
        change = (state.tilt_command[i] - current) * (1.0 - decay)
        if change > step_max:
            change = step_max
        elif change < -step_max:
            change = -step_max
        state.tilts[i] = current + change
    tilted_columns(params.vertical_columns, params.lateral_columns, state.tilts, state.columns)


@jit_inline
def actuators_at(params: PlantParams, state: PlantState, stage: int) -> None:
    """The lagging actuators at an RK4 stage (``stage`` 0, 1, 2: ``s = 0, dt/2, dt`` into the step) from their
    start (:func:`hold_actuator_start`) towards the held command (docs/model.md §3.2, *Actuator dynamics*).

    A rotor's speed lags its command ``w_c`` as ``w' = (w_c - w) / tau_w``, so ``w(s) = w_c + (w_0 - w_c)
    exp(-s / tau_w)`` and ``w^2`` holds ``exp(-s / tau_w)`` and ``exp(-2 s / tau_w)``. RK4 weighs its stages by
    Simpson's rule, which overweights a transient the step does not resolve (``tau_w < dt``: the old speed for
    ``dt / 6`` instead of ``tau_w``), so each transient is scaled by ``kappa(tau) = (exact mean of exp(-s / tau)
    over the step) / (its Simpson mean)``: ``speed_stages[stage] = (kappa(tau_w) exp(-s / tau_w),
    kappa(tau_w / 2) exp(-2 s / tau_w))``. The stages then apply the exact step mean; ``kappa = 1 -
    O((dt / tau)^4)`` keeps RK4's order for a resolved lag, and ``kappa -> 6 tau / dt`` makes the lag vanish as
    ``tau -> 0``. A tilt, the same with ``tau_alpha`` (``tilt_stages[stage, 0]``), its change then limited to
    ``tilt_rate_max s`` (``tilt_stages[stage, 1]``); in wrench actuation with a rotor time constant, each
    component of the applied wrench as a speed. :func:`actuators_after_step` sets their exact values at
    ``dt``."""
    start = state.actuator_start
    linear = params.speed_stages[stage, 0]
    if params.wrench_lag:
        for i in range(6):
            state.body_wrench[i] = lagged(start[i], state.wrench_command[i], linear)
        return
    if params.rotor_lag:
        square = params.speed_stages[stage, 1]
        for i in range(state.speeds.shape[0]):
            target = state.speed_command[i]
            gap = start[i] - target
            state.speeds[i] = target + gap * linear
            state.speed_sq[i] = target * target + (2.0 * target * gap) * linear + (gap * gap) * square  # w >= 0
    if params.tilt_lag:
        _tilts_from_start(params, state, params.tilt_stages[stage, 0], params.tilt_stages[stage, 1])
    update_actuator_wrench(params, state)


@jit_inline
def actuators_after_step(params: PlantParams, state: PlantState) -> None:
    """The lagging actuators at the end of the RK4 step, exactly (the lag solved over ``dt`` from their start,
    the tilts' change then limited to ``tilt_rate_max dt``): ``w <- w_c + (w_0 - w_c) exp(-dt / tau_w)``."""
    start = state.actuator_start
    if params.wrench_lag:
        for i in range(6):
            state.body_wrench[i] = lagged(start[i], state.wrench_command[i], params.speed_decay)
        return
    if params.rotor_lag:
        for i in range(state.speeds.shape[0]):
            speed = lagged(start[i], state.speed_command[i], params.speed_decay)
            state.speeds[i] = speed
            state.speed_sq[i] = abs(speed) * speed
    if params.tilt_lag:
        _tilts_from_start(params, state, params.tilt_decay, params.tilt_step_max)
    update_actuator_wrench(params, state)


@jit_inline
def advance_actuators(params: PlantParams, state: PlantState) -> None:
    """The lagging actuators one RK4 step ``dt`` on (where the RK4 step leaves them)."""
    hold_actuator_start(params, state)
    actuators_after_step(params, state)


@jit_inline
def set_wrench_command(params: PlantParams, state: PlantState, wrench) -> None:  # noqa: ANN001
    """Hold a body wrench (6,): force [N] and torque [N m], FRD (wrench actuation). With a lag
    (``wrench_lag``) it is what the applied wrench approaches (:func:`actuators_at`); the first command is
    also the applied wrench at the start (as the rotors start spun up)."""
    status = state.status[0]
    first = not status.wrench_commanded
    status.wrench_commanded = True
    for i in range(6):
        state.wrench_command[i] = wrench[i]
        if first and params.wrench_lag:
            state.body_wrench[i] = wrench[i]
    update_actuator_wrench(params, state)


@jit_inline
def cut_thrust(params: PlantParams, state: PlantState) -> None:
    """Failsafe: all rotors stopped, zero wrench (tilts are kept); with a rotor lag they spin down (the wrench
    decays)."""
    state.wrench_command[:] = 0.0
    state.status[0].wrench_commanded = True
    state.speed_command[:] = 0.0
    if not params.rotor_lag:
        state.speeds[:] = 0.0
        state.speed_sq[:] = 0.0
    update_actuator_wrench(params, state)


@jit_inline
def stage_wrench(params: PlantParams, state: PlantState, t: float, x) -> tuple:  # noqa: ANN001
    """Force world excluding gravity [N] and torque body [N m] at an RK4 stage (time ``t``, state ``x``)."""
    rotation = state_rotation(x)
    wrench = state.body_wrench
    if not params.wrench_actuation and has_thrust_effects(params.surfaces):
        ground_capped, ceiling_capped = thrust_ratios(params.surfaces, x[POSITION_Z], rotation[2], state.ratios)
        status = state.status[0]
        if ground_capped:
            status.ground_capped = True
        if ceiling_capped:
            status.ceiling_capped = True
        (fx, fy, fz), (tx, ty, tz) = scaled_rotor_wrench(state.columns, state.speed_sq, state.ratios)
    else:
        fx, fy, fz, tx, ty, tz = wrench[0], wrench[1], wrench[2], wrench[3], wrench[4], wrench[5]
    fx, fy, fz = mat_vec3(rotation, (fx, fy, fz))
    if has_external_wrench(params):
        (ex, ey, ez), (ux, uy, uz) = external_wrench_at(params, state, t, x, rotation)
        return (fx + ex, fy + ey, fz + ez), (tx + ux, ty + uy, tz + uz)
    return (fx, fy, fz), (tx, ty, tz)


@jit_inline
def has_external_wrench(params: PlantParams) -> bool:
    """Whether anything beyond the rotors' ``c_f w^2``, ``c_m w^2`` acts: disturbances or aerodynamics."""
    return params.disturbances.shape[0] > 0 or has_aerodynamics(params.aero)


@jit_inline
def external_wrench_at(params: PlantParams, state: PlantState, t: float, x, rotation: Mat3) -> tuple:  # noqa: ANN001
    """The external wrench at time ``t`` in state ``x`` (attitude rows ``rotation``), (force world NED [N], torque
    body FRD [N m]): everything the controller's rotor model (``c_f w^2``, ``c_m w^2``) leaves out - the
    disturbances and the aerodynamics in the wind (the rotors' at their current speeds); what the plant feels
    beyond its rotors and what ``wrench_truth`` publishes."""
    force, torque = external_wrench(params.disturbances, params.disturbance_knots, t, rotation)
    if has_aerodynamics(params.aero):
        wx, wy, wz = wind_velocity(state.gusts)
        vx, vy, vz = state_velocity(x)
        air = mat_t_vec3(rotation, (vx - wx, vy - wy, vz - wz))
        (ax, ay, az), (mx, my, mz) = aerodynamic_wrench(params.aero, state.columns, state.speeds, air,
                                                         state_angular_velocity(x))
        ax, ay, az = mat_vec3(rotation, (ax, ay, az))
        force = (force[0] + ax, force[1] + ay, force[2] + az)
        torque = (torque[0] + mx, torque[1] + my, torque[2] + mz)
    return force, torque


@jit_inline
def _rates(params: PlantParams, state: PlantState, t: float, x, out) -> None:  # noqa: ANN001
    force, torque = stage_wrench(params, state, t, x)
    rigid_body_rates(x, params.mass, params.inertia, params.inertia_inv, force, torque, out)


@jit_inline
def rk4_step(params: PlantParams, state: PlantState, t: float) -> None:
    """One classical RK4 step of ``params.dt`` from time ``t`` [s] (the quaternion renormalised). Lagging
    actuators move within the step (:func:`actuators_at` at each stage: fourth-order in them too) and are left
    at their exact values of ``t + dt``."""
    x, work = state.x, state.work
    k1, k2, k3, k4, stage = work[0], work[1], work[2], work[3], work[4]
    dt = params.dt
    h = 0.5 * dt
    lagging = params.rotor_lag or params.tilt_lag or params.wrench_lag
    if lagging:
        hold_actuator_start(params, state)
        actuators_at(params, state, 0)
    _rates(params, state, t, x, k1)
    if lagging:
        actuators_at(params, state, 1)
    stage_state(x, k1, h, stage)
    _rates(params, state, t + h, stage, k2)
    stage_state(x, k2, h, stage)
    _rates(params, state, t + h, stage, k3)
    if lagging:
        actuators_at(params, state, 2)
    stage_state(x, k3, dt, stage)
    _rates(params, state, t + dt, stage, k4)
    rk4_combine(x, k1, k2, k3, k4, dt)
    if lagging:
        actuators_after_step(params, state)


@jit_inline
def _hold_at(state: PlantState, rest_z: float) -> None:
    x = state.x
    x[POSITION_Z] = rest_z
    x[VELOCITY_X] = x[VELOCITY_Y] = x[VELOCITY_Z] = 0.0  # held by the surface (no bounce, no sliding)
    x[ANGULAR_VELOCITY_X] = x[ANGULAR_VELOCITY_Y] = x[ANGULAR_VELOCITY_Z] = 0.0


@jit_inline
def apply_contact(params: PlantParams, state: PlantState) -> None:
    """Ground (and, when enabled, ceiling) contact after an RK4 step (module docstring)."""
    surfaces, x, status = params.surfaces, state.x, state.status[0]
    status.in_contact = False
    if surfaces.ground:
        rest_z = ground_rest_z(surfaces)
        if not x[POSITION_Z] < rest_z:
            status.in_contact = True
            if x[VELOCITY_Z] > status.max_impact:
                status.max_impact = x[VELOCITY_Z]
            _hold_at(state, rest_z)
    if surfaces.ceiling:
        status.at_ceiling = False
        rest_z = ceiling_rest_z(surfaces)
        if not x[POSITION_Z] > rest_z:
            status.at_ceiling = True
            if -x[VELOCITY_Z] > status.max_ceiling_impact:  # upward (negative NED z) speed
                status.max_ceiling_impact = -x[VELOCITY_Z]
            _hold_at(state, rest_z)


@jit_inline
def plant_step(params: PlantParams, state: PlantState) -> None:
    """Advance one control period: ``substeps`` RK4 steps of ``dt`` with contact; count the steps in which a
    thrust ratio was held at a surface's ``max_ratio``."""
    status = state.status[0]
    time = plant_time(params, state)
    for sub in range(params.substeps):
        rk4_step(params, state, time + sub * params.dt)
        apply_contact(params, state)
        if state.gusts.shape[0]:
            advance_gusts(params.turbulence, state.gust_states, state.gusts,
                          int(status.step_index) * params.substeps + sub)
    if status.ground_capped:
        status.ground_cap_steps += 1
    if status.ceiling_capped:
        status.ceiling_cap_steps += 1
    status.ground_capped = False
    status.ceiling_capped = False
    status.step_index += 1


@jit_inline
def divergence(params: PlantParams, state: PlantState) -> int:
    """Why the simulation cannot go on, as a code (``RUNNING``: it can): a non-finite state, a speed or spin
    beyond ``MAX_SPEED`` / ``MAX_SPIN``, an impact faster than ``crash_speed``."""
    x = state.x
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            return NOT_FINITE
    vx, vy, vz = state_velocity(x)
    if math.sqrt(vx * vx + vy * vy + vz * vz) > MAX_SPEED:
        return TOO_FAST
    wx, wy, wz = state_angular_velocity(x)
    if math.sqrt(wx * wx + wy * wy + wz * wz) > MAX_SPIN:
        return SPINNING
    status = state.status[0]
    if status.max_impact > params.crash_speed:
        return GROUND_CRASH
    if status.max_ceiling_impact > params.crash_speed:
        return CEILING_CRASH
    return RUNNING


@jit_inline
def plant_external_wrench(params: PlantParams, state: PlantState) -> tuple:
    """The true external wrench now (:func:`external_wrench_at`): (force world NED [N], torque body FRD [N m])."""
    return external_wrench_at(params, state, plant_time(params, state), state.x, state_rotation(state.x))


@jit
def applied_wrench_log(params: PlantParams, state: PlantState, commands, mean) -> None:  # noqa: ANN001
    """The body wrench a wrench-actuated plant applies for commands along a log, with the plant's own functions:
    command ``k`` (``commands`` (N, 6): force [N], torque [N m], body FRD) held by :func:`set_wrench_command` on
    the scratch ``state`` (fresh: the first command is the applied wrench), then ``substeps`` RK4 steps of its
    actuator dynamics (:func:`advance_actuators`); ``mean`` (N, 6) gets the applied wrench averaged over each
    control period's RK4 steps as they apply it (:func:`period_mean_lagged`; the command without a lag)."""
    for k in range(commands.shape[0]):
        set_wrench_command(params, state, commands[k])
        for i in range(6):
            mean[k, i] = period_mean_lagged(state.body_wrench[i], state.wrench_command[i], params.speed_decay,
                                            params.speed_mean, params.substeps) \
                if params.wrench_lag else state.body_wrench[i]
        if params.wrench_lag:
            for _ in range(params.substeps):
                advance_actuators(params, state)


@jit
def actuator_wrench_log(params: PlantParams, state: PlantState, speeds, tilts, with_tilts: bool, ratios,  # noqa: ANN001
                        force, torque) -> None:  # noqa: ANN001
    """The actuator wrench the plant applies for rotor commands along a log, with the plant's own functions:
    command ``k`` (``speeds`` (N, n) [rad/s], ``tilts`` (N, n) [rad]) held by :func:`set_rotor_command` on the
    scratch ``state``, at thrust ratios ``ratios`` (N, n); body force (N, 3) [N] and torque (N, 3) [N m]."""
    for k in range(speeds.shape[0]):
        set_rotor_command(params, state, speeds[k], tilts[k], with_tilts)
        f, t = scaled_rotor_wrench(state.columns, state.speed_sq, ratios[k])
        force[k, 0], force[k, 1], force[k, 2] = f
        torque[k, 0], torque[k, 1], torque[k, 2] = t
