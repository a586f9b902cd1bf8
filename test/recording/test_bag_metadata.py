"""What rosbag2 reads about a bag besides its messages: channel metadata and the BagMetadata YAML."""

import yaml

from rigid_rot_sim.recording.bag_metadata import (
    DURABILITY_TRANSIENT_LOCAL,
    BagTopic,
    BagTopics,
    QosProfile,
    channel_metadata,
)


def test_a_copied_channel_keeps_its_definition_and_qos_and_an_empty_hash_is_left_out():
    # what repair passes for a channel read back from a crashed file
    definition, metadata = channel_metadata("pkg/msg/Unknown", None, "float64 x\n", "", "- depth: 3\n")
    assert definition == "float64 x\n"
    assert metadata == {"offered_qos_profiles": "- depth: 3\n"}


def test_qos_profiles_are_stored_as_integer_policies():
    _, metadata = channel_metadata(
        "pkg/msg/Unknown", [QosProfile(depth=1, durability=DURABILITY_TRANSIENT_LOCAL), QosProfile()], "", "h"
    )
    profiles = yaml.safe_load(metadata["offered_qos_profiles"])
    assert [p["depth"] for p in profiles] == [1, 10]
    assert profiles[0]["durability"] == 1 and profiles[1]["durability"] == 2
    assert metadata["topic_type_hash"] == "h"


def test_bag_metadata_counts_messages_per_topic_and_spans_their_log_times():
    topics = BagTopics()
    a = BagTopic.of_channel("/a", "pkg/msg/A", 1, {"offered_qos_profiles": "q", "topic_type_hash": "ha"})
    b = BagTopic.of_channel("/b", "pkg/msg/B", 2, {"offered_qos_profiles": "q"})
    topics.add(a)
    topics.add(b)
    for t in (500, 200, 900):
        topics.count(a, t)
    topics.count(b, 300)
    assert topics.message_count == 4 and a.message_count == 3
    document = yaml.safe_load(topics.metadata_yaml("run.mcap", "jazzy"))
    assert document["version"] == 8 and document["message_count"] == 4
    assert document["starting_time"] == {"nanoseconds_since_epoch": 200}
    assert document["duration"] == {"nanoseconds": 700}
    counts = {t["topic_metadata"]["name"]: t["message_count"] for t in document["topics_with_message_count"]}
    assert counts == {"/a": 3, "/b": 1}
    assert document["topics_with_message_count"][1]["topic_metadata"]["type_description_hash"] == ""


def test_an_empty_bag_starts_at_zero_with_zero_duration():
    document = yaml.safe_load(BagTopics().metadata_yaml("run.mcap", "humble"))
    assert document["message_count"] == 0 and document["duration"] == {"nanoseconds": 0}
    assert document["ros_distro"] == "humble" and document["relative_file_paths"] == ["run.mcap"]
