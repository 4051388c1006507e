"""Ending a helper node (controller, estimator, recorder) by itself when the flight it serves has ended.

The simulator publishes ``sim_status`` (std_msgs/String JSON, latched) with ``state`` ``running`` and, at
the end, ``finished``, ``diverged`` or ``stopped``. A helper watches one ``sim_status`` topic per vehicle
(a fleet recorder watches every namespace it records) and is *ended* when

1. every watched topic reported a final state, and
2. it then had no message for ``quiet`` s while no other node publishes on the topics it listens to any
   more (the producers have gone: everything they sent was acknowledged before they exited), or it had
   no message for ``linger`` s whatever the graph looks like (a producer kept running).

:class:`FlightEndRule` is the rule (plain Python, testable without ROS); :class:`FlightEndWatch` wires it to
a node's ``sim_status`` subscriptions. A node reports each message it handles with
:meth:`FlightEndWatch.activity`.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterable

FINAL_STATES = ("finished", "diverged", "stopped")
QUIET_S = 0.1  # s without a message, once every producer has gone
LINGER_S = 1.5  # s without a message while some producer still runs


def final_state(text: str) -> str | None:
    """The final state of a ``sim_status`` JSON text (``finished``, ``diverged``, ``stopped``), else None."""
    try:
        state = json.loads(text).get("state")
    except (ValueError, AttributeError):
        return None
    return state if state in FINAL_STATES else None


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


class FlightEndWatch:
    """Subscribes a node to ``sim_status`` (relative: its namespace) and applies :class:`FlightEndRule`."""

    def __init__(self, node: object, quiet: float = QUIET_S, linger: float = LINGER_S) -> None:
        from std_msgs.msg import String

        from fsr_sim.ros.qos import LATCHED_QOS

        self.node = node
        self.subscription = node.create_subscription(
            String, "sim_status", lambda msg: self.rule.status(self.topic, msg.data), LATCHED_QOS
        )
        self.topic = self.subscription.topic_name
        self.rule = FlightEndRule([self.topic], quiet, linger)
        self.reported = False

    def activity(self) -> None:
        self.rule.activity()

    def ended(self) -> bool:
        """True when the node should end; logs why, once."""
        if not self.rule.ended(self._producers_gone):
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
