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
from fsr_control.core.law_terms import INERTIA, Compensation, Measured, VehicleState, matrix_at
from fsr_control.core.reference import ReferenceSample
from fsr_sim.core.jit import jit_inline
from fsr_sim.core.rotors import measured_rotor_wrench
from fsr_sim.core.so3 import Vec3, cross3, mat_vec3

MATRICES = geometric.MATRICES  # the geometric law's: inertia, K_p, K_v, K_i, K_R, K_W


class LowPass(NamedTuple):
    """The low-pass's step ``x <- Phi x + Gamma u`` at the control period, ``x = (y, y_dot)``, ``u`` the sample."""

    phi: tuple[tuple[float, float], tuple[float, float]]  # rows: y, y_dot from (y, y_dot)
    gamma: tuple[float, float]  # y, y_dot from u

    @classmethod
    def unused(cls) -> LowPass:
        """Placeholder coefficients (a controller that flies another law)."""
        return cls(((0.0, 0.0), (0.0, 0.0)), (0.0, 0.0))


class IndiParams(NamedTuple):
    mass: float  # nominal mass [kg]
    matrices: np.ndarray  # (6, 3, 3): MATRICES, matrices[INERTIA] the inertia
    integral: bool  # the integral term is on (k_i != 0)
    integral_limit: float  # [N] bound on |K_i int e_p| (anti-windup)
    filter: LowPass  # the low-pass's Phi and Gamma at the control period
    allocation: np.ndarray  # (6, n) nominal wrench per signed squared rotor speed [N, N m per (rad/s)^2]
    c_f: float  # thrust coefficient [N s^2]
    rotor_state: bool  # the rotors' speeds are measured (rotor_state); False: the previous command's wrench
    bridge: BridgeParams  # enabled: odom is a measurement, fly on the IMU-bridged estimate (imu_bridge)

    @classmethod
    def unused(cls) -> IndiParams:
        """Placeholder parameters, for a controller that flies another law."""
        return cls(0.0, np.zeros((len(MATRICES), 3, 3)), False, 0.0, LowPass.unused(), np.zeros((6, 0)), 0.0,
                   False, BridgeParams.unused())


FILTERED = np.dtype([
    ("value", np.float64, (3,)),  # y: the filtered 3-vector
    ("rate", np.float64, (3,)),  # y_dot: its rate [its unit per s]
], align=True)
"""The low-pass's state of one filtered signal (a field of :data:`INDI_MEMORY`)."""
INDI_MEMORY = np.dtype([
    ("has_filter", np.bool_),  # the filters hold a sample
    ("has_command", np.bool_),  # a command was recorded
    ("command_force", np.float64, (3,)),  # the previous step's commanded wrench, body: force [N]
    ("command_torque", np.float64, (3,)),  # and torque [N m]
    # the filtered signals (FILTERED): the IMU's angular velocity [rad/s] and specific force [m/s^2], the
    # rotors' force [N] and torque [N m], body FRD
    ("angular_velocity", FILTERED),
    ("specific_force", FILTERED),
    ("rotor_force", FILTERED),
    ("rotor_torque", FILTERED),
], align=True)
"""INDI's own memory (``LawMemory.indi[0]``); the estimate (``IndiParams.bridge``) is the bridge's."""


@jit_inline
def _filtered(low_pass: LowPass, signal, sample: Vec3, first: bool) -> tuple:  # noqa: ANN001
    """Step the low-pass of a ``signal`` (its :data:`FILTERED` record) with its ``sample`` (``first``: start at
    rest on it); returns its (value, rate)."""
    y, y_dot = signal.value, signal.rate
    phi, gamma = low_pass.phi, low_pass.gamma
    for i in range(3):
        if first:
            y[i], y_dot[i] = sample[i], 0.0
        else:
            value, rate = y[i], y_dot[i]
            y[i] = phi[0][0] * value + phi[0][1] * rate + gamma[0] * sample[i]
            y_dot[i] = phi[1][0] * value + phi[1][1] * rate + gamma[1] * sample[i]
    return ((y[0], y[1], y[2]), (y_dot[0], y_dot[1], y_dot[2]))


@jit_inline
def indi_law(params: IndiParams, memory, t: float, reference: ReferenceSample, state: VehicleState,  # noqa: ANN001
             measured: Measured) -> tuple:
    """``(status, [0, 0, -u_T], tau_b, R_d)`` of INDI (:mod:`fsr_control.controllers.indi`) on ``odom``'s
    ``state`` and the IMU's and (``rotor_state``) the rotors' ``measured`` of the same stamp; ``memory`` the
    controller's ``LawMemory``."""
    position, rotation, velocity_world, _ = state
    imu = measured.imu
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
        force_r, torque_r = measured_rotor_wrench(params.allocation, params.c_f, False, measured.speeds,
                                                  measured.tilts)
    elif own_memory.has_command:
        force_c, torque_c = own_memory.command_force, own_memory.command_torque
        force_r = (force_c[0], force_c[1], force_c[2])
        torque_r = (torque_c[0], torque_c[1], torque_c[2])
    else:  # no command yet: the rotors are taken to hold the vehicle as measured (no external wrench)
        force_r = (m * specific_force[0], m * specific_force[1], m * specific_force[2])
        torque_r = cross3(gyro, mat_vec3(inertia, gyro))
    low_pass = params.filter
    omega_f, omega_dot_f = _filtered(low_pass, own_memory.angular_velocity, gyro, first)
    force_f = _filtered(low_pass, own_memory.specific_force, specific_force, first)[0]
    rotor_force_f = _filtered(low_pass, own_memory.rotor_force, force_r, first)[0]
    rotor_torque_f = _filtered(low_pass, own_memory.rotor_torque, torque_r, first)[0]
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
    return geometric.geometric_law(own, memory.geometric[0], t, reference,
                                   VehicleState(position, rotation, velocity_world, gyro), increment)


@jit_inline
def indi_allocated(params: IndiParams, memory, force: Vec3, torque: Vec3, shortfall) -> None:  # noqa: ANN001
    """After the allocation: keep the wrench the command produces (``force``, ``torque``, body [N, N m]) for the
    next step's increment (without ``rotor_state``), and hold the integral as the geometric law does
    (``memory``: the controller's ``LawMemory``)."""
    own_memory = memory.indi[0]
    force_c, torque_c = own_memory.command_force, own_memory.command_torque
    force_c[0], force_c[1], force_c[2] = force
    torque_c[0], torque_c[1], torque_c[2] = torque
    own_memory.has_command = True
    geometric.geometric_allocated(GeometricParams(params.mass, params.matrices, params.integral,
                                                  params.integral_limit, True, 0.0, True, params.bridge),
                                  memory.geometric[0], shortfall)
