"""The closed loop in one process, with exactly the modules of the node graph and its lockstep contract.

Per step ``k`` (``t_k = k * control_period``, stamps in integer ns as ``Plant.stamp_ns``):

1. the ``odom`` round trip: :func:`fsr_sim.model.odometry.odometry_values` (what the simulator publishes)
   and :func:`fsr_sim.model.odometry.state_from_odometry_values` (what the nodes read back), the same
   arithmetic as the graph, so results agree with it to rounding;
2. ``FlightController.command(t_k, ...)`` -> wrench (what is applied), rotor speeds / tilts, reference;
3. the estimator: :class:`fsr_estimation.core.stamped.StampedEstimator` gets the state and the command
   stamped ``t_k``, as the estimator node does with ``odom`` and ``wrench_cmd``;
4. the plant holds the command over ``[t_k, t_k+1]`` (``physics_substeps`` RK4 steps); a state that
   diverges (``Plant.divergence()``) ends the flight, as the simulator does.

The final state ``t_N`` is published and answered (the controller does not know it is the last) but not
applied. With a recording, :class:`fsr_bringup.recording.flight_recording.FlightRecorder` writes what the
nodes publish, with their own message functions. Ctrl-C (KeyboardInterrupt) ends the flight as
``stopped``: the arrays and the recording hold every step flown.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fsr_control.config.controller_config import controller_config
from fsr_control.flight_controller import FlightController, seconds_from_ns
from fsr_sim.config.scenario import Scenario, plant_from_config, simulation_config
from fsr_sim.model.odometry import odometry_values, state_from_odometry_values
from fsr_sim.model.so3 import rotations_from_quaternions
from fsr_sim.ros.runtime import EXIT_DIVERGED, EXIT_INTERRUPTED


@dataclass
class FlightRun:
    """One flight as arrays over the published states ``k = 0..K`` (K = step count, or the last step flown).

    Attributes
    ----------
    time : numpy.ndarray, shape (K+1,)
        Simulated time [s] of each state.
    state : numpy.ndarray, shape (K+1, 13)
        Position world [m], velocity world [m/s], quaternion ``[x, y, z, w]`` (``w >= 0``, as published),
        angular velocity body [rad/s].
    reference_position, reference_velocity, reference_acceleration : numpy.ndarray, shape (K+1, 3)
        The planner's reference, world NED [m, m/s, m/s^2]; ``reference_rotation`` (K+1, 3, 3).
    rotation_commanded : numpy.ndarray, shape (K+1, 3, 3)
        The attitude the control law commanded (geometric: ``R_d`` from the thrust direction).
    force_desired, torque_desired : numpy.ndarray, shape (K+1, 3)
        The law's body wrench before allocation [N, N m].
    force_cmd, torque_cmd : numpy.ndarray, shape (K+1, 3)
        The body wrench commanded after allocation (what ``wrench_cmd`` carries) [N, N m].
    rotor_speeds, tilt_angles : numpy.ndarray, shape (K+1, n), or None
        [rad/s], [rad] (None in wrench actuation / for fixed rotors).
    external_force_body, external_torque_body : numpy.ndarray, shape (K+1, 3)
        The true external wrench, body frame (as ``wrench_truth``) [N, N m].
    estimate_force_body, estimate_torque_body, mass_estimate : numpy.ndarray or None
        The estimator's outputs (None when it is disabled).
    end_reason : str
        ``finished``, ``diverged`` or ``stopped`` (interrupted); ``reason`` says why.
    compensation : dict
        ``{"mode": "none"}``, or with ``controller.compensation: estimate`` the steps compensated, the steps
        switched off by contact, the late estimates (0: the observer is in the controller) and the gaps
        (:class:`fsr_control.compensation.CompensationReport`).
    """

    time: np.ndarray
    state: np.ndarray
    reference_position: np.ndarray
    reference_velocity: np.ndarray
    reference_acceleration: np.ndarray
    reference_rotation: np.ndarray
    force_cmd: np.ndarray
    torque_cmd: np.ndarray
    rotor_speeds: np.ndarray | None
    tilt_angles: np.ndarray | None
    external_force_body: np.ndarray
    external_torque_body: np.ndarray
    estimate_force_body: np.ndarray | None
    estimate_torque_body: np.ndarray | None
    mass_estimate: np.ndarray | None
    saturation: dict[str, Any]
    tilt_saturation: dict[str, Any]
    end_reason: str  # "finished" | "diverged"
    reason: str
    wall_time: float
    rotation_commanded: np.ndarray | None = None
    force_desired: np.ndarray | None = None
    torque_desired: np.ndarray | None = None
    scenario: Scenario | None = None
    failures: list[str] = field(default_factory=list)
    interrupted: bool = False
    compensation: dict[str, Any] = field(default_factory=lambda: {"mode": "none"})  # FlightController's summary

    @property
    def sim_time(self) -> float:
        return float(self.time[-1])

    @property
    def exit_code(self) -> int:
        if self.interrupted:
            return EXIT_INTERRUPTED
        return EXIT_DIVERGED if self.end_reason == "diverged" else 0

    @property
    def real_time_factor(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else float("nan")

    @property
    def position(self) -> np.ndarray:
        return self.state[:, 0:3]

    @property
    def velocity(self) -> np.ndarray:
        return self.state[:, 3:6]

    @property
    def rotation(self) -> np.ndarray:
        """(K+1, 3, 3) body -> world."""
        return rotations_from_quaternions(self.state[:, 6:10])

    @property
    def angular_velocity(self) -> np.ndarray:
        """(K+1, 3) [rad/s], body FRD."""
        return self.state[:, 10:13]

    @property
    def thrust(self) -> np.ndarray:
        return -self.force_cmd[:, 2]

    def save_mcap(self, path: str | Path) -> Path:
        """Write this flight's recording, the file ``fsr-fly --in-process`` writes: the flight is flown again
        (it is deterministic, bit for bit) with the recorder on, up to the last step of this run."""
        if self.scenario is None:
            raise ValueError("this run has no scenario to fly again")
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        again = fly_in_process(self.scenario, path, max_steps=len(self.time) - 1)
        if again.state.shape != self.state.shape or not np.array_equal(again.state, self.state):
            raise RuntimeError("the flight flown again differs from this run (is the scenario deterministic?)")
        return path


InProcessResult = FlightRun  # the name before the Python API


def fly_in_process(scenario: Any, recording: Path | None = None, max_steps: int | None = None) -> FlightRun:
    """Fly ``scenario`` (a :class:`Scenario`, or the runner's checked scenario holding one) in one process.

    ``recording``: write the MCAP file there. ``max_steps``: stop after that many steps (default: the
    scenario's duration). Ctrl-C ends the flight early (``end_reason`` ``stopped``, ``interrupted``).
    """
    from fsr_estimation.config.estimator_config import estimator_config
    from fsr_estimation.core.stamped import StampedEstimator

    scenario = getattr(scenario, "scenario", scenario)
    sim = simulation_config(scenario)
    config = controller_config(scenario)
    estimation = estimator_config(scenario)
    plant = plant_from_config(sim)
    controller = FlightController(config, sim.vehicle, sim.actuation, sim.initial.position, sim.initial.rotation)
    estimator = (StampedEstimator(estimation.mass, estimation.inertia, estimation.c0, estimation.r, sim.control_period)
                 if estimation.enabled else None)
    rotors = sim.actuation == "rotors"
    n = sim.vehicle.rotor_count
    steps = sim.step_count if max_steps is None else min(sim.step_count, int(max_steps))
    size = steps + 1
    arrays = {key: np.zeros((size, 3)) for key in ("p", "v", "a", "force", "torque", "force_desired",
                                                    "torque_desired", "ext_force", "ext_torque")}
    times, states = np.zeros(size), np.zeros((size, 13))
    ref_rotation, rotation_commanded = np.zeros((size, 3, 3)), np.zeros((size, 3, 3))
    speeds = np.zeros((size, n)) if rotors else None
    tilts = np.zeros((size, n)) if rotors and sim.vehicle.is_tilting else None
    est_force = np.zeros((size, 3)) if estimator is not None else None
    est_torque = np.zeros((size, 3)) if estimator is not None else None
    mass_est = np.zeros(size) if estimator is not None else None
    recorder = None
    if recording is not None:
        from fsr_bringup.recording.flight_recording import FlightRecorder

        recorder = FlightRecorder(Path(recording), scenario.dump(), rotors, n, sim.vehicle.is_tilting)
    end_reason, reason, interrupted = "finished", f"reached the scenario duration {sim.duration:g} s", False
    if steps < sim.step_count:
        reason = f"stopped after {steps} steps"
    start = time.perf_counter()
    last = -1
    try:
        if recorder is not None:
            recorder.status(0, "running", "", 0)
        for k in range(size):
            stamp_ns = plant.stamp_ns
            position, rotation, velocity_world, angular_velocity = state_from_odometry_values(
                *odometry_values(plant.state_vector))
            output = controller.command(seconds_from_ns(stamp_ns), position, rotation, velocity_world,
                                        angular_velocity)
            force_world, torque_body = plant.external_wrench()
            external = (rotation.T @ force_world if sim.disturbances else np.zeros(3),
                        np.asarray(torque_body, dtype=float))
            estimate = None
            if estimator is not None:
                estimator.add_state(stamp_ns, rotation, velocity_world, angular_velocity)
                estimate = estimator.add_command(stamp_ns, output.force_body, output.torque_body)
                est_force[k], est_torque[k], mass_est[k] = estimate.force_body, estimate.torque_body, estimate.mass
            times[k] = seconds_from_ns(stamp_ns)
            states[k] = plant.state_vector
            states[k, 6:10] = odometry_values(plant.state_vector)[1]
            reference = output.reference
            arrays["p"][k], arrays["v"][k], arrays["a"][k] = (reference.position, reference.velocity,
                                                              reference.acceleration)
            ref_rotation[k] = reference.rotation
            rotation_commanded[k] = output.desired.rotation_commanded
            arrays["force_desired"][k], arrays["torque_desired"][k] = (output.desired.force_body,
                                                                       output.desired.torque_body)
            arrays["force"][k], arrays["torque"][k] = output.force_body, output.torque_body
            if speeds is not None:
                speeds[k] = output.rotor_speeds
            if tilts is not None:
                tilts[k] = output.tilt_angles
            arrays["ext_force"][k], arrays["ext_torque"][k] = external
            if recorder is not None:
                recorder.step(stamp_ns, plant.state_vector, plant.external_wrench() if sim.disturbances else None,
                              output, estimate)
            last = k
            if k == steps:
                break
            if rotors:
                plant.set_rotor_command(output.rotor_speeds, output.tilt_angles)
            else:
                plant.set_wrench_command(output.thrust, output.torque_body)
            plant.step()
            divergence = plant.divergence()
            if divergence is not None:
                end_reason, reason = "diverged", divergence
                break
    except KeyboardInterrupt:
        end_reason, reason, interrupted = "stopped", "received SIGINT", True
    finally:
        if recorder is not None:
            try:
                final_ns = int(round(times[max(last, 0)] * 1e9)) if last >= 0 else 0
                recorder.status(final_ns, end_reason, reason, max(last, 0))
            finally:
                recorder.close()
    wall = time.perf_counter() - start
    keep = slice(0, last + 1)

    def cut(array: np.ndarray | None) -> np.ndarray | None:
        return None if array is None else array[keep]

    failures = {"diverged": [f"flight diverged: {reason}"], "stopped": ["flight interrupted (SIGINT)"]}
    return FlightRun(
        time=times[keep], state=states[keep], reference_position=arrays["p"][keep],
        reference_velocity=arrays["v"][keep], reference_acceleration=arrays["a"][keep],
        reference_rotation=ref_rotation[keep], force_cmd=arrays["force"][keep], torque_cmd=arrays["torque"][keep],
        rotor_speeds=cut(speeds), tilt_angles=cut(tilts), external_force_body=arrays["ext_force"][keep],
        external_torque_body=arrays["ext_torque"][keep], estimate_force_body=cut(est_force),
        estimate_torque_body=cut(est_torque), mass_estimate=cut(mass_est),
        saturation=controller.saturation.as_dict(), tilt_saturation=controller.tilt_saturation.as_dict(),
        end_reason=end_reason, reason=reason, wall_time=wall, rotation_commanded=rotation_commanded[keep],
        force_desired=arrays["force_desired"][keep], torque_desired=arrays["torque_desired"][keep],
        scenario=scenario, failures=failures.get(end_reason, []), interrupted=interrupted,
        compensation=controller.compensation_summary(),
    )
