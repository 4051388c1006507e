"""fsr-record's pure helpers: topic list, stamps read from raw CDR, sim_status time."""

from __future__ import annotations

import json

import numpy as np
import pytest
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64, String

from fsr_bringup.recording.recorder_node import (
    STANDARD_TOPICS,
    final_status_ns,
    stamp_ns,
    starts_with_stamp,
    status_time_ns,
    topic_list,
)
from fsr_sim.ros.conversions import odometry_from_state, rotor_command, time_from_ns
from fsr_sim.ros.message_schema import message_class


def test_default_topics_are_relative_plus_clock() -> None:
    topics = dict(topic_list([], []))
    assert topics["/clock"] == "rosgraph_msgs/msg/Clock"
    assert {name for name in topics if name != "/clock"} == set(STANDARD_TOPICS)


def test_namespaces_and_extra_topics() -> None:
    topics = dict(topic_list(["uav1", "/uav2/"], ["extra:std_msgs/msg/String", "/abs:std_msgs/msg/Float64"]))
    assert topics["/uav1/odom"] == "nav_msgs/msg/Odometry" and topics["/uav2/sim_status"] == "std_msgs/msg/String"
    assert topics["/uav1/extra"] == topics["/uav2/extra"] == "std_msgs/msg/String"
    assert topics["/abs"] == "std_msgs/msg/Float64" and "/clock" in topics
    assert len(topics) == 1 + 2 * (len(STANDARD_TOPICS) + 1) + 1


def test_bad_topic_argument() -> None:
    with pytest.raises(ValueError, match="NAME:TYPE"):
        topic_list([], ["odom"])


def test_stamp_read_from_raw_bytes() -> None:
    stamp = 12_345_678_901
    odom = odometry_from_state(stamp, np.zeros(3), np.eye(3), np.zeros(3), np.zeros(3))
    assert stamp_ns(serialize_message(odom)) == stamp
    assert stamp_ns(serialize_message(rotor_command(stamp, np.ones(4)))) == stamp
    assert stamp_ns(serialize_message(Clock(clock=time_from_ns(stamp)))) == stamp
    for type_name in STANDARD_TOPICS.values():
        has_header = "header" in message_class(type_name).get_fields_and_field_types()
        assert starts_with_stamp(message_class(type_name)) == has_header
    assert starts_with_stamp(Clock) and not starts_with_stamp(Float64)


def test_status_time() -> None:
    status = {"state": "finished", "reason": "", "sim_time": 2.5, "steps": 2500}
    assert status_time_ns(serialize_message(String(data=json.dumps(status)))) == 2_500_000_000
    assert status_time_ns(serialize_message(String(data="not json"))) is None


@pytest.mark.parametrize(("state", "expected"), [
    ("running", None), ("finished", 5_123_000_000), ("diverged", 5_123_000_000), ("stopped", 5_123_000_000),
])
def test_final_status_gives_the_stamp_of_the_last_state(state: str, expected: int | None) -> None:
    status = {"state": state, "reason": "", "sim_time": 5.123, "steps": 5123}
    assert final_status_ns(serialize_message(String(data=json.dumps(status)))) == expected
    assert final_status_ns(serialize_message(String(data="not json"))) is None
    assert final_status_ns(serialize_message(String(data='{"state": "stopped"}'))) is None  # no sim_time
