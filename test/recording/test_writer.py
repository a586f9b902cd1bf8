"""The MCAP recorder: what rosbag2 needs is in the file, and I/O errors never escape."""

import shutil
import time
from pathlib import Path

import pytest
import yaml
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader

from rigid_rot_sim.recording import definitions
from rigid_rot_sim.recording.bag_metadata import DURABILITY_TRANSIENT_LOCAL, QosProfile
from rigid_rot_sim.recording.reader import BagReader, scan
from rigid_rot_sim.recording.writer import Recorder, RecorderError

rclpy_serialization = pytest.importorskip("rclpy.serialization")
from geometry_msgs.msg import WrenchStamped  # noqa: E402

TF = {
    "transforms": [
        {
            "header": {"stamp": {"sec": 1, "nanosec": 0}, "frame_id": "world"},
            "child_frame_id": "body",
            "transform": {
                "translation": {"x": 0.0, "y": 0.0, "z": 0.0},
                "rotation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
            },
        }
    ]
}


def record_synthetic(path: Path, n: int = 300) -> None:
    with Recorder(path) as recorder:
        recorder.add_topic("/sim/torque", "geometry_msgs/msg/WrenchStamped")
        recorder.add_topic("/tf", "tf2_msgs/msg/TFMessage", QosProfile(depth=100))
        recorder.add_topic(
            "/sim/mass_properties",
            "geometry_msgs/msg/InertiaStamped",
            QosProfile(depth=1, durability=DURABILITY_TRANSIENT_LOCAL),
        )
        recorder.add_metadata("scene", {"file": "free_tumble.yaml", "yaml": "body: {}\n"})
        from geometry_msgs.msg import InertiaStamped

        recorder.write_message("/sim/mass_properties", InertiaStamped(), 1_000)
        for i in range(n):
            msg = WrenchStamped()
            msg.header.stamp.sec = i
            msg.header.frame_id = "body"
            msg.wrench.torque.z = 0.5 * i
            recorder.write_message("/sim/torque", msg, 2_000 + 10 * i, 1_500 + 10 * i)
            recorder.write_fields("/tf", TF, 2_005 + 10 * i)


def test_rosbags_reads_every_message_and_the_counts_match(tmp_path):
    path = tmp_path / "run.mcap"
    record_synthetic(path, n=300)
    counts = {}
    with AnyReader([path]) as reader:
        for connection, _, raw in reader.messages():
            msg = reader.deserialize(raw, connection.msgtype)
            counts[connection.topic] = counts.get(connection.topic, 0) + 1
            if connection.topic == "/sim/torque":
                assert msg.wrench.torque.z == 0.5 * msg.header.stamp.sec
                assert msg.header.frame_id == "body"
        assert {c.topic: c.msgcount for c in reader.connections} == counts
        qos = {c.topic: c.ext.offered_qos_profiles[0] for c in reader.connections}
    assert counts == {"/sim/torque": 300, "/tf": 300, "/sim/mass_properties": 1}
    assert qos["/sim/mass_properties"].durability.name == "TRANSIENT_LOCAL"
    assert qos["/tf"].depth == 100


def test_summary_statistics_indexes_and_channel_metadata_are_present(tmp_path):
    path = tmp_path / "run.mcap"
    record_synthetic(path, n=50)
    with open(path, "rb") as stream:
        reader = make_reader(stream)
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        stats = summary.statistics
        assert stats.message_count == 101
        assert (stats.message_start_time, stats.message_end_time) == (1_000, 2_005 + 490)
        assert summary.chunk_indexes and all(ci.message_index_offsets for ci in summary.chunk_indexes)
        assert {m.name for m in summary.metadata_indexes} == {"scene", "rosbag2"}
        schemas = {s.name: s for s in summary.schemas.values()}
        assert set(schemas) == {
            "geometry_msgs/msg/WrenchStamped",
            "tf2_msgs/msg/TFMessage",
            "geometry_msgs/msg/InertiaStamped",
        }
        assert all(s.encoding == "ros2msg" for s in schemas.values())
        for channel in summary.channels.values():
            assert channel.message_encoding == "cdr"
            profiles = yaml.safe_load(channel.metadata["offered_qos_profiles"])
            # integer form: what Humble reads, and Jazzy for metadata version <= 8
            assert all(isinstance(profiles[0][k], int) for k in ("history", "reliability", "durability", "liveliness"))
            type_name = schemas_by_id(summary)[channel.schema_id]
            assert channel.metadata["topic_type_hash"] == definitions.type_hash(type_name)
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    bag = yaml.safe_load(metadata["rosbag2"]["serialized_metadata"])
    assert bag["version"] == 8
    assert bag["message_count"] == 101
    assert bag["starting_time"]["nanoseconds_since_epoch"] == 1_000
    per_topic = {t["topic_metadata"]["name"]: t["message_count"] for t in bag["topics_with_message_count"]}
    assert per_topic == {"/sim/torque": 50, "/tf": 50, "/sim/mass_properties": 1}
    assert metadata["scene"]["file"] == "free_tumble.yaml"


def schemas_by_id(summary):
    return {i: s.name for i, s in summary.schemas.items()}


def test_finish_is_idempotent_and_writes_after_finish_are_refused(tmp_path):
    recorder = Recorder(tmp_path / "a.mcap")
    recorder.add_topic("/x", "geometry_msgs/msg/WrenchStamped")
    assert recorder.write_message("/x", WrenchStamped(), 5)
    recorder.finish()
    recorder.finish()
    assert not recorder.write_message("/x", WrenchStamped(), 6)
    assert BagReader(tmp_path / "a.mcap").complete


def test_unwritable_path_raises_recorder_error_naming_the_path(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with pytest.raises(RecorderError, match=str(blocker)):
        Recorder(blocker / "run.mcap")


def test_device_without_space_is_refused_at_start():
    with pytest.raises(RecorderError, match="/dev/full"):
        Recorder("/dev/full")


FILE_SIZE_LIMIT_SCRIPT = """
import resource, signal, sys, time
from geometry_msgs.msg import WrenchStamped
from rigid_rot_sim.recording.writer import Recorder
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)   # writes past the limit fail with EFBIG instead
resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000))
errors = []
recorder = Recorder(sys.argv[1], flush_period=0.05, compression="none", on_error=errors.append)
recorder.add_topic("/x", "geometry_msgs/msg/WrenchStamped")
steps = 0
deadline = time.monotonic() + 20.0
while recorder.active and time.monotonic() < deadline:
    recorder.write_message("/x", WrenchStamped(), time.time_ns())   # never raises
    steps += 1
    time.sleep(0.001)
for _ in range(1000):   # the caller (the simulation) carries on
    assert recorder.write_message("/x", WrenchStamped(), time.time_ns()) is False
    steps += 1
recorder.finish()
print(len(errors), steps)
print(errors[0])
"""


def test_write_error_mid_run_stops_recording_and_the_caller_keeps_running(tmp_path):
    import subprocess
    import sys

    path = tmp_path / "limited.mcap"
    done = subprocess.run(
        [sys.executable, "-c", FILE_SIZE_LIMIT_SCRIPT, str(path)], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr
    count_line, message = done.stdout.strip().splitlines()[:2]
    n_errors, steps = map(int, count_line.split())
    assert n_errors == 1 and steps > 1000
    assert str(path) in message and "File too large" in message and "bag repair" in message
    # what was flushed before the error is readable
    assert len(BagReader(path).counts()) == 1


def test_data_older_than_the_flush_period_is_on_disk_before_finish(tmp_path):
    path = tmp_path / "live.mcap"
    recorder = Recorder(path, flush_period=0.1)
    recorder.add_topic("/x", "geometry_msgs/msg/WrenchStamped")
    for i in range(20):
        recorder.write_message("/x", WrenchStamped(), 100 + i)
    deadline = time.monotonic() + 5.0
    found = 0
    while found < 20 and time.monotonic() < deadline:
        snapshot = tmp_path / "snapshot.mcap"
        shutil.copy(path, snapshot)  # what a SIGKILL right now would leave
        found = len(scan(snapshot).messages)
        time.sleep(0.02)
    recorder.finish()
    assert found == 20


def test_topic_type_conflict_is_a_value_error(tmp_path):
    with Recorder(tmp_path / "c.mcap") as recorder:
        recorder.add_topic("/x", "geometry_msgs/msg/WrenchStamped")
        recorder.add_topic("/x", "geometry_msgs/WrenchStamped")  # same type, no-op
        with pytest.raises(ValueError, match="/x"):
            recorder.add_topic("/x", "geometry_msgs/msg/Vector3Stamped")


def test_rosbag2_metadata_has_every_key_the_version_8_decoder_reads(tmp_path):
    # rosbag2_storage/yaml.hpp decodes, for version 8: version, storage_identifier, duration,
    # starting_time, message_count, topics_with_message_count (name, type,
    # serialization_format, offered_qos_profiles >= v4, type_description_hash >= v7),
    # relative_file_paths, compression_* (>= v3), files (>= v5), custom_data (>= v6),
    # ros_distro (>= v8). A missing key makes `ros2 bag info` throw.
    path = tmp_path / "keys.mcap"
    record_synthetic(path, n=3)
    bag = yaml.safe_load(BagReader(path).metadata["rosbag2"]["serialized_metadata"])
    assert {
        "version",
        "storage_identifier",
        "duration",
        "starting_time",
        "message_count",
        "topics_with_message_count",
        "relative_file_paths",
        "compression_format",
        "compression_mode",
        "files",
        "custom_data",
        "ros_distro",
    } <= set(bag)
    assert bag["storage_identifier"] == "mcap" and bag["relative_file_paths"] == ["keys.mcap"]
    assert set(bag["duration"]) == {"nanoseconds"} and set(bag["starting_time"]) == {"nanoseconds_since_epoch"}
    (file_info,) = bag["files"]
    assert set(file_info) == {"path", "starting_time", "duration", "message_count"}
    assert file_info["message_count"] == bag["message_count"] == 7
    for topic in bag["topics_with_message_count"]:
        meta = topic["topic_metadata"]
        assert set(meta) == {"name", "type", "serialization_format", "offered_qos_profiles", "type_description_hash"}
        assert isinstance(meta["offered_qos_profiles"], str)  # a YAML string inside the YAML, as rosbag2 writes it
        assert yaml.safe_load(meta["offered_qos_profiles"])[0]["reliability"] == 1
    assert isinstance(bag["custom_data"], dict)
