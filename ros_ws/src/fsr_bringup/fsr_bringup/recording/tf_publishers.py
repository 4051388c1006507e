"""``/tf`` and ``/tf_static`` over DDS (``tf2_msgs/msg/TFMessage``), as the recorder writes them: what RViz or any
ROS tool on the flight's domain reads as the frames.

The pip wheels of ROS 2 have no ``tf2_msgs``; ``scripts/build_tf2_msgs.sh`` (run by ``scripts/setup.sh``) builds its
message with the ROS build tools that come as wheels. Where it is missing, nothing is published and the recorder
says so once: the frames are then in the recording and on ``--live`` only.

* ``/tf_static`` (the contract's ``latched`` QoS: a subscriber that comes later gets it): every vehicle's static
  frames in one message, published again when a vehicle's are added, as tf2's static broadcaster does (the
  recording keeps one message per vehicle);
* ``/tf`` (the contract's ``stream`` QoS): each message the recording gets, while a subscriber is matched (none:
  nothing is published, so a flight nobody watches pays nothing).
"""

from __future__ import annotations

from typing import Any

from fsr_sim.contract import TF, TF_STATIC


class TfPublishers:
    """The node's ``/tf`` and ``/tf_static`` publishers (build with :meth:`create`)."""

    def __init__(self, node: Any, message: type) -> None:
        from fsr_sim.ros.qos import qos_of

        self.message = message
        self.tf = node.create_publisher(message, TF.name, qos_of(TF))
        self.tf_static = node.create_publisher(message, TF_STATIC.name, qos_of(TF_STATIC))
        self.static_transforms: list[Any] = []

    @classmethod
    def create(cls, node: Any) -> TfPublishers | None:
        """The publishers of ``node``, or None (said once in its log) when ``tf2_msgs`` is not installed."""
        from fsr_sim.ros.message_schema import message_class

        try:
            message = message_class(TF.type)
        except ImportError:
            node.get_logger().info("no tf2_msgs in this environment (scripts/build_tf2_msgs.sh builds it): /tf and "
                                   "/tf_static are written to the recording, not published over DDS")
            return None
        return cls(node, message)

    def publish(self, topic: str, data: bytes) -> None:
        """Publish a derived message (CDR) if it is a frame message."""
        if topic == TF.name:
            if self.tf.get_subscription_count():
                self.tf.publish(data)
        elif topic == TF_STATIC.name:
            from rclpy.serialization import deserialize_message

            self.static_transforms += deserialize_message(data, self.message).transforms
            self.tf_static.publish(self.message(transforms=self.static_transforms))
