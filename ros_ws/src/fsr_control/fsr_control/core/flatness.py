"""Desired attitude and its rates from a thrust vector and a heading (compiled core).

For perfect tracking the geometric controller's desired attitude is built from a thrust-axis vector ``n``
(world NED, any positive scale; ``n = -a`` with ``a`` the law's desired force):

    z_d = n / |n|,  y_d = (z_d x x_c) / |z_d x x_c|,  x_d = y_d x z_d,  x_c = [cos psi_d, sin psi_d, 0],

``R_d = [x_d y_d z_d]``; differentiating with ``n_dot``, ``n_ddot`` and the heading's rate and acceleration
gives ``S(omega_d) = R_d^T R_d_dot`` and ``omega_dot_d = vee(skew part of R_d^T R_d_ddot)`` analytically. For a
unit vector ``u = w / |w|``: ``u_dot = (w_dot - u (u.w_dot)) / |w|`` and
``u_ddot = (w_ddot - 2 u_dot (u.w_dot) - u (u_dot.w_dot + u.w_ddot)) / |w|``.
"""

from __future__ import annotations

import math

from fsr_sim.core.jit import jit
from fsr_sim.core.so3 import IDENTITY, Vec3, cross3, dot3

ATTITUDE_OK, ZERO_THRUST, YAW_UNDEFINED = 0, 1, 2
ATTITUDE_ERRORS = {ZERO_THRUST: "desired thrust vector is zero: the attitude is undefined",
                   YAW_UNDEFINED: "desired thrust axis is horizontal along the heading: the yaw is undefined"}


@jit
def _sum2(a: Vec3, b: Vec3) -> Vec3:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@jit
def _sum3(a: Vec3, b: Vec3, c: Vec3) -> Vec3:
    """``a + 2 b + c`` (product rule of a second derivative)."""
    return (a[0] + 2.0 * b[0] + c[0], a[1] + 2.0 * b[1] + c[1], a[2] + 2.0 * b[2] + c[2])


@jit
def _normalised_with_rates(w: Vec3, w_dot: Vec3, w_ddot: Vec3) -> tuple:
    """``u = w/|w|`` and its first two time derivatives."""
    inv = 1.0 / math.sqrt(dot3(w, w))
    u = (w[0] * inv, w[1] * inv, w[2] * inv)
    uw = dot3(u, w_dot)
    u_dot = ((w_dot[0] - u[0] * uw) * inv, (w_dot[1] - u[1] * uw) * inv, (w_dot[2] - u[2] * uw) * inv)
    second = dot3(u_dot, w_dot) + dot3(u, w_ddot)
    u_ddot = ((w_ddot[0] - 2.0 * u_dot[0] * uw - u[0] * second) * inv,
              (w_ddot[1] - 2.0 * u_dot[1] * uw - u[1] * second) * inv,
              (w_ddot[2] - 2.0 * u_dot[2] * uw - u[2] * second) * inv)
    return u, u_dot, u_ddot


@jit
def attitude_from_thrust_vector(n: Vec3, n_dot: Vec3, n_ddot: Vec3, yaw: float, yaw_rate: float,
                                yaw_acceleration: float) -> tuple:
    """``(status, R_d rows, omega_d, omega_dot_d)`` (module docstring); yaw [rad], yaw_rate [rad/s],
    yaw_acceleration [rad/s^2]; rates in the desired body frame. ``status`` is ``ZERO_THRUST`` when ``n``
    vanishes (free fall) and ``YAW_UNDEFINED`` when it is horizontal along the heading (the other outputs are
    then meaningless)."""
    zero = (0.0, 0.0, 0.0)
    if dot3(n, n) < 1e-18:
        return ZERO_THRUST, IDENTITY, zero, zero
    z, z_dot, z_ddot = _normalised_with_rates(n, n_dot, n_ddot)
    c, s = math.cos(yaw), math.sin(yaw)
    rate_sq = yaw_rate * yaw_rate
    xc = (c, s, 0.0)
    xc_dot = (-s * yaw_rate, c * yaw_rate, 0.0)
    xc_ddot = (-s * yaw_acceleration - c * rate_sq, c * yaw_acceleration - s * rate_sq, 0.0)
    w = cross3(z, xc)
    if dot3(w, w) < 1e-18:
        return YAW_UNDEFINED, IDENTITY, zero, zero
    w_dot = _sum2(cross3(z_dot, xc), cross3(z, xc_dot))
    w_ddot = _sum3(cross3(z_ddot, xc), cross3(z_dot, xc_dot), cross3(z, xc_ddot))
    y, y_dot, y_ddot = _normalised_with_rates(w, w_dot, w_ddot)
    x = cross3(y, z)
    x_dot = _sum2(cross3(y_dot, z), cross3(y, z_dot))
    x_ddot = _sum3(cross3(y_ddot, z), cross3(y_dot, z_dot), cross3(y, z_ddot))
    omega = (dot3(z, y_dot), dot3(x, z_dot), dot3(y, x_dot))  # vee(R^T R_dot)
    omega_dot = (
        0.5 * (dot3(z, y_ddot) - dot3(y, z_ddot)),
        0.5 * (dot3(x, z_ddot) - dot3(z, x_ddot)),
        0.5 * (dot3(y, x_ddot) - dot3(x, y_ddot)),
    )
    rotation = ((x[0], y[0], z[0]), (x[1], y[1], z[1]), (x[2], y[2], z[2]))
    return ATTITUDE_OK, rotation, omega, omega_dot
