"""Record ROS 2 messages to one MCAP file that rosbag2 (Humble and Jazzy) reads as a bag.

What the file holds, and why (rosbag2's MCAP storage plugin, ``rosbag2_storage_mcap``,
writes and expects the same):

* header profile ``ros2``; one schema per type, encoding ``ros2msg``, named
  ``pkg/msg/Type``, with the complete definition (:mod:`.definitions`); channels with
  message encoding ``cdr``;
* per channel the metadata ``offered_qos_profiles`` (YAML, policies as *integers*) and
  ``topic_type_hash`` (:mod:`.bag_metadata` says why integers and ``version: 8``);
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
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from mcap.writer import CompressionType, Writer

from rigid_rot_sim import __version__
from rigid_rot_sim.recording.bag_metadata import MESSAGE_ENCODING, BagTopic, BagTopics, QosProfile, channel_metadata
from rigid_rot_sim.recording.definitions import dynamic_encoder, normalize_type_name

PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
LIBRARY = f"rigid_rot_sim/{__version__}"
_COMPRESSIONS = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}


class RecorderError(RuntimeError):
    """The recording could not be started or had to stop; the message says why and where."""


def _check_options(chunk_size: int, compression: str, flush_period: float) -> None:
    """ValueError naming the first of :class:`Recorder`'s options that is out of range."""
    if not flush_period > 0.0:
        raise ValueError(f"flush_period must be > 0 s, got {flush_period}")
    if not chunk_size > 0:
        raise ValueError(f"chunk_size must be > 0 bytes, got {chunk_size}")
    if compression not in _COMPRESSIONS:
        raise ValueError(f"compression must be one of {sorted(_COMPRESSIONS)}, got {compression!r}")


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
        _check_options(chunk_size, compression, flush_period)
        self.path = Path(path)
        self.flush_period = float(flush_period)
        self.ros_distro = ros_distro or os.environ.get("ROS_DISTRO") or "jazzy"
        self._fsync = fsync
        self._on_error = on_error
        self._lock = threading.RLock()
        self._topics = BagTopics()
        self._schemas: dict[str, int] = {}
        self._unflushed = 0
        self._error: RecorderError | None = None
        self._finished = False
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._stream = open(self.path, "wb")
        except OSError as exc:
            raise RecorderError(f"cannot record to {self.path}: {exc.strerror or exc}") from exc
        self._writer = Writer(self._stream, chunk_size=chunk_size, compression=_COMPRESSIONS[compression])
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
        return self._topics.message_count

    def topics(self) -> list[str]:
        """Names of the registered topics."""
        return self._topics.names()

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

        The definition and hash default to those of the installed type; pass them to copy
        a channel from another file (:func:`.bag_metadata.channel_metadata`).
        """
        type_name = normalize_type_name(type_name)
        with self._lock:
            if self._topics.registered(topic, type_name):
                return
            definition, metadata = channel_metadata(type_name, qos, definition, type_hash, offered_qos_profiles)
            if not self.active:
                return
            try:
                schema_id = self._schemas.get(type_name)
                if schema_id is None:
                    schema_id = self._writer.register_schema(
                        name=type_name, encoding=SCHEMA_ENCODING, data=definition.encode("utf-8")
                    )
                    self._schemas[type_name] = schema_id
                channel_id = self._writer.register_channel(
                    topic=topic, message_encoding=MESSAGE_ENCODING, schema_id=schema_id, metadata=metadata
                )
            except OSError as exc:
                self._fail(exc)
                return
            self._topics.add(BagTopic.of_channel(topic, type_name, channel_id, metadata))

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
                    sequence=entry.message_count,
                )
            except OSError as exc:
                self._fail(exc)
                return False
            self._topics.count(entry, log_time_ns)
            self._unflushed += 1
            return True

    def write_message(self, topic: str, msg: Any, log_time_ns: int, publish_time_ns: int | None = None) -> bool:
        """Serialise an rclpy message object with ``rclpy.serialization`` and write it."""
        from rclpy.serialization import serialize_message

        return self.write(topic, serialize_message(msg), log_time_ns, publish_time_ns)

    def write_fields(self, topic: str, fields: Any, log_time_ns: int, publish_time_ns: int | None = None) -> bool:
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
                    metadata = self._topics.metadata_yaml(self.path.name, self.ros_distro)
                    self._writer.add_metadata("rosbag2", {"serialized_metadata": metadata})
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

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.finish()

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
