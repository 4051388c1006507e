"""QoS profiles shared by every node and the recorder.

The lockstep topics are reliable with a deep queue so that a slower listener (estimator, recorder) gets
every step instead of dropping samples; ``/clock`` is reliable (rclpy's best-effort clock subscription
matches it).
"""

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

STREAM_DEPTH = 5000  # messages: about 5 s of a 1 kHz stream

STREAM_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
    history=HistoryPolicy.KEEP_LAST,
    depth=STREAM_DEPTH,
)

CLOCK_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
    history=HistoryPolicy.KEEP_LAST,
    depth=10,
)

# One-off messages (goals, status) that a late subscriber should still receive.
LATCHED_QOS = QoSProfile(
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
)
