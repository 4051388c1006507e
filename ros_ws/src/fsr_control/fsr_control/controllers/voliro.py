"""Voliro-style feedback-linearising controller for tilting-rotor vehicles (report exercise 5, SPEC §3.7).

World NED, body FRD. The auxiliary inputs are accelerations (``A u + b = [p_ddot; w_dot]``):

    v = -K_p e_p - K_d e_v + p_ddot_d                                            [m/s^2, world]
    w = -K_R e_R - K_w e_w - S(w_b) R_b^T R_d w_d + R_b^T R_d w_dot_d            [rad/s^2, body]
        (``angular_feedforward: consistent``, default: the same feed-forward as the geometric controller)
    w = -K_R e_R - K_w e_w + I_b (S(w_b) R_b^T R_d w_d + R_b^T R_d w_dot_d)      (``report``: as printed)

with ``A = Mbar^-1 blkdiag(R_b, I) G``, ``b = Mbar^-1 [m g e3; -w_b x I_b w_b]``, ``Mbar = blkdiag(m I, I_b)``
and ``G`` the static 6 x 2n allocation. The report's ``u = A^+ (-b + [v; w])`` is computed here as a body
wrench followed by ``G^+``: ``A = B G`` with ``B`` invertible, so ``A u = y`` and ``G u = B^-1 y`` have the
same solutions and, ``A`` having full row rank, the same minimum-norm one, ``A^+ y = G^+ B^-1 y``, where

    B^-1 (-b + [v; w]) = [R_b^T m (v - g e3);  I_b w + w_b x I_b w_b]            (force [N], torque [N m], body)

is the wrench returned by :meth:`VoliroController.compute`. ``G^+`` is constant (no per-step SVD), and the
null space of ``A`` is that of ``G`` (see :mod:`fsr_control.nullspace` for the secondary objective).
With ``controller.compensation: estimate`` the estimated external wrench ``(f_hat, tau_hat)`` is subtracted from
this wrench, all six axes (:mod:`fsr_control.compensation`).
Report gains: ``K_p = diag(50, 50, 100)``, ``K_d = diag(10, 10, 50)``, ``K_R = diag(100, 100, 100)``,
``K_w = diag(10, 10, 50)``.
"""

from __future__ import annotations

import numpy as np

from fsr_control.controllers.common import Compensation, WrenchCommand, gain_rows, linear_feedback, tracking_errors
from fsr_control.planning.trajectory import Reference
from fsr_sim.model.frames import GRAVITY
from fsr_sim.model.so3 import attitude_error3, cross3, mat_t_mat3, mat_t_vec3, mat_vec3
from fsr_sim.model.vehicle import Vehicle

REPORT_GAINS = {
    "k_p": np.diag((50.0, 50.0, 100.0)),
    "k_d": np.diag((10.0, 10.0, 50.0)),
    "k_r": np.diag((100.0, 100.0, 100.0)),
    "k_w": np.diag((10.0, 10.0, 50.0)),
}
ANGULAR_FEEDFORWARDS = ("consistent", "report")


class VoliroController:
    """The Voliro law of the module docstring on the nominal ``vehicle`` (tilting rotors).

    Parameters
    ----------
    vehicle : Vehicle
        Nominal model: mass [kg] and inertia [kg m^2] (must have tilting rotors).
    gains : dict
        ``k_p``, ``k_d`` [1/s^2, 1/s], ``k_r``, ``k_w`` [1/s^2, 1/s]: (3, 3) arrays (acceleration gains).
    angular_feedforward : {"consistent", "report"}
        The feed-forward of ``w`` (module docstring).
    """

    def __init__(self, vehicle: Vehicle, gains: dict[str, np.ndarray], angular_feedforward: str = "consistent") -> None:
        if not vehicle.is_tilting:
            raise ValueError(f"the voliro controller needs tilting rotors; '{vehicle.name}' has fixed rotors")
        if angular_feedforward not in ANGULAR_FEEDFORWARDS:
            raise ValueError(f"angular_feedforward must be one of {ANGULAR_FEEDFORWARDS}, got '{angular_feedforward}'")
        self.mass = vehicle.mass
        self.inertia = np.array(vehicle.inertia, dtype=float)
        self.k_p, self.k_d = np.asarray(gains["k_p"], float), np.asarray(gains["k_d"], float)
        self.k_r, self.k_w = np.asarray(gains["k_r"], float), np.asarray(gains["k_w"], float)
        self.report_feedforward = angular_feedforward == "report"
        # The per-step arithmetic is on Python floats (3-vectors: far cheaper than numpy calls).
        self._k_p, self._k_d, self._k_r, self._k_w = (gain_rows(k) for k in (self.k_p, self.k_d, self.k_r, self.k_w))
        self._inertia = gain_rows(self.inertia)

    def compute(
        self,
        reference: Reference,
        position: np.ndarray,
        rotation: np.ndarray,
        velocity_world: np.ndarray,
        angular_velocity_body: np.ndarray,
        compensation: Compensation | None = None,
    ) -> WrenchCommand:
        """Body wrench ``B^-1 (-b + [v; w])`` for the state (arguments: :meth:`ControlLaw.compute`).

        Parameters
        ----------
        compensation : Compensation, optional
            The estimated external wrench to cancel (:mod:`fsr_control.compensation`), the whole 6-D wrench:
            ``force_body = R_b^T (m (v - g e3) - f_hat)`` with ``f_hat`` [N] world NED, ``torque_body =
            I_b w + w_b x I_b w_b - tau_hat`` with ``tau_hat`` [N m] body FRD. None: the law as written.

        Returns
        -------
        WrenchCommand
            ``force_body`` [N] and ``torque_body`` [N m] (body FRD), ``rotation_commanded = R_d``.
        """
        e_p, e_v = tracking_errors(reference, position, velocity_world)
        v = linear_feedback(self._k_p, e_p, self._k_d, e_v, 1.0, reference.acceleration.tolist())
        r = rotation.tolist()
        rotation_desired = reference.rotation.tolist()
        relative = mat_t_mat3(r, rotation_desired)  # R_b^T R_d
        w_b = angular_velocity_body.tolist()
        omega_d_body = mat_vec3(relative, reference.angular_velocity.tolist())
        omega_dot_d_body = mat_vec3(relative, reference.angular_acceleration.tolist())
        e_r = attitude_error3(r, rotation_desired)
        e_w = (w_b[0] - omega_d_body[0], w_b[1] - omega_d_body[1], w_b[2] - omega_d_body[2])
        feedback = linear_feedback(self._k_r, e_r, self._k_w, e_w, 0.0, (0.0, 0.0, 0.0))
        turn = cross3(w_b, omega_d_body)
        inertia = self._inertia
        if self.report_feedforward:
            ff = mat_vec3(inertia, tuple(turn[i] + omega_dot_d_body[i] for i in range(3)))
            w = tuple(feedback[i] + ff[i] for i in range(3))
        else:
            w = tuple(feedback[i] - turn[i] + omega_dot_d_body[i] for i in range(3))
        m = self.mass
        inertia_w = mat_vec3(inertia, w)
        gyro = cross3(w_b, mat_vec3(inertia, w_b))
        if compensation is not None:
            (fx, fy, fz), (tx, ty, tz) = compensation[0], compensation[1]
            force = mat_t_vec3(r, (m * v[0] - fx, m * v[1] - fy, m * (v[2] - GRAVITY) - fz))
            return WrenchCommand(np.array(force), np.array((inertia_w[0] + gyro[0] - tx, inertia_w[1] + gyro[1] - ty,
                                                            inertia_w[2] + gyro[2] - tz)), reference.rotation)
        force_body = mat_t_vec3(r, (v[0], v[1], v[2] - GRAVITY))
        return WrenchCommand(np.array((m * force_body[0], m * force_body[1], m * force_body[2])),
                             np.array(tuple(inertia_w[i] + gyro[i] for i in range(3))), reference.rotation)
