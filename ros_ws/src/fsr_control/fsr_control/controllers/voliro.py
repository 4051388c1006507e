"""Voliro-style feedback-linearising controller for tilting-rotor vehicles (report exercise 5, docs/model.md §3.7).

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

The law is written once, in the compiled core (:func:`fsr_control.core.voliro_law.voliro_law`).
"""

from __future__ import annotations

import numpy as np

from fsr_control.controllers.common import CompiledLaw, check_actuation, diagonal_gains, law_matrices
from fsr_control.core import laws, voliro_law
from fsr_sim.model.vehicle import Vehicle

# The report's exercise-5 gains (docs/model.md §3.7), used when a scenario gives none.
DEFAULT_GAINS = diagonal_gains(k_p=(50.0, 50.0, 100.0), k_d=(10.0, 10.0, 50.0), k_r=(100.0, 100.0, 100.0),
                               k_w=(10.0, 10.0, 50.0))
ANGULAR_FEEDFORWARDS = ("consistent", "report")


def pack_voliro(vehicle: Vehicle, gains: dict[str, np.ndarray], angular_feedforward: str = "consistent"
                ) -> voliro_law.VoliroParams:
    """The core's parameters of the Voliro law (module docstring).

    Parameters
    ----------
    vehicle : Vehicle
        Nominal model: mass [kg] and inertia [kg m^2] (must be fully actuated).
    gains : dict
        ``k_p``, ``k_d`` [1/s^2, 1/s], ``k_r``, ``k_w`` [1/s^2, 1/s]: (3, 3) arrays (acceleration gains).
    angular_feedforward : {"consistent", "report"}
        The feed-forward of ``w`` (module docstring).
    """
    check_actuation("the voliro controller", True, vehicle)
    if angular_feedforward not in ANGULAR_FEEDFORWARDS:
        raise ValueError(f"angular_feedforward must be one of {ANGULAR_FEEDFORWARDS}, got '{angular_feedforward}'")
    return voliro_law.VoliroParams(float(vehicle.mass), law_matrices(vehicle, gains, voliro_law.MATRICES[1:]),
                                   angular_feedforward == "report")


class VoliroController(CompiledLaw):
    """The Voliro law of the module docstring on the nominal ``vehicle`` (tilting or canted rotors), with the
    parameters of :func:`pack_voliro`.

    ``compute(...)`` returns the body wrench ``B^-1 (-b + [v; w])``; with a ``compensation`` (the whole 6-D
    wrench): ``force_body = R_b^T (m (v - g e3) - f_hat)`` with ``f_hat`` [N] world NED, ``torque_body =
    I_b w + w_b x I_b w_b - tau_hat`` with ``tau_hat`` [N m] body FRD; ``rotation_commanded = R_d``.
    """

    def __init__(self, vehicle: Vehicle, gains: dict[str, np.ndarray], angular_feedforward: str = "consistent") -> None:
        super().__init__(laws.law_params(laws.VOLIRO, pack_voliro(vehicle, gains, angular_feedforward)))
