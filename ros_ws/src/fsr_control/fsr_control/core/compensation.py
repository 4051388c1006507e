"""Disturbance compensation per step (compiled core): the controller's own momentum observer, its contact gate
and the estimate's rates. Timing, model and contact rule are explained in :mod:`fsr_control.compensation`.

Per step: :func:`compensation_estimate` before the law (the estimate of the previous stamp, or an inactive
:class:`~fsr_control.core.law_terms.Compensation` when gated), :func:`compensation_record` after the allocation
(state and commanded wrench of this stamp).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from fsr_control.core.law_terms import NO_COMPENSATION, Compensation
from fsr_estimation.core.observer_step import ObserverParams, ObserverState, observer_update, reset_observer
from fsr_sim.core.jit import jit_inline, zeroed_record
from fsr_sim.core.so3 import (
    Mat3,
    Vec3,
    euler_zyx_from_rotation_rows,
    inverse_euler_rate_rows,
    mat_t_vec3,
    mat_vec3,
    matrix_rows,
)
from fsr_sim.core.surfaces import Surfaces, in_contact

PERIOD_TOLERANCE = 0.01  # relative: a stamp step further than this from the control period is a gap

COMPENSATION_MEMORY = np.dtype([
    ("history_count", np.int64),  # force estimates kept in CompensationState.history (0 .. 3)
    ("has_last_stamp", np.bool_),
    ("last_stamp", np.float64),  # [s]
    ("ready", np.bool_),  # the observer has a recorded sample of the previous stamp (its estimate may be used)
    ("contact", np.bool_),  # the vehicle was on a surface at the last stamp (the estimate is gated)
    ("compensated_steps", np.int64),  # steps with an estimate cancelled
    ("contact_steps", np.int64),  # steps gated by contact
    ("gaps", np.int64),  # stamp steps further than PERIOD_TOLERANCE from the control period
], align=True)
"""The fields of ``CompensationState.memory``, read and written in place as ``memory[0].ready``."""


def new_compensation_memory() -> np.ndarray:
    """A zeroed :data:`COMPENSATION_MEMORY` record (1-element record array)."""
    return zeroed_record(COMPENSATION_MEMORY)


class CompensationParams(NamedTuple):
    enabled: bool  # controller.compensation: estimate
    observer: ObserverParams  # on the controller's nominal model
    period: float  # control period [s]
    smooth: bool  # r >= 2: the estimate's second difference is used
    surfaces: Surfaces  # the contact rule's geometry
    measured: bool  # the observer takes the rotors' measured wrench (rotor_state) instead of the commanded one
    rates: bool  # the estimate's rates are handed to the law (False: zero, R_d's rates the reference's alone)


class CompensationState(NamedTuple):
    observer: ObserverState
    history: np.ndarray  # (3, 3) the last force estimates [N], oldest first
    rate_inverse: np.ndarray  # (3, 3) Q^-1 of the last recorded sample
    memory: np.ndarray  # (1,) COMPENSATION_MEMORY record


@jit_inline
def compensation_estimate(params: CompensationParams, state: CompensationState, stamp: float,
                          position_down: float) -> Compensation:
    """The estimate of the previous stamp for the state at ``stamp`` [s], or inactive (in contact, first step,
    after a gap: the observer is restarted). The rates are backward differences of the last estimates (zero
    until there are two, three); the second difference only for ``r >= 2`` (with ``r = 1`` the estimate's rate
    jumps with every step of its input, so its second difference is an impulse); zero unless ``params.rates``."""
    memory = state.memory[0]
    period = params.period
    if memory.has_last_stamp and abs(stamp - memory.last_stamp - period) > PERIOD_TOLERANCE * period:
        memory.gaps += 1
        memory.ready = False
    memory.has_last_stamp, memory.last_stamp = True, stamp
    memory.contact = in_contact(params.surfaces, position_down)
    if memory.contact:
        memory.contact_steps += 1
        memory.ready = False
    if not memory.ready:
        reset_observer(state.observer)
        memory.history_count = 0
        return NO_COMPENSATION
    memory.compensated_steps += 1
    w = state.observer.estimate  # [f_e (world); tau_e (eta coordinates)]
    history = state.history
    count = int(memory.history_count)
    if count == 3:  # keep the last three: drop the oldest
        for j in range(3):
            history[0, j], history[1, j] = history[1, j], history[2, j]
    else:
        count += 1
    history[count - 1, 0], history[count - 1, 1], history[count - 1, 2] = w[0], w[1], w[2]
    memory.history_count = count
    rate = (0.0, 0.0, 0.0)
    acceleration = (0.0, 0.0, 0.0)
    if count >= 2:
        a, b = history[count - 2], history[count - 1]
        rate = ((b[0] - a[0]) / period, (b[1] - a[1]) / period, (b[2] - a[2]) / period)
    if count == 3 and params.smooth:
        c, a, b = history[0], history[1], history[2]
        scale = 1.0 / (period * period)
        acceleration = ((b[0] - 2.0 * a[0] + c[0]) * scale, (b[1] - 2.0 * a[1] + c[1]) * scale,
                        (b[2] - 2.0 * a[2] + c[2]) * scale)
    torque = mat_t_vec3(matrix_rows(state.rate_inverse), (w[3], w[4], w[5]))  # Q^-T tau_e (body)
    if not params.rates:
        return Compensation(True, (w[0], w[1], w[2]), torque, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    return Compensation(True, (w[0], w[1], w[2]), torque, rate, acceleration)


@jit_inline
def compensation_record(params: CompensationParams, state: CompensationState, rotation: Mat3,
                        velocity_world: Vec3, angular_velocity: Vec3, force_body: tuple, torque_body: tuple) -> None:
    """Feed the observer the state of this stamp and the body wrench commanded for it [N, N m]."""
    phi, theta, psi = euler_zyx_from_rotation_rows(rotation)
    inverse = inverse_euler_rate_rows(phi, theta)
    for i in range(3):  # Q^-1 of this sample: the estimate's torque in the body frame next step
        for j in range(3):
            state.rate_inverse[i, j] = inverse[i][j]
    eta_dot = mat_vec3(inverse, angular_velocity)
    observer_update(params.observer, state.observer, velocity_world, (phi, theta, psi), eta_dot, force_body,
                    torque_body)
    state.memory[0].ready = True
