"""Record ROS 2 messages to one MCAP file that rosbag2 (Humble and Jazzy) reads as a bag.

What the file holds, and why (sources in ../shared/rosbag2-mcap-facts.md):

* header profile ``ros2``; one schema per type, encoding ``ros2msg``, named
  ``pkg/msg/Type``, with the complete definition (:mod:`.definitions`); channels with
  message encoding ``cdr``;
* per channel the metadata ``offered_qos_profiles`` (YAML, policies as *integers*) and
  ``topic_type_hash``. Jazzy's rosbag2 decodes integer policies only when the bag's
  metadata version is <= 8 (``rosbag2_storage/src/rosbag2_storage/qos.cpp``), and Humble
  decodes nothing else; so the ``rosbag2`` metadata record below says ``version: 8``;
* a summary with Statistics (rosbag2 takes message count, start and duration from it),
  chunk indexes and message indexes (needed to read in time order), metadata indexes;
* an MCAP metadata record ``rosbag2`` with ``serialized_metadata`` (a BagMetadata YAML),
  written when the file is finished, plus whatever the caller adds with
  :meth:`Recorder.add_metadata` (written at once, so a crashed file still has them).

Nothing lost: a background thread closes the open chunk at least every ``flush_period``
seconds of wall time and pushes it to the disk, so after SIGKILL or power loss all but
the last period is readable (:func:`rigid_rot_sim.recording.reader.repair` rewrites the
summary). A write error (full disk, vanished path) stops the recording with a
:class:`RecorderError` kept in :attr:`Recorder.error` and passed once to ``on_error``;
:meth:`Recorder.write` never raises, so the simulation that feeds it keeps running.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

import yaml
from mcap.writer import CompressionType, Writer

from rigid_rot_sim import __version__
from rigid_rot_sim.recording.definitions import dynamic_encoder, message_type, normalize_type_name

PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"
BAG_METADATA_VERSION = 8
LIBRARY = f"rigid_rot_sim/{__version__}"

# rmw enum values, as rosbag2 (metadata <= 8) writes them.
HISTORY_KEEP_LAST, HISTORY_KEEP_ALL = 1, 2
RELIABILITY_RELIABLE, RELIABILITY_BEST_EFFORT = 1, 2
DURABILITY_TRANSIENT_LOCAL, DURABILITY_VOLATILE = 1, 2
LIVELINESS_AUTOMATIC = 1


class RecorderError(RuntimeError):
    """The recording could not be started or had to stop; the message says why and where."""


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
    def from_rclpy(cls, profile: Any) -> "QosProfile":
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


@dataclass
class _Topic:
    name: str
    type_name: str
    channel_id: int
    offered_qos_profiles: str
    type_hash: str
    sequence: int = 0


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


class Recorder:
    """Write serialised ROS 2 messages to an MCAP file (a lone-file rosbag2 bag).

    Use as a context manager, or call :meth:`finish` (idempotent; :meth:`close` is the
    same). Every method is thread-safe.

    Parameters
    ----------
    path : str or Path
        Output file; parent directories are created. An unwritable path raises
        :class:`RecorderError` here.
    chunk_size : int
        Bytes after which a chunk is closed even within the flush period.
    compression : {"zstd", "lz4", "none"}
        Chunk compression (rosbag2, Foxglove and rosbags read all three).
    flush_period : float
        Wall-clock seconds between forced chunk flushes (> 0).
    fsync : bool
        Also push flushed data to the disk (survives power loss, not only SIGKILL).
    on_error : callable or None
        Called once with the :class:`RecorderError` when recording stops on an error.
    ros_distro : str
        Stored in the rosbag2 metadata; defaults to ``$ROS_DISTRO`` or ``jazzy``.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        chunk_size: int = 1024 * 1024,
        compression: str = "zstd",
        flush_period: float = 1.0,
        fsync: bool = True,
        on_error: Callable[[RecorderError], None] | None = None,
        ros_distro: str | None = None,
    ) -> None:
        if not flush_period > 0.0:
            raise ValueError(f"flush_period must be > 0 s, got {flush_period}")
        if not chunk_size > 0:
            raise ValueError(f"chunk_size must be > 0 bytes, got {chunk_size}")
        compressions = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}
        if compression not in compressions:
            raise ValueError(f"compression must be one of {sorted(compressions)}, got {compression!r}")
        self.path = Path(path)
        self.flush_period = float(flush_period)
        self.ros_distro = ros_distro or os.environ.get("ROS_DISTRO") or "jazzy"
        self._fsync = fsync
        self._on_error = on_error
        self._lock = threading.RLock()
        self._topics: dict[str, _Topic] = {}
        self._schemas: dict[str, int] = {}
        self._counts: Counter[str] = Counter()
        self._start_ns: int | None = None
        self._end_ns = 0
        self._unflushed = 0
        self._error: RecorderError | None = None
        self._finished = False
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._stream = open(self.path, "wb")  # noqa: SIM115 - closed in finish()
        except OSError as exc:
            raise RecorderError(f"cannot record to {self.path}: {exc.strerror or exc}") from exc
        self._writer = Writer(self._stream, chunk_size=chunk_size, compression=compressions[compression])
        try:
            self._writer.start(profile=PROFILE, library=LIBRARY)
            self._stream.flush()
        except OSError as exc:
            with contextlib.suppress(OSError):
                self._stream.close()  # the failed buffer fails again on close
            raise RecorderError(f"cannot record to {self.path}: {exc.strerror or exc}") from exc
        self._stop = threading.Event()
        self._flusher = threading.Thread(target=self._flush_loop, name="mcap-flush", daemon=True)
        self._flusher.start()

    # -- state -----------------------------------------------------------------------

    @property
    def error(self) -> RecorderError | None:
        """Why the recording stopped early, or None."""
        return self._error

    @property
    def active(self) -> bool:
        """True while messages are being recorded (not finished, no error)."""
        return not self._finished and self._error is None

    @property
    def message_count(self) -> int:
        """Messages written so far."""
        return sum(self._counts.values())

    def topics(self) -> list[str]:
        """Names of the registered topics."""
        return list(self._topics)

    # -- registration ----------------------------------------------------------------

    def add_topic(
        self,
        topic: str,
        type_name: str,
        qos: QosProfile | list[QosProfile] | None = None,
        *,
        definition: str | None = None,
        type_hash: str | None = None,
        offered_qos_profiles: str | None = None,
    ) -> None:
        """Register a topic (a channel) before writing to it.

        The definition and hash default to those of the installed type
        (:func:`.definitions.message_type`); pass them to copy a channel from another
        file. ``offered_qos_profiles`` (a ready YAML string) overrides ``qos``.
        """
        type_name = normalize_type_name(type_name)
        with self._lock:
            if topic in self._topics:
                existing = self._topics[topic].type_name
                if existing != type_name:
                    raise ValueError(f"topic {topic!r} is already recorded as {existing}, not {type_name}")
                return
            if definition is None or type_hash is None:
                known = message_type(type_name)
                definition = known.definition if definition is None else definition
                type_hash = known.hash if type_hash is None else type_hash
            if offered_qos_profiles is None:
                profiles = [qos] if isinstance(qos, QosProfile) else list(qos or [QosProfile()])
                offered_qos_profiles = offered_qos_yaml(profiles)
            if not self.active:
                return
            try:
                schema_id = self._schemas.get(type_name)
                if schema_id is None:
                    schema_id = self._writer.register_schema(
                        name=type_name, encoding=SCHEMA_ENCODING, data=definition.encode("utf-8")
                    )
                    self._schemas[type_name] = schema_id
                metadata = {"offered_qos_profiles": offered_qos_profiles}
                if type_hash:
                    metadata["topic_type_hash"] = type_hash
                channel_id = self._writer.register_channel(
                    topic=topic, message_encoding=MESSAGE_ENCODING, schema_id=schema_id, metadata=metadata
                )
            except OSError as exc:
                self._fail(exc)
                return
            self._topics[topic] = _Topic(topic, type_name, channel_id, offered_qos_profiles, type_hash)

    def add_metadata(self, name: str, data: Mapping[str, Any]) -> None:
        """Write an MCAP metadata record now; values are stored as strings."""
        with self._lock:
            if not self.active:
                return
            try:
                self._writer.add_metadata(name, {str(k): str(v) for k, v in data.items()})
                self._stream.flush()
            except OSError as exc:
                self._fail(exc)

    # -- writing ---------------------------------------------------------------------

    def write(self, topic: str, data: bytes, log_time_ns: int, publish_time_ns: int | None = None) -> bool:
        """Append one serialised (CDR) message; False when recording has stopped.

        ``log_time_ns`` is the receive time (rosbag2's recv_timestamp), ``publish_time_ns``
        the send time (defaults to the log time). Writing to an unregistered topic is a
        KeyError (a programming error, not an I/O condition).
        """
        with self._lock:
            if not self.active:
                return False
            entry = self._topics[topic]
            log_time_ns = int(log_time_ns)
            try:
                self._writer.add_message(
                    channel_id=entry.channel_id,
                    log_time=log_time_ns,
                    data=data,
                    publish_time=log_time_ns if publish_time_ns is None else int(publish_time_ns),
                    sequence=entry.sequence,
                )
            except OSError as exc:
                self._fail(exc)
                return False
            entry.sequence += 1
            self._counts[topic] += 1
            self._unflushed += 1
            if self._start_ns is None or log_time_ns < self._start_ns:
                self._start_ns = log_time_ns
            if log_time_ns > self._end_ns:
                self._end_ns = log_time_ns
            return True

    def write_message(self, topic: str, msg: Any, log_time_ns: int, publish_time_ns: int | None = None) -> bool:
        """Serialise an rclpy message object with ``rclpy.serialization`` and write it."""
        from rclpy.serialization import serialize_message

        return self.write(topic, serialize_message(msg), log_time_ns, publish_time_ns)

    def write_fields(
        self, topic: str, fields: Any, log_time_ns: int, publish_time_ns: int | None = None
    ) -> bool:
        """Encode nested mappings to CDR from the topic's definition and write them.

        For types whose Python package is not installed (``tf2_msgs/msg/TFMessage``).
        """
        data = dynamic_encoder(self._topics[topic].type_name)(fields)
        return self.write(topic, data, log_time_ns, publish_time_ns)

    def flush(self) -> None:
        """Close the open chunk and push everything written so far to the disk."""
        with self._lock:
            if not self.active or self._unflushed == 0:
                return
            try:
                self._writer.flush()
                self._unflushed = 0
            except OSError as exc:
                self._fail(exc)
                return
        if self._fsync:
            try:
                os.fsync(self._stream.fileno())
            except (OSError, ValueError):
                pass  # fsync is best effort: a closed or special file cannot be synced

    def finish(self) -> None:
        """Write the summary and close the file. Idempotent; also after an error."""
        with self._lock:
            if self._finished:
                return
            self._finished = True
            self._stop.set()
            if self._error is None:
                try:
                    self._writer.add_metadata("rosbag2", {"serialized_metadata": self._bag_metadata()})
                    self._writer.finish()
                    self._stream.flush()
                    if self._fsync:
                        os.fsync(self._stream.fileno())
                except OSError as exc:
                    self._finished = False
                    self._fail(exc)
                    self._finished = True
            try:
                self._stream.close()
            except OSError:
                pass  # the error was reported already; closing cannot repair it
        if threading.current_thread() is not self._flusher:
            self._flusher.join(timeout=5.0)

    close = finish

    def __enter__(self) -> "Recorder":
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.finish()

    # -- internals -------------------------------------------------------------------

    def _bag_metadata(self) -> str:
        topics = [
            (t.name, t.type_name, t.offered_qos_profiles, t.type_hash, self._counts[t.name])
            for t in self._topics.values()
        ]
        return bag_metadata_yaml(self.path.name, topics, self._start_ns or 0, self._end_ns, self.ros_distro)

    def _flush_loop(self) -> None:
        while not self._stop.wait(self.flush_period):
            self.flush()

    def _fail(self, exc: OSError) -> None:
        if self._error is not None:
            return
        self._error = RecorderError(
            f"recording to {self.path} stopped after {self.message_count} messages: "
            f"{exc.strerror or exc}; the file keeps what was flushed before "
            f"(`rigid-rot bag repair {self.path}` restores its index)"
        )
        self._error.__cause__ = exc
        self._stop.set()
        try:
            self._stream.close()
        except OSError:
            pass  # a full disk may refuse the final buffer as well
        if self._on_error is not None:
            self._on_error(self._error)
