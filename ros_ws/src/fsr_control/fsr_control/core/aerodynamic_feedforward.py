"""The nominal vehicle's aerodynamics along the reference, as a wrench the law cancels (compiled core).

With ``controller.aerodynamics: model`` (and no ``compensation``) the controller predicts the aerodynamic wrench
of its model (:func:`fsr_sim.core.aerodynamics.aerodynamic_wrench`: parasitic drag, rotor drag, induced inflow,
translational lift, blade flapping) on the reference - velocity ``v_d`` in still air (the wind is not known),
the attitude and rates the flatness map gives the thrust vector ``n = m (g e3 - a_d)`` and the reference's yaw
(:func:`fsr_control.core.flatness.attitude_from_thrust_vector`), every rotor at the speed of that thrust
``w_d = sqrt(|n| / (n_r c_f))`` - and hands it to the law in the compensation's slot: force world NED
[N], torque body FRD [N m], with the force's first and second backward differences [N/s, N/s^2] that turn
``R_d`` with it. Taken on the reference, the prediction is a pure feed-forward: the measured state and the last
command do not enter it, so neither their noise nor a loop through the rotor speeds does (predicted from the
measured velocity and the commanded speeds, the induced inflow's term closes a loop through the attitude gains
that diverged on the hummingbird's figure-8).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_control.core.flatness import ATTITUDE_OK, attitude_from_thrust_vector
from fsr_control.core.law_terms import Compensation
from fsr_control.core.reference import ReferenceSample
from fsr_sim.core.aerodynamics import AeroParams, aerodynamic_wrench
from fsr_sim.core.jit import jit, zeroed_record
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.core.so3 import dot3, mat_t_vec3


class AeroFeedforward(NamedTuple):
    enabled: bool  # controller.aerodynamics: model, and the model has some aerodynamics
    aerodynamics: AeroParams  # the nominal vehicle's
    columns: np.ndarray  # (n, 9) the nominal rotors' columns (fsr_sim.core.rotors)
    mass: float  # nominal mass [kg]
    thrust_coefficient_sum: float  # n c_f [N s^2]


AERO_MEMORY = np.dtype([
    ("samples", np.int64),  # how many samples came before (0, 1, 2: at most)
    ("previous_time", np.float64),  # the last one's time [s]
    ("force", np.float64, (3,)),  # its force [N], world NED
    ("force_rate", np.float64, (3,)),  # its first backward difference [N/s]
    ("force_acceleration", np.float64, (3,)),  # its second [N/s^2]
], align=True)
"""What the feed-forward keeps of its last sample (:attr:`AeroMemory.last`)."""


class AeroMemory(NamedTuple):
    """The feed-forward's memory (``ControllerState.aerodynamics``)."""

    last: np.ndarray  # 1-element AERO_MEMORY record: the last sample
    speeds: np.ndarray  # (n,) scratch: the rotor speeds of the prediction [rad/s]


def new_aero_memory(rotor_count: int) -> AeroMemory:
    """The feed-forward's memory for ``rotor_count`` rotors, zeroed (no sample yet)."""
    return AeroMemory(zeroed_record(AERO_MEMORY), np.zeros(rotor_count))


@jit
def _vector(values) -> tuple:  # noqa: ANN001
    return values[0], values[1], values[2]


@jit
def aerodynamic_feedforward(params: AeroFeedforward, memory: AeroMemory, t: float,
                            reference: ReferenceSample) -> Compensation:
    """The model's aerodynamic wrench on the reference at ``t`` [s] (module docstring); the differences are zero
    until there are two, three samples; a stamp that does not advance gets the last answer's force and rates."""
    m, a, j, q = params.mass, reference.acceleration, reference.jerk, reference.snap
    thrust_vector = (-m * a[0], -m * a[1], m * (GRAVITY - a[2]))  # m (g e3 - a_d): the flatness map's n
    status, rotation, omega, _ = attitude_from_thrust_vector(
        thrust_vector, (-m * j[0], -m * j[1], -m * j[2]), (-m * q[0], -m * q[1], -m * q[2]), reference.yaw,
        reference.yaw_rate, reference.yaw_acceleration)
    if status != ATTITUDE_OK:  # free fall: no thrust, no rotor speed
        rotation, omega = reference.rotation, reference.angular_velocity
    speeds = memory.speeds
    speeds[:] = math.sqrt(math.sqrt(dot3(thrust_vector, thrust_vector)) / params.thrust_coefficient_sum)
    force_body, torque = aerodynamic_wrench(params.aerodynamics, params.columns, speeds,
                                            mat_t_vec3(rotation, reference.velocity), omega)
    last = memory.last[0]
    samples = last.samples
    if samples > 0 and not t > last.previous_time:
        return Compensation(True, _vector(last.force), torque, _vector(last.force_rate),
                            _vector(last.force_acceleration))
    dt = t - last.previous_time
    forces, rates, accelerations = last.force, last.force_rate, last.force_acceleration
    for i in range(3):
        force = rotation[i][0] * force_body[0] + rotation[i][1] * force_body[1] + rotation[i][2] * force_body[2]
        rate = (force - forces[i]) / dt if samples >= 1 else 0.0
        accelerations[i] = (rate - rates[i]) / dt if samples >= 2 else 0.0
        rates[i] = rate
        forces[i] = force
    last.samples = min(samples + 1, 2)
    last.previous_time = t
    return Compensation(True, _vector(forces), torque, _vector(rates), _vector(accelerations))
