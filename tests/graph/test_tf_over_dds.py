"""/tf and /tf_static over DDS: scripts/build_tf2_msgs.sh (run by scripts/setup.sh) builds tf2_msgs/msg/TFMessage
with the ROS build tools from the wheels, with the type hash of ROS 2 Jazzy's own (so RViz and the ros2 CLI of a
Jazzy install match its topics), and the recorder publishes the frames it records: /tf for every odom, /tf_static
latched for a subscriber that comes late."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from fsr_sim.contract import BODY_FRAME, MAP_FRAME, ODOM, TF, TF_STATIC, WORLD_FRAME
from fsr_sim.ros.message_schema import message_class

# tf2_msgs/msg/TFMessage's RIHS01 type hash in ROS 2 Jazzy (what `ros2 topic info -v /tf` shows on a Jazzy install)
JAZZY_TF_MESSAGE_HASH = "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"
RECORD = str(Path(sys.executable).parent / "fsr-record")
N = 300


def tf_message() -> type:
    try:
        return message_class(TF.type)
    except ImportError as error:
        pytest.fail(f"tf2_msgs is not built in this environment: run scripts/build_tf2_msgs.sh ({error})")


def test_the_built_tfmessage_has_jazzy_s_type_hash():
    tf_message()
    description = json.loads((Path(sys.prefix) / "share" / "tf2_msgs" / "msg" / "TFMessage.json").read_text())
    hashes = {entry["type_name"]: entry["hash_string"] for entry in description["type_hashes"]}
    assert hashes[TF.type] == JAZZY_TF_MESSAGE_HASH


@pytest.mark.graph
def test_the_recorder_publishes_the_frames_over_dds(ros_graph, tmp_path):
    from nav_msgs.msg import Odometry

    from fsr_sim.ros.conversions import odometry_from_state
    from fsr_sim.ros.qos import qos_of

    message = tf_message()
    recorder = ros_graph.start("recorder", [RECORD, "--out", str(tmp_path / "run.mcap")])
    odom = ros_graph.publisher(ODOM.name, Odometry)
    frames = ros_graph.subscribe(TF.name, message, qos_of(TF))
    assert ros_graph.wait_for_subscribers(odom, timeout=30), ros_graph.log(recorder)
    assert ros_graph.spin_until(lambda: frames.subscription.get_publisher_count() >= 1, 30), ros_graph.log(recorder)

    poses = {}
    for k in range(N):
        angle = 0.01 * k
        rotation = np.array([[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0], [0, 0, 1]])
        sent = odometry_from_state(k * 1_000_000, np.array([0.1 * k, -0.2 * k, -1.0]), rotation, np.zeros(3),
                                   np.zeros(3))
        poses[k * 1_000_000] = sent.pose.pose
        odom.publish(sent)
        ros_graph.spin_for(0.002)

    def last_is_in(messages: list) -> bool:
        return any(t.header.stamp.nanosec == (N - 1) * 1_000_000 for m in messages for t in m.transforms)

    assert ros_graph.spin_until(lambda: last_is_in(frames.messages), 30), ros_graph.log(recorder)
    bodies = [t for m in frames.messages for t in m.transforms if t.child_frame_id == BODY_FRAME]
    assert bodies
    for transform in bodies:
        pose = poses[transform.header.stamp.sec * 1_000_000_000 + transform.header.stamp.nanosec]
        t, r = transform.transform.translation, transform.transform.rotation
        p, q = pose.position, pose.orientation
        assert (t.x, t.y, t.z, r.x, r.y, r.z, r.w) == (p.x, p.y, p.z, q.x, q.y, q.z, q.w)

    (static,) = ros_graph.collect(TF_STATIC.name, message, count=1, timeout=10, qos=qos_of(TF_STATIC))  # late
    assert (MAP_FRAME, WORLD_FRAME) in {(t.header.frame_id, t.child_frame_id) for t in static.transforms}
