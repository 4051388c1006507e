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
from fsr_sim.ros import cdr_pack

WORLD_FRAME = "world_ned"
BODY_FRAME = "base_link_frd"


class ControllerPackets:
    """Packs output rows of the core tick into ``(topic, CDR bytes)`` pairs (relative topic names).

    ``rotor_count`` and ``tilting`` fix ``rotor_cmd``'s joint names (rotor actuation, ``rotors`` True)."""

    def __init__(self, rotors: bool, rotor_count: int = 0, tilting: bool = False) -> None:
        self.rotors = rotors
        self.rotor_count = rotor_count
        self.tilting = tilting
        names = [f"rotor_{i + 1}" for i in range(rotor_count)]
        if tilting:
            names += [f"tilt_{i + 1}" for i in range(rotor_count)]
        count = len(names)
        self._rotor = cdr_pack.joint_state(BODY_FRAME, names, count, count) if rotors else None
        self._wrench = cdr_pack.wrench_stamped(BODY_FRAME)
        self._reference = cdr_pack.trajectory_point(WORLD_FRAME, BODY_FRAME)
        self._attitude = cdr_pack.quaternion_stamped(WORLD_FRAME)
        self.templates: dict[str, cdr_pack.StampedDoubles] = {  # topic (relative) -> its payload's template
            "wrench_cmd": self._wrench, "wrench_shortfall": self._wrench, "reference": self._reference,
            "attitude_cmd": self._attitude, "wrench_desired": self._wrench}
        if self._rotor is not None:
            self.templates["rotor_cmd"] = self._rotor

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
            zeros = np.zeros_like(speeds)
            if self.tilting:
                tilts = rows[..., core.ROTOR_SPEEDS + n:core.ROTOR_SPEEDS + 2 * n]
                published.append(("rotor_cmd", np.concatenate((zeros, tilts, speeds, zeros), axis=-1)))
            else:
                published.append(("rotor_cmd", np.concatenate((zeros, speeds), axis=-1)))
        published.append(("wrench_cmd", rows[..., core.FORCE:core.FORCE + 6]))
        published.append(("wrench_shortfall", rows[..., core.SHORTFALL:core.SHORTFALL + 6]))
        published.append(("reference", rows[..., core.REFERENCE_POSITION:
                                            core.REFERENCE_POSITION + core.REFERENCE_MESSAGE_SIZE]))
        published.append(("attitude_cmd", rows[..., core.COMMANDED_QUATERNION:core.COMMANDED_QUATERNION + 4]))
        published.append(("wrench_desired", rows[..., core.DESIRED_FORCE:core.DESIRED_FORCE + 6]))
        return published
