"""Geometric (SE(3)) controller for fixed-rotor multirotors (Lee et al.; report exercise 4, docs/model.md §3.6).

World NED, body FRD, ``e3 = [0, 0, 1]`` (down), ``g = 9.81``:

    e_p = p - p_d,   e_v = v - v_d                                   (world)
    a   = -K_p e_p - K_v e_v - m g e3 + m p_ddot_d                   [N]
    u_T = -a^T R_b e3,   z_bd = -a / |a|                             (thrust [N] along -z_b)
    y_bd = (z_bd x x_c) / |z_bd x x_c|,  x_bd = y_bd x z_bd,  x_c = [cos psi_d, sin psi_d, 0]
    e_R = vee(R_d^T R_b - R_b^T R_d) / 2,   e_w = w_b - R_b^T R_d w_d
    tau_b = -K_R e_R - K_w e_w + S(w_b) I_b w_b - I_b (S(w_b) R_b^T R_d w_d - R_b^T R_d w_dot_d)   [N m]

``w_d`` and ``w_dot_d`` are the exact rates of this ``R_d`` (:mod:`fsr_control.planning.flatness`): with
``a_dot = -K_p e_v - K_v e_a + m p_dddot_d`` and ``a_ddot = -K_p e_a - K_v e_j + m p_ddddot_d``, where the
acceleration error ``e_a`` uses the *measured* acceleration, from differencing consecutive velocities (the
model's ``g e3 - u_T R_b e3 / m`` would miss unmodelled forces: with a constant disturbance it predicts
an acceleration that never comes and keeps ``R_d`` turning; the model's value is used only at the first
step), and the jerk error ``e_j`` the model's ``p_dddot = -(u_T_dot R_b e3 + u_T R_b S(w_b) e3) / m``
(zero at any equilibrium); ``controller.acceleration_filter_hz`` low-passes that measured acceleration (first
order; the default 0 keeps it raw: noisy velocities make it noisy a thousandfold at 1 kHz), and the
compensated estimate's rates with it. Without the
feedback part of these rates (only the reference's) the attitude loop lags the outer loop and, with the
report's gains and the exercise-4 inertia (1.24 kg m^2), the lateral loop is unstable:
``1.49 s^4 + 12 s^3 + 12 s^2 + 200 s + 200`` fails Routh's test. The controller uses the nominal model (mass, inertia).
With ``controller.compensation: estimate`` the estimated external wrench is cancelled: ``a -= f_hat`` (world)
before ``u_T`` and ``z_bd`` (and its rates in ``a_dot``, ``a_ddot``), ``tau_b -= tau_hat`` (body); see
:mod:`fsr_control.compensation`.
Report gains: ``K_p = K_v = diag(20, 20, 100)``, ``K_R = K_w = diag(10, 10, 100)``.

The law is written once, in the compiled core (:func:`fsr_control.core.laws.geometric_law`).
"""

from __future__ import annotations

import numpy as np

from fsr_control.controllers.common import CompiledLaw, pack_law
from fsr_control.core import laws
from fsr_sim.model.vehicle import Vehicle

DEFAULT_GAINS = {  # the report's exercise-4 gains (docs/model.md §3.6), used when a scenario gives none
    "k_p": np.diag((20.0, 20.0, 100.0)),
    "k_v": np.diag((20.0, 20.0, 100.0)),
    "k_r": np.diag((10.0, 10.0, 100.0)),
    "k_w": np.diag((10.0, 10.0, 100.0)),
}


class GeometricController(CompiledLaw):
    """The geometric law of the module docstring on the nominal ``vehicle`` (fixed rotors).

    Parameters
    ----------
    vehicle : Vehicle
        Nominal model: mass [kg] and inertia [kg m^2] (must have fixed rotors).
    gains : dict
        ``k_p``, ``k_v`` [N/m, N s/m], ``k_r``, ``k_w`` [N m/rad, N m s/rad]: (3, 3) arrays (or anything
        ``np.asarray`` makes one of).

    ``compute(reference, position, rotation, velocity_world, angular_velocity_body, compensation=None)``
    returns the body wrench ``[0, 0, -u_T]`` [N], ``tau_b`` [N m] and ``rotation_commanded = R_d``. With a
    ``compensation`` ``(f_hat, tau_hat, f_hat_dot, f_hat_ddot)`` (:mod:`fsr_control.compensation`), ``f_hat`` [N]
    in world NED enters the desired force before the thrust direction is taken, ``a -= f_hat`` (a side wind is
    met by tilting), and its rates the rates of ``R_d`` (``a_dot -= f_hat_dot``, ``a_ddot -= f_hat_ddot``: without
    them ``R_d`` turns with the estimate unannounced and the attitude lags); ``tau_hat`` [N m] in body FRD the
    torque, ``tau_b -= tau_hat``. None: the law as written (bit for bit).
    """

    def __init__(self, vehicle: Vehicle, gains: dict[str, np.ndarray]) -> None:
        if vehicle.fully_actuated:
            raise ValueError(f"the geometric controller is for vehicles that produce thrust along -z_b and a torque; "
                             f"'{vehicle.name}' is fully actuated (use voliro)")
        super().__init__(pack_law(vehicle, gains, laws.GEOMETRIC, tuple(DEFAULT_GAINS)))
