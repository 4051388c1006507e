"""What an IMU at the centre of mass senses of the true plant (compiled core): the angular velocity ``omega_b``
[rad/s] and the specific force

    f_s = R^T (p_ddot - g e3)      [m/s^2], body FRD

at the published state, with every non-gravitational force acting on it then: the actuators' wrench as the
plant holds it at that instant (the command applied over the step that ended there, the rotors' actual speeds
and tilts, the thrust ratios near surfaces), the disturbances and the turbulence's drag - the force the RK4
stages evaluate (:func:`fsr_sim.core.plant.stage_wrench`), so ``f_s = R^T F / m``. A surface that holds the
vehicle (the ground it rests on or is pushed into, the ceiling it is pressed against: the contact rule of
:func:`fsr_sim.core.plant.apply_contact`) adds the reaction that keeps it still: ``p_ddot = 0`` and
``f_s = -g R^T e3`` (``[0, 0, -g]`` level on the ground). Before the first command (``t_0``) the rotors are
still: an airborne vehicle reads free fall.

:func:`publish_imu` writes the true values and the IMU stage's measurement of them
(:func:`fsr_sim.core.sensors.measure_imu`) into the published row (:mod:`fsr_sim.core.odometry`).
"""

from __future__ import annotations

from fsr_sim.core.jit import jit, jit_inline
from fsr_sim.core.odometry import (
    IMU_ANGULAR_VELOCITY,
    IMU_END,
    IMU_TRUE_ANGULAR_VELOCITY,
    IMU_TRUE_LINEAR_ACCELERATION,
)
from fsr_sim.core.plant import (
    PlantParams,
    PlantState,
    plant_time,
    stage_wrench,
)
from fsr_sim.core.rigid_body import GRAVITY, POSITION_Z, state_angular_velocity, state_rotation
from fsr_sim.core.sensors import IMU_SIZE, measure_imu
from fsr_sim.core.so3 import Vec3, mat_t_vec3
from fsr_sim.core.surfaces import ceiling_rest_z, ground_rest_z


@jit_inline
def specific_force(params: PlantParams, state: PlantState) -> Vec3:
    """``R^T (p_ddot - g e3)`` [m/s^2], body FRD, of the current state (module docstring)."""
    x, status = state.x, state.status[0]
    ground_capped, ceiling_capped = status.ground_capped, status.ceiling_capped
    (fx, fy, fz), _ = stage_wrench(params, state, plant_time(params, state), x)
    status.ground_capped, status.ceiling_capped = ground_capped, ceiling_capped  # a measurement, not a step
    inverse_mass = 1.0 / params.mass
    ax, ay, az = fx * inverse_mass, fy * inverse_mass, fz * inverse_mass  # p_ddot - g e3, world
    surfaces = params.surfaces
    pressed_down = az + GRAVITY >= 0.0  # what acts pushes the vehicle down (NED), into a ground below it
    if ((surfaces.ground and not x[POSITION_Z] < ground_rest_z(surfaces) and pressed_down)
            or (surfaces.ceiling and not x[POSITION_Z] > ceiling_rest_z(surfaces) and not pressed_down)):
        ax, ay, az = 0.0, 0.0, -GRAVITY  # held still: the surface's reaction cancels the rest
    return mat_t_vec3(state_rotation(x), (ax, ay, az))


@jit_inline
def publish_imu(params: PlantParams, state: PlantState, out) -> None:  # noqa: ANN001
    """With an IMU, its numbers of the current state into the published row ``out``: the true angular velocity
    and specific force, and ``imu``'s measurement of them; nothing without one."""
    imu = params.sensors.imu
    if not imu.enabled:
        return
    x = state.x
    sx, sy, sz = specific_force(params, state)
    true = IMU_TRUE_ANGULAR_VELOCITY
    out[true], out[true + 1], out[true + 2] = state_angular_velocity(x)
    out[IMU_TRUE_LINEAR_ACCELERATION] = sx
    out[IMU_TRUE_LINEAR_ACCELERATION + 1] = sy
    out[IMU_TRUE_LINEAR_ACCELERATION + 2] = sz
    for i in range(IMU_SIZE):
        out[IMU_ANGULAR_VELOCITY + i] = out[true + i]
    measure_imu(imu, state.sensor_memory, int(state.status[0].step_index), out[IMU_ANGULAR_VELOCITY:IMU_END])


@jit
def true_specific_force(params: PlantParams, state: PlantState) -> Vec3:
    """:func:`specific_force` callable from Python (tests, a plant stepped by hand)."""
    return specific_force(params, state)
