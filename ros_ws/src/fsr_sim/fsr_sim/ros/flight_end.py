"""Ending after the simulator: a node that answers states answers every state the simulator published.

The simulator's last word is its latched ``sim_status`` (``finished`` / ``diverged`` / ``stopped``) with
``sim_time``, the stamp of the last state it published (``t_K = K * control_period``). When a node that
answers states (controller, estimator) is asked to stop after that, it keeps taking what is queued until
it has answered ``t_K``, then waits until its subscribers have acknowledged what it published, so that a
recorder stopped after it holds every message up to ``t_K``:

1. wait up to ``STATUS_GRACE_S`` for a final ``sim_status`` (already queued when the simulator exited
   first: it waits for every subscriber to acknowledge it). Without one (the simulator still runs, or
   never started) the node stops at once, as before;
2. spin until ``answered() >= t_K``, giving up after ``QUIET_S`` without progress (an input that never
   comes: the controller died) or ``DRAIN_MAX_S`` in total;
3. ``wait_for_all_acked`` on the node's publishers, at most ``ACK_TIMEOUT_S``.

Stamps are integer nanoseconds; ``t_K`` is ``round(sim_time * 1e9)`` and matched within ``STAMP_TOLERANCE_NS``.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from typing import Any

FINAL_STATES = ("finished", "diverged", "stopped")
STATUS_GRACE_S = 0.3  # s to wait for a final sim_status at shutdown
QUIET_S = 1.0  # s without progress after which the drain gives up
DRAIN_MAX_S = 10.0  # s: bound on the whole drain
ACK_TIMEOUT_S = 2.0  # s: bound on waiting for subscribers to acknowledge
STAMP_TOLERANCE_NS = 1000  # sim_time is a float of seconds; steps are >= 1 us apart


def final_stamp_ns(status_json: str) -> int | None:
    """Stamp [ns] of the last published state from a ``sim_status`` JSON text, or None while it is
    ``running`` (or the text is not a status)."""
    try:
        status = json.loads(status_json)
        if status.get("state") not in FINAL_STATES:
            return None
        return int(round(float(status["sim_time"]) * 1e9))
    except (ValueError, KeyError, TypeError, AttributeError):
        return None


class FlightEnd:
    """Follows ``sim_status`` (latched) for a node; :meth:`drain` runs the shutdown rule above."""

    def __init__(self, node: Any, topic: str = "sim_status") -> None:
        from std_msgs.msg import String

        from fsr_sim.ros.qos import LATCHED_QOS

        self.final_ns: int | None = None
        self.subscription = node.create_subscription(String, topic, self._on_status, LATCHED_QOS)

    def _on_status(self, msg: Any) -> None:
        stamp = final_stamp_ns(msg.data)
        if stamp is not None:
            self.final_ns = stamp

    def drain(self, node: Any, answered: Callable[[], int | None], publishers: Sequence[Any]) -> bool:
        """Answer what is queued up to the simulator's last state, then wait for acknowledgements.

        ``answered()`` is the stamp [ns] of the last state the node answered (None before the first).
        Returns True when the node answered the last state (or there was no final status to wait for).
        """
        from rclpy.duration import Duration

        executor = node.executor
        if executor is None:
            return True
        deadline = time.monotonic() + STATUS_GRACE_S
        while self.final_ns is None and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.02)
        if self.final_ns is None:
            return True
        final = self.final_ns - STAMP_TOLERANCE_NS
        start = progress_at = time.monotonic()
        last = answered()
        while last is None or last < final:
            now = time.monotonic()
            if now - progress_at > QUIET_S or now - start > DRAIN_MAX_S:
                where = "nothing" if last is None else f"t = {last * 1e-9:.4f} s"
                node.get_logger().warning(
                    f"stopping after answering {where}, short of the simulator's last state t = "
                    f"{self.final_ns * 1e-9:.4f} s (no input for {now - progress_at:.1f} s)"
                )
                break
            executor.spin_once(timeout_sec=0.05)
            current = answered()
            if current != last:
                last, progress_at = current, time.monotonic()
        complete = last is not None and last >= final
        if complete:
            node.get_logger().info(f"answered every state up to the simulator's last, t = {self.final_ns * 1e-9:.4f} s")
        ack_deadline = time.monotonic() + ACK_TIMEOUT_S
        for pub in publishers:
            remaining = ack_deadline - time.monotonic()
            if remaining <= 0.0 or not pub.wait_for_all_acked(Duration(nanoseconds=int(remaining * 1e9))):
                node.get_logger().warning(f"'{pub.topic_name}': not every subscriber acknowledged the last messages")
                break
        return complete
