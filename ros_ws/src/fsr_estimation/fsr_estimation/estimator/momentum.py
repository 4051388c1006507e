"""Generalised momentum and its model-predicted derivative for a whole log (docs/model.md §3.8), vectorised.

Frames and units: world NED (``+g e3`` is down), body FRD, Euler angles ZYX ``eta = [roll, pitch, yaw]``
[rad], ``omega_body = Q(eta) eta_dot``, ``M(eta) = Q^T I_b Q``, ``C(eta, eta_dot)`` as in
:mod:`fsr_sim.model.so3` (the one source of those matrices).

* momentum ``q[k] = [m v[k]; M(eta[k-1]) eta_dot[k]]`` [kg m/s; kg m^2 rad/s]: the Euler-coordinate part
  uses ``M`` of the *earlier* sample, as the recursion that produced the report's tables (``q[0]`` uses
  ``M(eta[0])``).
* ``b_k = [m g e3 + R_b,k f_b,k ; C_k^T eta_dot_k + Q_k^T tau_b,k]`` [N; N m], with the full body force
  ``f_b`` [N] of the actuators. For fixed rotors ``f_b = [0, 0, -u_T]`` (thrust along ``-z_b``), so
  ``R_b f_b = -u_T R_b e3`` and ``b`` is exactly the report's ``m g e3 - u_T R_b e3``; a tilting vehicle
  passes its full ``f_b``.

With these, ``q[k+1] - q[k] ~ T_s (b_k + w_ext)``: the observer filters the residual.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.frames import E3
from fsr_sim.model.so3 import (
    euler_coriolis_matrix,
    euler_mass_matrix,
    euler_rate_matrix,
    rotation_from_euler_zyx,
)


def generalized_momentum(mass: float, inertia: ArrayLike, velocity_world: ArrayLike, eta: ArrayLike,
                         eta_dot: ArrayLike) -> np.ndarray:
    """``q[k] = [m v[k]; M(eta[k-1]) eta_dot[k]]`` for a whole log, shape (N, 6).

    mass [kg]; inertia (3, 3) [kg m^2] body; velocity_world (N, 3) [m/s] NED; eta (N, 3) [rad];
    eta_dot (N, 3) [rad/s].
    """
    v = np.asarray(velocity_world, dtype=float)
    eta = np.asarray(eta, dtype=float)
    eta_dot = np.asarray(eta_dot, dtype=float)
    mass_matrix = euler_mass_matrix(eta, inertia)
    q = np.empty((len(v), 6))
    q[:, :3] = mass * v
    q[0, 3:] = mass_matrix[0] @ eta_dot[0]
    q[1:, 3:] = np.einsum("kij,kj->ki", mass_matrix[:-1], eta_dot[1:])
    return q


def model_momentum_rate(mass: float, inertia: ArrayLike, eta: ArrayLike, eta_dot: ArrayLike,
                        force_body: ArrayLike, torque_body: ArrayLike, gravity: float = GRAVITY) -> np.ndarray:
    """``b_k = [m g e3 + R_b f_b ; C^T eta_dot + Q^T tau_b]`` for a whole log, shape (N, 6).

    force_body, torque_body (N, 3) [N, N m] in body FRD (the actuator wrench, not the external one).
    """
    eta = np.asarray(eta, dtype=float)
    eta_dot = np.asarray(eta_dot, dtype=float)
    force_body = np.asarray(force_body, dtype=float)
    torque_body = np.asarray(torque_body, dtype=float)
    rotation = rotation_from_euler_zyx(eta)
    rate_matrix = euler_rate_matrix(eta)
    coriolis = euler_coriolis_matrix(eta, eta_dot, inertia)
    b = np.empty((len(eta), 6))
    b[:, :3] = mass * gravity * E3 + np.einsum("kij,kj->ki", rotation, force_body)
    b[:, 3:] = np.einsum("kji,kj->ki", coriolis, eta_dot) + np.einsum("kji,kj->ki", rate_matrix, torque_body)
    return b


def observer_input(mass: float, inertia: ArrayLike, velocity_world: ArrayLike, eta: ArrayLike,
                   eta_dot: ArrayLike, force_body: ArrayLike, torque_body: ArrayLike, sample_time: float,
                   gravity: float = GRAVITY) -> np.ndarray:
    """``u[k] = (q[k+1] - q[k]) - T_s b_k`` for k = 0..N-2 and ``u[N-1] = 0``, shape (N, 6).

    The residual momentum change over one sample [kg m/s; kg m^2 rad/s] that the observer filters
    (``u / T_s`` is the external wrench seen through the model).
    """
    q = generalized_momentum(mass, inertia, velocity_world, eta, eta_dot)
    b = model_momentum_rate(mass, inertia, eta, eta_dot, force_body, torque_body, gravity)
    u = np.zeros_like(q)
    u[:-1] = (q[1:] - q[:-1]) - sample_time * b[:-1]
    return u
