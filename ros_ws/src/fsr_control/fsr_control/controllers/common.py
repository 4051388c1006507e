"""What the control laws share: their interface, gains as float rows and the tracking errors (1 kHz).

The interface (:class:`ControlLaw`): ``compute(reference, position, rotation, velocity_world,
angular_velocity_body) -> WrenchCommand``, the body wrench to produce and the attitude it commands;
allocation (fsr_control.allocation) turns the wrench into rotor speeds and tilts. Both laws start from the
position and velocity errors ``e_p = p - p_d``, ``e_v = v - v_d`` (world NED); the 3-vector algebra is
fsr_sim.model.so3's single-sample float functions (one definition of each formula for the whole stack).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from fsr_control.planning.trajectory import Reference
from fsr_sim.model.so3 import Mat3, Vec3

Compensation = tuple[Vec3, Vec3, Vec3, Vec3]
"""The estimated external wrench a law cancels (:mod:`fsr_control.compensation`): ``(f_hat, tau_hat, f_hat_dot,
f_hat_ddot)``: force [N] world NED, torque [N m] body FRD, the force's first and second time differences
[N/s, N/s^2] (world; the geometric law turns ``R_d`` with them)."""


@dataclass
class WrenchCommand:
    """What a control law asks for at one state.

    Attributes
    ----------
    force_body : numpy.ndarray, shape (3,)
        Body force [N], FRD (a fixed-rotor vehicle: ``[0, 0, -u_T]``).
    torque_body : numpy.ndarray, shape (3,)
        Body torque [N m], FRD.
    rotation_commanded : numpy.ndarray, shape (3, 3)
        The attitude the law steers to, body FRD -> world NED (geometric: ``R_d`` built from the thrust
        direction; Voliro: the reference attitude).
    """

    force_body: np.ndarray
    torque_body: np.ndarray
    rotation_commanded: np.ndarray

    @property
    def thrust(self) -> float:
        """``u_T = -f_z`` [N] (thrust along ``-z_b``)."""
        return -float(self.force_body[2])


class ControlLaw(Protocol):
    """A control law on the nominal vehicle model (frames: position and velocity world NED [m, m/s],
    ``rotation`` body FRD -> world NED, angular velocity body FRD [rad/s])."""

    def compute(self, reference: Reference, position: np.ndarray, rotation: np.ndarray, velocity_world: np.ndarray,
                angular_velocity_body: np.ndarray, compensation: Compensation | None = None) -> WrenchCommand:
        """The body wrench for this state and reference.

        Parameters
        ----------
        reference : Reference
            The planner's desired state at this time.
        position, velocity_world : numpy.ndarray, shape (3,)
            [m], [m/s], world NED.
        rotation : numpy.ndarray, shape (3, 3)
            Body FRD -> world NED.
        angular_velocity_body : numpy.ndarray, shape (3,)
            [rad/s], body FRD.
        compensation : Compensation, optional
            The estimated external wrench to cancel (:data:`Compensation`; None: uncompensated, bit for bit
            the law as written). How each law uses it: its own ``compute``.

        Returns
        -------
        WrenchCommand
        """


def gain_rows(gain: np.ndarray) -> Mat3:
    """A 3x3 gain matrix as float rows (for :func:`fsr_sim.model.so3.mat_vec3`)."""
    return tuple(tuple(row) for row in np.asarray(gain, dtype=float).tolist())


def tracking_errors(reference: Reference, position: np.ndarray, velocity_world: np.ndarray) -> tuple[Vec3, Vec3]:
    """``(e_p, e_v) = (p - p_d, v - v_d)`` [m, m/s] (world NED), as float tuples."""
    px, py, pz = position.tolist()
    dx, dy, dz = reference.position.tolist()
    vx, vy, vz = velocity_world.tolist()
    ux, uy, uz = reference.velocity.tolist()
    return (px - dx, py - dy, pz - dz), (vx - ux, vy - uy, vz - uz)


def linear_feedback(k_a: Mat3, e_a: Vec3, k_b: Mat3, e_b: Vec3, scale: float, feedforward: Vec3) -> Vec3:
    """``-K_a e_a - K_b e_b + scale * feedforward`` (the PD terms of both laws)."""
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = k_a
    (b00, b01, b02), (b10, b11, b12), (b20, b21, b22) = k_b
    x, y, z = e_a
    u, v, w = e_b
    fx, fy, fz = feedforward
    return (
        -(a00 * x + a01 * y + a02 * z) - (b00 * u + b01 * v + b02 * w) + scale * fx,
        -(a10 * x + a11 * y + a12 * z) - (b10 * u + b11 * v + b12 * w) + scale * fy,
        -(a20 * x + a21 * y + a22 * z) - (b20 * u + b21 * v + b22 * w) + scale * fz,
    )
