"""The closed loop in one process (compiled core): the node graph's per-step functions and its lockstep
contract, for many steps per call.

Per step ``k`` (``t_k = k T``, stamps in integer ns, ``t_k = stamp * 1e-9`` as the nodes compute it):

1. the simulator's published state (the ``odom``, ``wrench_truth`` and, with an IMU, ``imu`` row of
   :mod:`fsr_sim.core.odometry`: ``published[k]``, ``imu``'s numbers from ``IMU_ANGULAR_VELOCITY`` on, the
   rotors' actual state in ``actuators[k]``) is read back by the controller
   (:func:`fsr_sim.core.odometry.read_odometry`), the same arithmetic as over DDS, so a flight here and in the
   graph agree;
2. the controller's tick (:func:`fsr_control.core.controller.controller_tick`) for the state stamped ``t_k``;
3. the estimator (:func:`fsr_estimation.core.observer_step.estimate_from_state`) on the state and the
   commanded wrench of ``t_k``, as the estimator node pairs ``odom`` and ``wrench_cmd`` (``estimator.input:
   measured``: the wrench of the rotors' speeds and tilts of ``t_k``, as it pairs ``odom`` and ``rotor_state``);
4. the true state ``t_k`` checked against the reference answered for it (:func:`fsr_sim.core.control_loss.
   control_loss`: attitude error against ``R_c`` or position error beyond the scenario's ``divergence`` bounds),
   as the simulator node checks it: a flight that lost control ends there;
5. the command held over ``[t_k, t_k+1]``, the plant stepped and the state ``t_k+1`` published by the
   simulator node's own step (:func:`fsr_sim.core.lockstep.advance`); a state that diverges ends the flight,
   as the simulator does.

The final state ``t_N`` is published and answered (the controller does not know it is the last) but not
applied. :func:`fly` runs steps ``first..last`` and returns, so the Python driver
(:mod:`fsr_bringup.runner.in_process_flight`) can notice Ctrl-C and write the recording between calls; what it
does with each step is the caller's (``what``): write its rows (the in-process flight), measure it into the
row of a sweep (:mod:`fsr_bringup.core.flight_measures`, without per-step arrays), or both.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from fsr_bringup.core.flight_measures import (
    Measurement,
    held_wrench,
    measure_first,
    measure_sample,
    measure_step,
    reset,
)
from fsr_control.core.allocation import TILTING, WRENCH
from fsr_control.core.controller import (
    COMMANDED_QUATERNION,
    FORCE,
    REFERENCE_POSITION,
    ROTOR_SPEEDS,
    TORQUE,
    ControllerParams,
    ControllerState,
    controller_tick,
)
from fsr_control.core.flatness import ATTITUDE_OK
from fsr_control.core.law_terms import Measured, VehicleState
from fsr_estimation.core.observer_step import ObserverParams, ObserverState, estimate_from_state
from fsr_sim.core.control_loss import IN_CONTROL, control_loss, held_by_surface
from fsr_sim.core.jit import jit, jit_inline
from fsr_sim.core.lockstep import actuator_row, advance, publish
from fsr_sim.core.odometry import IMU_ANGULAR_VELOCITY, read_odometry
from fsr_sim.core.plant import RUNNING, PlantParams, PlantState, set_rotor_command, set_wrench_command
from fsr_sim.core.rigid_body import state_rotation
from fsr_sim.core.rotors import measured_rotor_wrench

GOING_ON, FINISHED, DIVERGED, CONTROLLER_FAILED, LOST_CONTROL = 0, 1, 2, 3, 4  # outcomes of fly
RECORD, MEASURE = 1, 2  # what fly does with each step (flags): write its rows; measure it (a sweep's row)


class LoopPlant(NamedTuple):
    """The simulated vehicle of the loop (:mod:`fsr_sim.core.plant`)."""

    params: PlantParams
    state: PlantState


class LoopController(NamedTuple):
    """The controller of the loop (:func:`fsr_control.core.controller.controller_tick`)."""

    params: ControllerParams
    state: ControllerState


class LoopEstimator(NamedTuple):
    """The estimator of the loop (:func:`fsr_estimation.core.observer_step.estimate_from_state`)."""

    enabled: bool
    measured: bool  # estimator.input: measured (the rotors' measured wrench of rotor_state)
    params: ObserverParams
    state: ObserverState


class LoopTrace(NamedTuple):
    """The rows :func:`fly` writes per step (RECORD: row ``k`` of step ``k``; else two scratch rows)."""

    states: np.ndarray  # (rows, 13) the true state
    published: np.ndarray  # (rows, PUBLISHED_SIZE) the published row (fsr_sim.core.odometry)
    actuators: np.ndarray  # (rows, 2n) the rotors' actual speeds, then tilts (rotor_state)
    control: np.ndarray  # (rows, output size) the controller's output row (fsr_control.core.controller)
    estimates: np.ndarray  # (rows, 7) the estimator's


@jit_inline
def hold_command(plant: PlantParams, plant_state: PlantState, mode: int, row, force, torque) -> None:  # noqa: ANN001
    """Hand the controller's output ``row`` to the plant for the next period: in wrench actuation ``u_T = -f_z``
    along ``-z_b`` and ``tau_b`` (``force``, ``torque`` of the row), else the rotor speeds (and tilts)."""
    if mode == WRENCH:  # the RK4 stage row as scratch: copied before use
        wrench = plant_state.work[4, :6]
        wrench[0], wrench[1], wrench[2] = 0.0, 0.0, force[2]
        wrench[3], wrench[4], wrench[5] = torque
        set_wrench_command(plant, plant_state, wrench)
    else:
        n = (row.shape[0] - ROTOR_SPEEDS) // 2
        set_rotor_command(plant, plant_state, row[ROTOR_SPEEDS:ROTOR_SPEEDS + n],
                          row[ROTOR_SPEEDS + n:ROTOR_SPEEDS + 2 * n], mode == TILTING)


@jit_inline
def closed_loop_tick(controller: LoopController, estimator: LoopEstimator, t: float, odometry, speeds,  # noqa: ANN001
                     tilts, row, estimate) -> tuple:  # noqa: ANN001
    """The controller's answer ``row`` to the published ``odometry`` of ``t`` [s] (the published row: odom and,
    with an IMU, imu) and the rotors' measured ``speeds``, ``tilts`` (``rotor_state``) and, with the estimator
    (``estimator.enabled``), its estimate of that state and the commanded wrench (``estimator.measured``: the
    rotors' measured wrench) into ``estimate``. Returns ``(status, force, torque)``: the law's status and the
    commanded wrench (on a failure the estimator is not called)."""
    position, rotation, velocity_world, angular_velocity = read_odometry(odometry)
    imu = odometry[IMU_ANGULAR_VELOCITY:IMU_ANGULAR_VELOCITY + 6]
    status = controller_tick(controller.params, controller.state, t,
                             VehicleState(position, rotation, velocity_world, angular_velocity),
                             Measured(imu, speeds, tilts), row)
    force = (row[FORCE], row[FORCE + 1], row[FORCE + 2])
    torque = (row[TORQUE], row[TORQUE + 1], row[TORQUE + 2])
    if status == ATTITUDE_OK and estimator.enabled:
        force_e, torque_e = force, torque
        if estimator.measured:
            allocation = controller.params.allocation
            force_e, torque_e = measured_rotor_wrench(allocation.allocation, allocation.c_f,
                                                      allocation.mode == TILTING, speeds, tilts)
        estimate_from_state(estimator.params, estimator.state, rotation, velocity_world, angular_velocity, force_e,
                            torque_e, estimate)
    return status, force, torque


@jit
def fly(simulated: LoopPlant, controller: LoopController, estimator: LoopEstimator, first: int, last: int,
        step_count: int, period_ns: int, control_bounds: tuple, what: int, trace: LoopTrace,
        measurement: Measurement) -> tuple:
    """Steps ``first..last`` (``last <= step_count``), each written and/or measured as ``what`` says
    (:data:`RECORD` | :data:`MEASURE`).

    RECORD: row ``k`` of each of ``trace``'s arrays gets what step ``k`` published. Without it they hold two
    rows each, step ``k`` in row ``k % 2`` (scratch). MEASURE: the step is measured into ``measurement.acc``
    (:mod:`fsr_bringup.core.flight_measures`), reset at step 0. ``estimator.measured``: the estimator takes the
    rotors' measured wrench (``estimator.input: measured``).

    Returns ``(outcome, k, detail)``: ``GOING_ON`` after ``last``; ``FINISHED`` at ``step_count``;
    ``DIVERGED`` with the divergence code after step ``k`` (state ``k + 1`` is not recorded);
    ``CONTROLLER_FAILED`` with the law's status at step ``k`` (its row holds only the reference);
    ``LOST_CONTROL`` with the :func:`fsr_sim.core.control_loss.control_loss` code of state ``k`` (``k < step_count``:
    the simulator node does not check the final state either) against its answer, within ``control_bounds``
    (:meth:`fsr_sim.model.control_loss.ControlBounds.pack`): row ``k`` is complete."""
    plant, plant_state = simulated.params, simulated.state
    record = (what & RECORD) != 0
    mode = controller.params.allocation.mode
    states, published, actuators, control, estimates = trace
    measures, acc, rotor_rows = measurement.params, measurement.acc, measurement.rotor_rows
    with_estimator = estimator.enabled
    truth = (what & MEASURE) != 0 and with_estimator and measures.truth
    rotor_truth = truth and mode != WRENCH
    n = actuators.shape[1] // 2
    if first == 0:
        publish(plant, plant_state, published[0])
        actuator_row(plant_state, actuators[0])
        if what & MEASURE:
            reset(acc)
        if rotor_truth:
            measure_first(measures, plant_state.x, rotor_rows)
    for k in range(first, last + 1):
        t = (k * period_ns) * 1e-9
        now = k if record else k % 2
        after = k + 1 if record else (k + 1) % 2
        x = states[now]
        for i in range(plant_state.x.shape[0]):
            x[i] = plant_state.x[i]
        row = control[now]
        status, force, torque = closed_loop_tick(controller, estimator, t, published[now],
                                                 actuators[now, :n], actuators[now, n:], row, estimates[now])
        if status != ATTITUDE_OK:
            return CONTROLLER_FAILED, k, status
        if what & MEASURE:
            measure_sample(measures, acc, k, x, state_rotation(x), row)
        if k == step_count:
            return FINISHED, k, 0
        lost = control_loss(control_bounds, plant_state.x, row[REFERENCE_POSITION:REFERENCE_POSITION + 3],
                            row[COMMANDED_QUATERNION:COMMANDED_QUATERNION + 4], held_by_surface(plant_state))
        if lost != IN_CONTROL:
            return LOST_CONTROL, k, lost
        hold_command(plant, plant_state, mode, row, force, torque)
        force_held, torque_held = held_wrench(plant, plant_state, force, torque) if truth and not rotor_truth \
            else (force, torque)
        if k == 0:  # rotor_state of t_0: the rotors spin at the first command from the start, as the node publishes
            actuator_row(plant_state, actuators[0])
        code = advance(plant, plant_state, published[after])
        actuator_row(plant_state, actuators[after])
        if code != RUNNING:
            return DIVERGED, k, code
        if truth:
            measure_step(measurement, plant, plant_state, rotor_truth, k, t, ((k + 1) * period_ns) * 1e-9, x,
                         published[now], row, actuators[now], (force, torque), (force_held, torque_held),
                         estimates[now])
    return GOING_ON, last, 0
