"""Geometric (SE(3)) controller for fixed-rotor multirotors (Lee et al.; report exercise 4, docs/model.md §3.6).

World NED, body FRD, ``e3 = [0, 0, 1]`` (down), ``g = 9.81``:

    e_p = p - p_d,   e_v = v - v_d                                   (world)
    a   = -K_p e_p - K_v e_v - m g e3 + m p_ddot_d                   [N]
    u_T = -a^T R_b e3,   z_bd = -a / |a|                             (thrust [N] along -z_b)
    y_bd = (z_bd x x_c) / |z_bd x x_c|,  x_bd = y_bd x z_bd,  x_c = [cos psi_d, sin psi_d, 0]
    e_R = vee(R_d^T R_b - R_b^T R_d) / 2,   e_w = w_b - R_b^T R_d w_d
    tau_b = -K_R e_R - K_w e_w + S(w_b) I_b w_b - I_b (S(w_b) R_b^T R_d w_d - R_b^T R_d w_dot_d)   [N m]

``w_d`` and ``w_dot_d`` are the rates of ``R_d`` through the flatness map (:mod:`fsr_control.core.flatness`),
from ``a_dot`` and ``a_ddot``; ``controller.feedforward`` says where those come from:

* ``reference`` (the flight stacks' law: Lee, Leok & McClamroch 2010; Mellinger & Kumar 2011; Faessler et al.
  2018; the default of ``controller.profile: flight``): from the reference alone, ``a_dot = m p_dddot_d``,
  ``a_ddot = m p_ddddot_d`` (and the yaw's rate and acceleration). No measured acceleration enters the torque,
  so sensor noise, a motor lag or a force step reach it only through the PD terms. The attitude loop must then
  be faster than the position loop (several times: :mod:`fsr_control.design.gain_design` designs such gains from
  the vehicle), since ``R_d`` turning with the feedback is left to the attitude feedback.
* ``measured`` (the report's law, ``controller.profile: report``): the exact rates of this ``R_d``, with
  ``a_dot = -K_p e_v - K_v e_a + m p_dddot_d`` and ``a_ddot = -K_p e_a - K_v e_j + m p_ddddot_d``, where the
  acceleration error ``e_a`` uses the *measured* acceleration, from differencing consecutive velocities (the
  model's ``g e3 - u_T R_b e3 / m`` would miss unmodelled forces: with a constant disturbance it predicts an
  acceleration that never comes and keeps ``R_d`` turning; the model's value is used only at the first step),
  and the jerk error ``e_j`` the model's ``p_dddot = -(u_T_dot R_b e3 + u_T R_b S(w_b) e3) / m`` (zero at any
  equilibrium); ``controller.acceleration_filter_hz`` low-passes that measured acceleration (first order; the
  default 0 keeps it raw: noisy velocities make it noisy a thousandfold at 1 kHz). Without the feedback part
  of these rates (only the reference's) the attitude loop lags the outer loop and, with the report's gains and
  the exercise-4 inertia (1.24 kg m^2), whose attitude loop is slower than its position loop, the lateral loop
  is unstable: ``1.49 s^4 + 12 s^3 + 12 s^2 + 200 s + 200`` fails Routh's test.

The controller uses the nominal model (mass, inertia). An integral of the position error (``gains.k_i``, zero
by default in ``report``, designed in ``flight``) adds ``-K_i int e_p dt`` to ``a`` (and, ``measured``, its
rates ``-K_i e_p``, ``-K_i e_v`` to ``a_dot``, ``a_ddot``), with two anti-windup rules: the integral is scaled
back so that ``|K_i int e_p| <= controller.integral_limit`` [N] (a clamp on its force), and it is not integrated
at a step after the allocation fell short of the commanded thrust or roll/pitch torque (conditional
integration: the rotors at a limit; yaw giving way does not count).
With ``controller.compensation: estimate`` the estimated external wrench is cancelled: ``a -= f_hat`` (world)
before ``u_T`` and ``z_bd``, ``tau_b -= tau_hat`` (body); see :mod:`fsr_control.compensation`. With the measured
feed-forward the estimate's rates enter ``a_dot``, ``a_ddot`` (the report's law); with the reference
feed-forward ``R_d``'s rates stay the reference's alone: the estimate holds what the command itself causes (a
lagging motor, the aerodynamics of the rotors' speeds), and its rates in ``R_d`` closed a loop through the
attitude that lost control in every flight under sensor noise. The aerodynamics model's prediction
(``controller.aerodynamics: model``), a function of the reference alone, turns ``R_d`` with its rates.

**State** (``controller.use_imu``, the flight profile's default on a vehicle with an IMU): the attitude loop damps
with the gyro (the IMU's angular velocity, not ``odom``'s, which is late and averaged over its period) and,
where ``odom`` is a measurement (noisy, late or held), the law flies on the IMU-bridged estimate of the pose and
velocity at the current step (:func:`fsr_control.core.imu_bridge.bridged_state`, INDI's): the designed gains
then have no odometry delay to survive (:func:`fsr_control.design.gain_design.design_lag`).
Report gains: ``K_p = K_v = diag(20, 20, 100)``, ``K_R = K_w = diag(10, 10, 100)``.

The law is written once, in the compiled core (:func:`fsr_control.core.geometric_law.geometric_law`).
"""

from __future__ import annotations

import numpy as np

from fsr_control.controllers.common import (
    CompiledLaw,
    check_actuation,
    diagonal_gains,
    integrates,
    law_matrices,
    pack_bridge,
)
from fsr_control.core import geometric_law, laws
from fsr_sim.model.vehicle import Vehicle

# The report's exercise-4 gains (docs/model.md §3.6), used when a scenario gives none.
DEFAULT_GAINS = diagonal_gains(k_p=(20.0, 20.0, 100.0), k_v=(20.0, 20.0, 100.0), k_r=(10.0, 10.0, 100.0),
                               k_w=(10.0, 10.0, 100.0))
OPTIONAL_GAINS = ("k_i",)  # zero unless given (the report's law has no integral)
FEEDFORWARDS = ("measured", "reference")  # not a topic name: controller.feedforward's values
MEASURED_FEEDFORWARD, REFERENCE_FEEDFORWARD = FEEDFORWARDS


def pack_geometric(vehicle: Vehicle, gains: dict[str, np.ndarray], feedforward: str = MEASURED_FEEDFORWARD,
                   acceleration_filter_hz: float = 0.0, integral_limit: float = 0.0, imu: bool = False,
                   period: float = 0.0, odometry_measured: bool = False,
                   delay_steps: int = 0) -> geometric_law.GeometricParams:
    """The core's parameters of the geometric law (module docstring).

    Parameters
    ----------
    vehicle : Vehicle
        Nominal model: mass [kg] and inertia [kg m^2] (must have fixed rotors).
    gains : dict
        ``k_p``, ``k_v`` [N/m, N s/m], ``k_r``, ``k_w`` [N m/rad, N m s/rad] and optionally ``k_i`` [N/(m s)]:
        (3, 3) arrays (or anything ``np.asarray`` makes one of).
    feedforward : {"measured", "reference"}
        Where the rates of ``R_d`` come from (module docstring); ``measured``: the report's law.
    acceleration_filter_hz : float
        ``measured``: the cutoff [Hz] of the low-pass on the measured acceleration (and, either, on the
        compensated estimate's rates); 0: none.
    integral_limit : float
        Bound [N] on the integral's force (needed with a non-zero ``k_i``).
    imu, period, odometry_measured, delay_steps
        Fly on the IMU (module docstring, "State"): ``compute(..., imu=...)`` then takes its angular velocity
        and specific force (6,); with ``odometry_measured`` the estimate bridges ``odom``'s ``delay_steps`` at
        the control ``period`` [s].
    """
    check_actuation("the geometric controller", False, vehicle)
    if feedforward not in FEEDFORWARDS:
        raise ValueError(f"feedforward must be one of {FEEDFORWARDS}, got '{feedforward}'")
    matrices = law_matrices(vehicle, gains, geometric_law.MATRICES[1:], OPTIONAL_GAINS)
    integral = integrates(matrices, geometric_law.K_I, integral_limit)
    bridge = imu and odometry_measured
    if bridge and not period > 0.0:
        raise ValueError(f"the IMU-bridged estimate needs a control period > 0 s, got {period}")
    return geometric_law.GeometricParams(float(vehicle.mass), matrices, integral, float(integral_limit),
                                         feedforward == REFERENCE_FEEDFORWARD, float(acceleration_filter_hz),
                                         bool(imu), pack_bridge(bridge, period, delay_steps if bridge else 0))


class GeometricController(CompiledLaw):
    """The geometric law of the module docstring on the nominal ``vehicle`` (fixed rotors), with the parameters
    of :func:`pack_geometric`.

    ``compute(reference, position, rotation, velocity_world, angular_velocity_body, compensation=None)``
    returns the body wrench ``[0, 0, -u_T]`` [N], ``tau_b`` [N m] and ``rotation_commanded = R_d``. With a
    ``compensation`` ``(f_hat, tau_hat, f_hat_dot, f_hat_ddot)`` (:mod:`fsr_control.compensation`), ``f_hat`` [N]
    in world NED enters the desired force before the thrust direction is taken, ``a -= f_hat`` (a side wind is
    met by tilting), and its rates the rates of ``R_d`` (``a_dot -= f_hat_dot``, ``a_ddot -= f_hat_ddot``: without
    them ``R_d`` turns with the estimate unannounced and the attitude lags); ``tau_hat`` [N m] in body FRD the
    torque, ``tau_b -= tau_hat``. None: the law as written (bit for bit). Outside the controller's tick nothing
    tells it of the allocation, so its integral is never held (only clamped).
    """

    def __init__(self, vehicle: Vehicle, gains: dict[str, np.ndarray], feedforward: str = MEASURED_FEEDFORWARD,
                 acceleration_filter_hz: float = 0.0, integral_limit: float = 0.0, imu: bool = False,
                 period: float = 0.0, odometry_measured: bool = False, delay_steps: int = 0) -> None:
        own = pack_geometric(vehicle, gains, feedforward, acceleration_filter_hz, integral_limit, imu, period,
                             odometry_measured, delay_steps)
        super().__init__(laws.law_params(laws.GEOMETRIC, own))
