"""Recording an in-process flight: the graph's topics, with the payloads the nodes publish.

Per published state ``t_k`` the CDR bytes the node graph records, packed by the nodes' own code:

* simulator: ``odom``, ``wrench_truth`` (:class:`fsr_sim.nodes.state_packets.StatePackets`) and
  ``sim_status`` (running at the start, the final state at the end);
* controller: ``rotor_cmd`` (rotor actuation), ``wrench_cmd``, ``wrench_shortfall``, ``reference``,
  ``attitude_cmd``, ``wrench_desired`` (:class:`fsr_control.nodes.packets.ControllerPackets`);
* estimator: ``wrench_estimate``, ``mass_estimate`` (:class:`fsr_estimation.nodes.packets.EstimatePackets`).

Log time = the message's simulated stamp, as the recorder node writes it. ``/clock`` is not written (it
carries nothing the odometry stamps do not). Per step only the numbers are kept (the packets' ``values``);
every ``BLOCK_STEPS`` steps, at a ``sim_status`` and at :meth:`FlightRecorder.close` they are packed and
written for the whole block with numpy (:meth:`fsr_sim.ros.cdr_pack.StampedDoubles.pack_rows`,
:meth:`fsr_sim.recording.writer.RecordingWriter.write_block`): the same payloads and the same file as
packing and writing each step's batch (tested byte for byte), 2-3x cheaper per step. A flight stopped by
Ctrl-C still gets every step it took: ``close()`` writes the pending block first.
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
PUBLICATION_ORDER = {topic: place for place, topic in enumerate(TOPIC_TYPES)}  # within a step (the nodes' order)
BLOCK_STEPS = 1000  # steps packed and written at once


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
        self._templates = {"/" + topic: template for packets in (self.state_packets, self.controller_packets,
                                                                 self.estimate_packets)
                           for topic, template in packets.templates.items()}
        self._stamps: list[int] = []  # the pending block's steps
        self._pending: dict[str, tuple[list[int], list[float]]] = {}  # topic -> (its steps, their values, flat)

    def step(self, stamp_ns: int, state_vector: np.ndarray, external: tuple[np.ndarray, np.ndarray] | None,
             output: Any, estimate: Any) -> None:
        """Record everything published for the state stamped ``stamp_ns``."""
        from fsr_sim.model.odometry import odometry_values

        self.step_values(stamp_ns, odometry_values(state_vector), external, output, estimate)

    def step_values(self, stamp_ns: int, published: tuple, external: tuple[np.ndarray, np.ndarray] | None,
                    output: Any, estimate: Any) -> None:
        """:meth:`step` with the state's :func:`~fsr_sim.model.odometry.odometry_values` already at hand."""
        step = len(self._stamps)
        self._stamps.append(stamp_ns)
        keep = self._keep
        odom, wrench = self.state_packets.values(published, external)
        keep("/odom", step, odom)
        keep("/wrench_truth", step, wrench)
        for topic, values in self.controller_packets.values(output):
            keep("/" + topic, step, values)
        if estimate is not None:
            wrench, mass = self.estimate_packets.values(estimate)
            keep("/wrench_estimate", step, wrench)
            keep("/mass_estimate", step, mass)
        if step + 1 >= BLOCK_STEPS:
            self.flush()

    def _keep(self, topic: str, step: int, values: Any) -> None:
        pending = self._pending.get(topic)
        if pending is None:
            pending = self._pending[topic] = ([], [])
        pending[0].append(step)
        pending[1].extend(values)  # flat: one float list per topic converts to an array fastest

    def flush(self) -> None:
        """Pack and write the pending block (topics registered in the order a step-by-step writer meets them)."""
        if not self._stamps:
            return
        stamps = np.array(self._stamps, dtype=np.int64)
        topics = sorted(self._pending, key=lambda topic: PUBLICATION_ORDER[topic])
        for topic in sorted(topics, key=lambda topic: self._pending[topic][0][0]):  # stable: first step, then order
            self._register(topic)
        messages = []
        for topic in topics:
            steps, values = self._pending[topic]
            every = len(steps) == len(stamps)
            payloads = self._templates[topic].pack_rows(stamps if every else stamps[steps],
                                                        np.array(values).reshape(len(steps), -1))
            messages.append((topic, None if every else steps, payloads))
        self._stamps, self._pending = [], {}
        self.writer.write_block(stamps, messages)

    def _register(self, topic: str) -> None:
        if topic not in self._registered:
            self.writer.add_topic(topic, TOPIC_TYPES[topic])
            self._registered.add(topic)

    def status(self, stamp_ns: int, state: str, reason: str, steps: int) -> None:
        """A ``sim_status`` message as the simulator publishes it."""
        from fsr_sim.ros import cdr_pack

        self.flush()
        text = json.dumps({"state": state, "reason": reason, "sim_time": stamp_ns * 1e-9, "steps": steps})
        self._register("/sim_status")
        self.writer.write_batch([("/sim_status", cdr_pack.string(text))], stamp_ns)

    def close(self) -> None:
        """Write the pending block, then finish the file (also when the block fails)."""
        try:
            self.flush()
        finally:
            self.writer.close()
