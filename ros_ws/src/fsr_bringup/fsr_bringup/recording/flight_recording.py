"""Recording an in-process flight: the graph's topics, with the payloads the nodes publish.

Per published state ``t_k`` the CDR bytes the node graph records, packed by the nodes' own code:

* simulator: ``odom``, ``wrench_truth`` (:class:`fsr_sim.nodes.state_packets.StatePackets`) and
  ``sim_status`` (running at the start, the final state at the end);
* controller: ``rotor_cmd`` (rotor actuation), ``wrench_cmd``, ``wrench_shortfall``, ``reference``,
  ``attitude_cmd``, ``wrench_desired`` (:class:`fsr_control.nodes.packets.ControllerPackets`);
* estimator: ``wrench_estimate``, ``mass_estimate`` (:class:`fsr_estimation.nodes.packets.EstimatePackets`).

Log time = the message's simulated stamp, as the recorder node writes it. ``/clock`` is not written (it
carries nothing the odometry stamps do not). The messages of one step go into the file as one batch
(:meth:`fsr_sim.recording.writer.RecordingWriter.write_batch`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

TOPIC_TYPES = {
    "/odom": "nav_msgs/msg/Odometry",
    "/wrench_truth": "geometry_msgs/msg/WrenchStamped",
    "/rotor_cmd": "sensor_msgs/msg/JointState",
    "/wrench_cmd": "geometry_msgs/msg/WrenchStamped",
    "/wrench_shortfall": "geometry_msgs/msg/WrenchStamped",
    "/reference": "trajectory_msgs/msg/MultiDOFJointTrajectory",
    "/attitude_cmd": "geometry_msgs/msg/QuaternionStamped",
    "/wrench_desired": "geometry_msgs/msg/WrenchStamped",
    "/wrench_estimate": "geometry_msgs/msg/WrenchStamped",
    "/mass_estimate": "std_msgs/msg/Float64",
    "/sim_status": "std_msgs/msg/String",
}


class FlightRecorder:
    """Streams one in-process flight into a standard ROS 2 MCAP file (``close()`` finishes the file)."""

    def __init__(self, path: Path, scenario_yaml: str, rotors: bool, rotor_count: int = 0,
                 tilting: bool = False) -> None:
        from fsr_control.nodes.packets import ControllerPackets
        from fsr_estimation.nodes.packets import EstimatePackets
        from fsr_sim.nodes.state_packets import StatePackets
        from fsr_sim.recording.writer import RecordingWriter

        self.writer = RecordingWriter(path, metadata={"fsr_scenario": {"yaml": scenario_yaml}})
        self.rotors = rotors
        self.state_packets = StatePackets()
        self.controller_packets = ControllerPackets(rotors, rotor_count, tilting)
        self.estimate_packets = EstimatePackets()
        self._registered: set[str] = set()

    def step(self, stamp_ns: int, state_vector: np.ndarray, external: tuple[np.ndarray, np.ndarray] | None,
             output: Any, estimate: Any) -> None:
        """Write everything published for the state stamped ``stamp_ns``."""
        from fsr_sim.model.odometry import odometry_values

        self.step_values(stamp_ns, odometry_values(state_vector), external, output, estimate)

    def step_values(self, stamp_ns: int, published: tuple, external: tuple[np.ndarray, np.ndarray] | None,
                    output: Any, estimate: Any) -> None:
        """:meth:`step` with the state's :func:`~fsr_sim.model.odometry.odometry_values` already at hand."""
        state = self.state_packets
        state.fill_from_values(stamp_ns, published, external)
        batch = [("/odom", state.odom), ("/wrench_truth", state.wrench)]
        batch += [("/" + topic, data) for topic, data in self.controller_packets.pack(stamp_ns, output)]
        if estimate is not None:
            wrench, mass = self.estimate_packets.pack(estimate)
            batch += [("/wrench_estimate", wrench), ("/mass_estimate", mass)]
        self._register(batch)
        self.writer.write_batch(batch, stamp_ns)

    def _register(self, batch: list[tuple[str, bytes]]) -> None:
        for topic, _ in batch:
            if topic not in self._registered:
                self.writer.add_topic(topic, TOPIC_TYPES[topic])
                self._registered.add(topic)

    def status(self, stamp_ns: int, state: str, reason: str, steps: int) -> None:
        """A ``sim_status`` message as the simulator publishes it."""
        from fsr_sim.ros import cdr_pack

        text = json.dumps({"state": state, "reason": reason, "sim_time": stamp_ns * 1e-9, "steps": steps})
        batch = [("/sim_status", cdr_pack.string(text))]
        self._register(batch)
        self.writer.write_batch(batch, stamp_ns)

    def close(self) -> None:
        self.writer.close()
