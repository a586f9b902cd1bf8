"""Read recordings back, also after a crash, and rewrite a crashed file with its index.

A file finished by :class:`~rigid_rot_sim.recording.writer.Recorder` has a summary and is
read through it. A file cut short (SIGKILL, power loss, full disk) has no summary and no
footer; :class:`BagReader` then scans it from the start and keeps every complete chunk
whose CRC checks out, which is everything up to the last flush. :func:`repair` rewrites
such a file with a proper summary so that every tool (``ros2 bag``, Foxglove) opens it.
"""

from __future__ import annotations

import io
import os
import struct
from collections import Counter
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Chunk, Message, Metadata, Schema
from mcap.stream_reader import MAGIC_SIZE, StreamReader, breakup_chunk

from rigid_rot_sim.recording.bag_metadata import (
    DURABILITY_TRANSIENT_LOCAL,
    DURABILITY_VOLATILE,
    RELIABILITY_BEST_EFFORT,
    RELIABILITY_RELIABLE,
)
from rigid_rot_sim.recording.definitions import dynamic_decoder
from rigid_rot_sim.recording.writer import Recorder

_MAGIC = b"\x89MCAP0\r\n"
_OPCODE_CHUNK = 0x06
_RELIABILITY = {RELIABILITY_RELIABLE: "reliable", RELIABILITY_BEST_EFFORT: "best_effort"}
_DURABILITY = {DURABILITY_TRANSIENT_LOCAL: "transient_local", DURABILITY_VOLATILE: "volatile"}


class BagError(ValueError):
    """The file is not an MCAP recording this module can read."""


@dataclass(frozen=True)
class Topic:
    """One recorded channel."""

    name: str
    type_name: str
    definition: str
    channel_metadata: dict[str, str]


@dataclass(frozen=True)
class RecordedMessage:
    """One message as stored: serialised CDR bytes and the two timestamps (ns)."""

    topic: str
    type_name: str
    log_time_ns: int
    publish_time_ns: int
    data: bytes


@dataclass
class ScanResult:
    """What a scan of a file without summary found."""

    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    metadata: list[Metadata] = field(default_factory=list)
    messages: list[Message] = field(default_factory=list)
    chunks: int = 0
    bad_chunks: int = 0
    unread_bytes: int = 0


def _valid_prefix_length(data: bytes) -> int:
    """Length of the leading run of complete records (after the magic)."""
    position = MAGIC_SIZE
    while position + 9 <= len(data):
        (length,) = struct.unpack_from("<Q", data, position + 1)
        end = position + 9 + length
        if end > len(data):
            break
        position = end
    return position


def scan(path: str | os.PathLike[str]) -> ScanResult:
    """Read every complete record of an MCAP file front to back, without its summary.

    Chunks whose CRC does not match (a torn write) are counted in ``bad_chunks`` and
    skipped; a trailing partial record is counted in ``unread_bytes``.
    """
    data = Path(path).read_bytes()
    if not data.startswith(_MAGIC):
        raise BagError(f"{path}: not an MCAP file (bad magic)")
    valid = _valid_prefix_length(data)
    result = ScanResult(unread_bytes=len(data) - valid)
    records = StreamReader(io.BytesIO(data[:valid]), emit_chunks=True).records
    pending: list[Any] = []
    try:
        for record in records:
            if isinstance(record, Chunk):
                result.chunks += 1
                try:
                    pending.extend(breakup_chunk(record, validate_crc=True))
                except (McapError, ValueError, struct.error):
                    result.bad_chunks += 1
            else:
                pending.append(record)
    except (McapError, struct.error, EOFError):
        pass  # the stream ends without a footer: that is what a crash leaves
    for record in pending:
        if isinstance(record, Schema):
            result.schemas[record.id] = record
        elif isinstance(record, Channel):
            result.channels[record.id] = record
        elif isinstance(record, Metadata):
            result.metadata.append(record)
        elif isinstance(record, Message):
            result.messages.append(record)
    return result


class BagReader:
    """Messages, topics and metadata records of one MCAP recording.

    ``complete`` tells whether the file has its summary; when it does not, the file
    is scanned (see :func:`scan`) and everything up to the last complete chunk is read.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise FileNotFoundError(f"no such recording: {self.path}")
        self.complete = self._has_summary()
        self._start_time_ns: int | None = None
        self._scan: ScanResult | None = None if self.complete else scan(self.path)
        self.topics: dict[str, Topic] = {}
        self.metadata: dict[str, dict[str, str]] = {}
        if self.complete:
            with open(self.path, "rb") as stream:
                reader = make_reader(stream)
                summary = reader.get_summary()
                assert summary is not None
                schemas, channels = summary.schemas, summary.channels
                metadata = list(reader.iter_metadata())
                statistics = summary.statistics
                if statistics is not None and statistics.message_count:
                    self._start_time_ns = int(statistics.message_start_time)
        else:
            assert self._scan is not None
            schemas, channels, metadata = self._scan.schemas, self._scan.channels, self._scan.metadata
        self._channels = channels
        for channel in channels.values():
            schema = schemas.get(channel.schema_id)
            self.topics[channel.topic] = Topic(
                name=channel.topic,
                type_name=schema.name if schema else "",
                definition=schema.data.decode("utf-8") if schema else "",
                channel_metadata=dict(channel.metadata),
            )
        for record in metadata:
            self.metadata[record.name] = dict(record.metadata)

    @property
    def start_time_ns(self) -> int | None:
        """The bag's start: the log time of its first message on any topic (ns), None when it has none.

        The Statistics record's ``message_start_time``, as rosbag2 reads it (``ros2 bag info``'s
        start, where ``ros2 bag play`` starts its clock); a file without a summary: its first message's.
        """
        if self._start_time_ns is None and not self.complete:
            first = next(iter(self.messages()), None)
            self._start_time_ns = None if first is None else first.log_time_ns
        return self._start_time_ns

    def _has_summary(self) -> bool:
        size = self.path.stat().st_size
        with open(self.path, "rb") as stream:
            if stream.read(len(_MAGIC)) != _MAGIC:
                raise BagError(f"{self.path}: not an MCAP file (bad magic)")
            if size < 2 * len(_MAGIC) + 9:
                return False
            stream.seek(size - len(_MAGIC))
            if stream.read(len(_MAGIC)) != _MAGIC:
                return False
            stream.seek(0)
            try:
                summary = make_reader(stream).get_summary()
            except (McapError, struct.error, ValueError):
                return False
        return summary is not None and summary.statistics is not None

    def messages(self, topics: Iterable[str] | None = None) -> Iterator[RecordedMessage]:
        """Messages in log-time order (file order among equal times)."""
        wanted = None if topics is None else set(topics)
        if self.complete:
            with open(self.path, "rb") as stream:
                reader = make_reader(stream)
                for schema, channel, message in reader.iter_messages(
                    topics=None if wanted is None else sorted(wanted), log_time_order=True
                ):
                    yield RecordedMessage(
                        channel.topic,
                        schema.name if schema else "",
                        message.log_time,
                        message.publish_time,
                        bytes(message.data),
                    )
            return
        assert self._scan is not None
        ordered = sorted(self._scan.messages, key=lambda m: m.log_time)
        for message in ordered:
            scanned = self._channels.get(message.channel_id)
            if scanned is None or (wanted is not None and scanned.topic not in wanted):
                continue
            yield RecordedMessage(
                scanned.topic,
                self.topics[scanned.topic].type_name,
                message.log_time,
                message.publish_time,
                bytes(message.data),
            )

    def decoded(self, topics: Iterable[str] | None = None) -> Iterator[tuple[RecordedMessage, Any]]:
        """Messages with their content decoded from the definitions stored in the file."""
        for message in self.messages(topics):
            topic = self.topics[message.topic]
            yield message, dynamic_decoder(topic.type_name, topic.definition)(message.data)

    def find_topic(self, role: str, type_name: str) -> str | None:
        """The topic playing ``role`` (``state``, ``events``, ...), or None.

        From the ``rigid_rot_sim`` metadata record written when the run was closed; for a
        repaired crash (no such record) the single topic of ``type_name`` (for ``events``:
        the one ending in ``sim_events``).
        """
        roles = self.metadata.get("rigid_rot_sim", {})
        if role in roles and roles[role] in self.topics:
            return roles[role]
        matches = [t.name for t in self.topics.values() if t.type_name == type_name]
        if role == "events":
            matches = [m for m in matches if m.endswith("sim_events")]
        return matches[0] if len(matches) == 1 else None

    def counts(self) -> Counter[str]:
        """Messages per topic (from a pass over the messages, not from the summary)."""
        return Counter(m.topic for m in self.messages())


class Bag:
    """One MCAP file, or the MCAP files of a rosbag2 directory (``metadata.yaml``), read as one (topics,
    metadata and decoded messages of every file)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self.readers = [BagReader(p) for p in mcap_files(self.path)]
        self.topics: dict[str, Topic] = {}
        self.metadata: dict[str, dict[str, str]] = {}
        for reader in self.readers:
            self.topics.update(reader.topics)
            for name, record in reader.metadata.items():
                self.metadata.setdefault(name, record)

    def listing(self) -> str:
        """The bag's topics and types, for error messages."""
        return ", ".join(f"{t.name} ({t.type_name})" for t in sorted(self.topics.values(), key=lambda t: t.name))

    def require(self, topic: str, types: Sequence[str], option: str) -> None:
        if topic not in self.topics:
            raise ValueError(f"{option} {topic}: no such topic in {self.path}; it has {self.listing()}")
        if self.topics[topic].type_name not in types:
            raise ValueError(f"{option} {topic}: type {self.topics[topic].type_name}, expected {' or '.join(types)}")

    def decoded(self, topic: str) -> Iterator[tuple[RecordedMessage, Any]]:
        for reader in self.readers:
            if topic in reader.topics:
                yield from reader.decoded([topic])

    def find_topic(self, role: str, type_name: str) -> str | None:
        for reader in self.readers:
            found = reader.find_topic(role, type_name)
            if found is not None:
                return found
        return None


def mcap_files(path: Path) -> list[Path]:
    """The MCAP files of a bag: the file itself, or a rosbag2 directory's (its ``metadata.yaml`` order)."""
    if path.is_file():
        return [path]
    if not path.is_dir():
        raise FileNotFoundError(f"no such bag: {path}")
    metadata = path / "metadata.yaml"
    files: list[Path] = []
    if metadata.is_file():
        info = (yaml.safe_load(metadata.read_text(encoding="utf-8")) or {}).get("rosbag2_bagfile_information", {})
        storage = info.get("storage_identifier", "mcap")
        if storage != "mcap":
            raise ValueError(f"{path}: storage {storage!r}; only MCAP bags are read (ros2 bag convert them)")
        files = [path / name for name in info.get("relative_file_paths", [])]
    if not files:
        files = sorted(path.glob("*.mcap"))
    if not files:
        raise ValueError(f"{path}: a directory without MCAP files")
    return files


@dataclass(frozen=True)
class RepairReport:
    """What :func:`repair` did."""

    output: Path
    messages: int
    chunks: int
    bad_chunks: int
    unread_bytes: int
    backup: Path | None
    already_complete: bool


def repair(
    path: str | os.PathLike[str],
    output: str | os.PathLike[str] | None = None,
    *,
    backup: bool = True,
) -> RepairReport:
    """Rewrite a recording cut short by a crash, with summary, indexes and rosbag2 record.

    Without ``output`` the file is replaced in place and the original kept as
    ``<file>.crashed`` (unless ``backup`` is False). A file that already has its
    summary is left alone (``already_complete``).
    """
    source = Path(path)
    reader = BagReader(source)
    if reader.complete:
        return RepairReport(Path(output or source), 0, 0, 0, 0, None, True)
    result = reader._scan
    assert result is not None
    target = Path(output) if output is not None else source.with_name(source.name + ".repairing")
    with Recorder(target) as recorder:
        for topic in reader.topics.values():
            recorder.add_topic(
                topic.name,
                topic.type_name,
                definition=topic.definition,
                type_hash=topic.channel_metadata.get("topic_type_hash", ""),
                offered_qos_profiles=topic.channel_metadata.get("offered_qos_profiles", ""),
            )
        for name, data in reader.metadata.items():
            if name != "rosbag2":
                recorder.add_metadata(name, data)
        count = 0
        for message in reader.messages():
            recorder.write(message.topic, message.data, message.log_time_ns, message.publish_time_ns)
            count += 1
    if recorder.error is not None:
        raise recorder.error
    kept: Path | None = None
    if output is None:
        if backup:
            kept = source.with_name(source.name + ".crashed")
            os.replace(source, kept)
        os.replace(target, source)
        target = source
    return RepairReport(target, count, result.chunks, result.bad_chunks, result.unread_bytes, kept, False)


def log_time_base(reader: BagReader) -> str:
    """``sim`` or ``wall``: what the recording's log times measure (``wall`` for files
    from before the ``log_time`` metadata record, and for other recorders' files)."""
    return reader.metadata.get("log_time", {}).get("base", "wall")


def info(path: str | os.PathLike[str]) -> str:
    """A human-readable summary of a recording (like ``ros2 bag info``)."""
    reader = BagReader(path)
    counts = reader.counts()
    times = [(m.log_time_ns) for m in reader.messages()]
    size = reader.path.stat().st_size
    index = (
        "complete (summary, statistics, chunk and message indexes)"
        if reader.complete
        else "MISSING (crashed recording: run `rigid-rot bag repair`)"
    )
    lines = [f"File:       {reader.path}", f"Size:       {size / 1e6:.3f} MB", f"Index:      {index}"]
    base = log_time_base(reader)
    if times:
        start, end = min(times), max(times)
        if base == "sim":
            lines.append(f"Duration:   {(end - start) / 1e9:.3f} s (sim time: log times are the run's sim time)")
            lines.append(f"Start:      {start / 1e9:.6f} s of sim time")
        else:
            lines.append(f"Duration:   {(end - start) / 1e9:.3f} s (wall clock)")
            lines.append(f"Start:      {start / 1e9:.6f} s since epoch")
    lines.append(f"Messages:   {sum(counts.values())}")
    lines.append("Topics:")
    width = max((len(name) for name in reader.topics), default=0)
    for name, topic in sorted(reader.topics.items()):
        qos_text = topic.channel_metadata.get("offered_qos_profiles", "")
        qos = ""
        try:
            profiles = yaml.safe_load(qos_text) if qos_text else None
            if profiles:
                p = profiles[0]
                reliability = _RELIABILITY.get(p.get("reliability"), str(p.get("reliability")))
                durability = _DURABILITY.get(p.get("durability"), str(p.get("durability")))
                qos = f"  [{reliability}, {durability}, depth {p.get('depth')}]"
        except yaml.YAMLError:
            qos = "  [unreadable QoS]"
        lines.append(f"  {name:<{width}}  {counts.get(name, 0):>8}  {topic.type_name}{qos}")
    scene = reader.metadata.get("scene", {})
    integrator = reader.metadata.get("integrator", {})
    if scene:
        lines.append(f"Scene:      {scene.get('file', '?')}")
    if integrator:
        lines.append(f"Integrator: {integrator.get('method', '?')}, dt = {integrator.get('dt', '?')} s")
    digest = reader.metadata.get("digest", {})
    if digest:
        lines.append(
            f"Digest:     {digest.get('digest', '?')} "
            f"(run digest at the last ~/state, stamp {digest.get('stamp', '?')} s)"
        )
    versions = reader.metadata.get("versions", {})
    if versions:
        lines.append(
            f"Recorded by rigid_rot_sim {versions.get('rigid_rot_sim', '?')} "
            f"(numpy {versions.get('numpy', '?')}, scipy {versions.get('scipy', '?')}, "
            f"rclpy {versions.get('ros-rclpy', '?')})"
        )
    lines.append(f"Metadata:   {', '.join(sorted(reader.metadata)) or 'none'}")
    return "\n".join(lines)
