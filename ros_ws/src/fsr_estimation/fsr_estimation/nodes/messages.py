"""The estimator's outgoing messages (the node publishes them; a recorded in-process flight writes the same)."""

from __future__ import annotations

from geometry_msgs.msg import WrenchStamped
from std_msgs.msg import Float64

from fsr_estimation.core.stamped import Estimate
from fsr_sim.ros.conversions import wrench_stamped


def estimate_messages(estimate: Estimate) -> tuple[WrenchStamped, Float64]:
    """``wrench_estimate`` and ``mass_estimate`` of one estimate (the node publishes them; a recording of an
    in-process flight writes the same messages)."""
    return (wrench_stamped(estimate.stamp_ns, estimate.force_body, estimate.torque_body),
            Float64(data=float(estimate.mass)))
