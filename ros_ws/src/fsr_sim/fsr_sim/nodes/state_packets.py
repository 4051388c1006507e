"""The simulator's per-step messages as packed CDR bytes (what the simulator node publishes and an in-process
recording writes): ``odom``, ``wrench_truth`` and ``/clock`` of one state.

The values are those of :class:`fsr_sim.nodes.state_messages.StateMessages` (same arithmetic:
:func:`fsr_sim.model.odometry.odometry_values`; ``wrench_truth`` force ``R^T f_ext,world`` with ``R`` from the
published quaternion); the bytes are :mod:`fsr_sim.ros.cdr_pack`'s (no rclpy needed).
"""

from __future__ import annotations

import numpy as np

from fsr_sim.model.odometry import odometry_values
from fsr_sim.model.so3 import rotation_from_quaternion
from fsr_sim.ros import cdr_pack

WORLD_FRAME = "world_ned"
BODY_FRAME = "base_link_frd"
_ZERO_WRENCH = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


class StatePackets:
    """Packs the state stamped ``stamp_ns``: after :meth:`fill_from`, ``odom``, ``wrench`` and ``clock`` hold
    the CDR payloads of ``odom``, ``wrench_truth`` and ``/clock``."""

    def __init__(self) -> None:
        self._odom = cdr_pack.odometry(WORLD_FRAME, BODY_FRAME)
        self._wrench = cdr_pack.wrench_stamped(BODY_FRAME)
        self._clock = cdr_pack.clock()
        self.templates = {"odom": self._odom, "wrench_truth": self._wrench}  # topic (relative) -> template
        self.odom = self.wrench = self.clock = b""
        self.stamp_ns = -1

    def fill_from(self, stamp_ns: int, state_vector: np.ndarray,
                  external: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Pack the messages of a state vector (13,) and the true external wrench (force world [N], torque
        body [N m]; None: zero) at ``stamp_ns`` [ns]."""
        self.fill_from_values(stamp_ns, odometry_values(state_vector), external)

    def fill_from_values(self, stamp_ns: int, published: tuple, external: tuple[np.ndarray, np.ndarray] | None
                         ) -> None:
        """:meth:`fill_from` with the state's :func:`~fsr_sim.model.odometry.odometry_values` already at hand."""
        odom, wrench = self.values(published, external)
        self.odom = self._odom.pack(stamp_ns, odom)
        self.wrench = self._wrench.pack(stamp_ns, wrench)
        self.clock = self._clock.pack(stamp_ns, ())
        self.stamp_ns = stamp_ns

    @staticmethod
    def values(published: tuple, external: tuple[np.ndarray, np.ndarray] | None) -> tuple[tuple, tuple]:
        """The numbers of ``odom`` (position, orientation x y z w, body velocity, angular velocity) and of
        ``wrench_truth`` (``R^T f_ext,world``, torque body; zero without a disturbance), in field order."""
        position, quaternion, velocity_body, angular_velocity = published
        odom = (*position, *quaternion, *velocity_body, *angular_velocity)
        if external is None:
            return odom, _ZERO_WRENCH
        force_world, torque_body = external
        rotation = rotation_from_quaternion(quaternion)
        return odom, (*(rotation.T @ force_world).tolist(), *np.asarray(torque_body, dtype=float).tolist())
