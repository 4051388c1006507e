"""fsr_sim.recording.cdr_columns: whole topics of CDR bytes -> numpy columns, checked against rclpy."""

from __future__ import annotations

import numpy as np
from rclpy.serialization import deserialize_message, serialize_message

from fsr_sim.model.so3 import rotation_from_euler_zyx
from fsr_sim.recording.cdr_columns import decode_columns
from fsr_sim.ros.conversions import odometry_from_state, rotor_command, wrench_stamped
from fsr_sim.ros.message_schema import message_class


def _field(msg, path: str):
    for part in path.split("."):
        msg = msg[int(part)] if part.isdigit() else getattr(msg, part)
    return msg


def test_columns_equal_rclpy_decoding_for_odometry_wrench_and_joint_state() -> None:
    rng = np.random.default_rng(3)
    cases = {
        "nav_msgs/msg/Odometry": (
            [odometry_from_state(1_000_003 * k, rng.normal(size=3), rotation_from_euler_zyx(rng.normal(size=3)),
                                 rng.normal(size=3), rng.normal(size=3)) for k in range(40)],
            ("header.stamp.sec", "header.stamp.nanosec", "pose.pose.position.z", "pose.pose.orientation.w",
             "twist.twist.linear.y", "twist.twist.angular.x", "pose.covariance"),
        ),
        "geometry_msgs/msg/WrenchStamped": (
            [wrench_stamped(k * 10**6, rng.normal(size=3), rng.normal(size=3)) for k in range(40)],
            ("header.stamp.nanosec", "wrench.force.x", "wrench.torque.z"),
        ),
        "sensor_msgs/msg/JointState": (
            [rotor_command(k * 10**6, rng.uniform(0, 800, 4), rng.uniform(-1, 1, 4)) for k in range(40)],
            ("velocity", "position"),
        ),
    }
    for type_name, (messages, paths) in cases.items():
        payloads = [serialize_message(m) for m in messages]
        columns = decode_columns(payloads, type_name)
        cls = message_class(type_name)
        for index in (0, 17, len(payloads) - 1):
            msg = deserialize_message(payloads[index], cls)
            for path in paths:
                np.testing.assert_array_equal(columns.get(path)[index], np.asarray(_field(msg, path)), err_msg=path)
        assert columns.strings["header.frame_id"][0] == messages[0].header.frame_id


def test_layouts_that_differ_between_messages_are_split() -> None:
    msgs = [rotor_command(k, np.full(4, float(k)), np.arange(4.0) if k % 3 == 0 else None) for k in range(10)]
    msgs[5].header.frame_id = "x"  # another string length
    columns = decode_columns([serialize_message(m) for m in msgs], "sensor_msgs/msg/JointState")
    np.testing.assert_array_equal(columns.get("velocity")[:, 0], np.arange(10.0))
    assert np.isnan(columns.get("position")[1, 4]) and columns.get("position")[3, 5] == 1.0
    assert columns.strings["header.frame_id"][5] == "x" and columns.strings["name.4"][0] == "tilt_1"


def test_empty_trailing_sequence_without_padding_is_decoded() -> None:
    # serialize_message pads after the last (empty) sequence's count; Fast DDS publishes the same
    # JointState 4 bytes shorter, without that padding (seen on rotor_cmd). Both must decode.
    cls = message_class("sensor_msgs/msg/JointState")
    msg = cls(name=[f"rotor_{i}" for i in range(1, 9)], position=[0.0] * 8, velocity=[500.0 + i for i in range(8)])
    padded = serialize_message(msg)
    for payload in (padded, padded[:-4]):
        columns = decode_columns([payload], "sensor_msgs/msg/JointState")
        assert np.array_equal(columns.get("velocity")[0], [500.0 + i for i in range(8)])
        assert columns.get("effort").shape == (1, 0)


def test_stamped_columns_sorts_by_stamp_and_decodes_many_layouts_message_by_message(tmp_path) -> None:
    """The one decoder of fsr-analyze and fsr-estimate: header-stamp order, and beyond MAX_LAYOUTS layouts
    (40 frame-id lengths here) the same columns from single-message decoding."""
    from fsr_sim.recording.cdr_columns import MAX_LAYOUTS, stamped_columns
    from fsr_sim.recording.reader import open_recording
    from fsr_sim.recording.writer import RecordingWriter

    count = MAX_LAYOUTS + 8
    order = np.random.default_rng(3).permutation(count)  # written out of stamp order
    path = tmp_path / "layouts.mcap"
    with RecordingWriter(path) as writer:
        writer.add_topic("/wrench_cmd", "geometry_msgs/msg/WrenchStamped")
        for k in order.tolist():
            msg = wrench_stamped(k * 1_000_000, np.array((k, -k, 0.5 * k), float), np.array((0.0, 0.0, k), float))
            msg.header.frame_id = "f" * (k + 1)
            writer.write_message("/wrench_cmd", msg, 0)
    stamps, columns = stamped_columns(open_recording(path), "wrench_cmd")
    np.testing.assert_array_equal(stamps, np.arange(count) * 1_000_000)
    np.testing.assert_array_equal(columns.get("wrench.force.y"), -np.arange(count, dtype=float))
    np.testing.assert_array_equal(columns.get("wrench.torque.z"), np.arange(count, dtype=float))
    assert [len(s) for s in columns.strings["header.frame_id"]] == list(range(1, count + 1))


def test_a_layout_walked_before_is_reused_only_for_the_same_key_bytes_and_fields_select_paths() -> None:
    """Blocks of the same size whose frame ids differ (same length) get their own layout, not the one walked
    first; ``fields`` keeps only the paths under the prefixes given."""
    from fsr_sim.ros import cdr_pack

    values = np.random.default_rng(5).normal(size=(6, 13))
    stamps = np.arange(6, dtype=np.int64) * 1_000_000
    for frame in ("world_aa", "world_bb", "world_aa"):
        rows = cdr_pack.odometry(frame, "base_link_frd").pack_rows(stamps, values)
        columns = decode_columns(rows, "nav_msgs/msg/Odometry", ("pose.pose.position.", "header.stamp."))
        assert set(columns.strings["header.frame_id"]) == {frame}
        assert sorted(columns.numbers) == ["header.stamp.nanosec", "header.stamp.sec", "pose.pose.position.x",
                                           "pose.pose.position.y", "pose.pose.position.z"]
        assert np.array_equal(columns.get("pose.pose.position.y"), values[:, 1])
        assert np.array_equal(columns.get("header.stamp.nanosec"), stamps)
