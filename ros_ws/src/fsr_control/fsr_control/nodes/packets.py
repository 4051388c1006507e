"""The controller's per-step messages as packed CDR bytes: what the controller node publishes and what an
in-process recording writes (:mod:`fsr_sim.ros.cdr_pack`; no rclpy needed).

Same topics and values as :func:`fsr_control.nodes.messages.controller_messages` (tested equal field by
field): ``rotor_cmd`` (rotor actuation only: ``rotor_i`` velocities, zero positions, and ``tilt_i`` positions
with zero velocities for a tilting vehicle), ``wrench_cmd``, ``wrench_shortfall`` (when the allocation reports
one), ``reference``, ``attitude_cmd``, ``wrench_desired``, all stamped with the answered state's stamp.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from fsr_control.flight_controller import ControlOutput
from fsr_sim.ros import cdr_pack

WORLD_FRAME = "world_ned"
BODY_FRAME = "base_link_frd"


class ControllerPackets:
    """Packs a :class:`ControlOutput` into ``(topic, CDR bytes)`` pairs (relative topic names).

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
        self._zeros = [0.0] * rotor_count
        self._wrench = cdr_pack.wrench_stamped(BODY_FRAME)
        self._reference = cdr_pack.trajectory_point(WORLD_FRAME, BODY_FRAME)
        self._attitude = cdr_pack.quaternion_stamped(WORLD_FRAME)
        self.templates: dict[str, cdr_pack.StampedDoubles] = {  # topic (relative) -> its payload's template
            "wrench_cmd": self._wrench, "wrench_shortfall": self._wrench, "reference": self._reference,
            "attitude_cmd": self._attitude, "wrench_desired": self._wrench}
        if self._rotor is not None:
            self.templates["rotor_cmd"] = self._rotor

    def pack(self, stamp_ns: int, output: ControlOutput) -> list[tuple[str, bytes]]:
        """Everything the controller publishes for the state stamped ``stamp_ns`` [ns], in publication order."""
        templates = self.templates
        return [(topic, templates[topic].pack(stamp_ns, values)) for topic, values in self.values(output)]

    def values(self, output: ControlOutput) -> list[tuple[str, Sequence[float]]]:
        """``(topic, numbers in field order)`` of everything published for ``output``, in publication order."""
        published: list[tuple[str, Sequence[float]]] = []
        if self.rotors:
            speeds = output.rotor_speeds.tolist()
            if output.tilt_angles is not None:
                values = [*self._zeros, *output.tilt_angles.tolist(), *speeds, *self._zeros]
            else:
                values = [*self._zeros, *speeds]
            published.append(("rotor_cmd", values))
        published.append(("wrench_cmd", (*output.force_body.tolist(), *output.torque_body.tolist())))
        if output.shortfall is not None:
            published.append(("wrench_shortfall", output.shortfall.tolist()))
        reference = output.reference
        rows = reference.rotation.tolist()
        published.append(("reference", (
            *reference.position.tolist(), *quaternion_of_rows(rows),
            *reference.velocity.tolist(), *_mat_vec(rows, reference.angular_velocity.tolist()),
            *reference.acceleration.tolist(), *_mat_vec(rows, reference.angular_acceleration.tolist()),
        )))
        published.append(("attitude_cmd", quaternion_of_rows(output.rotation_cmd.tolist())))
        published.append(("wrench_desired", (*output.force_desired.tolist(), *output.torque_desired.tolist())))
        return published


def quaternion_of_rows(r: list[list[float]]) -> tuple[float, float, float, float]:
    """Unit quaternion ``[x, y, z, w]``, ``w >= 0``, of the rows of a rotation matrix: Shepperd's method of
    :func:`fsr_sim.model.so3.quaternion_from_rotation` on floats (equal to it to rounding, ~1 us instead of ~7)."""
    trace = r[0][0] + r[1][1] + r[2][2]
    if trace > 0.0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = ((r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s, 0.25 * s)
    elif r[0][0] > r[1][1] and r[0][0] > r[2][2]:
        s = 2.0 * math.sqrt(1.0 + r[0][0] - r[1][1] - r[2][2])
        q = (0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s, (r[2][1] - r[1][2]) / s)
    elif r[1][1] > r[2][2]:
        s = 2.0 * math.sqrt(1.0 + r[1][1] - r[0][0] - r[2][2])
        q = ((r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s, (r[0][2] - r[2][0]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + r[2][2] - r[0][0] - r[1][1])
        q = ((r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s, (r[1][0] - r[0][1]) / s)
    x, y, z, w = q
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if w < 0.0:
        norm = -norm
    return x / norm, y / norm, z / norm, w / norm


def _mat_vec(rows: list[list[float]], v: list[float]) -> tuple[float, float, float]:
    return tuple(row[0] * v[0] + row[1] * v[1] + row[2] * v[2] for row in rows)
