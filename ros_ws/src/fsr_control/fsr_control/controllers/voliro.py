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
Report gains: ``K_p = diag(50, 50, 100)``, ``K_d = diag(10, 10, 50)``, ``K_R = diag(100, 100, 100)``,
``K_w = diag(10, 10, 50)``.
"""

from __future__ import annotations

import numpy as np

from fsr_control.controllers._vec import cross3
from fsr_control.planning.trajectory import Reference
from fsr_sim.model.so3 import attitude_error
from fsr_sim.model.vehicle import GRAVITY, Vehicle

REPORT_GAINS = {
    "k_p": np.diag((50.0, 50.0, 100.0)),
    "k_d": np.diag((10.0, 10.0, 50.0)),
    "k_r": np.diag((100.0, 100.0, 100.0)),
    "k_w": np.diag((10.0, 10.0, 50.0)),
}
ANGULAR_FEEDFORWARDS = ("consistent", "report")


class VoliroController:
    """``compute(reference, state) -> (force_body [N], torque_body [N m])`` (module docstring)."""

    def __init__(self, vehicle: Vehicle, gains: dict[str, np.ndarray], angular_feedforward: str = "consistent") -> None:
        if angular_feedforward not in ANGULAR_FEEDFORWARDS:
            raise ValueError(f"angular_feedforward must be one of {ANGULAR_FEEDFORWARDS}, got '{angular_feedforward}'")
        self.mass = vehicle.mass
        self.inertia = np.array(vehicle.inertia, dtype=float)
        self.k_p, self.k_d = np.asarray(gains["k_p"], float), np.asarray(gains["k_d"], float)
        self.k_r, self.k_w = np.asarray(gains["k_r"], float), np.asarray(gains["k_w"], float)
        self.report_feedforward = angular_feedforward == "report"
        self._gravity = np.array((0.0, 0.0, GRAVITY))

    def compute(
        self,
        reference: Reference,
        position: np.ndarray,
        rotation: np.ndarray,
        velocity_world: np.ndarray,
        angular_velocity_body: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        e_p = position - reference.position
        e_v = velocity_world - reference.velocity
        v = -(self.k_p @ e_p) - self.k_d @ e_v + reference.acceleration
        rotation_desired = reference.rotation
        relative = rotation.T @ rotation_desired
        w_b = angular_velocity_body
        omega_d_body = relative @ reference.angular_velocity
        omega_dot_d_body = relative @ reference.angular_acceleration
        e_r = attitude_error(rotation, rotation_desired)
        e_w = w_b - omega_d_body
        feedback = -(self.k_r @ e_r) - self.k_w @ e_w
        if self.report_feedforward:
            w = feedback + self.inertia @ (cross3(w_b, omega_d_body) + omega_dot_d_body)
        else:
            w = feedback - cross3(w_b, omega_d_body) + omega_dot_d_body
        force_body = self.mass * (rotation.T @ (v - self._gravity))
        torque_body = self.inertia @ w + cross3(w_b, self.inertia @ w_b)
        return force_body, torque_body
