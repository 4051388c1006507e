"""How a helper node (controller, estimator, recorder) ends with the flight it serves.

The simulator publishes ``sim_status`` (std_msgs/String JSON, latched) with ``state`` ``running`` and, at
the end, ``finished``, ``diverged`` or ``stopped`` with ``sim_time``, the stamp of the last state it
published (``t_K``). Two rules follow it:

**Ending by itself** (``exit_on_finish``, :class:`FlightEndRule`): a helper watches one ``sim_status`` per
vehicle (a fleet recorder every namespace it records) and ends when

1. every watched topic reported a final state, and
2. it then had no message for ``quiet`` s while no other node publishes on the topics it listens to any
   more (the producers have gone: everything they sent was acknowledged before they exited), or it had
   no message for ``linger`` s whatever the graph looks like (a producer kept running).

**Draining when stopped** (:meth:`FlightEnd.drain`): a node that answers states and is asked to stop (a
signal) after the simulator ended keeps taking what is queued until it has answered ``t_K``, then waits
until its subscribers acknowledged what it published, so that a recorder stopped after it holds every
message up to ``t_K``:

1. wait up to ``STATUS_GRACE_S`` for a final ``sim_status``; without one (the simulator still runs, or
   never started) the node stops at once;
2. spin until ``answered() >= t_K``, giving up after ``DRAIN_QUIET_S`` without progress (an input that never
   comes: the controller died) or ``DRAIN_MAX_S`` in total;
3. ``wait_for_all_acked`` on the node's publishers, at most ``ACK_TIMEOUT_S``;

all of it within ``SIGNAL_DRAIN_S`` of the signal (the node's ``stop_flag``, set by ``run_node``).

Stamps are integer nanoseconds; ``t_K`` is ``round(sim_time * 1e9)``, matched within ``STAMP_TOLERANCE_NS``
(the topic, its states and the tolerance: :mod:`fsr_sim.contract`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from fsr_sim.contract import SIM_STATUS, STAMP_TOLERANCE_NS, SimStatus

QUIET_S = 0.1  # s without a message, once every producer has gone
LINGER_S = 1.5  # s without a message while some producer still runs
STATUS_GRACE_S = 0.3  # s to wait for a final sim_status when stopped
DRAIN_QUIET_S = 1.0  # s without progress after which the drain gives up
DRAIN_MAX_S = 10.0  # s: bound on the whole drain
ACK_TIMEOUT_S = 2.0  # s: bound on waiting for subscribers to acknowledge
SIGNAL_DRAIN_S = 1.2  # s after a signal: the drain ends then at the latest


def _final_status(text: str) -> SimStatus | None:
    status = SimStatus.from_json(text)
    return status if status is not None and status.final else None


def final_state(text: str) -> str | None:
    """The final state of a ``sim_status`` JSON text (``finished``, ``diverged``, ``stopped``), else None."""
    status = _final_status(text)
    return None if status is None else status.state


def final_stamp_ns(text: str) -> int | None:
    """Stamp [ns] of the last published state from a final ``sim_status`` JSON text; None while ``running``
    (or the text is not a status)."""
    status = _final_status(text)
    return None if status is None else status.stamp_ns


class FlightEndRule:
    """Decides when a helper may end: every status topic final, then quiet (see the module docstring)."""

    def __init__(self, topics: Iterable[str], quiet: float = QUIET_S, linger: float = LINGER_S,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.finals: dict[str, str | None] = {topic: None for topic in topics}
        if not self.finals:
            raise ValueError("FlightEndRule: expected at least one sim_status topic, got none")
        self.quiet = quiet
        self.linger = linger
        self.clock = clock
        self.last_event = clock()

    def status(self, topic: str, text: str) -> None:
        """A ``sim_status`` message arrived on ``topic``."""
        state = final_state(text)
        if state is not None and self.finals.get(topic) is None:
            self.finals[topic] = state
        self.last_event = self.clock()

    def activity(self) -> None:
        """Any other message was handled."""
        self.last_event = self.clock()

    def all_final(self) -> bool:
        return all(state is not None for state in self.finals.values())

    def ended(self, producers_gone: Callable[[], bool]) -> bool:
        """True once every topic is final and the node has been quiet long enough (``producers_gone()`` is
        asked only when needed: it queries the ROS graph)."""
        if not self.all_final():
            return False
        idle = self.clock() - self.last_event
        return idle >= self.linger or (idle >= self.quiet and producers_gone())

    def describe(self) -> str:
        return ", ".join(f"{topic} {state}" for topic, state in self.finals.items())


class FlightEnd:
    """Follows a node's ``sim_status`` (relative: its namespace) for both rules of the module docstring.

    ``exit_on_finish``: :meth:`ended` may become True (otherwise the node runs until stopped).
    """

    def __init__(self, node: Any, exit_on_finish: bool = True, quiet: float = QUIET_S,
                 linger: float = LINGER_S) -> None:
        from std_msgs.msg import String

        from fsr_sim.ros.qos import qos_of

        self.node = node
        self.exit_on_finish = exit_on_finish
        self.final_ns: int | None = None
        self.subscription = node.create_subscription(String, SIM_STATUS.name, self._on_status,
                                                     qos_of(SIM_STATUS))
        self.topic = self.subscription.topic_name
        self.rule = FlightEndRule([self.topic], quiet, linger)
        self.reported = False

    def _on_status(self, msg: Any) -> None:
        self.rule.status(self.topic, msg.data)
        stamp = final_stamp_ns(msg.data)
        if stamp is not None:
            self.final_ns = stamp

    def activity(self) -> None:
        """The node handled a message (the flight is not over for it yet)."""
        self.rule.activity()

    def ended(self) -> bool:
        """True when the node should end by itself (``exit_on_finish``); logs why, once."""
        if not self.exit_on_finish or not self.rule.ended(self._producers_gone):
            return False
        if not self.reported:
            self.reported = True
            self.node.get_logger().info(f"flight ended ({self.rule.describe()}): exiting (exit_on_finish)")
        return True

    def _producers_gone(self) -> bool:
        """No other node publishes on any topic this node subscribes to (its own publishers excluded)."""
        own = {(self.node.get_name(), self.node.get_namespace())}
        for subscription in self.node.subscriptions:
            for info in self.node.get_publishers_info_by_topic(subscription.topic_name):
                if (info.node_name, info.node_namespace) not in own:
                    return False
        return True

    def drain(self, answered: Callable[[], int | None], publishers: Sequence[Any]) -> bool:
        """Answer what is queued up to the simulator's last state, then wait for acknowledgements.

        ``answered()`` is the stamp [ns] of the last state the node answered (None before the first).
        Returns True when the node answered the last state (or there was no final status to wait for).
        """
        from rclpy.duration import Duration

        from fsr_sim.ros.runtime import signal_deadline

        node = self.node
        executor = node.executor
        if executor is None:
            return True
        # After SIGINT/SIGTERM the whole drain keeps within SIGNAL_DRAIN_S (a node exits within 2 s of a signal).
        end = signal_deadline(getattr(node, "stop_flag", None), SIGNAL_DRAIN_S, DRAIN_MAX_S + ACK_TIMEOUT_S)
        deadline = min(time.monotonic() + STATUS_GRACE_S, end)
        while self.final_ns is None and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.02)
        if self.final_ns is None:
            return True
        final = self.final_ns - STAMP_TOLERANCE_NS
        start = progress_at = time.monotonic()
        last = answered()
        while last is None or last < final:
            now = time.monotonic()
            if now - progress_at > DRAIN_QUIET_S or now - start > DRAIN_MAX_S or now >= end:
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
        ack_deadline = min(time.monotonic() + ACK_TIMEOUT_S, end)
        for pub in publishers:
            remaining = ack_deadline - time.monotonic()
            if remaining <= 0.0 or not pub.wait_for_all_acked(Duration(nanoseconds=int(remaining * 1e9))):
                node.get_logger().warning(f"'{pub.topic_name}': not every subscriber acknowledged the last messages")
                break
        return complete
