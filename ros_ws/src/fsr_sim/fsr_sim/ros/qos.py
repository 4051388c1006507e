"""QoS profiles shared by every node and the recorder.

The lockstep topics are reliable with a deep queue so that a slower listener (estimator, recorder) gets
every step instead of dropping samples, and transient-local so that a listener matched a little late (DDS
discovery is asynchronous: the estimator may see the controller's ``wrench_cmd`` some milliseconds after
the first commands went out) still receives the history it missed. A volatile subscriber (e.g. a user's
tool) matches these publishers; a volatile *publisher* does not match our subscribers, so external
inputs that users publish by hand (``goal``) use ``GOAL_QOS``. ``/clock`` is reliable (rclpy's
best-effort clock subscription matches it).
"""

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from fsr_sim.contract import Topic

STREAM_DEPTH = 5000  # messages: about 5 s of a 1 kHz stream


def _reliable(durability: DurabilityPolicy, depth: int) -> QoSProfile:
    """Every profile is reliable and keeps the last ``depth`` messages; they differ in durability and depth."""
    return QoSProfile(reliability=ReliabilityPolicy.RELIABLE, durability=durability, history=HistoryPolicy.KEEP_LAST,
                      depth=depth)


STREAM_QOS = _reliable(DurabilityPolicy.TRANSIENT_LOCAL, STREAM_DEPTH)
# Inputs published by users (any durability matches a volatile subscriber).
GOAL_QOS = _reliable(DurabilityPolicy.VOLATILE, 10)
# /clock: reliable and as deep as the streams, so that the recorder keeps every step even when it falls a few
# hundred messages behind (with depth 10 it lost ~5 %); volatile, so rclpy's own best-effort clock
# subscription (use_sim_time) still matches.
CLOCK_QOS = _reliable(DurabilityPolicy.VOLATILE, STREAM_DEPTH)
# sim_progress: a watcher wants the latest value only.
PROGRESS_QOS = _reliable(DurabilityPolicy.VOLATILE, 1)
# One-off messages (goals, status) that a late subscriber should still receive.
LATCHED_QOS = _reliable(DurabilityPolicy.TRANSIENT_LOCAL, 1)

_PROFILES = {"STREAM": STREAM_QOS, "GOAL": GOAL_QOS, "CLOCK": CLOCK_QOS, "PROGRESS": PROGRESS_QOS,
             "LATCHED": LATCHED_QOS}


def qos_of(topic: Topic) -> QoSProfile:
    """The profile a contract topic is published and subscribed with (:attr:`fsr_sim.contract.Topic.qos`)."""
    return _PROFILES[topic.qos]
