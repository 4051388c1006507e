"""Incremental nonlinear dynamic inversion per step (compiled core): thrust along ``-z_b`` and a body torque, for
fixed rotors, from the vehicle's own measurements.

Its equations are in :mod:`fsr_control.controllers.indi` (the Python shell); its parameters are
:class:`IndiParams`, its memory the :data:`INDI_MEMORY` record (``LawMemory.indi``) beside the geometric law's
(``LawMemory.geometric``: the geometric law runs on it) and the IMU bridge's (``LawMemory.bridge``).

Every signal the increment uses passes through the same second-order low-pass (``IndiParams.filter``: the
exact discretisation ``x <- Phi x + Gamma u`` of ``y_ddot = w_n^2 (u - y) - 2 zeta w_n y_dot``, ``x = (y,
y_dot)``), so that they are synchronous: the IMU's angular velocity (its filtered derivative is the angular
acceleration), the IMU's specific force, and the rotors' force and torque (their measured speeds through the
nominal allocation, or without ``rotor_state`` the wrench commanded at the previous step). The increment is
then the external wrench the filtered signals imply, handed to the geometric law with reference feed-forward as
its compensation (:func:`fsr_control.core.geometric_law.geometric_law`); the rates of ``R_d`` are the
reference's alone (its jerk and snap): nothing measured is differentiated into them.

The attitude loop damps with the gyro (the IMU's angular velocity, not ``odom``'s). Where ``odom`` is a
measurement (``IndiParams.bridge``: noisy, late or slower than the control rate), the law flies on its own
estimate of the pose and velocity at the current step, the IMU bridge the geometric law of the flight profile
flies on as well (:func:`fsr_control.core.imu_bridge.bridged_state`, kept in ``LawMemory.bridge``): the IMU
integrated (strapdown) from step to step, corrected at each new ``odom`` sample towards it by the share
``BridgeParams.correction`` of the difference to the estimate of the step that sample measured
(``BridgeParams.delay`` steps back), so that the sample's delay and hold are bridged by the IMU and its noise is
averaged.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from fsr_control.core import geometric_law as geometric
from fsr_control.core.geometric_law import GeometricParams
from fsr_control.core.imu_bridge import BridgeParams, bridged_state
from fsr_control.core.law_terms import INERTIA, Compensation, matrix_at
from fsr_control.core.reference import ReferenceSample
from fsr_sim.core.jit import jit_inline
from fsr_sim.core.rotors import measured_rotor_wrench
from fsr_sim.core.so3 import Mat3, Vec3, cross3, mat_vec3

MATRICES = geometric.MATRICES  # the geometric law's: inertia, K_p, K_v, K_i, K_R, K_W
FILTER_SIZE = 6  # IndiParams.filter: Phi (2 x 2, row by row), then Gamma (2)


class IndiParams(NamedTuple):
    mass: float  # nominal mass [kg]
    matrices: np.ndarray  # (6, 3, 3): MATRICES, matrices[INERTIA] the inertia
    integral: bool  # the integral term is on (k_i != 0)
    integral_limit: float  # [N] bound on |K_i int e_p| (anti-windup)
    filter: np.ndarray  # (FILTER_SIZE,): the low-pass's Phi and Gamma at the control period
    allocation: np.ndarray  # (6, n) nominal wrench per signed squared rotor speed [N, N m per (rad/s)^2]
    c_f: float  # thrust coefficient [N s^2]
    rotor_state: bool  # the rotors' speeds are measured (rotor_state); False: the previous command's wrench
    bridge: BridgeParams  # enabled: odom is a measurement, fly on the IMU-bridged estimate (imu_bridge)

    @classmethod
    def unused(cls) -> IndiParams:
        """Placeholder parameters, for a controller that flies another law."""
        return cls(0.0, np.zeros((len(MATRICES), 3, 3)), False, 0.0, np.zeros(FILTER_SIZE), np.zeros((6, 0)), 0.0,
                   False, BridgeParams.unused())


ANGULAR_VELOCITY, SPECIFIC_FORCE, ROTOR_FORCE, ROTOR_TORQUE = range(4)  # the filtered signals
FILTER_STATES = 6  # per signal: 3 values, then 3 rates
INDI_MEMORY = np.dtype([
    ("has_filter", np.bool_),  # the filter holds a sample
    ("has_command", np.bool_),  # a command was recorded
    ("command", np.float64, (6,)),  # the previous step's commanded wrench: force [N], torque [N m], body
    ("filters", np.float64, (4, FILTER_STATES)),  # per filtered signal: its 3 values and their 3 rates
], align=True)
"""INDI's own memory (``LawMemory.indi[0]``); the estimate (``IndiParams.bridge``) is the bridge's."""


@jit_inline
def _filtered(params: IndiParams, memory, signal: int, value: Vec3, first: bool) -> tuple:  # noqa: ANN001
    """Step the low-pass of ``signal`` with the sample ``value`` (``first``: start at rest on it); returns its
    (value, rate)."""
    x = memory.filters[signal]
    f = params.filter
    for i in range(3):
        if first:
            x[i], x[3 + i] = value[i], 0.0
        else:
            y, y_dot = x[i], x[3 + i]
            x[i] = f[0] * y + f[1] * y_dot + f[4] * value[i]
            x[3 + i] = f[2] * y + f[3] * y_dot + f[5] * value[i]
    return ((x[0], x[1], x[2]), (x[3], x[4], x[5]))


@jit_inline
def indi_law(params: IndiParams, memory, t: float, reference: ReferenceSample, position: Vec3,  # noqa: ANN001
             rotation: Mat3, velocity_world: Vec3, angular_velocity: Vec3, imu, speeds, tilts) -> tuple:  # noqa: ANN001
    """``(status, [0, 0, -u_T], tau_b, R_d)`` of INDI (:mod:`fsr_control.controllers.indi`): ``imu`` (6,) the
    IMU's angular velocity [rad/s] and specific force [m/s^2] (body FRD), ``speeds``, ``tilts`` (n,) the rotors'
    (``rotor_state``); ``memory`` the controller's ``LawMemory``."""
    if params.bridge.enabled:
        position, rotation, velocity_world = bridged_state(params.bridge, memory.bridge[0], position, rotation,
                                                           velocity_world, imu)
    own_memory = memory.indi[0]
    m = params.mass
    inertia = matrix_at(params.matrices, INERTIA)
    gyro = (imu[0], imu[1], imu[2])
    specific_force = (imu[3], imu[4], imu[5])
    first = not own_memory.has_filter
    if params.rotor_state:
        force_r, torque_r = measured_rotor_wrench(params.allocation, params.c_f, False, speeds, tilts)
    elif own_memory.has_command:
        c = own_memory.command
        force_r = (c[0], c[1], c[2])
        torque_r = (c[3], c[4], c[5])
    else:  # no command yet: the rotors are taken to hold the vehicle as measured (no external wrench)
        force_r = (m * specific_force[0], m * specific_force[1], m * specific_force[2])
        torque_r = cross3(gyro, mat_vec3(inertia, gyro))
    omega_f, omega_dot_f = _filtered(params, own_memory, ANGULAR_VELOCITY, gyro, first)
    force_f = _filtered(params, own_memory, SPECIFIC_FORCE, specific_force, first)[0]
    rotor_force_f = _filtered(params, own_memory, ROTOR_FORCE, force_r, first)[0]
    rotor_torque_f = _filtered(params, own_memory, ROTOR_TORQUE, torque_r, first)[0]
    own_memory.has_filter = True
    # m s = f_rotors + f_ext (body) and I w_dot + w x I w = tau_rotors + tau_ext, on the filtered signals
    external_body = (m * force_f[0] - rotor_force_f[0], m * force_f[1] - rotor_force_f[1],
                     m * force_f[2] - rotor_force_f[2])
    inertia_rate = mat_vec3(inertia, omega_dot_f)
    gyroscopic = cross3(omega_f, mat_vec3(inertia, omega_f))
    external_torque = (inertia_rate[0] + gyroscopic[0] - rotor_torque_f[0],
                       inertia_rate[1] + gyroscopic[1] - rotor_torque_f[1],
                       inertia_rate[2] + gyroscopic[2] - rotor_torque_f[2])
    zero = (0.0, 0.0, 0.0)
    # R_d's rates from the reference alone: the increment's rate is not fed forward (a rate of the measured
    # force turns R_d with every rotor-speed change the aerodynamics feel, a loop that tumbles the vehicle)
    increment = Compensation(True, mat_vec3(rotation, external_body), external_torque, zero, zero)
    own = GeometricParams(m, params.matrices, params.integral, params.integral_limit, True, 0.0, True, params.bridge)
    return geometric.geometric_law(own, memory.geometric[0], t, reference, position, rotation, velocity_world, gyro,
                                   increment)


@jit_inline
def indi_allocated(params: IndiParams, memory, force: Vec3, torque: Vec3, shortfall) -> None:  # noqa: ANN001
    """After the allocation: keep the wrench the command produces (``force``, ``torque``, body [N, N m]) for the
    next step's increment (without ``rotor_state``), and hold the integral as the geometric law does
    (``memory``: the controller's ``LawMemory``)."""
    own_memory = memory.indi[0]
    c = own_memory.command
    c[0], c[1], c[2] = force
    c[3], c[4], c[5] = torque
    own_memory.has_command = True
    geometric.geometric_allocated(GeometricParams(params.mass, params.matrices, params.integral,
                                                  params.integral_limit, True, 0.0, True, params.bridge),
                                  memory.geometric[0], shortfall)
