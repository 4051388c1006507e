"""Rotations and 3-vectors on floats: the single-sample algebra of the flight core (compiled, :mod:`.jit`).

Conventions (the one place fsr states them; ``docs/model.md``):

* ``R`` (``rotation``) maps body (FRD) coordinates to world (NED) coordinates: ``v_world = R v_body``.
* Quaternions are scalar-last ``[x, y, z, w]`` (ROS ``geometry_msgs/Quaternion`` and scipy order), active
  rotation, the same map as ``R``.
* Euler angles ``eta = [phi, theta, psi]`` (roll, pitch, yaw, rad) are ZYX: ``R = Rz(psi) Ry(theta) Rx(phi)``.
* ``Q(eta)`` maps Euler-angle rates to body angular velocity, ``omega_body = Q(eta) eta_dot``, with
  ``Q = [[1, 0, -s_th], [0, c_ph, c_th s_ph], [0, -s_ph, c_th c_ph]]``.
* ``S(v)`` is the skew matrix with ``S(v) w = v x w`` and ``vee(S(v)) = v``.

A 3-vector is a tuple of 3 floats, a 3x3 matrix a tuple of its 3 row tuples (``Vec3``, ``Mat3``):
values that live in registers, not arrays (:func:`put3`, :func:`put_rows3` write them into a row laid out by
index constants). Whole logs use the vectorised functions of
:mod:`fsr_sim.model.so3`, built on these.
"""

from __future__ import annotations

import math

from fsr_sim.core.jit import jit

Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]  # rows
IDENTITY: Mat3 = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


@jit
def cross3(a: Vec3, b: Vec3) -> Vec3:
    """``a x b``."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return (a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0)


@jit
def dot3(a: Vec3, b: Vec3) -> float:
    """``a . b``."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@jit
def add3(a: Vec3, b: Vec3) -> Vec3:
    """``a + b``."""
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@jit
def sub3(a: Vec3, b: Vec3) -> Vec3:
    """``a - b``."""
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@jit
def scale3(s: float, a: Vec3) -> Vec3:
    """``s a``."""
    return (s * a[0], s * a[1], s * a[2])


@jit
def mat_vec3(m: Mat3, v: Vec3) -> Vec3:
    """``M v``."""
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = m
    x, y, z = v
    return (m00 * x + m01 * y + m02 * z, m10 * x + m11 * y + m12 * z, m20 * x + m21 * y + m22 * z)


@jit
def mat_t_vec3(m: Mat3, v: Vec3) -> Vec3:
    """``M^T v``."""
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = m
    x, y, z = v
    return (m00 * x + m10 * y + m20 * z, m01 * x + m11 * y + m21 * z, m02 * x + m12 * y + m22 * z)


@jit
def mat_t_mat3(a: Mat3, b: Mat3) -> Mat3:
    """``A^T B`` (e.g. ``R_b^T R_d``)."""
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = a
    (b00, b01, b02), (b10, b11, b12), (b20, b21, b22) = b
    return (
        (a00 * b00 + a10 * b10 + a20 * b20, a00 * b01 + a10 * b11 + a20 * b21, a00 * b02 + a10 * b12 + a20 * b22),
        (a01 * b00 + a11 * b10 + a21 * b20, a01 * b01 + a11 * b11 + a21 * b21, a01 * b02 + a11 * b12 + a21 * b22),
        (a02 * b00 + a12 * b10 + a22 * b20, a02 * b01 + a12 * b11 + a22 * b21, a02 * b02 + a12 * b12 + a22 * b22),
    )


@jit
def matrix_rows(array) -> Mat3:  # noqa: ANN001 - a float64 array of shape (3, 3)
    """The rows of a (3, 3) array as a :data:`Mat3`."""
    return ((array[0, 0], array[0, 1], array[0, 2]), (array[1, 0], array[1, 1], array[1, 2]),
            (array[2, 0], array[2, 1], array[2, 2]))


@jit
def rotation_rows_from_quaternion(x: float, y: float, z: float, w: float) -> Mat3:
    """Rows of the rotation matrix of the quaternion ``[x, y, z, w]`` (normalised here)."""
    scale = 2.0 / (x * x + y * y + z * z + w * w)
    xx, yy, zz = scale * x * x, scale * y * y, scale * z * z
    xy, xz, yz = scale * x * y, scale * x * z, scale * y * z
    wx, wy, wz = scale * w * x, scale * w * y, scale * w * z
    return (
        (1.0 - (yy + zz), xy - wz, xz + wy),
        (xy + wz, 1.0 - (xx + zz), yz - wx),
        (xz - wy, yz + wx, 1.0 - (xx + yy)),
    )


@jit
def quaternion_from_rotation_rows(r: Mat3) -> tuple[float, float, float, float]:
    """Unit quaternion ``[x, y, z, w]`` with ``w >= 0`` of a rotation matrix (Shepperd's method)."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = r
    trace = r00 + r11 + r22
    if trace > 0.0:
        s = 2.0 * math.sqrt(1.0 + trace)
        x, y, z, w = (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s, 0.25 * s
    elif r00 > r11 and r00 > r22:
        s = 2.0 * math.sqrt(1.0 + r00 - r11 - r22)
        x, y, z, w = 0.25 * s, (r01 + r10) / s, (r02 + r20) / s, (r21 - r12) / s
    elif r11 > r22:
        s = 2.0 * math.sqrt(1.0 + r11 - r00 - r22)
        x, y, z, w = (r01 + r10) / s, 0.25 * s, (r12 + r21) / s, (r02 - r20) / s
    else:
        s = 2.0 * math.sqrt(1.0 + r22 - r00 - r11)
        x, y, z, w = (r02 + r20) / s, (r12 + r21) / s, 0.25 * s, (r10 - r01) / s
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if w < 0.0:
        norm = -norm
    return x / norm, y / norm, z / norm, w / norm


@jit
def rotation_rows_from_euler_zyx(phi: float, theta: float, psi: float) -> Mat3:
    """Rows of ``R = Rz(psi) Ry(theta) Rx(phi)``."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    cps, sps = math.cos(psi), math.sin(psi)
    return (
        (cps * cth, cps * sth * sph - sps * cph, cps * sth * cph + sps * sph),
        (sps * cth, sps * sth * sph + cps * cph, sps * sth * cph - cps * sph),
        (-sth, cth * sph, cth * cph),
    )


@jit
def yaw_rotation_rows(yaw: float) -> Mat3:
    """Rows of ``Rz(psi)``."""
    c, s = math.cos(yaw), math.sin(yaw)
    return ((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0))


@jit
def _clamp_unit(value: float) -> float:
    return -1.0 if value < -1.0 else (1.0 if value > 1.0 else value)


@jit
def euler_zyx_from_rotation_rows(rotation: Mat3) -> Vec3:
    """``(roll, pitch, yaw)`` [rad] of ``R``; pitch in [-pi/2, pi/2]. At pitch = +-pi/2 (gimbal lock) roll
    is 0 and the rest of the rotation is put in yaw."""
    (r00, r01, _), (r10, r11, _), (r20, r21, r22) = rotation
    if abs(r20) > 1.0 - 1e-12:
        return (0.0, math.asin(_clamp_unit(-r20)), math.atan2(-r01, r11))
    return (math.atan2(r21, r22), math.asin(_clamp_unit(-r20)), math.atan2(r10, r00))


@jit
def euler_rate_rows(phi: float, theta: float) -> Mat3:
    """Rows of ``Q(eta)`` (it does not depend on yaw)."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    return ((1.0, 0.0, -sth), (0.0, cph, cth * sph), (0.0, -sph, cth * cph))


@jit
def inverse_euler_rate_rows(phi: float, theta: float) -> Mat3:
    """Rows of ``Q(eta)^-1`` (``eta_dot = Q^-1 omega_body``): ``[[1, s_phi t_theta, c_phi t_theta], [0, c_phi,
    -s_phi], [0, s_phi / c_theta, c_phi / c_theta]]``, singular at pitch = +-90 deg."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth = math.cos(theta)
    tth = math.sin(theta) / cth
    return ((1.0, sph * tth, cph * tth), (0.0, cph, -sph), (0.0, sph / cth, cph / cth))


@jit
def euler_rates3(phi: float, theta: float, omega: Vec3) -> Vec3:
    """``eta_dot = Q(eta)^-1 omega_body`` [rad/s] (closed form); singular at pitch = +-pi/2."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    wx, wy, wz = omega
    turn = sph * wy + cph * wz
    return (wx + sth * turn / cth, cph * wy - sph * wz, turn / cth)


@jit
def euler_rate_transpose_solve3(phi: float, theta: float, torque: Vec3) -> Vec3:
    """``x`` with ``Q(eta)^T x = torque`` (``Q^-T tau``); singular at pitch = +-pi/2."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    t0, t1, t2 = torque
    b = (t2 + sth * t0) / cth
    return (t0, cph * t1 + sph * b, -sph * t1 + cph * b)


@jit
def euler_rate_derivative_rows(phi: float, theta: float, phi_dot: float, theta_dot: float) -> Mat3:
    """Rows of ``Q_dot(eta, eta_dot)``."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    return (
        (0.0, 0.0, -cth * theta_dot),
        (0.0, -sph * phi_dot, -sth * sph * theta_dot + cth * cph * phi_dot),
        (0.0, -cph * phi_dot, -sth * cph * theta_dot - cth * sph * phi_dot),
    )


@jit
def attitude_error3(rotation: Mat3, rotation_desired: Mat3) -> Vec3:
    """``e_R = vee(R_d^T R - R^T R_d) / 2`` (Lee et al.).

    With ``A = R_d^T R``: ``vee(A - A^T) / 2 = [A21 - A12, A02 - A20, A10 - A01] / 2`` and
    ``A_ij = sum_k Rd_ki R_kj``.
    """
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = rotation
    (d00, d01, d02), (d10, d11, d12), (d20, d21, d22) = rotation_desired
    a21 = d02 * r01 + d12 * r11 + d22 * r21
    a12 = d01 * r02 + d11 * r12 + d21 * r22
    a02 = d00 * r02 + d10 * r12 + d20 * r22
    a20 = d02 * r00 + d12 * r10 + d22 * r20
    a10 = d01 * r00 + d11 * r10 + d21 * r20
    a01 = d00 * r01 + d10 * r11 + d20 * r21
    return (0.5 * (a21 - a12), 0.5 * (a02 - a20), 0.5 * (a10 - a01))


@jit
def put3(out, at: int, v: Vec3) -> None:  # noqa: ANN001 - a float64 array
    """``v`` into ``out[at], out[at + 1], out[at + 2]`` (a row laid out by index constants)."""
    out[at], out[at + 1], out[at + 2] = v[0], v[1], v[2]


@jit
def put_rows3(out, at: int, rows: Mat3) -> None:  # noqa: ANN001 - a float64 array
    """The matrix ``rows`` into ``out[at:at + 9]``, row by row."""
    for i in range(3):
        put3(out, at + 3 * i, rows[i])
