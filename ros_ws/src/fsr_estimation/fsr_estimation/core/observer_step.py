"""The momentum observer per sample (compiled core, :mod:`fsr_sim.core.jit`).

Discrete recursion (all states zero at k = 0), with ``K_1 .. K_r`` from
:func:`fsr_estimation.estimator.filter_design.gain_chain`:

    gamma_1[k+1] = gamma_1[k] + K_1 ((q[k+1] - q[k]) - T_s (w_hat[k] + b_k))
    gamma_j[k+1] = gamma_j[k] + K_j T_s (gamma_{j-1}[k] - w_hat[k]),   j = 2..r
    w_hat[k+1]   = gamma_r[k+1]

with the generalised momentum ``q[k] = [m v[k]; M(eta[k-1]) eta_dot[k]]`` (``M`` of the earlier sample; ``q[0]``
uses ``M(eta[0])``) and ``b_k = [m g e3 + R_b,k f_b,k ; C_k^T eta_dot_k + Q_k^T tau_b,k]``, computed here in the
lean form ``M = Q^T I_b Q`` and ``C^T eta_dot = Q_dot^T I_b omega`` (the other term of ``C^T eta_dot``,
``-Q^T I_b (omega x omega)``, is zero). ``w_hat = [f_e (world NED) [N]; tau_e (Euler-angle coordinates) [N m]]``;
in the body frame (comparable with ``wrench_truth``): force ``R_b^T f_e``, torque ``Q(eta)^-T tau_e``.

The node's :class:`fsr_estimation.estimator.stamped.StampedEstimator`, the controller's compensation and the
in-process loop all run these functions; :class:`fsr_estimation.estimator.observer.MomentumObserver` is their
Python shell.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from fsr_sim.core.jit import jit, jit_inline
from fsr_sim.core.so3 import (
    Mat3,
    euler_rate_derivative_rows,
    euler_rate_rows,
    euler_rate_transpose_solve3,
    euler_rates3,
    euler_zyx_from_rotation_rows,
    mat_t_mat3,
    mat_t_vec3,
    mat_vec3,
    matrix_rows,
    rotation_rows_from_euler_zyx,
)


class ObserverParams(NamedTuple):
    mass: float  # model mass [kg]
    inertia: np.ndarray  # (3, 3) model inertia [kg m^2], body
    gains: np.ndarray  # (r,) K_1 .. K_r
    sample_time: float  # T_s [s]
    gravity: float  # [m/s^2]


class ObserverState(NamedTuple):
    gamma: np.ndarray  # (r, 6)
    estimate: np.ndarray  # (6,) w_hat[k]
    previous_momentum: np.ndarray  # (6,) q[k]
    previous_rate: np.ndarray  # (6,) b_k
    mass_matrix: np.ndarray  # (3, 3) M(eta[k])
    rotation: np.ndarray  # (3, 3) R_b of the latest sample
    euler: np.ndarray  # (2,) roll, pitch of the latest sample [rad]
    samples: np.ndarray  # (1,) samples taken since the last reset


def new_observer_state(order: int) -> ObserverState:
    """A state at sample k = 0 for a filter of order ``order``."""
    return ObserverState(np.zeros((order, 6)), np.zeros(6), np.zeros(6), np.zeros(6), np.zeros((3, 3)), np.eye(3),
                         np.zeros(2), np.zeros(1))


@jit_inline
def reset_observer(state: ObserverState) -> None:
    """Forget all history: the next update is sample k = 0 again (estimate zero)."""
    state.gamma[:] = 0.0
    state.estimate[:] = 0.0
    state.samples[0] = 0.0


@jit
def _put_rows(array, rows: Mat3) -> None:  # noqa: ANN001
    for i in range(3):
        for j in range(3):
            array[i, j] = rows[i][j]


@jit_inline
def _store_sample_terms(params: ObserverParams, state: ObserverState, eta: tuple, eta_dot: tuple,
                        force_body: tuple, torque_body: tuple) -> None:
    """b_k, M(eta[k]) and R_b,k for the next step and for :func:`wrench_body`."""
    phi, theta, psi = eta
    rotation = rotation_rows_from_euler_zyx(phi, theta, psi)
    rate = euler_rate_rows(phi, theta)
    rate_dot = euler_rate_derivative_rows(phi, theta, eta_dot[0], eta_dot[1])
    inertia = matrix_rows(params.inertia)
    inertia_omega = mat_vec3(inertia, mat_vec3(rate, eta_dot))  # I_b omega
    fx, fy, fz = mat_vec3(rotation, force_body)
    cx, cy, cz = mat_t_vec3(rate_dot, inertia_omega)  # C^T eta_dot
    tx, ty, tz = mat_t_vec3(rate, torque_body)  # Q^T tau_b
    b = state.previous_rate
    b[0], b[1], b[2] = fx, fy, fz + params.mass * params.gravity
    b[3], b[4], b[5] = cx + tx, cy + ty, cz + tz
    _put_rows(state.mass_matrix, mat_t_mat3(rate, mat_t_mat3(inertia, rate)))  # Q^T (I_b Q), I_b symmetric
    _put_rows(state.rotation, rotation)
    state.euler[0], state.euler[1] = phi, theta


@jit_inline
def observer_update(params: ObserverParams, state: ObserverState, velocity_world: tuple, eta: tuple,
                    eta_dot: tuple, force_body: tuple, torque_body: tuple) -> None:
    """Take sample k (velocity world [m/s], ZYX Euler angles [rad] and rates [rad/s], the actuator wrench of
    the sample, body [N, N m], used from the next sample on); ``state.estimate`` is then ``w_hat[k]``."""
    mass = params.mass
    mx, my, mz = mass * velocity_world[0], mass * velocity_world[1], mass * velocity_world[2]
    if state.samples[0] == 0.0:
        _store_sample_terms(params, state, eta, eta_dot, force_body, torque_body)  # q[0] uses M(eta[0])
    ax, ay, az = mat_vec3(matrix_rows(state.mass_matrix), eta_dot)  # M(eta[k-1]) eta_dot[k]
    if state.samples[0] != 0.0:
        momentum = (mx, my, mz, ax, ay, az)
        ts, gains, gamma, previous = params.sample_time, params.gains, state.gamma, state.estimate
        order = gamma.shape[0]
        for j in range(order - 1, 0, -1):  # last to first: each uses its predecessor's previous value
            gain = gains[j] * ts
            for i in range(6):
                gamma[j, i] = gamma[j, i] + gain * (gamma[j - 1, i] - previous[i])
        for i in range(6):
            residual = (momentum[i] - state.previous_momentum[i]) - ts * (previous[i] + state.previous_rate[i])
            gamma[0, i] = gamma[0, i] + gains[0] * residual
        for i in range(6):
            previous[i] = gamma[order - 1, i]
        _store_sample_terms(params, state, eta, eta_dot, force_body, torque_body)
    q = state.previous_momentum
    q[0], q[1], q[2], q[3], q[4], q[5] = mx, my, mz, ax, ay, az
    state.samples[0] += 1.0


@jit_inline
def wrench_body(params: ObserverParams, state: ObserverState) -> tuple:
    """The latest estimate in body FRD: (force ``R_b^T f_e`` [N], torque ``Q^-T tau_e`` [N m])."""
    w = state.estimate
    force = mat_t_vec3(matrix_rows(state.rotation), (w[0], w[1], w[2]))
    torque = euler_rate_transpose_solve3(state.euler[0], state.euler[1], (w[3], w[4], w[5]))
    return force, torque


@jit_inline
def mass_estimate(params: ObserverParams, state: ObserverState) -> float:
    """``m_model + f_e,z / g`` [kg]."""
    return params.mass + state.estimate[2] / params.gravity


@jit
def euler_inputs(rotation: Mat3, angular_velocity_body: tuple) -> tuple:
    """(ZYX Euler angles [rad], their rates [rad/s]) of an attitude and body angular velocity: the observer's
    inputs from a state."""
    eta = euler_zyx_from_rotation_rows(rotation)
    return eta, euler_rates3(eta[0], eta[1], angular_velocity_body)


@jit_inline
def estimate_from_state(params: ObserverParams, state: ObserverState, rotation: Mat3, velocity_world: tuple,
                        angular_velocity_body: tuple, force_body: tuple, torque_body: tuple, out) -> None:  # noqa: ANN001
    """One sample from a state (``R``, velocity world, angular velocity body) and the command for it; ``out``
    (7,): the estimate's body force [N], body torque [N m] and mass [kg] (what ``wrench_estimate`` and
    ``mass_estimate`` carry)."""
    eta, eta_dot = euler_inputs(rotation, angular_velocity_body)
    observer_update(params, state, velocity_world, eta, eta_dot, force_body, torque_body)
    force, torque = wrench_body(params, state)
    out[0], out[1], out[2] = force
    out[3], out[4], out[5] = torque
    out[6] = mass_estimate(params, state)
