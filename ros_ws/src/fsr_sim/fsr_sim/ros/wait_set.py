"""Taking messages without an executor: a raw rcl wait set over a fixed list of subscriptions.

rclpy's executors dispatch one callback per message; at 1 kHz (thousands of messages per second) that
dispatch dominates. The simulator (its command topic), the recorder (every topic) and, through
:class:`WaitSetSpinner`, the controller and estimator (their per-step inputs) instead wait on the
subscriptions' handles and take everything queued in one go (ROS2_FROM_PIP.md: the fastest measured style).
This uses rclpy's private ``rclpy_implementation.WaitSet``; this module is the only place that does.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from contextlib import ExitStack
from typing import Any


class SubscriptionWaitSet:
    """Wait on ``subscriptions`` (of ``node``) and take their queued messages.

    Each subscription's callback never runs: messages are taken here, deserialised unless the subscription
    was created with ``raw=True`` (then CDR ``bytes``).
    """

    def __init__(self, node: Any, subscriptions: list[Any]) -> None:
        from rclpy.impl.implementation_singleton import rclpy_implementation

        self.context = node.context
        self.subscriptions = list(subscriptions)
        self._wait_set = rclpy_implementation.WaitSet(len(self.subscriptions), 0, 0, 0, 0, 0, self.context.handle)

    def take_ready(self, timeout_ns: int) -> list[tuple[int, Any, dict]]:
        """Wait up to ``timeout_ns`` for data, then take every queued message of every ready subscription.

        Returns ``(index, message, info)`` in subscription order, then arrival order; ``info`` holds
        ``source_timestamp`` and ``received_timestamp`` [ns, wall clock]. Empty after a timeout.
        """
        taken: list[tuple[int, Any, dict]] = []
        wait_set = self._wait_set
        with ExitStack() as stack:
            stack.enter_context(self.context.handle)
            for sub in self.subscriptions:
                stack.enter_context(sub.handle)
            wait_set.clear_entities()
            for sub in self.subscriptions:
                wait_set.add_subscription(sub.handle)
            wait_set.wait(timeout_ns)
            ready = set(wait_set.get_ready_entities("subscription"))
            for index, sub in enumerate(self.subscriptions):
                if sub.handle.pointer not in ready:
                    continue
                while True:
                    message = sub.handle.take_message(sub.msg_type, sub.raw)
                    if message is None:
                        break
                    taken.append((index, message[0], message[1]))
        return taken


EXECUTOR_PERIOD = 0.05  # s: how often a WaitSetSpinner lets the executor run the node's other entities
WAIT_TIMEOUT_NS = 50_000_000  # longest single wait: signals and the executor's turn are noticed within it


class WaitSetSpinner:
    """Drives a node's per-step subscriptions without the executor (``run_node`` uses it for a node with
    ``hot_subscriptions``, a list of (subscription, callback) pairs).

    Each turn takes every queued message of those subscriptions and calls their callbacks (a ``raw=True``
    subscription's callback gets the CDR bytes, as from the executor); every ``EXECUTOR_PERIOD`` s the
    executor gets one turn for the node's other entities (goals, ``sim_status``, services). The executor
    still knows the hot subscriptions, so it can drain them alone (a node's ``close()``). ``gather`` > 0: after
    a batch, sleep that long so that the next one is larger (one wake-up per batch instead of one per message;
    for a node whose answers nobody waits for step by step, e.g. the estimator, whose queues are deep).
    """

    def __init__(self, node: Any, subscriptions: list[tuple[Any, Callable[[Any], None]]],
                 gather: float = 0.0) -> None:
        self.callbacks = [callback for _subscription, callback in subscriptions]
        self.gather = gather
        self.wait_set = SubscriptionWaitSet(node, [subscription for subscription, _callback in subscriptions])
        self.next_executor = time.monotonic() + EXECUTOR_PERIOD

    def spin_once(self, executor: Any, _stop: object = None) -> None:
        """One turn: dispatch what is queued (waiting at most ``WAIT_TIMEOUT_NS`` for it); then the executor's
        turn when it is due."""
        callbacks = self.callbacks
        taken = self.wait_set.take_ready(WAIT_TIMEOUT_NS)
        for index, message, _info in taken:
            callbacks[index](message)
        if taken and self.gather:
            time.sleep(self.gather)  # let the next batch gather (a node off the lockstep's critical path)
        now = time.monotonic()
        if now >= self.next_executor:
            self.next_executor = now + EXECUTOR_PERIOD
            executor.spin_once(timeout_sec=0.0)
