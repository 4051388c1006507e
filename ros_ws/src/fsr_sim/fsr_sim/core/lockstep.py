"""One lockstep step of the simulator (compiled core): what the simulator node and the in-process loop both
call once per control period.

The contract: the state stamped ``t_k`` is published; the command stamped ``t_k`` is applied over
``[t_k, t_k+1]`` (:func:`apply_rotor_command` / :func:`apply_wrench_command`, or the failsafe: the last
command held, or :func:`fsr_sim.core.plant.cut_thrust`); :func:`advance` steps the plant and publishes the
state ``t_k+1`` (the row of :mod:`fsr_sim.core.odometry`), or reports why it diverged. The node keeps only
the handshake, the waiting and the failsafe policy (:mod:`fsr_sim.nodes.lockstep`).
"""

from __future__ import annotations

import math

from fsr_sim.core.imu import publish_imu
from fsr_sim.core.jit import jit_inline
from fsr_sim.core.odometry import publish_state
from fsr_sim.core.plant import PlantParams, PlantState, divergence, plant_external_wrench, plant_step
from fsr_sim.core.sensors import measure_odometry


@jit_inline
def publish(params: PlantParams, state: PlantState, out) -> None:  # noqa: ANN001
    """The published row (:data:`fsr_sim.core.odometry.PUBLISHED_SIZE`,) of the current state: ``odom`` as the
    sensor stage measures it (:mod:`fsr_sim.core.sensors`; the true state when it is off), the true
    ``wrench_truth`` and, with an IMU, ``imu`` and its true values (:mod:`fsr_sim.core.imu`)."""
    publish_state(state.x, plant_external_wrench(params, state), out)
    measure_odometry(params.sensors.odometry, state.sensor_memory, int(state.status[0].step_index), out)
    publish_imu(params, state, out)


@jit_inline
def actuator_row(state: PlantState, out) -> None:  # noqa: ANN001
    """The rotors' actual speeds [rad/s] then tilts [rad] into ``out`` (2n,): ``rotor_state``'s numbers."""
    n = state.speeds.shape[0]
    for i in range(n):
        out[i] = state.speeds[i]
        out[n + i] = state.tilts[i]


@jit_inline
def advance(params: PlantParams, state: PlantState, out) -> int:  # noqa: ANN001
    """Step the plant one control period with the held command; publish the new state into ``out`` (the
    published row) if it is finite. Returns the divergence code (``RUNNING``: go on)."""
    plant_step(params, state)
    code = divergence(params, state)
    x = state.x
    finite = True
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            finite = False
    if finite:
        publish(params, state, out)
    return code
