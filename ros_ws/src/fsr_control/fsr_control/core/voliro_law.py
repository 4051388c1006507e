"""The Voliro law per step (compiled core): a whole body wrench, for fully actuated vehicles.

Its equations are in :mod:`fsr_control.controllers.voliro` (the Python shell); its parameters are
:class:`VoliroParams`; it keeps no memory (no field of ``LawMemory``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from fsr_control.core.flatness import ATTITUDE_OK
from fsr_control.core.law_terms import INERTIA, Compensation, VehicleState, linear_feedback, matrix_at
from fsr_control.core.reference import ReferenceSample
from fsr_sim.core.jit import jit_inline
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.core.so3 import attitude_error3, cross3, mat_t_mat3, mat_t_vec3, mat_vec3

# VoliroParams.matrices: the nominal inertia [kg m^2], K_p [1/s^2], K_d [1/s], K_R [1/s^2], K_w [1/s]
MATRICES = ("inertia", "k_p", "k_d", "k_r", "k_w")
K_P, K_D, K_R, K_W = range(1, len(MATRICES))


class VoliroParams(NamedTuple):
    mass: float  # nominal mass [kg]
    matrices: np.ndarray  # (5, 3, 3): MATRICES, matrices[INERTIA] the inertia
    report_feedforward: bool  # the report's angular feed-forward (controller.angular_feedforward: report)

    @classmethod
    def unused(cls) -> VoliroParams:
        """Placeholder parameters, for a controller that flies another law."""
        return cls(0.0, np.zeros((len(MATRICES), 3, 3)), False)


@jit_inline
def voliro_law(params: VoliroParams, reference: ReferenceSample, state: VehicleState,
               compensation: Compensation) -> tuple:
    """``(status, f_b, tau_b, R_d)`` of the Voliro law (:mod:`fsr_control.controllers.voliro`): the body wrench
    ``[R_b^T m (v - g e3); I_b w + w_b x I_b w_b]`` (minus the compensated wrench)."""
    position, rotation, velocity_world, angular_velocity = state
    e_p = (position[0] - reference.position[0], position[1] - reference.position[1],
           position[2] - reference.position[2])
    e_v = (velocity_world[0] - reference.velocity[0], velocity_world[1] - reference.velocity[1],
           velocity_world[2] - reference.velocity[2])
    k_p, k_d = matrix_at(params.matrices, K_P), matrix_at(params.matrices, K_D)
    v = linear_feedback(k_p, e_p, k_d, e_v, 1.0, reference.acceleration)
    r = rotation
    rotation_desired = reference.rotation
    relative = mat_t_mat3(r, rotation_desired)  # R_b^T R_d
    w_b = angular_velocity
    omega_d_body = mat_vec3(relative, reference.angular_velocity)
    omega_dot_d_body = mat_vec3(relative, reference.angular_acceleration)
    e_r = attitude_error3(r, rotation_desired)
    e_w = (w_b[0] - omega_d_body[0], w_b[1] - omega_d_body[1], w_b[2] - omega_d_body[2])
    k_r, k_w = matrix_at(params.matrices, K_R), matrix_at(params.matrices, K_W)
    feedback = linear_feedback(k_r, e_r, k_w, e_w, 0.0, (0.0, 0.0, 0.0))
    turn = cross3(w_b, omega_d_body)
    inertia = matrix_at(params.matrices, INERTIA)
    if params.report_feedforward:
        ff = mat_vec3(inertia, (turn[0] + omega_dot_d_body[0], turn[1] + omega_dot_d_body[1],
                                turn[2] + omega_dot_d_body[2]))
        w = (feedback[0] + ff[0], feedback[1] + ff[1], feedback[2] + ff[2])
    else:
        w = (feedback[0] - turn[0] + omega_dot_d_body[0], feedback[1] - turn[1] + omega_dot_d_body[1],
             feedback[2] - turn[2] + omega_dot_d_body[2])
    m = params.mass
    inertia_w = mat_vec3(inertia, w)
    gyro = cross3(w_b, mat_vec3(inertia, w_b))
    if compensation.active:
        fx, fy, fz = compensation.force
        tx, ty, tz = compensation.torque
        force = mat_t_vec3(r, (m * v[0] - fx, m * v[1] - fy, m * (v[2] - GRAVITY) - fz))
        torque = (inertia_w[0] + gyro[0] - tx, inertia_w[1] + gyro[1] - ty, inertia_w[2] + gyro[2] - tz)
        return ATTITUDE_OK, force, torque, rotation_desired
    force_body = mat_t_vec3(r, (v[0], v[1], v[2] - GRAVITY))
    return (ATTITUDE_OK, (m * force_body[0], m * force_body[1], m * force_body[2]),
            (inertia_w[0] + gyro[0], inertia_w[1] + gyro[1], inertia_w[2] + gyro[2]), rotation_desired)
