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
nodes publish, the payloads their own packers build (byte for byte the graph's). Ctrl-C (KeyboardInterrupt)
ends the flight as ``stopped``: the arrays and the recording hold every step flown.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fsr_control.config.controller_config import controller_config
from fsr_control.flight_controller import FlightController, seconds_from_ns
from fsr_sim.config.scenario import Scenario, plant_from_config, simulation_config
from fsr_sim.model.odometry import odometry_values, state_from_odometry_values
from fsr_sim.model.so3 import rotations_from_quaternions
from fsr_sim.ros.runtime import EXIT_DIVERGED, EXIT_INTERRUPTED, process_age


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
    startup_time: float | None = None  # s from the process start to the first step (None: unknown)

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


class _Stopped(KeyboardInterrupt):
    """``stop()`` asked for the end of the flight (between two steps)."""

    def __init__(self, signal_name: str) -> None:
        super().__init__(signal_name)
        self.signal_name = signal_name


def fly_in_process(scenario: Any, recording: Path | None = None, max_steps: int | None = None,
                   stop: Callable[[], str | None] | None = None) -> FlightRun:
    """Fly ``scenario`` (a :class:`Scenario`, or the runner's checked scenario holding one) in one process.

    ``recording``: write the MCAP file there. ``max_steps``: stop after that many steps (default: the
    scenario's duration). ``stop``: polled before each step; a signal name (e.g. ``"SIGINT"``) ends the flight
    there, between two steps (``end_reason`` ``stopped``, ``interrupted``). A KeyboardInterrupt (Ctrl-C in a
    notebook) ends it too, wherever it strikes.
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
    # Per-step values are collected in lists (one append per value, no small numpy writes) and stacked at the end.
    rows: dict[str, list] = {key: [] for key in (
        "time", "state", "quaternion", "p", "v", "a", "ref_rotation", "rotation_commanded", "force", "torque",
        "force_desired", "torque_desired", "speeds", "tilts", "ext_force", "ext_torque", "est_force", "est_torque",
        "mass_est")}
    recorder = None
    if recording is not None:
        from fsr_bringup.recording.flight_recording import FlightRecorder

        recorder = FlightRecorder(Path(recording), scenario.dump(), rotors, n, sim.vehicle.is_tilting)
    end_reason, reason, interrupted = "finished", f"reached the scenario duration {sim.duration:g} s", False
    if steps < sim.step_count:
        reason = f"stopped after {steps} steps"
    disturbed = bool(sim.disturbances)
    tilting = rotors and sim.vehicle.is_tilting
    append = {key: values.append for key, values in rows.items()}
    startup = process_age()
    start = time.perf_counter()
    last = -1
    try:
        if recorder is not None:
            recorder.status(0, "running", "", 0)
        for k in range(size):
            signal_name = stop() if stop is not None else None
            if signal_name:
                raise _Stopped(signal_name)
            stamp_ns = plant.stamp_ns
            state_vector = plant.state_vector
            published = odometry_values(state_vector)
            position, rotation, velocity_world, angular_velocity = state_from_odometry_values(*published)
            output = controller.command(seconds_from_ns(stamp_ns), position, rotation, velocity_world,
                                        angular_velocity)
            external_wrench = plant.external_wrench() if disturbed else None
            if external_wrench is not None:
                append["ext_force"](rotation.T @ external_wrench[0])
                append["ext_torque"](external_wrench[1])
            estimate = None
            if estimator is not None:
                estimator.add_state(stamp_ns, rotation, velocity_world, angular_velocity)
                estimate = estimator.add_command(stamp_ns, output.force_body, output.torque_body)
                append["est_force"](estimate.force_body)
                append["est_torque"](estimate.torque_body)
                append["mass_est"](estimate.mass)
            append["time"](seconds_from_ns(stamp_ns))
            append["state"](state_vector.tolist())
            append["quaternion"](published[1])
            reference = output.reference
            append["p"](reference.position)
            append["v"](reference.velocity)
            append["a"](reference.acceleration)
            append["ref_rotation"](reference.rotation)
            append["rotation_commanded"](output.desired.rotation_commanded)
            append["force_desired"](output.desired.force_body)
            append["torque_desired"](output.desired.torque_body)
            append["force"](output.force_body)
            append["torque"](output.torque_body)
            if rotors:
                append["speeds"](output.rotor_speeds)
                if tilting:
                    append["tilts"](output.tilt_angles)
            if recorder is not None:
                recorder.step_values(stamp_ns, published, external_wrench, output, estimate)
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
    except KeyboardInterrupt as stop:  # Ctrl-C (fsr-fly also turns SIGTERM into one)
        end_reason, reason, interrupted = "stopped", f"received {getattr(stop, 'signal_name', 'SIGINT')}", True
    finally:
        if recorder is not None:
            try:
                final_ns = int(round(rows["time"][last] * 1e9)) if last >= 0 else 0
                recorder.status(final_ns, end_reason, reason, max(last, 0))
            finally:
                recorder.close()
    wall = time.perf_counter() - start
    count = last + 1

    def stack(key: str, shape: tuple[int, ...], present: bool = True) -> np.ndarray | None:
        """The first ``count`` rows of a column (zeros where the loop did not fill it), or None."""
        if not present:
            return None
        values = rows[key][:count]
        if not values:
            return np.zeros((count, *shape))
        return np.array(values, dtype=float).reshape((len(values), *shape))

    states = stack("state", (13,))
    states[:, 6:10] = stack("quaternion", (4,))
    external_force = stack("ext_force", (3,)) if disturbed else np.zeros((count, 3))
    external_torque = stack("ext_torque", (3,)) if disturbed else np.zeros((count, 3))
    with_estimator = estimator is not None
    failures = {"diverged": [f"flight diverged: {reason}"], "stopped": [f"flight interrupted ({reason})"]}
    return FlightRun(
        time=np.array(rows["time"][:count], dtype=float), state=states, reference_position=stack("p", (3,)),
        reference_velocity=stack("v", (3,)), reference_acceleration=stack("a", (3,)),
        reference_rotation=stack("ref_rotation", (3, 3)), force_cmd=stack("force", (3,)),
        torque_cmd=stack("torque", (3,)), rotor_speeds=stack("speeds", (n,), rotors),
        tilt_angles=stack("tilts", (n,), tilting), external_force_body=external_force,
        external_torque_body=external_torque, estimate_force_body=stack("est_force", (3,), with_estimator),
        estimate_torque_body=stack("est_torque", (3,), with_estimator),
        mass_estimate=stack("mass_est", (), with_estimator),
        saturation=controller.saturation.as_dict(), tilt_saturation=controller.tilt_saturation.as_dict(),
        end_reason=end_reason, reason=reason, wall_time=wall, rotation_commanded=stack("rotation_commanded", (3, 3)),
        force_desired=stack("force_desired", (3,)), torque_desired=stack("torque_desired", (3,)),
        scenario=scenario, failures=failures.get(end_reason, []), interrupted=interrupted,
        compensation=controller.compensation_summary(), startup_time=startup,
    )
