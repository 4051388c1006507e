"""Recording an in-process flight: the graph's topics, with the payloads the nodes publish.

Per published state ``t_k`` the CDR bytes the node graph records, packed from the flight loop's arrays by
the nodes' own templates (:meth:`fsr_sim.ros.cdr_pack.StampedDoubles.pack_rows`, many steps at once):

* simulator: ``odom``, ``wrench_truth``, with an IMU ``imu`` and with a measured ``odom`` ``odom_truth`` (the
  published rows,
  :class:`fsr_sim.nodes.state_packets.StatePackets`' templates), ``rotor_state`` (with actuator dynamics: the
  rotors' actual speeds and tilts) and ``sim_status`` (running at the start, the final state at the end);
* controller: ``rotor_cmd`` (rotor actuation), ``wrench_cmd``, ``wrench_shortfall``, ``reference``,
  ``attitude_cmd``, ``wrench_desired`` (slices of the controller's output rows,
  :class:`fsr_control.nodes.packets.ControllerPackets`);
* estimator: ``wrench_estimate``, ``mass_estimate`` (:class:`fsr_estimation.nodes.packets.EstimatePackets`).

Log time = the message's simulated stamp, as the recorder node writes it. ``/clock`` is not written (it
carries nothing the odometry stamps do not). Steps are written in blocks of at most ``BLOCK_STEPS``
(:meth:`fsr_sim.recording.writer.RecordingWriter.write_block`): the file does not depend on the block size
(tested byte for byte). A flight stopped by Ctrl-C keeps every step it took: the loop hands each block over
as soon as it is flown.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fsr_sim.contract import (
    IMU,
    MASS_ESTIMATE,
    ODOM,
    ODOM_TRUTH,
    ROTOR_STATE,
    SIM_STATUS,
    WRENCH_ESTIMATE,
    WRENCH_TRUTH,
    SimStatus,
    recorded_topics,
)

if TYPE_CHECKING:
    from fsr_bringup.live.server import LiveServer
    from fsr_sim.core.sensors import ImuParams

TOPIC_TYPES = {"/" + name: type_name for name, type_name in recorded_topics().items()}
BLOCK_STEPS = 1000  # steps packed and written at once
# Bigger chunks than the recorder node's, which a SIGKILL may cut: close() always finishes this file, and each chunk
# costs a fixed share (compression, index records; ex4: 1 MiB instead of 256 KiB, 1 us per step less, 5 % smaller).
CHUNK_SIZE = 1024 * 1024


class InProcessRecorder:
    """Streams one in-process flight into a standard ROS 2 MCAP file and/or a live server (``close()`` finishes
    the file)."""

    def __init__(self, path: Path | None, scenario_yaml: str, rotors: bool, rotor_count: int = 0,
                 tilting: bool = False, topics: frozenset[str] | None = None, rotor_state: bool = False,
                 imu: ImuParams | None = None, live: LiveServer | None = None, odom_truth: bool = False) -> None:
        """``topics``: record only these (:func:`fsr_sim.contract.recording_selection`; None: all);
        ``rotor_state``: the plant has actuator dynamics (the simulator then publishes ``rotor_state``);
        ``imu``: the plant's IMU stage (enabled: the simulator publishes ``imu``); ``live``: also serve everything
        written there (without ``path``: only serve it); ``odom_truth``: ``odom`` is measured (a sensor stage on),
        the true state is recorded beside it on ``odom_truth``."""
        from fsr_bringup.recording.derived import DerivedTopics
        from fsr_bringup.recording.metadata import scenario_from_text
        from fsr_control.nodes.packets import ControllerPackets
        from fsr_estimation.nodes.packets import EstimatePackets
        from fsr_sim.nodes.state_packets import StatePackets
        from fsr_sim.recording.reader import SCENARIO_METADATA
        from fsr_sim.recording.writer import RecordingWriter

        self.writer = live
        if path is not None:
            path = Path(path)
            self.writer = RecordingWriter(path, metadata={SCENARIO_METADATA: {"yaml": scenario_yaml}},
                                          chunk_size=CHUNK_SIZE)
            self.writer = self.writer if live is None else live.tee(self.writer)
        scenario, _ = scenario_from_text(scenario_yaml, "/", f"{path or 'the flight'} ({SCENARIO_METADATA} metadata)",
                                         Path.cwd() if path is None else path.parent)
        self.derived = DerivedTopics(scenario, "/", topics)
        for topic, type_name in self.derived.topics().items():
            self.writer.add_topic(topic, type_name)
        for topic, stamps, rows in self.derived.static():
            self.writer.write_block(stamps, [(topic, None, rows)])
        self.controller_packets = ControllerPackets(rotors, rotor_count, tilting)
        self.rotor_state = rotor_state
        self.rotor_count = rotor_count
        self.tilting = tilting
        self.imu = imu is not None and imu.enabled
        self.odom_truth = odom_truth
        state_packets = StatePackets(rotor_count if rotor_state else 0, tilting, imu, odom_truth)
        self._templates = {"/" + topic: template for packets in (state_packets, self.controller_packets,
                                                                 EstimatePackets())
                           for topic, template in packets.templates.items()}
        self._registered: set[str] = set()
        self._topics = topics

    def write_steps(self, stamps_ns: np.ndarray, published: np.ndarray, control: np.ndarray,
                    estimates: np.ndarray | None, actuators: np.ndarray | None = None) -> None:
        """Record everything published for the states stamped ``stamps_ns`` (K,): their published rows (K, width),
        the controller's output rows (K, width), the estimates (K, 7) or None (estimator off) and the rotors'
        actual speeds and tilts (K, 2n) (``rotor_state``, recorded with actuator dynamics)."""
        from fsr_sim.core.odometry import IMU_ANGULAR_VELOCITY, IMU_END, ODOM_SIZE, TRUE_ODOM, WRENCH_TRUTH_END
        from fsr_sim.nodes.state_packets import joint_values

        for start in range(0, len(stamps_ns), BLOCK_STEPS):
            block = slice(start, start + BLOCK_STEPS)
            columns = [("/" + ODOM.name, published[block, :ODOM_SIZE]),
                       ("/" + WRENCH_TRUTH.name, published[block, ODOM_SIZE:WRENCH_TRUTH_END])]
            if self.odom_truth:
                columns.insert(1, ("/" + ODOM_TRUTH.name, published[block, TRUE_ODOM:TRUE_ODOM + ODOM_SIZE]))
            if self.rotor_state:
                n = self.rotor_count
                rows = actuators[block]
                columns.append(("/" + ROTOR_STATE.name, joint_values(rows[:, :n], rows[:, n:] if self.tilting
                                                                     else None)))
            if self.imu:
                columns.append(("/" + IMU.name, published[block, IMU_ANGULAR_VELOCITY:IMU_END]))
            columns += [("/" + topic, values) for topic, values in self.controller_packets.values(control[block])]
            if estimates is not None:
                columns += [("/" + WRENCH_ESTIMATE.name, estimates[block, :6]),
                            ("/" + MASS_ESTIMATE.name, estimates[block, 6:])]
            stamps = stamps_ns[block]
            if self._topics is not None:
                columns = [(topic, values) for topic, values in columns if topic[1:] in self._topics]
            for topic, _ in columns:
                self._register(topic)
            messages = [(topic, None, self._templates[topic].pack_rows(stamps, values)) for topic, values in columns]
            derived = [(topic, np.searchsorted(stamps, steps), rows) for source, _, payloads in messages
                       for topic, steps, rows in self.derived.take(source[1:], stamps, payloads)]
            self.writer.write_block(stamps, messages + derived)

    def _register(self, topic: str) -> None:
        if topic not in self._registered:
            self.writer.add_topic(topic, TOPIC_TYPES[topic])
            self._registered.add(topic)

    def status(self, stamp_ns: int, state: str, reason: str, steps: int) -> None:
        """A ``sim_status`` message as the simulator publishes it."""
        from fsr_sim.ros import cdr_pack

        text = SimStatus(state, reason, stamp_ns * 1e-9, steps).to_json()
        topic = "/" + SIM_STATUS.name
        self._register(topic)
        self.writer.write_batch([(topic, cdr_pack.string(text))], stamp_ns)

    def close(self) -> None:
        """Finish the file."""
        self.writer.close()
