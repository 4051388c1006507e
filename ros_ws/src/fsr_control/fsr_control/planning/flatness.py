"""Angular feed-forward of a thrust-vectoring (fixed-rotor) vehicle from the flat outputs (p_d, psi_d).

For perfect tracking the geometric controller's desired attitude (SPEC §3.6) is built from

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

Written on Python floats (3-vectors): it runs every 1 kHz control step.
"""

from __future__ import annotations

import math

import numpy as np

from fsr_sim.model.frames import GRAVITY
from fsr_sim.model.so3 import Mat3, Vec3, cross3, dot3

Vec = Vec3


def _sum2(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _sum3(a: Vec, b: Vec, c: Vec) -> Vec:
    """``a + 2 b + c`` (product rule of a second derivative)."""
    return (a[0] + 2.0 * b[0] + c[0], a[1] + 2.0 * b[1] + c[1], a[2] + 2.0 * b[2] + c[2])


def _normalised_with_rates(w: Vec, w_dot: Vec, w_ddot: Vec) -> tuple[Vec, Vec, Vec]:
    """``u = w/|w|`` and its first two time derivatives."""
    norm = math.sqrt(dot3(w, w))
    inv = 1.0 / norm
    u = (w[0] * inv, w[1] * inv, w[2] * inv)
    uw = dot3(u, w_dot)
    u_dot = tuple((w_dot[i] - u[i] * uw) * inv for i in range(3))
    second = dot3(u_dot, w_dot) + dot3(u, w_ddot)
    u_ddot = tuple((w_ddot[i] - 2.0 * u_dot[i] * uw - u[i] * second) * inv for i in range(3))
    return u, u_dot, u_ddot


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
    as_floats = [v.tolist() if isinstance(v, np.ndarray) else v for v in (n, n_dot, n_ddot)]
    rotation, omega, omega_dot = attitude_rows_from_thrust_vector(*as_floats, yaw, yaw_rate, yaw_acceleration)
    return np.array(rotation), np.array(omega), np.array(omega_dot)


def attitude_rows_from_thrust_vector(
    n: Vec3, n_dot: Vec3, n_ddot: Vec3, yaw: float, yaw_rate: float, yaw_acceleration: float
) -> tuple[Mat3, Vec3, Vec3]:
    """:func:`attitude_from_thrust_vector` on Python floats: rows of ``R_d``, ``omega_d``, ``omega_dot_d``."""
    n = tuple(float(v) for v in n)
    if dot3(n, n) < 1e-18:
        raise ValueError("desired thrust vector is zero: the attitude is undefined")
    z, z_dot, z_ddot = _normalised_with_rates(n, tuple(float(v) for v in n_dot), tuple(float(v) for v in n_ddot))
    c, s = math.cos(yaw), math.sin(yaw)
    xc = (c, s, 0.0)
    xc_dot = (-s * yaw_rate, c * yaw_rate, 0.0)
    xc_ddot = (-s * yaw_acceleration - c * yaw_rate**2, c * yaw_acceleration - s * yaw_rate**2, 0.0)
    w = cross3(z, xc)
    if dot3(w, w) < 1e-18:
        raise ValueError("desired thrust axis is horizontal along the heading: the yaw is undefined")
    w_dot = _sum2(cross3(z_dot, xc), cross3(z, xc_dot))
    w_ddot = _sum3(cross3(z_ddot, xc), cross3(z_dot, xc_dot), cross3(z, xc_ddot))
    y, y_dot, y_ddot = _normalised_with_rates(w, w_dot, w_ddot)
    x = cross3(y, z)
    x_dot = _sum2(cross3(y_dot, z), cross3(y, z_dot))
    x_ddot = _sum3(cross3(y_ddot, z), cross3(y_dot, z_dot), cross3(y, z_ddot))
    # omega_d = vee(R^T R_dot) = [z.y_dot, x.z_dot, y.x_dot]
    omega = (dot3(z, y_dot), dot3(x, z_dot), dot3(y, x_dot))
    # omega_dot_d = vee(antisymmetric part of R^T R_ddot)
    omega_dot = (
        0.5 * (dot3(z, y_ddot) - dot3(y, z_ddot)),
        0.5 * (dot3(x, z_ddot) - dot3(z, x_ddot)),
        0.5 * (dot3(y, x_ddot) - dot3(x, y_ddot)),
    )
    rotation = ((x[0], y[0], z[0]), (x[1], y[1], z[1]), (x[2], y[2], z[2]))
    return rotation, omega, omega_dot


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
