"""SO(3) and Euler-angle math: the one place where fsr defines its rotation conventions.

Conventions (SPEC §2):

* ``R`` (``rotation``) maps body (FRD) coordinates to world (NED) coordinates: ``v_world = R v_body``.
* Quaternions are scalar-last ``[x, y, z, w]`` (ROS ``geometry_msgs/Quaternion`` and scipy order),
  active rotation, the same map as ``R``.
* Euler angles ``eta = [phi, theta, psi]`` (roll, pitch, yaw, rad) are ZYX:
  ``R = Rz(psi) Ry(theta) Rx(phi)``.
* ``Q(eta)`` maps Euler-angle rates to body angular velocity, ``omega_body = Q(eta) eta_dot``, with
  ``Q = [[1, 0, -s_th], [0, c_ph, c_th s_ph], [0, -s_ph, c_th c_ph]]``.
* ``S(v)`` is the skew matrix with ``S(v) w = v x w`` and ``vee(S(v)) = v``.

Functions whose argument is documented with a leading ``...`` accept stacked inputs (a whole log) and
are vectorised; the others are written for one sample and kept free of avoidable allocations because
they run in the 1 kHz loop.

Single-sample fast path: the functions ending in ``3`` or ``_rows`` (:func:`cross3`, :func:`dot3`,
:func:`mat_vec3`, :func:`mat_t_vec3`, :func:`mat_t_mat3`, :func:`attitude_error3`,
:func:`rotation_rows_from_quaternion`, :func:`rotation_rows_from_euler_zyx`,
:func:`euler_zyx_from_rotation_rows`, :func:`euler_rate_rows`, :func:`euler_rate_derivative_rows`) work
on Python floats: a 3-vector is a tuple (or list) of 3 floats and a 3x3 matrix a tuple of 3 row tuples
(``ndarray.tolist()`` gives both). On 3-vectors numpy spends ~1 us per call in overhead (``np.cross``
~10 us), plain float arithmetic ~0.1 us, so the 1 kHz code (plant, controllers, observer) uses these,
and the vectorised functions use them for their single-sample case: one definition of each formula.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]  # rows


# ----- single sample on Python floats (the 1 kHz loop) ------------------------------------------------
def cross3(a: Vec3, b: Vec3) -> Vec3:
    """``a x b`` for two 3-vectors of floats."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return (a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0)


def dot3(a: Vec3, b: Vec3) -> float:
    """``a . b`` for two 3-vectors of floats."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def mat_vec3(m: Mat3, v: Vec3) -> Vec3:
    """``M v`` for a 3x3 matrix given by its rows and a 3-vector."""
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = m
    x, y, z = v
    return (m00 * x + m01 * y + m02 * z, m10 * x + m11 * y + m12 * z, m20 * x + m21 * y + m22 * z)


def mat_t_vec3(m: Mat3, v: Vec3) -> Vec3:
    """``M^T v`` for a 3x3 matrix given by its rows and a 3-vector."""
    (m00, m01, m02), (m10, m11, m12), (m20, m21, m22) = m
    x, y, z = v
    return (m00 * x + m10 * y + m20 * z, m01 * x + m11 * y + m21 * z, m02 * x + m12 * y + m22 * z)


def mat_t_mat3(a: Mat3, b: Mat3) -> Mat3:
    """``A^T B`` for two 3x3 matrices given by their rows (e.g. ``R_b^T R_d``)."""
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = a
    (b00, b01, b02), (b10, b11, b12), (b20, b21, b22) = b
    return (
        (a00 * b00 + a10 * b10 + a20 * b20, a00 * b01 + a10 * b11 + a20 * b21, a00 * b02 + a10 * b12 + a20 * b22),
        (a01 * b00 + a11 * b10 + a21 * b20, a01 * b01 + a11 * b11 + a21 * b21, a01 * b02 + a11 * b12 + a21 * b22),
        (a02 * b00 + a12 * b10 + a22 * b20, a02 * b01 + a12 * b11 + a22 * b21, a02 * b02 + a12 * b12 + a22 * b22),
    )


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


def rotation_rows_from_euler_zyx(phi: float, theta: float, psi: float) -> Mat3:
    """Rows of ``R = Rz(psi) Ry(theta) Rx(phi)`` (see :func:`rotation_from_euler_zyx`)."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    cps, sps = math.cos(psi), math.sin(psi)
    return (
        (cps * cth, cps * sth * sph - sps * cph, cps * sth * cph + sps * sph),
        (sps * cth, sps * sth * sph + cps * cph, sps * sth * cph - cps * sph),
        (-sth, cth * sph, cth * cph),
    )


def euler_zyx_from_rotation_rows(rotation: Mat3) -> Vec3:
    """``(roll, pitch, yaw)`` [rad] of the rows of ``R`` (see :func:`euler_zyx_from_rotation`)."""
    (r00, r01, _), (r10, r11, _), (r20, r21, r22) = rotation
    if abs(r20) > 1.0 - 1e-12:  # gimbal lock: roll 0, the rest in yaw
        return (0.0, math.asin(max(-1.0, min(1.0, -r20))), math.atan2(-r01, r11))
    return (math.atan2(r21, r22), math.asin(max(-1.0, min(1.0, -r20))), math.atan2(r10, r00))


def euler_rate_rows(phi: float, theta: float) -> Mat3:
    """Rows of ``Q(eta)`` (see :func:`euler_rate_matrix`; it does not depend on yaw)."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    return ((1.0, 0.0, -sth), (0.0, cph, cth * sph), (0.0, -sph, cth * cph))


def euler_rates3(phi: float, theta: float, omega: Vec3) -> Vec3:
    """``eta_dot = Q(eta)^-1 omega_body`` [rad/s] on floats (closed form of :func:`euler_rates`; equal to it to
    rounding). Singular at pitch = +-pi/2 (``ZeroDivisionError``)."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    wx, wy, wz = omega
    turn = sph * wy + cph * wz
    return (wx + sth * turn / cth, cph * wy - sph * wz, turn / cth)


def euler_rate_transpose_solve3(phi: float, theta: float, torque: Vec3) -> Vec3:
    """``x`` with ``Q(eta)^T x = torque`` (``Q^-T tau``) on floats; singular at pitch = +-pi/2."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    t0, t1, t2 = torque
    b = (t2 + sth * t0) / cth
    return (t0, cph * t1 + sph * b, -sph * t1 + cph * b)


def euler_rate_derivative_rows(phi: float, theta: float, phi_dot: float, theta_dot: float) -> Mat3:
    """Rows of ``Q_dot(eta, eta_dot)`` (see :func:`euler_rate_matrix_derivative`)."""
    cph, sph = math.cos(phi), math.sin(phi)
    cth, sth = math.cos(theta), math.sin(theta)
    return (
        (0.0, 0.0, -cth * theta_dot),
        (0.0, -sph * phi_dot, -sth * sph * theta_dot + cth * cph * phi_dot),
        (0.0, -cph * phi_dot, -sth * cph * theta_dot - cth * sph * phi_dot),
    )


def attitude_error3(rotation: Mat3, rotation_desired: Mat3) -> Vec3:
    """``e_R = vee(R_d^T R - R^T R_d) / 2`` (see :func:`attitude_error`) for rows of ``R`` and ``R_d``.

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


# ----- vectorised (whole logs) and general single-sample functions ------------------------------------


def _as_vector3(value: ArrayLike, name: str) -> FloatArray:
    array = np.asarray(value, dtype=float)
    if array.shape[-1:] != (3,):
        raise ValueError(f"Expected {name} with shape (..., 3), got array of shape {array.shape}")
    return array


def skew(vector: ArrayLike) -> FloatArray:
    """Skew-symmetric matrix ``S(v)`` with ``S(v) w = v x w``.

    vector: array-like, shape (..., 3). Returns shape (..., 3, 3).
    """
    v = _as_vector3(vector, "vector")
    if v.ndim == 1:
        x, y, z = v.tolist()
        return np.array(((0.0, -z, y), (z, 0.0, -x), (-y, x, 0.0)))
    zero = np.zeros(v.shape[:-1])
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return np.stack(
        (
            np.stack((zero, -z, y), axis=-1),
            np.stack((z, zero, -x), axis=-1),
            np.stack((-y, x, zero), axis=-1),
        ),
        axis=-2,
    )


def vee(matrix: ArrayLike) -> FloatArray:
    """Inverse of :func:`skew`: ``vee(S) = [S32, S13, S21]`` for a skew-symmetric ``S``, shape (..., 3, 3)."""
    m = np.asarray(matrix, dtype=float)
    if m.shape[-2:] != (3, 3):
        raise ValueError(f"Expected matrix with shape (..., 3, 3), got array of shape {m.shape}")
    if m.ndim == 2:
        return np.array((m[2, 1], m[0, 2], m[1, 0]))
    return np.stack((m[..., 2, 1], m[..., 0, 2], m[..., 1, 0]), axis=-1)


def rotation_from_euler_zyx(eta: ArrayLike) -> FloatArray:
    """Rotation matrix ``R = Rz(psi) Ry(theta) Rx(phi)`` (body FRD -> world NED).

    eta: array-like, shape (..., 3), ``[roll, pitch, yaw]`` in rad. Returns shape (..., 3, 3).
    """
    e = _as_vector3(eta, "eta")
    if e.ndim == 1:
        return np.array(rotation_rows_from_euler_zyx(*e.tolist()))
    cph, sph = np.cos(e[..., 0]), np.sin(e[..., 0])
    cth, sth = np.cos(e[..., 1]), np.sin(e[..., 1])
    cps, sps = np.cos(e[..., 2]), np.sin(e[..., 2])
    return np.stack(
        (
            np.stack((cps * cth, cps * sth * sph - sps * cph, cps * sth * cph + sps * sph), axis=-1),
            np.stack((sps * cth, sps * sth * sph + cps * cph, sps * sth * cph - cps * sph), axis=-1),
            np.stack((-sth, cth * sph, cth * cph), axis=-1),
        ),
        axis=-2,
    )


def euler_zyx_from_rotation(rotation: ArrayLike) -> FloatArray:
    """ZYX Euler angles ``[roll, pitch, yaw]`` (rad) of ``R``; pitch in [-pi/2, pi/2].

    rotation: array-like, shape (..., 3, 3). Returns shape (..., 3). At pitch = +-pi/2 (gimbal lock)
    roll is set to 0 and the remaining rotation is put in yaw.
    """
    r = np.asarray(rotation, dtype=float)
    if r.shape[-2:] != (3, 3):
        raise ValueError(f"Expected rotation matrix with shape (..., 3, 3), got array of shape {r.shape}")
    if r.ndim == 2:
        return np.array(euler_zyx_from_rotation_rows(r.tolist()))
    pitch = np.arcsin(np.clip(-r[..., 2, 0], -1.0, 1.0))
    roll = np.arctan2(r[..., 2, 1], r[..., 2, 2])
    yaw = np.arctan2(r[..., 1, 0], r[..., 0, 0])
    locked = np.abs(r[..., 2, 0]) > 1.0 - 1e-12
    if np.any(locked):
        roll = np.where(locked, 0.0, roll)
        yaw = np.where(locked, np.arctan2(-r[..., 0, 1], r[..., 1, 1]), yaw)
    return np.stack((roll, pitch, yaw), axis=-1)


def euler_rate_matrix(eta: ArrayLike) -> FloatArray:
    """``Q(eta)`` with ``omega_body = Q(eta) eta_dot`` (SPEC §2). eta: shape (..., 3) -> (..., 3, 3)."""
    e = _as_vector3(eta, "eta")
    if e.ndim == 1:
        return np.array(euler_rate_rows(float(e[0]), float(e[1])))
    cph, sph = np.cos(e[..., 0]), np.sin(e[..., 0])
    cth, sth = np.cos(e[..., 1]), np.sin(e[..., 1])
    one, zero = np.ones_like(cph), np.zeros_like(cph)
    return np.stack(
        (
            np.stack((one, zero, -sth), axis=-1),
            np.stack((zero, cph, cth * sph), axis=-1),
            np.stack((zero, -sph, cth * cph), axis=-1),
        ),
        axis=-2,
    )


def euler_rates(eta: ArrayLike, angular_velocity_body: ArrayLike) -> FloatArray:
    """``eta_dot = Q(eta)^-1 omega_body`` [rad/s]: ZYX Euler-angle rates from the body angular velocity.

    eta: shape (..., 3) [rad]; angular_velocity_body: shape (..., 3) [rad/s]. Returns shape (..., 3).
    Singular at pitch = +-pi/2 (gimbal lock: ``numpy.linalg.LinAlgError``).
    """
    omega = np.asarray(angular_velocity_body, dtype=float)
    return np.linalg.solve(euler_rate_matrix(eta), omega[..., None])[..., 0]


def euler_rate_matrix_derivative(eta: ArrayLike, eta_dot: ArrayLike) -> FloatArray:
    """Time derivative ``Q_dot(eta, eta_dot)`` of :func:`euler_rate_matrix`. Shapes (..., 3) -> (..., 3, 3)."""
    e = _as_vector3(eta, "eta")
    ed = _as_vector3(eta_dot, "eta_dot")
    if e.ndim == 1 and ed.ndim == 1:
        return np.array(euler_rate_derivative_rows(float(e[0]), float(e[1]), float(ed[0]), float(ed[1])))
    cph, sph = np.cos(e[..., 0]), np.sin(e[..., 0])
    cth, sth = np.cos(e[..., 1]), np.sin(e[..., 1])
    dph, dth = ed[..., 0], ed[..., 1]
    zero = np.zeros_like(cph)
    return np.stack(
        (
            np.stack((zero, zero, -cth * dth), axis=-1),
            np.stack((zero, -sph * dph, -sth * sph * dth + cth * cph * dph), axis=-1),
            np.stack((zero, -cph * dph, -sth * cph * dth - cth * sph * dph), axis=-1),
        ),
        axis=-2,
    )


def euler_mass_matrix(eta: ArrayLike, inertia: ArrayLike) -> FloatArray:
    """``M(eta) = Q^T I_b Q`` (kg m^2), the rotational inertia in Euler-angle coordinates."""
    q = euler_rate_matrix(eta)
    return np.swapaxes(q, -1, -2) @ np.asarray(inertia, dtype=float) @ q


def euler_coriolis_matrix(eta: ArrayLike, eta_dot: ArrayLike, inertia: ArrayLike) -> FloatArray:
    """``C(eta, eta_dot) = Q^T S(Q eta_dot) I_b Q + Q^T I_b Q_dot`` (SPEC §2), shape (..., 3, 3)."""
    inertia = np.asarray(inertia, dtype=float)
    q = euler_rate_matrix(eta)
    q_dot = euler_rate_matrix_derivative(eta, eta_dot)
    q_t = np.swapaxes(q, -1, -2)
    omega = (q @ np.asarray(eta_dot, dtype=float)[..., None])[..., 0]
    return q_t @ skew(omega) @ inertia @ q + q_t @ inertia @ q_dot


def rotation_from_quaternion(quaternion: ArrayLike) -> FloatArray:
    """Rotation matrix of a unit quaternion ``[x, y, z, w]`` (normalised here). Shape (4,) -> (3, 3)."""
    values = quaternion.tolist() if isinstance(quaternion, np.ndarray) else quaternion
    x, y, z, w = (float(v) for v in values)
    return np.array(rotation_rows_from_quaternion(x, y, z, w))


def rotations_from_quaternions(quaternions: ArrayLike) -> FloatArray:
    """Rotation matrices of unit quaternions ``[x, y, z, w]`` (normalised here), shape (n, 4) -> (n, 3, 3).

    The same arithmetic as :func:`rotation_rows_from_quaternion`, over whole logs at once.
    """
    q = np.asarray(quaternions, dtype=float)
    x, y, z, w = q.T
    scale = 2.0 / (x * x + y * y + z * z + w * w)
    xx, yy, zz = scale * x * x, scale * y * y, scale * z * z
    xy, xz, yz = scale * x * y, scale * x * z, scale * y * z
    wx, wy, wz = scale * w * x, scale * w * y, scale * w * z
    rows = (
        (1.0 - (yy + zz), xy - wz, xz + wy),
        (xy + wz, 1.0 - (xx + zz), yz - wx),
        (xz - wy, yz + wx, 1.0 - (xx + yy)),
    )
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=1)


def quaternion_from_rotation(rotation: ArrayLike) -> FloatArray:
    """Unit quaternion ``[x, y, z, w]`` with ``w >= 0`` of a rotation matrix (Shepperd's method)."""
    r = np.asarray(rotation, dtype=float)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    if trace > 0.0:
        s = 2.0 * np.sqrt(1.0 + trace)
        q = np.array(((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s))
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = np.array((0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s))
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * np.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = np.array(((r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s))
    else:
        s = 2.0 * np.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = np.array(((r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s, (r[1, 0] - r[0, 1]) / s))
    q /= np.linalg.norm(q)
    return -q if q[3] < 0.0 else q


def rotation_exp(rotation_vector: ArrayLike) -> FloatArray:
    """Exponential map (Rodrigues): ``exp(S(phi))`` for a rotation vector ``phi`` (rad), shape (3,)."""
    phi = np.asarray(rotation_vector, dtype=float)
    angle = float(np.linalg.norm(phi))
    s = skew(phi)
    if angle < 1e-8:
        return np.eye(3) + s + 0.5 * (s @ s)
    return np.eye(3) + (np.sin(angle) / angle) * s + ((1.0 - np.cos(angle)) / angle**2) * (s @ s)


def rotation_log(rotation: ArrayLike) -> tuple[FloatArray, float]:
    """Axis and angle of ``R`` (``R = exp(angle S(axis))``), angle in [0, pi]; axis = e_x for angle 0."""
    r = np.asarray(rotation, dtype=float)
    cos_angle = np.clip(0.5 * (np.trace(r) - 1.0), -1.0, 1.0)
    angle = float(np.arccos(cos_angle))
    if angle < 1e-12:
        return np.array((1.0, 0.0, 0.0)), 0.0
    if np.pi - angle < 1e-6:
        # Near pi the antisymmetric part vanishes: take the axis from the symmetric part.
        b = 0.5 * (r + np.eye(3))
        axis = b[:, int(np.argmax(np.diag(b)))]
        return axis / np.linalg.norm(axis), angle
    axis = vee(r - r.T) / (2.0 * np.sin(angle))
    return axis / np.linalg.norm(axis), angle


def project_to_so3(matrix: ArrayLike) -> FloatArray:
    """Closest rotation matrix (Frobenius norm) to a 3x3 matrix, by SVD with det = +1."""
    u, _, vt = np.linalg.svd(np.asarray(matrix, dtype=float))
    d = np.sign(np.linalg.det(u @ vt))
    return u @ np.diag((1.0, 1.0, d)) @ vt


def attitude_error(rotation: ArrayLike, rotation_desired: ArrayLike) -> FloatArray:
    """Geometric attitude error ``e_R = vee(R_d^T R - R^T R_d) / 2`` (Lee et al.), shape (3,)."""
    r = np.asarray(rotation, dtype=float).tolist()
    rd = np.asarray(rotation_desired, dtype=float).tolist()
    return np.array(attitude_error3(r, rd))


def relative_rotation_angles(rotation_desired: ArrayLike, rotation: ArrayLike) -> FloatArray:
    """Angle [rad] of ``R_d^T R`` for whole logs, (n, 3, 3) each -> (n,), in [0, pi].

    ``atan2(|vee(E - E^T)| / 2, (tr E - 1) / 2)`` with ``E = R_d^T R``: accurate to rounding near 0 (where
    ``acos`` of the trace or of a quaternion product turns 1e-16 rounding into ~1e-6 deg) and near pi.
    """
    e = np.einsum("kji,kjl->kil", np.asarray(rotation_desired, dtype=float), np.asarray(rotation, dtype=float))
    sin_part = 0.5 * np.sqrt((e[:, 2, 1] - e[:, 1, 2]) ** 2 + (e[:, 0, 2] - e[:, 2, 0]) ** 2
                             + (e[:, 1, 0] - e[:, 0, 1]) ** 2)
    cos_part = 0.5 * (e[:, 0, 0] + e[:, 1, 1] + e[:, 2, 2] - 1.0)
    return np.arctan2(sin_part, cos_part)
