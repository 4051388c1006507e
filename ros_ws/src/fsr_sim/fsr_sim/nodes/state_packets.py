"""The simulator's per-step messages as packed CDR bytes (what the simulator node publishes and an in-process
recording writes): ``odom``, ``wrench_truth`` and ``/clock`` of one state.

The values are the published row of the compiled core (:mod:`fsr_sim.core.odometry`: ``odom``, then
``wrench_truth`` force ``R^T f_ext,world`` and torque), the same as :class:`fsr_sim.nodes.state_messages.
StateMessages`; the bytes are :mod:`fsr_sim.ros.cdr_pack`'s (no rclpy needed).
"""

from __future__ import annotations

import numpy as np

from fsr_sim.contract import ODOM, WRENCH_TRUTH
from fsr_sim.core.odometry import ODOM_SIZE
from fsr_sim.model.odometry import published_row
from fsr_sim.ros import cdr_pack


class StatePackets:
    """Packs the state stamped ``stamp_ns``: after :meth:`fill_from_row`, ``odom``, ``wrench`` and ``clock`` hold
    the CDR payloads of ``odom``, ``wrench_truth`` and ``/clock``."""

    def __init__(self) -> None:
        self._odom = cdr_pack.odometry(ODOM.frame, ODOM.child_frame)
        self._wrench = cdr_pack.wrench_stamped(WRENCH_TRUTH.frame)
        self._clock = cdr_pack.clock()
        self.templates = {ODOM.name: self._odom, WRENCH_TRUTH.name: self._wrench}  # topic (relative) -> template
        self.odom = self.wrench = self.clock = b""
        self.stamp_ns = -1

    def fill_from(self, stamp_ns: int, state_vector: np.ndarray,
                  external: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Pack the messages of a state vector (13,) and the true external wrench (force world [N], torque
        body [N m]; None: zero) at ``stamp_ns`` [ns]."""
        self.fill_from_row(stamp_ns, published_row(state_vector, external))

    def fill_from_row(self, stamp_ns: int, row: np.ndarray) -> None:
        """Pack a published row (19,) of :mod:`fsr_sim.core.odometry` at ``stamp_ns`` [ns]."""
        values = row.tolist()
        self.odom = self._odom.pack(stamp_ns, values[:ODOM_SIZE])
        self.wrench = self._wrench.pack(stamp_ns, values[ODOM_SIZE:])
        self.clock = self._clock.pack(stamp_ns, ())
        self.stamp_ns = stamp_ns
