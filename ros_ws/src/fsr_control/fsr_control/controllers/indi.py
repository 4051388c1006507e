"""Incremental nonlinear dynamic inversion (INDI) for fixed-rotor multirotors (Smeur, de Croon & Chu, JGCD 2016;
Tal & Karaman, IEEE T-CST 2021).

INDI replaces the model of what acts on the vehicle by what its sensors measure: the command is the wrench the
rotors produce now plus what it takes to change the measured acceleration into the desired one. World NED,
body FRD, ``e3 = [0, 0, 1]`` (down), ``g = 9.81``, nominal mass ``m`` and inertia ``I``; every measured signal
``x`` enters through the same second-order low-pass, ``x_f`` (cutoff ``controller.filter_hz``, damping
1/sqrt(2)), so that the signals are synchronous:

    omega_f, omega_dot_f                       IMU angular velocity [rad/s] and its derivative [rad/s^2], body
    s_f                                        IMU specific force R^T (p_ddot - g e3) [m/s^2], body
    f_f, tau_f                                 rotor force [N] and torque [N m], body: the measured rotor speeds
                                               (rotor_state) through the nominal allocation (c_f, c_m, geometry)

**Linear.** ``m s = f_rotors + f_ext`` (body), so the desired rotor force (world) for a desired acceleration is

    a_des = -K_p e_p - K_v e_v (- K_i int e_p) + m p_ddot_d                 [N]   (the geometric law's PD)
    F     = R f_f + (a_des - m g e3) - R m s_f = a_des - m g e3 - f_hat,    f_hat = R (m s_f - f_f)

i.e. ``T_vec = T_f_vec + m (a_d - a_f)`` with ``a_f = R s_f + g e3`` the filtered acceleration (gravity
cancels: ``F - R f_f = m (a_d - a_f)`` with ``m a_d = a_des``). ``R_d`` is built from ``-F`` and the reference
yaw, the thrust is its projection ``u_T = -F^T R e3``, and the rates of ``R_d`` come from the reference's jerk
and snap through the flatness map (the geometric law's ``controller.feedforward: reference``).

**Angular.** ``I omega_dot + omega x I omega = tau_rotors + tau_ext``, so

    alpha_d = I^-1 (-K_R e_R - K_w e_w) - S(w) R^T R_d w_d + R^T R_d w_dot_d     (the geometric attitude PD)
    tau_b   = tau_f + I (alpha_d - omega_dot_f) + omega x I omega - omega_f x I omega_f

the geometric law's torque with ``tau_hat = I omega_dot_f + omega_f x I omega_f - tau_f``.

Both increments are an external wrench estimated from the filtered signals, ``(f_hat, tau_hat)``, handed to the
geometric law (reference feed-forward, :mod:`fsr_control.controllers.geometric`) in place of an observer's: the
law is written once. Without ``rotor_state`` (rotors without lag follow their commands within the step) the
rotors' wrench is the one commanded at the previous step (at the first step: the one that makes ``f_hat`` and
``tau_hat`` zero). No estimator is needed (``controller.compensation: estimate`` is refused: INDI is itself the
compensation). The law needs the IMU (``sensors.imu``).

**Rates and state.** ``omega`` above is the gyro's (the IMU's angular velocity), not ``odom``'s. Where ``odom`` is
a measurement (noisy, late or held: ``predict``) the law flies on its own estimate of the current pose and
velocity: the IMU integrated step to step, moved at each new ``odom`` sample by
:data:`~fsr_control.controllers.common.BRIDGE_CORRECTION` of its difference to the estimate of the step it measured
(``delay_steps`` back) - the delay and the hold bridged, the noise averaged
(:func:`fsr_control.core.imu_bridge.bridged_state`, shared with the geometric law of the flight profile).

**Filter.** ``y'' = w_n^2 (u - y) - 2 zeta w_n y'``, ``w_n = 2 pi filter_hz``, ``zeta = 1/sqrt(2)``
(Butterworth), discretised exactly for an input held over the control period ``T``: ``x_k = Phi x_(k-1) +
Gamma u_k`` with ``Phi = exp(A T)``, ``Gamma = A^-1 (Phi - 1) B``; started at rest on the first sample. The
default :data:`DEFAULT_FILTER_HZ` (30 Hz) keeps the gyro's derivative quiet at 1 kHz while the filter's group
delay (``2 zeta / w_n``, 7.5 ms) is part of the lag the gains are designed for (:func:`indi_lag`).

The law is written once, in the compiled core (:func:`fsr_control.core.indi_law.indi_law`).
"""

from __future__ import annotations

import math

import numpy as np

from fsr_control.controllers.common import CompiledLaw, integrates, law_matrices, pack_bridge
from fsr_control.controllers.geometric import OPTIONAL_GAINS
from fsr_control.core import indi_law, laws
from fsr_control.design.gain_design import design_gains
from fsr_sim.model.rotors import wrench_from_rotor_speed_sq
from fsr_sim.model.vehicle import Vehicle

DEFAULT_FILTER_HZ = 30.0  # controller.filter_hz: the low-pass on every measured signal [Hz]
DESIGN_PERIOD = 0.001  # s: the control period the designed gains assume (the scenarios' 1 kHz)
# The increment assumes the rotors' nominal effectiveness (c_f w^2); where the induced inflow adds to it (slow
# rotors in an axial flow: a hard braking) the loop gain rises with it. A quarter more lag designed for: the
# Hummingbird's race loses 2 of 20 flights under onboard sensors and gusts without it, none with it.
LAG_MARGIN = 1.25
FILTER_DAMPING = 1.0 / math.sqrt(2.0)  # Butterworth


def indi_lag(vehicle: Vehicle, filter_hz: float = DEFAULT_FILTER_HZ, period: float = DESIGN_PERIOD) -> float:
    """The lag [s] INDI's gains are designed for: :data:`LAG_MARGIN` times the vehicle's own motor (or servo)
    time constant, the filter's group delay ``2 zeta / w_n`` and half a control period. No sensor delay: the
    attitude loop damps with the gyro and, where ``odom`` is late, flies on the IMU-propagated estimate (module
    docstring)."""
    motor = max(vehicle.rotor_time_constant, vehicle.tilt_time_constant)
    return LAG_MARGIN * (motor + 2.0 * FILTER_DAMPING / (2.0 * math.pi * filter_hz) + 0.5 * period)


def designed_gains(vehicle: Vehicle) -> dict[str, np.ndarray]:
    """The gains of ``controller.profile: flight``: the geometric law's designed from the vehicle
    (:func:`fsr_control.design.gain_design.design_gains`) for INDI's own lag (:func:`indi_lag`: the vehicle's motor
    and the default filter, not the 30 ms motor and the odometry's delay the geometric law is designed for),
    without the integral (``k_i = 0``): the increment removes a constant external force itself, and an
    integral would only wind up during the transient and overshoot."""
    gains = design_gains(vehicle, lag=indi_lag(vehicle)).wrench_gains()
    gains["k_i"] = np.zeros((3, 3))
    return gains


def filter_coefficients(cutoff_hz: float, period: float) -> indi_law.LowPass:
    """``Phi`` and ``Gamma`` of the second-order low-pass of cutoff ``cutoff_hz`` [Hz] held over
    ``period`` [s] (module docstring). Raises ValueError for a cutoff or a period that is not positive, or a
    cutoff at or above the Nyquist frequency ``1 / (2 period)``."""
    if not (cutoff_hz > 0.0 and period > 0.0):
        raise ValueError(f"the filter needs a cutoff > 0 Hz and a period > 0 s, got {cutoff_hz} Hz, {period} s")
    if cutoff_hz >= 0.5 / period:
        raise ValueError(f"the filter's cutoff must be below the Nyquist frequency {0.5 / period:g} Hz, got "
                         f"{cutoff_hz:g} Hz")
    from scipy.linalg import expm  # here: scipy.linalg is 0.13 s of every command's start, and only INDI needs it

    w_n = 2.0 * math.pi * cutoff_hz
    a = np.array([[0.0, 1.0], [-w_n * w_n, -2.0 * FILTER_DAMPING * w_n]])
    b = np.array([0.0, w_n * w_n])
    phi = expm(a * period)
    gamma = np.linalg.solve(a, (phi - np.eye(2)) @ b)
    (phi_00, phi_01), (phi_10, phi_11) = phi.tolist()
    gamma_0, gamma_1 = gamma.tolist()
    return indi_law.LowPass(((phi_00, phi_01), (phi_10, phi_11)), (gamma_0, gamma_1))


def pack_indi(vehicle: Vehicle, gains: dict[str, np.ndarray], filter_hz: float, period: float, rotor_state: bool,
              integral_limit: float = 0.0, predict: bool = False, delay_steps: int = 0) -> indi_law.IndiParams:
    """The core's parameters of INDI (module docstring): the geometric law's ``gains`` (``k_p``, ``k_v``,
    ``k_r``, ``k_w``, optionally ``k_i``), the filter's cutoff [Hz] at the control ``period`` [s], whether the
    rotors' speeds are measured (``rotor_state``), the bound [N] on the integral's force, and whether ``odom``
    is a measurement to bridge with the IMU (``predict``) whose samples are ``delay_steps`` steps late."""
    if vehicle.fully_actuated or vehicle.has_servos:
        raise ValueError(f"INDI is for fixed rotors that produce thrust along -z_b; '{vehicle.name}' is not")
    matrices = law_matrices(vehicle, gains, indi_law.MATRICES[1:], OPTIONAL_GAINS)
    integral = integrates(matrices, indi_law.MATRICES.index("k_i"), integral_limit)
    return indi_law.IndiParams(float(vehicle.mass), matrices, integral, float(integral_limit),
                               filter_coefficients(filter_hz, period),
                               np.ascontiguousarray(wrench_from_rotor_speed_sq(vehicle)), float(vehicle.c_f),
                               bool(rotor_state), pack_bridge(predict, period, delay_steps))


class IndiController(CompiledLaw):
    """INDI (module docstring) on the nominal ``vehicle`` (fixed rotors), outside the controller's tick.

    ``compute(..., imu=..., speeds=...)`` takes the IMU's angular velocity and specific force (6,) and, with
    ``rotor_state``, the rotors' speeds (n,). Outside the tick nothing tells it of the allocation: without
    ``rotor_state`` its rotor wrench is then always the first step's (no external wrench), so fly it in the
    :class:`fsr_control.flight_controller.FlightController`.
    """

    def __init__(self, vehicle: Vehicle, gains: dict[str, np.ndarray], period: float,
                 filter_hz: float = DEFAULT_FILTER_HZ, rotor_state: bool = True, integral_limit: float = 0.0) -> None:
        own = pack_indi(vehicle, gains, filter_hz, period, rotor_state, integral_limit)
        super().__init__(laws.law_params(laws.INDI, own))
