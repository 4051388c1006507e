"""The MCAP writer/reader pair: standard, readable by mcap_ros2 and rosbags, and robust to cut files."""

from __future__ import annotations

import pytest
from geometry_msgs.msg import WrenchStamped
from mcap_ros2.reader import read_ros2_messages
from nav_msgs.msg import Odometry
from rclpy.serialization import serialize_message

from fsr_sim.recording.reader import RecordingError, open_recording
from fsr_sim.recording.writer import MCAP_ZSTD_LEVEL, RecordingWriter


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
        assert batched is False or writer.fast_path  # the pinned mcap writer takes the fast path
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


@pytest.mark.parametrize("chunk_size", [700, 4096, 1 << 20])
@pytest.mark.parametrize("fast", [True, False])
def test_block_writes_give_the_same_file(tmp_path, chunk_size, fast):
    """write_block (a whole block of steps packed with numpy, some topics not in every step) writes the file
    write_batch writes step by step, byte for byte; also without the fast path (any other mcap version)."""
    import numpy as np

    from fsr_sim.ros import cdr_pack

    odom, wrench, mass = (cdr_pack.odometry("world_ned", "base_link_frd"), cdr_pack.wrench_stamped("base_link_frd"),
                          cdr_pack.float64())
    rng = np.random.default_rng(7)
    steps = 900
    stamps = np.arange(steps, dtype=np.int64) * 1_000_000 + 5
    odom_values, wrench_values, mass_values = (rng.normal(size=(steps, n)) for n in (13, 6, 1))
    some = np.flatnonzero(rng.random(steps) < 0.3)  # wrench only in ~30 % of the steps
    files = []
    for block in (False, True):
        path = tmp_path / f"run_{block}.mcap"
        writer = RecordingWriter(path, {"fsr_scenario": {"yaml": "name: test\n"}}, chunk_size=chunk_size,
                                 fast_path=fast)
        assert writer.fast_path is fast
        for topic, type_name in (("/odom", "nav_msgs/msg/Odometry"), ("/wrench", "geometry_msgs/msg/WrenchStamped"),
                                 ("/mass", "std_msgs/msg/Float64")):
            writer.add_topic(topic, type_name)
        if block:
            for low, high in ((0, 400), (400, 401), (401, steps)):  # blocks of any length, one of one step
                mine = some[(some >= low) & (some < high)]
                window = slice(low, high)
                writer.write_block(stamps[window], [
                    ("/odom", None, odom.pack_rows(stamps[window], odom_values[window])),
                    ("/wrench", mine - low, wrench.pack_rows(stamps[mine], wrench_values[mine])),
                    ("/mass", None, mass.pack_rows(stamps[window], mass_values[window]))])
        else:
            for k in range(steps):
                stamp = int(stamps[k])
                batch = [("/odom", odom.pack(stamp, odom_values[k].tolist()))]
                if k in set(some.tolist()):
                    batch.append(("/wrench", wrench.pack(stamp, wrench_values[k].tolist())))
                batch.append(("/mass", mass.pack(0, mass_values[k].tolist())))
                writer.write_batch(batch, stamp)
        writer.close()
        files.append(path.read_bytes())
    assert files[0] == files[1]
    recording = open_recording(tmp_path / "run_True.mcap")
    assert (recording.count("/odom"), recording.count("/wrench"), recording.count("/mass")) == (steps, len(some), steps)


def test_block_with_an_unknown_topic_or_mismatched_steps_is_refused(tmp_path):
    import numpy as np

    from fsr_sim.ros import cdr_pack

    wrench = cdr_pack.wrench_stamped("base_link_frd")
    stamps = np.arange(3, dtype=np.int64)
    with RecordingWriter(tmp_path / "refused.mcap") as writer:
        with pytest.raises(KeyError, match="/wrench"):
            writer.write_block(stamps, [("/wrench", None, wrench.pack_rows(stamps, np.zeros((3, 6))))])
        writer.add_topic("/wrench", "geometry_msgs/msg/WrenchStamped")
        with pytest.raises(ValueError, match="2 steps but 3 payloads"):
            writer.write_block(stamps, [("/wrench", [0, 1], wrench.pack_rows(stamps, np.zeros((3, 6))))])


def test_unchunked_file_from_another_writer_is_read(tmp_path):
    """Messages outside chunks (an MCAP writer with chunking off) are read like chunked ones."""
    from mcap.writer import Writer

    from fsr_sim.ros.message_schema import message_class, message_definition

    path = tmp_path / "unchunked.mcap"
    with open(path, "wb") as stream:
        writer = Writer(stream, use_chunking=False)
        writer.start(profile="ros2", library="other")
        schema = writer.register_schema("nav_msgs/msg/Odometry", "ros2msg",
                                        message_definition(message_class("nav_msgs/msg/Odometry")).encode())
        channel = writer.register_channel("/odom", "cdr", schema)
        for k in range(5):
            writer.add_message(channel, k * 1_000_000, serialize_message(odometry(k)), k * 1_000_000)
        writer.finish()
    recording = open_recording(path)
    assert not recording.truncated and recording.topics == {"/odom": "nav_msgs/msg/Odometry"}
    assert [stamp for stamp, _ in recording.messages("odom")] == [k * 1_000_000 for k in range(5)]
    assert recording.messages("odom")[3][1].pose.pose.position.x == pytest.approx(0.003)


@pytest.mark.parametrize("fast", [True, False])
def test_block_with_sparse_topics_after_the_dense_ones_is_the_step_by_step_file(tmp_path, fast):
    """A block whose every-step topics come first and whose sparse ones follow (an in-process flight: its
    topics, then the markers and a second message size on /tf) is the file write_batch writes step by step, byte
    for byte (sequence numbers in written order, also on a topic given by two entries)."""
    import numpy as np

    from fsr_sim.ros import cdr_pack

    odom, other_odom = cdr_pack.odometry("world_ned", "base_link_frd"), cdr_pack.odometry("map", "rotor_1_link")
    wrench, mass = cdr_pack.wrench_stamped("base_link_frd"), cdr_pack.float64()
    rng = np.random.default_rng(11)
    steps = 700
    stamps = np.arange(steps, dtype=np.int64) * 1_000_000
    odom_values, other_values, wrench_values, mass_values = (rng.normal(size=(steps, n)) for n in (13, 13, 6, 1))
    sparse, second = np.arange(0, steps, 20), np.arange(0, steps, 20)[::2]
    files = []
    for block in (False, True):
        path = tmp_path / f"run_{block}.mcap"
        writer = RecordingWriter(path, chunk_size=64 * 1024, fast_path=fast)
        for topic, type_name in (("/odom", "nav_msgs/msg/Odometry"), ("/mass", "std_msgs/msg/Float64"),
                                 ("/wrench", "geometry_msgs/msg/WrenchStamped")):
            writer.add_topic(topic, type_name)
        if block:
            for low, high in ((0, 333), (333, steps)):
                window = slice(low, high)
                mine, theirs = (s[(s >= low) & (s < high)] for s in (sparse, second))
                writer.write_block(stamps[window], [
                    ("/odom", None, odom.pack_rows(stamps[window], odom_values[window])),
                    ("/mass", None, mass.pack_rows(stamps[window], mass_values[window])),
                    ("/wrench", mine - low, wrench.pack_rows(stamps[mine], wrench_values[mine])),
                    ("/odom", theirs - low, other_odom.pack_rows(stamps[theirs], other_values[theirs]))])
        else:
            for k in range(steps):
                stamp = int(stamps[k])
                batch = [("/odom", odom.pack(stamp, odom_values[k].tolist())),
                         ("/mass", mass.pack(0, mass_values[k].tolist()))]
                if k in set(sparse.tolist()):
                    batch.append(("/wrench", wrench.pack(stamp, wrench_values[k].tolist())))
                if k in set(second.tolist()):
                    batch.append(("/odom", other_odom.pack(stamp, other_values[k].tolist())))
                writer.write_batch(batch, stamp)
        writer.close()
        files.append(path.read_bytes())
    assert files[0] == files[1]


def test_chunks_finished_on_the_writer_thread_give_mcaps_file(tmp_path):
    """The fast path's chunks, compressed and written on the writer thread or inline, are the ones mcap's own
    writer makes (its API path), byte for byte, also across a flush; and the file survives a flush alone."""
    import numpy as np

    from fsr_sim.ros import cdr_pack

    odom = cdr_pack.odometry("world_ned", "base_link_frd")
    steps = 3000
    stamps = np.arange(steps, dtype=np.int64) * 1_000_000
    values = np.random.default_rng(3).normal(size=(steps, 13))
    files = []
    for fast, background in ((False, False), (True, False), (True, True)):
        path = tmp_path / f"run_{fast}_{background}.mcap"
        writer = RecordingWriter(path, {"fsr_scenario": {"yaml": "name: test\n"}}, chunk_size=16 * 1024,
                                 fast_path=fast, background=background, zstd_level=MCAP_ZSTD_LEVEL)
        writer.add_topic("/odom", "nav_msgs/msg/Odometry")
        for low in range(0, steps, 700):
            window = slice(low, low + 700)
            writer.write_block(stamps[window], [("/odom", None, odom.pack_rows(stamps[window], values[window]))])
            if low == 1400:
                writer.flush()
                flushed = open_recording(path)  # every chunk so far is in the file
                assert flushed.truncated and flushed.count("/odom") == 2100
        writer.close()
        files.append(path.read_bytes())
    assert files[0] == files[1] == files[2]
    assert sum(1 for m in read_ros2_messages(str(path)) if m.channel.topic == "/odom") == steps


def test_the_fast_paths_own_compression_level_writes_the_same_messages(tmp_path):
    """At its own level (:data:`ZSTD_LEVEL`) the fast path writes other chunk bytes than mcap's level, and the same
    messages."""
    import numpy as np

    from fsr_sim.recording.writer import ZSTD_LEVEL
    from fsr_sim.ros import cdr_pack

    assert ZSTD_LEVEL != MCAP_ZSTD_LEVEL
    odom = cdr_pack.odometry("world_ned", "base_link_frd")
    stamps = np.arange(2000, dtype=np.int64) * 1_000_000
    rows = odom.pack_rows(stamps, np.random.default_rng(5).normal(size=(len(stamps), 13)))
    paths = [tmp_path / f"level_{level}.mcap" for level in (ZSTD_LEVEL, MCAP_ZSTD_LEVEL)]
    for path, level in zip(paths, (ZSTD_LEVEL, MCAP_ZSTD_LEVEL), strict=True):
        with RecordingWriter(path, chunk_size=16 * 1024, zstd_level=level) as writer:
            writer.add_topic("/odom", "nav_msgs/msg/Odometry")
            writer.write_block(stamps, [("/odom", None, rows)])
    assert paths[0].read_bytes() != paths[1].read_bytes()
    decoded = [[(m.log_time_ns, m.ros_msg.pose.pose.position.x) for m in read_ros2_messages(str(path))]
               for path in paths]
    assert decoded[0] == decoded[1] and len(decoded[0]) == len(stamps)


def test_a_chunk_the_writer_thread_cannot_write_is_reported_with_the_file(tmp_path):
    """An error writing a chunk on the writer thread (a full disk) is raised to the caller by flush or close, one
    line naming the file."""
    import errno

    import numpy as np

    from fsr_sim.ros import cdr_pack

    path = tmp_path / "full.mcap"
    writer = RecordingWriter(path, chunk_size=4096)
    assert writer.fast_path
    writer.add_topic("/odom", "nav_msgs/msg/Odometry")
    stream = writer._fast.chunks.stream  # noqa: SLF001 - the file the writer thread writes

    class Full:
        name = stream.name

        def tell(self) -> int:
            return stream.tell()

        def write(self, _data: bytes) -> int:
            raise OSError(errno.ENOSPC, "No space left on device")

    writer._fast.chunks.stream = Full()  # noqa: SLF001
    stamps = np.arange(200, dtype=np.int64) * 1_000_000
    odom = cdr_pack.odometry("world_ned", "base_link_frd")
    # raised by the first call after the thread failed: the block's next chunk if the thread failed before it, or
    # the flush that waits for the thread
    with pytest.raises(OSError, match=f"cannot write recording '{path}': No space left on device"):
        writer.write_block(stamps, [("/odom", None, odom.pack_rows(stamps, np.zeros((200, 13))))])
        writer.flush()
    writer._fast.chunks.stream = stream  # noqa: SLF001
    writer.close()
