"""Angular feed-forward of a thrust-vectoring (fixed-rotor) vehicle from the flat outputs (p_d, psi_d).

For perfect tracking the geometric controller's desired attitude (docs/model.md §3.6) is built from

    n = g e3 - p_ddot_d   (the specific thrust direction, world NED; ``a = -m n`` without feedback),
    z_d = n / |n|,  y_d = (z_d x x_c) / |z_d x x_c|,  x_d = y_d x z_d,  x_c = [cos psi_d, sin psi_d, 0],

so ``R_d = [x_d y_d z_d]`` is a function of the acceleration and yaw of the reference. Differentiating it
with the reference's jerk, snap, yaw rate and yaw acceleration gives the desired body angular velocity
and acceleration analytically (:func:`flat_attitude_rates`). The geometric controller uses the general
form :func:`attitude_from_thrust_vector` with its commanded force ``n = -a`` (feedback included) and the
force's derivatives:

    S(omega_d) = R_d^T R_d_dot,   omega_dot_d = vee(skew part of R_d^T R_d_ddot).

For a unit vector ``u = w / |w|``: ``u_dot = (w_dot - u (u.w_dot)) / |w|`` and
``u_ddot = (w_ddot - 2 u_dot (u.w_dot) - u (u_dot.w_dot + u.w_ddot)) / |w|``.

The arithmetic is the compiled core's (:mod:`fsr_control.core.flatness`, which the geometric law calls every
step); these functions are its array API.
"""

from __future__ import annotations

import numpy as np

from fsr_control.core import flatness as core
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.so3 import vector3


def attitude_from_thrust_vector(
    n: tuple[float, float, float] | np.ndarray,
    n_dot: tuple[float, float, float] | np.ndarray,
    n_ddot: tuple[float, float, float] | np.ndarray,
    yaw: float,
    yaw_rate: float,
    yaw_acceleration: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(R_d, omega_d, omega_dot_d)`` with ``z_d = n / |n|`` and heading ``x_c(psi)`` (module docstring).

    n, n_dot, n_ddot: shape (3,), the desired thrust-axis vector (world NED, any positive scale, e.g. ``-a``
    [N]) and its first two time derivatives; yaw [rad], yaw_rate [rad/s], yaw_acceleration [rad/s^2].
    Returns ``R_d`` (3, 3) body FRD -> world, ``omega_d``, ``omega_dot_d`` (3,) in the desired body frame.
    Raises ValueError when ``n`` vanishes (free fall) or is horizontal along the heading.
    """
    status, rotation, omega, omega_dot = core.attitude_from_thrust_vector(
        vector3(n), vector3(n_dot), vector3(n_ddot), float(yaw), float(yaw_rate), float(yaw_acceleration))
    if status != core.ATTITUDE_OK:
        raise ValueError(core.ATTITUDE_ERRORS[status])
    return np.array(rotation), np.array(omega), np.array(omega_dot)


def flat_attitude_rates(
    acceleration: np.ndarray,
    jerk: np.ndarray,
    snap: np.ndarray,
    yaw: float,
    yaw_rate: float,
    yaw_acceleration: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(R_d, omega_d, omega_dot_d)`` that a reference (acceleration, jerk, snap [m/s^k, world NED], yaw)
    needs without feedback: :func:`attitude_from_thrust_vector` of ``n = g e3 - p_ddot_d``."""
    n = (-acceleration[0], -acceleration[1], GRAVITY - acceleration[2])
    return attitude_from_thrust_vector(n, -jerk, -snap, yaw, yaw_rate, yaw_acceleration)
