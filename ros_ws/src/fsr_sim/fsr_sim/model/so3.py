"""SO(3) and Euler-angle math on arrays: whole logs (vectorised with numpy) and the Python API.

The conventions and the single-sample functions of the per-step code (on floats, compiled) are in
:mod:`fsr_sim.core.so3`. The functions here take arrays, with a leading ``...`` when they accept stacked
inputs (a whole log; one sample is the same code on shape (3,) or (3, 3)); those without one call the core's
single-sample function. Reading a scenario (initial attitude, waypoints) uses only numpy here, so that a
process that does not fly (``fsr-analyze``, ``fsr-fly`` starting a graph) does not start numba's compiler.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fsr_sim.core.so3 import (
    Vec3,
    attitude_error3,
    matrix_rows,
    quaternion_from_rotation_rows,
    rotation_rows_from_quaternion,
)

FloatArray = NDArray[np.float64]


def _as_vector3(value: ArrayLike, name: str) -> FloatArray:
    array = np.asarray(value, dtype=float)
    if array.shape[-1:] != (3,):
        raise ValueError(f"Expected {name} with shape (..., 3), got array of shape {array.shape}")
    return array


def vector3(values: ArrayLike) -> Vec3:
    """A 3-vector as the compiled core takes it (:data:`~fsr_sim.core.so3.Vec3`: a tuple of Python floats)."""
    x, y, z = np.asarray(values, dtype=float).tolist()
    return x, y, z


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
    pitch = np.arcsin(np.clip(-r[..., 2, 0], -1.0, 1.0))
    roll = np.arctan2(r[..., 2, 1], r[..., 2, 2])
    yaw = np.arctan2(r[..., 1, 0], r[..., 0, 0])
    locked = np.abs(r[..., 2, 0]) > 1.0 - 1e-12
    if np.any(locked):
        roll = np.where(locked, 0.0, roll)
        yaw = np.where(locked, np.arctan2(-r[..., 0, 1], r[..., 1, 1]), yaw)
    return np.stack((roll, pitch, yaw), axis=-1)


def euler_rate_matrix(eta: ArrayLike) -> FloatArray:
    """``Q(eta)`` with ``omega_body = Q(eta) eta_dot`` (docs/model.md §2). eta: shape (..., 3) -> (..., 3, 3)."""
    e = _as_vector3(eta, "eta")
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
    """``C(eta, eta_dot) = Q^T S(Q eta_dot) I_b Q + Q^T I_b Q_dot`` (docs/model.md §2), shape (..., 3, 3)."""
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
    return np.array(quaternion_from_rotation_rows(matrix_rows(np.ascontiguousarray(rotation, dtype=float))))


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
    return np.array(attitude_error3(matrix_rows(np.ascontiguousarray(rotation, dtype=float)),
                                    matrix_rows(np.ascontiguousarray(rotation_desired, dtype=float))))


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
