"""Nothing published before the recorder listens: each node waits for a matched reader on its recorded topics.

DDS matches each writer-reader pair on its own, asynchronously. The simulator's handshake waits for the
recorder's ``odom`` reader, but the recorder's reader of, say, ``wrench_shortfall`` may match the controller's
writer later: after a lost discovery message, seconds later (measured once: a 0.5 s graph flight whose recording
held no ``wrench_shortfall`` at all, the controller having ended before the match). The streams are
transient-local, so a late match still delivers the writer's history, but only while the writer lives and
only its last ``STREAM_DEPTH`` messages.

So ``fsr-fly`` gives every node the topics its recorder takes (parameter ``recorded_topics``, relative names
as :func:`fsr_sim.contract.recording_selection` gives them: ``odom``, ``/clock``); before a node takes part in
the flight, each of its publishers on one of them has a matched subscription:

* the controller and the estimator wait before they subscribe to ``odom`` (the simulator's handshake waits
  for that subscription, so no state goes out before);
* the simulator makes it part of its handshake.

Default ``""``: wait for nothing (nodes started by hand, without a recorder).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

from fsr_sim.ros.node_usage import Parameter

RECORDED_TOPICS = Parameter("recorded_topics", "", "comma-separated topics a recorder takes (fsr-fly sets it): "
                                                   "wait for a matched reader on each this node publishes")
MATCH_TIMEOUT_S = 20.0  # s: then the node goes on, with a warning naming the topics
POLL_S = 0.01  # s between looks at the graph (matching is asynchronous)


def recorded_topics_parameter(node: Any) -> frozenset[str]:
    """Declare and read ``recorded_topics``: the set of names (empty: none)."""
    from rcl_interfaces.msg import ParameterDescriptor

    value = node.declare_parameter(RECORDED_TOPICS.name, RECORDED_TOPICS.default,
                                   ParameterDescriptor(dynamic_typing=True)).value
    return parse_recorded_topics(value)


def parse_recorded_topics(value: object) -> frozenset[str]:
    """The names of a comma-separated ``recorded_topics`` value (None or empty: none)."""
    if value is None:
        return frozenset()
    if not isinstance(value, str):
        from fsr_sim.config.validation import ConfigError

        raise ConfigError(f"parameter '{RECORDED_TOPICS.name}'", f"must be a comma-separated list of topics, "
                                                                 f"got {value!r}", "node")
    return frozenset(name.strip() for name in value.split(",") if name.strip())


def unmatched(publishers: Mapping[str, Any], recorded: frozenset[str]) -> list[str]:
    """The names among ``recorded`` whose publisher (``{relative name: publisher}``; None: not created) has no
    matched subscription yet."""
    return sorted(name for name, pub in publishers.items()
                  if pub is not None and name in recorded and pub.get_subscription_count() == 0)


def wait_until_recorded(node: Any, publishers: Mapping[str, Any], recorded: frozenset[str],
                        timeout: float = MATCH_TIMEOUT_S) -> list[str]:
    """Block until every recorded publisher has a reader, at most ``timeout`` s; return the topics still
    without one (warned about: their messages may be missing from the recording)."""
    deadline = time.monotonic() + timeout
    missing = unmatched(publishers, recorded)
    if missing:
        node.get_logger().info(f"waiting for a recorder reader on {', '.join(missing)}")
    while missing and time.monotonic() < deadline:
        time.sleep(POLL_S)
        missing = unmatched(publishers, recorded)
    if missing:
        node.get_logger().warning(f"no recorder reader after {timeout:g} s on {', '.join(missing)}: "
                                  "the recording may miss them")
    return missing
