"""goal_from_message: the world frame (or an empty frame) is accepted, any other frame is refused by name."""

import numpy as np
import pytest
from geometry_msgs.msg import PoseStamped

from fsr_control.nodes.messages import goal_from_message


def goal(frame_id: str) -> PoseStamped:
    msg = PoseStamped()
    msg.header.frame_id = frame_id
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = 1.0, 2.0, -3.0
    msg.pose.orientation.w = 1.0
    return msg


@pytest.mark.parametrize("frame_id", ["world_ned", ""])
def test_world_or_empty_frame_is_taken_as_ned(frame_id):
    position, rotation = goal_from_message(goal(frame_id))
    assert position.tolist() == [1.0, 2.0, -3.0]
    np.testing.assert_allclose(rotation, np.eye(3))


@pytest.mark.parametrize("frame_id", ["map", "world", "base_link_frd", "odom"])
def test_other_frame_is_refused_naming_the_frame(frame_id):
    with pytest.raises(ValueError, match=f"'{frame_id}'"):
        goal_from_message(goal(frame_id))
