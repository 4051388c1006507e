"""Recording an in-process flight: the graph's topics written with the nodes' own message functions.

Per published state ``t_k`` the same messages the node graph records, built by the same code:

* simulator: ``odom``, ``wrench_truth`` (:class:`fsr_sim.nodes.state_messages.StateMessages`) and
  ``sim_status`` (running at the start, the final state at the end);
* controller: ``rotor_cmd`` (rotor actuation), ``wrench_cmd``, ``reference``
  (:func:`fsr_control.nodes.messages.controller_messages`);
* estimator: ``wrench_estimate``, ``mass_estimate`` (:func:`fsr_estimation.nodes.messages.estimate_messages`).

Log time = the message's simulated stamp, as the recorder node writes it. ``/clock`` is not written (it
carries nothing the odometry stamps do not).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np


class FlightRecorder:
    """Streams one in-process flight into a standard ROS 2 MCAP file (``close()`` finishes the file)."""

    def __init__(self, path: Path, scenario_yaml: str, rotors: bool) -> None:
        from fsr_sim.nodes.state_messages import StateMessages
        from fsr_sim.recording.writer import RecordingWriter

        self.writer = RecordingWriter(path, metadata={"fsr_scenario": {"yaml": scenario_yaml}})
        self.rotors = rotors
        self.state_messages = StateMessages()

    def step(self, stamp_ns: int, state_vector: np.ndarray, external: tuple[np.ndarray, np.ndarray] | None,
             output: Any, estimate: Any) -> None:
        """Write everything published for the state stamped ``stamp_ns``."""
        from fsr_control.nodes.messages import controller_messages
        from fsr_estimation.nodes.messages import estimate_messages

        write = self.writer.write_message
        messages = self.state_messages
        messages.fill_from(stamp_ns, state_vector, external)
        write("/odom", messages.odom, stamp_ns)
        write("/wrench_truth", messages.wrench, stamp_ns)
        for topic, message in controller_messages(stamp_ns, output, self.rotors):
            write(f"/{topic}", message, stamp_ns)
        if estimate is not None:
            wrench, mass = estimate_messages(estimate)
            write("/wrench_estimate", wrench, stamp_ns)
            write("/mass_estimate", mass, stamp_ns)

    def status(self, stamp_ns: int, state: str, reason: str, steps: int) -> None:
        """A ``sim_status`` message as the simulator publishes it."""
        from std_msgs.msg import String

        text = json.dumps({"state": state, "reason": reason, "sim_time": stamp_ns * 1e-9, "steps": steps})
        self.writer.write_message("/sim_status", String(data=text), stamp_ns)

    def close(self) -> None:
        self.writer.close()
