"""The MCAP writer/reader pair: standard, readable by mcap_ros2 and rosbags, and robust to cut files."""

from __future__ import annotations

import pytest
from geometry_msgs.msg import WrenchStamped
from mcap_ros2.reader import read_ros2_messages
from nav_msgs.msg import Odometry
from rclpy.serialization import serialize_message

from fsr_sim.recording.reader import RecordingError, open_recording
from fsr_sim.recording.writer import RecordingWriter


def odometry(k: int) -> Odometry:
    msg = Odometry()
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(k * 1_000_000, 1_000_000_000)
    msg.header.frame_id = "world_ned"
    msg.pose.pose.position.x = 0.001 * k
    msg.pose.pose.orientation.w = 1.0
    return msg


def write_run(path, count: int, close: bool = True, chunk_size: int = 4096) -> RecordingWriter:
    writer = RecordingWriter(path, {"fsr_scenario": {"yaml": "name: test\n"}}, chunk_size=chunk_size)
    writer.add_topic("/odom", "nav_msgs/msg/Odometry")
    for k in range(count):
        writer.write("/odom", serialize_message(odometry(k)), k * 1_000_000)
        wrench = WrenchStamped()
        wrench.wrench.force.z = -float(k)
        writer.write_message("/wrench_cmd", wrench, k * 1_000_000)
    if close:
        writer.close()
    return writer


def test_round_trip_and_metadata(tmp_path):
    path = tmp_path / "run.mcap"
    write_run(path, 500)
    recording = open_recording(path)
    assert not recording.truncated
    assert recording.topics == {"/odom": "nav_msgs/msg/Odometry", "/wrench_cmd": "geometry_msgs/msg/WrenchStamped"}
    assert recording.scenario_yaml == "name: test\n"
    assert recording.count("odom") == recording.count("/wrench_cmd") == 500
    odom = recording.messages("odom")
    assert [m.pose.pose.position.x for _, m in odom] == [0.001 * k for k in range(500)]
    assert odom[7][0] == 7_000_000 and odom[7][1].header.stamp.nanosec == 7_000_000


def test_readable_by_mcap_ros2_and_rosbags(tmp_path):
    from rosbags.highlevel import AnyReader

    path = tmp_path / "run.mcap"
    write_run(path, 50)
    assert sum(1 for m in read_ros2_messages(str(path)) if m.channel.topic == "/odom") == 50
    with AnyReader([path]) as reader:
        connections = [c for c in reader.connections if c.topic == "/wrench_cmd"]
        forces = [reader.deserialize(raw, c.msgtype).wrench.force.z for c, _, raw in reader.messages(connections)]
    assert forces == [-float(k) for k in range(50)]


def test_cut_file_is_read_up_to_the_last_complete_chunk(tmp_path):
    path = tmp_path / "cut.mcap"
    writer = write_run(path, 2000, close=False)
    writer.flush()
    data = path.read_bytes()
    path.write_bytes(data[: len(data) - 100])  # the last chunk is incomplete, no footer
    recording = open_recording(path)
    assert recording.truncated
    count = recording.count("odom")
    assert 0 < count < 2000
    assert [m.pose.pose.position.x for _, m in recording.messages("odom")] == [0.001 * k for k in range(count)]


@pytest.mark.parametrize("content", [b"", b"not an mcap file at all"])
def test_not_mcap_is_refused(tmp_path, content):
    path = tmp_path / "bad.mcap"
    path.write_bytes(content)
    with pytest.raises(RecordingError, match="not an MCAP file"):
        open_recording(path)


def test_missing_file_and_topic(tmp_path):
    with pytest.raises(RecordingError, match="no such file"):
        open_recording(tmp_path / "absent.mcap")
    path = tmp_path / "run.mcap"
    write_run(path, 3)
    with pytest.raises(RecordingError, match="no topic 'reference'.*/odom"):
        open_recording(path).messages("reference")


def test_unwritable_path_names_it(tmp_path):
    with pytest.raises(OSError, match="cannot write recording .*missing"):
        RecordingWriter(tmp_path / "missing" / "run.mcap")


@pytest.mark.parametrize("chunk_size", [700, 4096, 1 << 20])
def test_batched_writes_give_the_same_file(tmp_path, chunk_size):
    """write_batch (records straight into the open chunk) writes the file write() does, byte for byte."""
    from fsr_sim.ros import cdr_pack

    odom, wrench = cdr_pack.odometry("world_ned", "base_link_frd"), cdr_pack.wrench_stamped("base_link_frd")
    files = []
    for batched in (False, True):
        path = tmp_path / f"run_{batched}.mcap"
        writer = RecordingWriter(path, {"fsr_scenario": {"yaml": "name: test\n"}}, chunk_size=chunk_size)
        assert batched is False or writer._fast is not None  # the pinned mcap writer takes the fast path
        writer.add_topic("/odom", "nav_msgs/msg/Odometry")
        writer.add_topic("/wrench_cmd", "geometry_msgs/msg/WrenchStamped")
        for k in range(300):
            stamp = k * 1_000_000
            batch = [("/odom", odom.pack(stamp, [0.001 * k] * 13)), ("/wrench_cmd", wrench.pack(stamp, [-k] * 6))]
            if batched:
                writer.write_batch(batch, stamp)
            else:
                for topic, data in batch:
                    writer.write(topic, data, stamp)
        writer.close()
        files.append(path.read_bytes())
    assert files[0] == files[1]
    recording = open_recording(tmp_path / "run_True.mcap")
    assert recording.count("/odom") == 300
