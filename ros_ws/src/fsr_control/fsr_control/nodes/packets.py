"""The controller's per-step messages as packed CDR bytes: what the controller node publishes and what an
in-process recording writes (:mod:`fsr_sim.ros.cdr_pack`; no rclpy needed).

The numbers are slices of the core tick's output row (:mod:`fsr_control.core.controller`), one or many
rows at once (:meth:`ControllerPackets.values`): ``rotor_cmd`` (rotor actuation only: ``rotor_i`` velocities,
zero positions, and ``tilt_i`` positions with zero velocities for a tilting vehicle), ``wrench_cmd``,
``wrench_shortfall``, ``reference``, ``attitude_cmd``, ``wrench_desired``, all stamped with the answered
state's stamp (same values as :func:`fsr_control.nodes.messages.controller_messages`, tested field by field).
"""

from __future__ import annotations

import numpy as np

from fsr_control.core import controller as core
from fsr_sim.contract import (
    ATTITUDE_CMD,
    REFERENCE,
    ROTOR_CMD,
    WRENCH_CMD,
    WRENCH_DESIRED,
    WRENCH_SHORTFALL,
)
from fsr_sim.nodes.state_packets import joint_state_template, joint_values
from fsr_sim.ros import cdr_pack


class ControllerPackets:
    """Packs output rows of the core tick into ``(topic, CDR bytes)`` pairs (relative topic names).

    ``rotor_count`` and ``tilting`` fix ``rotor_cmd``'s joint names (rotor actuation, ``rotors`` True)."""

    def __init__(self, rotors: bool, rotor_count: int = 0, tilting: bool = False) -> None:
        self.rotors = rotors
        self.rotor_count = rotor_count
        self.tilting = tilting
        self.templates: dict[str, cdr_pack.StampedDoubles] = {  # topic (relative) -> its payload's template
            topic.name: cdr_pack.wrench_stamped(topic.frame)
            for topic in (WRENCH_CMD, WRENCH_SHORTFALL, WRENCH_DESIRED)}
        self.templates[REFERENCE.name] = cdr_pack.trajectory_point(REFERENCE.frame, REFERENCE.child_frame)
        self.templates[ATTITUDE_CMD.name] = cdr_pack.quaternion_stamped(ATTITUDE_CMD.frame)
        if rotors:
            self.templates[ROTOR_CMD.name] = joint_state_template(ROTOR_CMD.frame, rotor_count, tilting)

    def pack(self, stamp_ns: int, row: np.ndarray) -> list[tuple[str, bytes]]:
        """Everything the controller publishes for the state stamped ``stamp_ns`` [ns], in publication order."""
        templates = self.templates
        return [(topic, templates[topic].pack(stamp_ns, values.tolist())) for topic, values in self.values(row)]

    def values(self, rows: np.ndarray) -> list[tuple[str, np.ndarray]]:
        """``(topic, numbers in field order)`` of everything published for an output row (or for the rows of a
        (K, width) array: then (K, m) each), in publication order."""
        n = self.rotor_count
        published: list[tuple[str, np.ndarray]] = []
        if self.rotors:
            speeds = rows[..., core.ROTOR_SPEEDS:core.ROTOR_SPEEDS + n]
            tilts = rows[..., core.ROTOR_SPEEDS + n:core.ROTOR_SPEEDS + 2 * n] if self.tilting else None
            published.append((ROTOR_CMD.name, joint_values(speeds, tilts)))
        published.append((WRENCH_CMD.name, rows[..., core.FORCE:core.FORCE + 6]))
        published.append((WRENCH_SHORTFALL.name, rows[..., core.SHORTFALL:core.SHORTFALL + 6]))
        published.append((REFERENCE.name, rows[..., core.REFERENCE_POSITION:
                                               core.REFERENCE_POSITION + core.REFERENCE_MESSAGE_SIZE]))
        published.append((ATTITUDE_CMD.name, rows[..., core.COMMANDED_QUATERNION:core.COMMANDED_QUATERNION + 4]))
        published.append((WRENCH_DESIRED.name, rows[..., core.DESIRED_FORCE:core.DESIRED_FORCE + 6]))
        return published
