"""The closed loop in one process, with exactly the modules of the node graph and its lockstep contract.

Per step ``k`` (``t_k = k * control_period``, stamps in integer ns as ``Plant.stamp_ns``):

1. the simulator's ``odom`` round trip: quaternion from the plant state (sign fixed to ``w >= 0``),
   ``R = rotation_from_quaternion(q)``, twist ``v_body = R^T v_world``, then the controller's
   ``state_from_odometry``: ``v_world = R v_body`` (the same float arithmetic as
   ``fsr_sim.nodes.state_messages`` + ``fsr_sim.ros.conversions``, so results agree with the graph to
   rounding);
2. ``FlightController.command(t_k, ...)`` -> wrench (what is applied), rotor speeds / tilts, reference;
3. the estimator (``fsr_estimation.core.observer.MomentumObserver``) takes the state at ``t_k`` and the
   wrench command stamped ``t_k``, as the estimator node pairs ``odom`` and ``wrench_cmd`` by stamp;
4. the plant holds the command over ``[t_k, t_k+1]`` (``physics_substeps`` RK4 steps); a state that
   diverges (``Plant.divergence()``) ends the flight, as the simulator does.

The final state ``t_N`` is published and answered (the controller does not know it is the last) but not
applied. With ``recording`` the same topics as the graph's recorder are written (log time = stamp).
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fsr_control.config.controller_config import controller_config
from fsr_control.flight_controller import FlightController, seconds_from_ns
from fsr_sim.config.scenario import Scenario, simulation_config
from fsr_sim.model.plant import Plant
from fsr_sim.model.so3 import euler_rate_matrix, euler_zyx_from_rotation, rotation_from_quaternion

EXIT_DIVERGED = 3


@dataclass
class InProcessResult:
    """Arrays over the published states ``k = 0..K`` (K = step count, or the step before a divergence).

    state: (K+1, 13) position world, velocity world, quaternion [x, y, z, w], angular velocity body.
    reference_*: the controller's reference; force_cmd / torque_cmd: the wrench it commanded (body);
    rotor_speeds / tilt_angles: (K+1, n) or None; external_*: true external wrench (body, as
    ``wrench_truth``); estimate_* and mass_estimate: the estimator's outputs (None when it is disabled).
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
    failures: list[str] = field(default_factory=list)
    interrupted: bool = False

    @property
    def sim_time(self) -> float:
        return float(self.time[-1])

    @property
    def exit_code(self) -> int:
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
        return np.array([rotation_from_quaternion(q) for q in self.state[:, 6:10]])

    @property
    def thrust(self) -> np.ndarray:
        return -self.force_cmd[:, 2]


def odometry_round_trip(state: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(quaternion as published, position, R, velocity world, angular velocity body) as the controller node
    sees the plant state after ``odom`` (see the module docstring)."""
    x, y, z, vx, vy, vz, qx, qy, qz, qw, wx, wy, wz = state.tolist()
    if qw < 0.0:
        qx, qy, qz, qw = -qx, -qy, -qz, -qw
    rotation = rotation_from_quaternion((qx, qy, qz, qw))
    velocity_body = rotation.T @ state[3:6]  # twist.linear of the odom
    # state_from_odometry rebuilds R from the same quaternion (bit-identical) and rotates the twist back.
    velocity_world = rotation @ velocity_body
    return np.array((qx, qy, qz, qw)), np.array((x, y, z)), rotation, velocity_world, np.array((wx, wy, wz))


def _make_estimator(scenario: Scenario, control_period: float):
    """The momentum observer configured by the scenario, or None (disabled or fsr_estimation missing)."""
    try:
        from fsr_estimation.config.estimator_config import estimator_config
        from fsr_estimation.core.observer import MomentumObserver
    except ImportError:
        return None
    config = estimator_config(scenario)
    if not config.enabled:
        return None
    return MomentumObserver(config.mass, config.inertia, config.c0, config.r, control_period)


class _Recorder:
    """Writes the graph's topics with ``RecordingWriter.write_message`` (log time = the message stamp)."""

    def __init__(self, path: Path, scenario: Scenario, rotors: bool) -> None:
        from fsr_sim.recording.writer import RecordingWriter

        self.writer = RecordingWriter(path, metadata={"fsr_scenario": {"yaml": scenario.dump()}})
        self.rotors = rotors

    def step(self, stamp_ns: int, quaternion, position, velocity_world, rotation, angular_velocity,
             external: tuple[np.ndarray, np.ndarray], output, estimate) -> None:
        from nav_msgs.msg import Odometry
        from std_msgs.msg import Float64

        from fsr_control.nodes.messages import attitude_command_message, reference_message
        from fsr_sim.ros.conversions import BODY_FRAME, WORLD_FRAME, rotor_command, time_from_ns, wrench_stamped

        odom = Odometry()
        odom.header.stamp = time_from_ns(stamp_ns)
        odom.header.frame_id = WORLD_FRAME
        odom.child_frame_id = BODY_FRAME
        pose = odom.pose.pose
        pose.position.x, pose.position.y, pose.position.z = position.tolist()
        pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = quaternion.tolist()
        twist = odom.twist.twist
        twist.linear.x, twist.linear.y, twist.linear.z = (rotation.T @ velocity_world).tolist()
        twist.angular.x, twist.angular.y, twist.angular.z = angular_velocity.tolist()
        write = self.writer.write_message
        write("/odom", odom, stamp_ns)
        write("/wrench_truth", wrench_stamped(stamp_ns, external[0], external[1]), stamp_ns)
        if self.rotors:
            write("/rotor_cmd", rotor_command(stamp_ns, output.rotor_speeds, output.tilt_angles), stamp_ns)
        write("/wrench_cmd", wrench_stamped(stamp_ns, output.force_body, output.torque_body), stamp_ns)
        write("/reference", reference_message(stamp_ns, output.reference), stamp_ns)
        write("/attitude_cmd", attitude_command_message(stamp_ns, output.rotation_cmd), stamp_ns)
        write("/wrench_desired", wrench_stamped(stamp_ns, output.force_desired, output.torque_desired), stamp_ns)
        if estimate is not None:
            write("/wrench_estimate", wrench_stamped(stamp_ns, estimate[0], estimate[1]), stamp_ns)
            write("/mass_estimate", Float64(data=float(estimate[2])), stamp_ns)

    def status(self, stamp_ns: int, state: str, reason: str, steps: int) -> None:
        from std_msgs.msg import String

        text = json.dumps({"state": state, "reason": reason, "sim_time": stamp_ns * 1e-9, "steps": steps})
        self.writer.write_message("/sim_status", String(data=text), stamp_ns)

    def close(self) -> None:
        self.writer.close()


def fly_in_process(scenario: Any, recording: Path | None = None) -> InProcessResult:
    """Fly ``scenario`` (a :class:`Scenario`, or the runner's checked scenario holding one) in one process."""
    scenario = getattr(scenario, "scenario", scenario)
    sim = simulation_config(scenario)
    config = controller_config(scenario)
    plant = Plant(sim)
    controller = FlightController(config, sim.vehicle, sim.actuation, sim.initial.position, sim.initial.rotation)
    observer = _make_estimator(scenario, sim.control_period)
    rotors = sim.actuation == "rotors"
    n = sim.vehicle.rotor_count
    steps = sim.step_count
    size = steps + 1
    times = np.zeros(size)
    states = np.zeros((size, 13))
    ref = {key: np.zeros((size, 3)) for key in ("p", "v", "a")}
    ref_rotation = np.zeros((size, 3, 3))
    force_cmd, torque_cmd = np.zeros((size, 3)), np.zeros((size, 3))
    speeds = np.zeros((size, n)) if rotors else None
    tilts = np.zeros((size, n)) if rotors and sim.vehicle.is_tilting else None
    ext_force, ext_torque = np.zeros((size, 3)), np.zeros((size, 3))
    est_force = np.zeros((size, 3)) if observer is not None else None
    est_torque = np.zeros((size, 3)) if observer is not None else None
    mass_est = np.zeros(size) if observer is not None else None
    recorder = _Recorder(Path(recording), scenario, rotors) if recording is not None else None
    end_reason, reason = "finished", "end of scenario"
    start = time.perf_counter()
    last = 0
    try:
        if recorder is not None:
            recorder.status(0, "running", "", 0)
        for k in range(size):
            stamp_ns = plant.stamp_ns
            quaternion, position, rotation, velocity_world, angular_velocity = odometry_round_trip(plant.state)
            output = controller.command(seconds_from_ns(stamp_ns), position, rotation, velocity_world,
                                        angular_velocity)
            force_world, torque_body = plant.external_wrench()
            external = (rotation.T @ force_world if sim.disturbances else np.zeros(3),
                        np.asarray(torque_body, dtype=float))
            estimate = None
            if observer is not None:
                eta = euler_zyx_from_rotation(rotation)
                eta_dot = np.linalg.solve(euler_rate_matrix(eta), angular_velocity)
                observer.update(velocity_world, eta, eta_dot, output.force_body, output.torque_body)
                f_est, t_est = observer.wrench_body()
                estimate = (f_est, t_est, observer.mass_estimate)
                est_force[k], est_torque[k], mass_est[k] = estimate
            times[k] = seconds_from_ns(stamp_ns)
            states[k] = plant.state
            states[k, 6:10] = quaternion
            reference = output.reference
            ref["p"][k], ref["v"][k], ref["a"][k] = reference.position, reference.velocity, reference.acceleration
            ref_rotation[k] = reference.rotation
            force_cmd[k], torque_cmd[k] = output.force_body, output.torque_body
            if speeds is not None:
                speeds[k] = output.rotor_speeds
            if tilts is not None:
                tilts[k] = output.tilt_angles
            ext_force[k], ext_torque[k] = external
            if recorder is not None:
                recorder.step(stamp_ns, quaternion, position, velocity_world, rotation, angular_velocity,
                              external, output, estimate)
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
        if recorder is not None:
            recorder.status(plant.stamp_ns, end_reason, reason, plant.step_index)
    finally:
        if recorder is not None:
            recorder.close()
    wall = time.perf_counter() - start
    keep = slice(0, last + 1)

    def cut(array: np.ndarray | None) -> np.ndarray | None:
        return None if array is None else array[keep]

    return InProcessResult(
        time=times[keep], state=states[keep], reference_position=ref["p"][keep],
        reference_velocity=ref["v"][keep], reference_acceleration=ref["a"][keep],
        reference_rotation=ref_rotation[keep], force_cmd=force_cmd[keep], torque_cmd=torque_cmd[keep],
        rotor_speeds=cut(speeds), tilt_angles=cut(tilts), external_force_body=ext_force[keep],
        external_torque_body=ext_torque[keep], estimate_force_body=cut(est_force),
        estimate_torque_body=cut(est_torque), mass_estimate=cut(mass_est),
        saturation=controller.saturation.as_dict(), tilt_saturation=controller.tilt_saturation.as_dict(),
        end_reason=end_reason, reason=reason, wall_time=wall,
        failures=[f"flight diverged: {reason}"] if end_reason == "diverged" else [],
    )
