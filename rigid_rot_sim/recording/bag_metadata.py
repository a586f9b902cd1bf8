"""What rosbag2 reads about a bag besides its messages: offered QoS, topic records, BagMetadata.

rosbag2 keeps per channel the QoS profiles the publishers offered (``offered_qos_profiles``,
a YAML list with policies as *integers*) and the type's hash, and per bag a BagMetadata
YAML (message counts, start and duration, the topics). Jazzy's rosbag2 decodes integer
policies only when the bag's metadata version is <= 8
(``rosbag2_storage/src/rosbag2_storage/qos.cpp``), and Humble decodes nothing else; so
:func:`bag_metadata_yaml` writes ``version: 8``.

:class:`BagTopics` keeps this per topic while :class:`~.writer.Recorder` writes, and
:func:`~.reader.repair` rebuilds it from a crashed file by writing it again.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import yaml

from rigid_rot_sim.recording.definitions import message_type

MESSAGE_ENCODING = "cdr"
BAG_METADATA_VERSION = 8

# rmw enum values, as rosbag2 (metadata <= 8) writes them.
HISTORY_KEEP_LAST, HISTORY_KEEP_ALL = 1, 2
RELIABILITY_RELIABLE, RELIABILITY_BEST_EFFORT = 1, 2
DURABILITY_TRANSIENT_LOCAL, DURABILITY_VOLATILE = 1, 2
LIVELINESS_AUTOMATIC = 1


@dataclass(frozen=True)
class QosProfile:
    """The QoS a publisher offered on a topic, in rmw's integer enums.

    Durations are ``(sec, nsec)``; ``(0, 0)`` means the rmw default (unspecified).
    """

    history: int = HISTORY_KEEP_LAST
    depth: int = 10
    reliability: int = RELIABILITY_RELIABLE
    durability: int = DURABILITY_VOLATILE
    deadline: tuple[int, int] = (0, 0)
    lifespan: tuple[int, int] = (0, 0)
    liveliness: int = LIVELINESS_AUTOMATIC
    liveliness_lease_duration: tuple[int, int] = (0, 0)
    avoid_ros_namespace_conventions: bool = False

    @classmethod
    def from_rclpy(cls, profile: Any) -> QosProfile:
        """Convert an ``rclpy.qos.QoSProfile`` (duck-typed; rclpy is not imported here)."""

        def duration(value: Any) -> tuple[int, int]:
            nanoseconds = int(value.nanoseconds)
            return nanoseconds // 1_000_000_000, nanoseconds % 1_000_000_000

        return cls(
            history=int(profile.history),
            depth=int(profile.depth),
            reliability=int(profile.reliability),
            durability=int(profile.durability),
            deadline=duration(profile.deadline),
            lifespan=duration(profile.lifespan),
            liveliness=int(profile.liveliness),
            liveliness_lease_duration=duration(profile.liveliness_lease_duration),
            avoid_ros_namespace_conventions=bool(profile.avoid_ros_namespace_conventions),
        )

    def as_dict(self) -> dict[str, Any]:
        """The mapping rosbag2 stores for one offered profile (integer form)."""

        def duration(value: tuple[int, int]) -> dict[str, int]:
            return {"sec": int(value[0]), "nsec": int(value[1])}

        return {
            "history": self.history,
            "depth": self.depth,
            "reliability": self.reliability,
            "durability": self.durability,
            "deadline": duration(self.deadline),
            "lifespan": duration(self.lifespan),
            "liveliness": self.liveliness,
            "liveliness_lease_duration": duration(self.liveliness_lease_duration),
            "avoid_ros_namespace_conventions": self.avoid_ros_namespace_conventions,
        }


def offered_qos_yaml(profiles: list[QosProfile]) -> str:
    """The ``offered_qos_profiles`` string of a channel (a YAML list, integer policies)."""
    return yaml.safe_dump([p.as_dict() for p in profiles], sort_keys=False, default_flow_style=False)


def channel_metadata(
    type_name: str,
    qos: QosProfile | list[QosProfile] | None = None,
    definition: str | None = None,
    type_hash: str | None = None,
    offered_qos_profiles: str | None = None,
) -> tuple[str, dict[str, str]]:
    """The definition and the MCAP channel metadata (``offered_qos_profiles``, ``topic_type_hash``) of a channel.

    The definition and hash default to those of the installed ``type_name``
    (:func:`.definitions.message_type`); ``offered_qos_profiles`` (a ready YAML string)
    overrides ``qos`` (one profile, several, or None for the default :class:`QosProfile`).
    An empty hash is left out.
    """
    if definition is None or type_hash is None:
        known = message_type(type_name)
        definition = known.definition if definition is None else definition
        type_hash = known.hash if type_hash is None else type_hash
    if offered_qos_profiles is None:
        profiles = [qos] if isinstance(qos, QosProfile) else list(qos or [QosProfile()])
        offered_qos_profiles = offered_qos_yaml(profiles)
    metadata = {"offered_qos_profiles": offered_qos_profiles}
    if type_hash:
        metadata["topic_type_hash"] = type_hash
    return definition, metadata


@dataclass
class BagTopic:
    """One recorded topic: its MCAP channel, what rosbag2 lists about it, and its messages so far."""

    name: str
    type_name: str
    channel_id: int
    offered_qos_profiles: str
    type_hash: str
    message_count: int = 0  # also the sequence number of the next message

    @classmethod
    def of_channel(cls, name: str, type_name: str, channel_id: int, metadata: dict[str, str]) -> BagTopic:
        """The topic of a channel registered with :func:`channel_metadata`'s ``metadata``."""
        return cls(name, type_name, channel_id, metadata["offered_qos_profiles"], metadata.get("topic_type_hash", ""))


class BagTopics:
    """The topics of a bag as they are written, and the time range of their messages (ns)."""

    def __init__(self) -> None:
        self._topics: dict[str, BagTopic] = {}
        self._start_ns: int | None = None
        self._end_ns = 0

    def __contains__(self, topic: str) -> bool:
        return topic in self._topics

    def __getitem__(self, topic: str) -> BagTopic:
        return self._topics[topic]

    def names(self) -> list[str]:
        return list(self._topics)

    def registered(self, topic: str, type_name: str) -> bool:
        """True if ``topic`` is registered already; ValueError if it is, with another type."""
        if topic not in self._topics:
            return False
        existing = self._topics[topic].type_name
        if existing != type_name:
            raise ValueError(f"topic {topic!r} is already recorded as {existing}, not {type_name}")
        return True

    def add(self, topic: BagTopic) -> None:
        self._topics[topic.name] = topic

    @property
    def message_count(self) -> int:
        return sum(t.message_count for t in self._topics.values())

    def count(self, topic: BagTopic, log_time_ns: int) -> None:
        """One more message of ``topic`` logged at ``log_time_ns``."""
        topic.message_count += 1
        if self._start_ns is None or log_time_ns < self._start_ns:
            self._start_ns = log_time_ns
        if log_time_ns > self._end_ns:
            self._end_ns = log_time_ns

    def metadata_yaml(self, file_name: str, ros_distro: str) -> str:
        """The BagMetadata YAML of these topics so far (see :func:`bag_metadata_yaml`)."""
        topics = [
            (t.name, t.type_name, t.offered_qos_profiles, t.type_hash, t.message_count) for t in self._topics.values()
        ]
        return bag_metadata_yaml(file_name, topics, self._start_ns or 0, self._end_ns, ros_distro)


def bag_metadata_yaml(
    file_name: str,
    topics: list[tuple[str, str, str, str, int]],
    start_ns: int,
    end_ns: int,
    ros_distro: str,
) -> str:
    """BagMetadata YAML (version 8) for the ``rosbag2`` record.

    ``topics`` holds ``(name, type, offered_qos_profiles, type_hash, message_count)``.
    """
    count = sum(t[4] for t in topics)
    duration = max(0, end_ns - start_ns) if count else 0
    start = start_ns if count else 0
    document = {
        "version": BAG_METADATA_VERSION,
        "storage_identifier": "mcap",
        "duration": {"nanoseconds": duration},
        "starting_time": {"nanoseconds_since_epoch": start},
        "message_count": count,
        "topics_with_message_count": [
            {
                "topic_metadata": {
                    "name": name,
                    "type": type_name,
                    "serialization_format": MESSAGE_ENCODING,
                    "offered_qos_profiles": qos,
                    "type_description_hash": type_hash,
                },
                "message_count": n,
            }
            for name, type_name, qos, type_hash, n in topics
        ],
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [file_name],
        "files": [
            {
                "path": file_name,
                "starting_time": {"nanoseconds_since_epoch": start},
                "duration": {"nanoseconds": duration},
                "message_count": count,
            }
        ],
        "custom_data": {},
        "ros_distro": ros_distro,
    }
    return yaml.safe_dump(document, sort_keys=False, default_flow_style=False)
