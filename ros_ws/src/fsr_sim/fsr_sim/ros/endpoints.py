"""Publishers and subscriptions of contract topics: the message type, relative name and QoS all come from the
topic's entry in :mod:`fsr_sim.contract`."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from fsr_sim.contract import Topic
from fsr_sim.ros.message_schema import message_class
from fsr_sim.ros.qos import qos_of


def publisher(node: Any, topic: Topic) -> Any:
    """``node``'s publisher of ``topic`` (relative names resolve in the node's namespace)."""
    return node.create_publisher(message_class(topic.type), topic.name, qos_of(topic))


def subscription(node: Any, topic: Topic, callback: Callable[[Any], None], raw: bool = False) -> Any:
    """``node``'s subscription to ``topic``; ``raw``: the callback gets the CDR bytes."""
    return node.create_subscription(message_class(topic.type), topic.name, callback, qos_of(topic), raw=raw)
