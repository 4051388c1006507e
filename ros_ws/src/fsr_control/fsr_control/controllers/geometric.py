"""Geometric (SE(3)) controller for fixed-rotor multirotors (Lee et al.; report exercise 4, SPEC §3.6).

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
(zero at any equilibrium). Without the
feedback part of these rates (only the reference's) the attitude loop lags the outer loop and, with the
report's gains and the exercise-4 inertia (1.24 kg m^2), the lateral loop is unstable:
``1.49 s^4 + 12 s^3 + 12 s^2 + 200 s + 200`` fails Routh's test. The controller uses the nominal model (mass, inertia).
With ``controller.compensation: estimate`` the estimated external wrench is cancelled: ``a -= f_hat`` (world)
before ``u_T`` and ``z_bd`` (and its rates in ``a_dot``, ``a_ddot``), ``tau_b -= tau_hat`` (body); see
:mod:`fsr_control.compensation`.
Report gains: ``K_p = K_v = diag(20, 20, 100)``, ``K_R = K_w = diag(10, 10, 100)``.
"""

from __future__ import annotations

import numpy as np

from fsr_control.controllers.common import Compensation, WrenchCommand, gain_rows, linear_feedback, tracking_errors
from fsr_control.planning.flatness import attitude_rows_from_thrust_vector
from fsr_control.planning.trajectory import Reference
from fsr_sim.model.frames import GRAVITY
from fsr_sim.model.so3 import Vec3, attitude_error3, cross3, dot3, mat_t_mat3, mat_vec3
from fsr_sim.model.vehicle import Vehicle

REPORT_GAINS = {
    "k_p": np.diag((20.0, 20.0, 100.0)),
    "k_v": np.diag((20.0, 20.0, 100.0)),
    "k_r": np.diag((10.0, 10.0, 100.0)),
    "k_w": np.diag((10.0, 10.0, 100.0)),
}


class GeometricController:
    """The geometric law of the module docstring on the nominal ``vehicle`` (fixed rotors).

    Parameters
    ----------
    vehicle : Vehicle
        Nominal model: mass [kg] and inertia [kg m^2] (must have fixed rotors).
    gains : dict
        ``k_p``, ``k_v`` [N/m, N s/m], ``k_r``, ``k_w`` [N m/rad, N m s/rad]: (3, 3) arrays (or anything
        ``np.asarray`` makes one of).
    """

    def __init__(self, vehicle: Vehicle, gains: dict[str, np.ndarray]) -> None:
        if vehicle.is_tilting:
            raise ValueError(f"the geometric controller needs fixed rotors; '{vehicle.name}' tilts")
        self.mass = vehicle.mass
        self.inertia = np.array(vehicle.inertia, dtype=float)
        self.k_p, self.k_v = np.asarray(gains["k_p"], float), np.asarray(gains["k_v"], float)
        self.k_r, self.k_w = np.asarray(gains["k_r"], float), np.asarray(gains["k_w"], float)
        # The per-step arithmetic is on Python floats (3-vectors: far cheaper than numpy calls).
        self._k_p, self._k_v, self._k_r, self._k_w = (gain_rows(k) for k in (self.k_p, self.k_v, self.k_r, self.k_w))
        self._inertia = gain_rows(self.inertia)
        self._previous: tuple[float, Vec3] | None = None  # (t [s], velocity world [m/s])

    def compute(
        self,
        reference: Reference,
        position: np.ndarray,
        rotation: np.ndarray,
        velocity_world: np.ndarray,
        angular_velocity_body: np.ndarray,
        compensation: Compensation | None = None,
    ) -> WrenchCommand:
        """Body wrench ``[0, 0, -u_T]``, ``tau_b`` and ``R_d`` for the state (arguments: :meth:`ControlLaw.compute`).

        Parameters
        ----------
        compensation : Compensation, optional
            The estimated external wrench to cancel (:mod:`fsr_control.compensation`): ``f_hat`` [N] in world
            NED enters the desired force before the thrust direction is taken, ``a -= f_hat`` (a side wind is
            met by tilting), and its rates the rates of ``R_d`` (``a_dot -= f_hat_dot``, ``a_ddot -=
            f_hat_ddot``: without them ``R_d`` turns with the estimate unannounced and the attitude lags);
            ``tau_hat`` [N m] in body FRD the torque, ``tau_b -= tau_hat``. None: the law as written (bit for
            bit).

        Returns
        -------
        WrenchCommand
            ``force_body = [0, 0, -u_T]`` [N], ``torque_body`` [N m], ``rotation_commanded = R_d``.
        """
        m = self.mass
        k_p, k_v, inertia = self._k_p, self._k_v, self._inertia
        e_p, e_v = tracking_errors(reference, position, velocity_world)
        a = linear_feedback(k_p, e_p, k_v, e_v, m, reference.acceleration.tolist())
        a = (a[0], a[1], a[2] - m * GRAVITY)  # - m g e3
        if compensation is not None:
            f_hat = compensation[0]
            a = (a[0] - f_hat[0], a[1] - f_hat[1], a[2] - f_hat[2])  # - f_hat (world)
        r = rotation.tolist()
        z_b = (r[0][2], r[1][2], r[2][2])
        thrust = -dot3(a, z_b)
        # R_d and its rates: differentiate a with the measured acceleration and the model's jerk of this thrust.
        w = angular_velocity_body.tolist()
        z_b_dot = mat_vec3(r, (w[1], -w[0], 0.0))  # R S(w) e3
        acceleration = self._measured_acceleration(reference.time, velocity_world.tolist(), thrust, z_b)
        acc_d, jerk_d = reference.acceleration.tolist(), reference.jerk.tolist()
        e_a = (acceleration[0] - acc_d[0], acceleration[1] - acc_d[1], acceleration[2] - acc_d[2])
        a_dot = linear_feedback(k_p, e_v, k_v, e_a, m, jerk_d)
        if compensation is not None:  # the estimate changes too: R_d turns with it (w_d, w_dot_d)
            f_dot, f_ddot = compensation[2], compensation[3]
            a_dot = (a_dot[0] - f_dot[0], a_dot[1] - f_dot[1], a_dot[2] - f_dot[2])
        thrust_dot = -dot3(a_dot, z_b) - dot3(a, z_b_dot)
        e_j = tuple(-(thrust_dot * z_b[i] + thrust * z_b_dot[i]) / m - jerk_d[i] for i in range(3))
        a_ddot = linear_feedback(k_p, e_a, k_v, e_j, m, reference.snap.tolist())
        if compensation is not None:
            a_ddot = (a_ddot[0] - f_ddot[0], a_ddot[1] - f_ddot[1], a_ddot[2] - f_ddot[2])
        rotation_desired, omega_d, omega_dot_d = attitude_rows_from_thrust_vector(
            (-a[0], -a[1], -a[2]), (-a_dot[0], -a_dot[1], -a_dot[2]), (-a_ddot[0], -a_ddot[1], -a_ddot[2]),
            reference.yaw, reference.yaw_rate, reference.yaw_acceleration,
        )
        relative = mat_t_mat3(r, rotation_desired)  # R_b^T R_d
        omega_d_body = mat_vec3(relative, omega_d)
        e_w = (w[0] - omega_d_body[0], w[1] - omega_d_body[1], w[2] - omega_d_body[2])
        gyro = cross3(w, mat_vec3(inertia, w))
        turn = cross3(w, omega_d_body)
        turn_d = mat_vec3(relative, omega_dot_d)
        feedforward = mat_vec3(inertia, (turn[0] - turn_d[0], turn[1] - turn_d[1], turn[2] - turn_d[2]))
        e_r = attitude_error3(r, rotation_desired)
        feedback = linear_feedback(self._k_r, e_r, self._k_w, e_w, 0.0, (0.0, 0.0, 0.0))
        torque = tuple(feedback[i] + gyro[i] - feedforward[i] for i in range(3))
        if compensation is not None:
            tau_hat = compensation[1]
            torque = (torque[0] - tau_hat[0], torque[1] - tau_hat[1], torque[2] - tau_hat[2])
        return WrenchCommand(np.array((0.0, 0.0, -thrust)), np.array(torque), np.array(rotation_desired))

    def _measured_acceleration(self, t: float, velocity_world: Vec3, thrust: float, z_b: Vec3) -> Vec3:
        """Acceleration [m/s^2] from consecutive velocities (includes unmodelled forces); the model's
        ``g e3 - u_T z_b / m`` at the first step or when time does not advance."""
        previous = self._previous
        self._previous = (t, velocity_world)
        if previous is not None and t > previous[0]:
            dt = t - previous[0]
            return tuple((velocity_world[i] - previous[1][i]) / dt for i in range(3))
        scale = thrust / self.mass
        return (-scale * z_b[0], -scale * z_b[1], GRAVITY - scale * z_b[2])
