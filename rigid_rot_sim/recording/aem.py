"""CCSDS Attitude Ephemeris Messages (AEM 2.0, CCSDS 504.0-B-2, KVN) from a recording.

Spacecraft tools (GMAT, Orekit, STK) exchange attitude histories as AEMs. :func:`write_aem`
turns the ``~/state`` messages of a recording into one:

* the header (table 4-2): ``CCSDS_AEM_VERS = 2.0``, ``CREATION_DATE``, ``ORIGINATOR``;
* one segment per stretch of strictly increasing sim time (table 4-1; 4.2.4.8.1 forbids
  repeated or decreasing time tags, and 4.2.4.8.3 says a new metadata block marks a
  discontinuity: a reset, or a ``set_state`` at the same time, starts a new segment);
* metadata (table 4-3, in its order): ``REF_FRAME_A`` an inertial frame of the SANA
  registry (``EME2000`` by default) for the run's world frame, ``REF_FRAME_B`` a spacecraft
  body frame (``SC_BODY_1``) for its body frame, the run's own frame names in ``COMMENT``
  lines, ``TIME_SYSTEM = UTC``, ``ATTITUDE_TYPE = QUATERNION`` or ``QUATERNION/ANGVEL``
  (with ``ANGVEL_FRAME`` = REF_FRAME_B: body rates);
* data lines ``EPOCH Q1 Q2 Q3 QC [ANGVEL_X ANGVEL_Y ANGVEL_Z]`` (table 4-4), the scalar last
  (annex B4), angular velocity in deg/s (4.2.4.6).

The quaternion: annex F2 defines the quaternion 'from frame A to frame B' as the rotation that
takes the basis vectors of A into those of B, with ``X_B = M_BA X_A``. The simulator's
orientation rotates body -> world (a body vector's world coordinates are ``R(q) v``), so the
body axes are the images of the world axes under ``R(q)``: the recorded ``q`` is the AEM
quaternion from A = world to B = body, component for component.

Time tags: the scene's ``epoch`` (UTC of sim time 0; ``scene_schema.DEFAULT_EPOCH`` when the
scene names none) plus the state's stamp, to the nanosecond. Sim time is uniform; a leap
second inside a run is not inserted (a COMMENT says so). Numbers are written with 16
significant digits, the most 6.8.4.2 allows; ``-0`` (not a valid value, 6.8.5) is written ``0``.
"""

from __future__ import annotations

import datetime as _dt
import math
import os
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from rigid_rot_sim.message_fields import quaternion_to_array, vector3_to_array
from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.scene.scene import parse_scene_text
from rigid_rot_sim.scene.scene_schema import DEFAULT_EPOCH

__all__ = [
    "INERTIAL_FRAMES",
    "AemOptions",
    "AttitudeSample",
    "format_aem",
    "read_attitude_samples",
    "write_aem",
]

#: Inertial frames of the SANA celestial-body reference frame registry accepted as REF_FRAME_A.
INERTIAL_FRAMES = ("EME2000", "GCRF", "ICRF", "ICRF2", "ICRF3", "MOD", "TOD", "TEME")
#: Spacecraft body frames (SANA spacecraft body reference frames): SC_BODY_<n> and the like.
_BODY_FRAME = re.compile(
    r"^(SC_BODY|ACTUATOR|CSS|DSS|ESA|GYRO_FRAME|IMU_FRAME|INSTRUMENT|MTA|RW|SA|SENSOR|"
    r"STARTRACKER|TAM)_[0-9A-Z]+$"
)
_TEXT = re.compile(r"^[A-Z0-9_\-./]+$")
_STATE_TYPE = "rigid_rot_msgs/msg/RigidBodyState"


@dataclass(frozen=True)
class AemOptions:
    """What the AEM says besides the attitudes; every text value upper case (6.8.6)."""

    ref_frame_a: str = "EME2000"
    ref_frame_b: str = "SC_BODY_1"
    angular_velocity: bool = False
    object_name: str | None = None  # None: the scene's name, upper case (UNKNOWN without one)
    object_id: str = "UNKNOWN"
    originator: str = "RIGID_ROT_SIM"

    def checked(self) -> AemOptions:
        """Self, or ValueError naming the value the standard does not allow."""
        if self.ref_frame_a not in INERTIAL_FRAMES:
            raise ValueError(
                f"REF_FRAME_A {self.ref_frame_a!r} is not an inertial frame of the CCSDS registry "
                f"(one of {', '.join(INERTIAL_FRAMES)})"
            )
        if not _BODY_FRAME.match(self.ref_frame_b):
            raise ValueError(
                f"REF_FRAME_B {self.ref_frame_b!r} is not a spacecraft body frame name of the CCSDS "
                "registry (e.g. SC_BODY_1)"
            )
        for key, value in (
            ("OBJECT_NAME", self.object_name or "UNKNOWN"),
            ("OBJECT_ID", self.object_id),
            ("ORIGINATOR", self.originator),
        ):
            if not _TEXT.match(value):
                raise ValueError(f"{key} {value!r}: upper-case letters, digits and _-./ only (CCSDS 504.0-B-2 6.8.6)")
        return self


@dataclass(frozen=True)
class AttitudeSample:
    """One recorded state: sim time (ns), orientation body -> world (x, y, z, w), body rate (rad/s)."""

    t_ns: int
    orientation: tuple[float, float, float, float]
    angular_velocity_body: tuple[float, float, float]


def parse_epoch(text: str) -> tuple[_dt.datetime, int]:
    """An ISO 8601 UTC date and time as (whole-second datetime, nanoseconds); ValueError if invalid."""
    match = re.fullmatch(r"(\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2})(?:\.(\d{1,9}))?Z?", text.strip())
    if match is None:
        raise ValueError(f"epoch {text!r} is not an ISO 8601 UTC date and time (YYYY-MM-DDThh:mm:ss[.f][Z])")
    whole = _dt.datetime.fromisoformat(match.group(1))
    fraction = (match.group(2) or "").ljust(9, "0")
    return whole, int(fraction)


def format_epoch(epoch: tuple[_dt.datetime, int], t_ns: int) -> str:
    """``epoch`` + ``t_ns`` as a CCSDS time tag (6.8.9), nanosecond digits."""
    whole, fraction_ns = epoch
    total = fraction_ns + t_ns
    seconds, nanoseconds = divmod(total, 1_000_000_000)
    when = whole + _dt.timedelta(seconds=seconds)
    return f"{when:%Y-%m-%dT%H:%M:%S}.{nanoseconds:09d}"


def _number(value: float) -> str:
    """16 significant digits in floating-point notation (6.8.4.2); never ``-0``."""
    if not math.isfinite(value):
        raise ValueError(f"{value!r} cannot be written in an AEM (6.8.5)")
    return f"{value + 0.0:.15e}" if value != 0.0 else "0.000000000000000e+00"


def _segments(samples: Sequence[AttitudeSample]) -> list[list[AttitudeSample]]:
    """Runs of strictly increasing time; an exact repeat of a line is dropped, any other repeat splits."""
    segments: list[list[AttitudeSample]] = []
    for sample in samples:
        if segments and sample.t_ns > segments[-1][-1].t_ns:
            segments[-1].append(sample)
        elif segments and sample == segments[-1][-1]:
            continue
        else:
            segments.append([sample])
    return segments


def format_aem(
    samples: Sequence[AttitudeSample],
    *,
    epoch: str = DEFAULT_EPOCH,
    options: AemOptions = AemOptions(),
    world_frame: str = "world",
    body_frame: str = "body",
    comments: Iterable[str] = (),
    creation_date: _dt.datetime | None = None,
) -> str:
    """The AEM (KVN text) of ``samples``; ValueError when there are none or an option is invalid."""
    options = options.checked()
    if not samples:
        raise ValueError("no states to export (the recording has no ~/state messages)")
    start = parse_epoch(epoch)
    created = creation_date or _dt.datetime.now(_dt.timezone.utc).replace(tzinfo=None)
    lines = ["CCSDS_AEM_VERS = 2.0"]
    lines += [f"COMMENT {comment}" for comment in comments]
    lines += [f"CREATION_DATE = {created:%Y-%m-%dT%H:%M:%S.%f}", f"ORIGINATOR = {options.originator}", ""]
    attitude_type = "QUATERNION/ANGVEL" if options.angular_velocity else "QUATERNION"
    for segment in _segments(samples):
        lines += [
            "META_START",
            f"COMMENT REF_FRAME_A {options.ref_frame_a} is the run's world frame '{world_frame}'",
            f"COMMENT REF_FRAME_B {options.ref_frame_b} is the run's body frame '{body_frame}'",
            f"COMMENT time tags: epoch {epoch} UTC (sim time 0) + sim time; no leap second inserted",
            f"OBJECT_NAME = {options.object_name or 'UNKNOWN'}",
            f"OBJECT_ID = {options.object_id}",
            f"REF_FRAME_A = {options.ref_frame_a}",
            f"REF_FRAME_B = {options.ref_frame_b}",
            "TIME_SYSTEM = UTC",
            f"START_TIME = {format_epoch(start, segment[0].t_ns)}",
            f"STOP_TIME = {format_epoch(start, segment[-1].t_ns)}",
            f"ATTITUDE_TYPE = {attitude_type}",
        ]
        if options.angular_velocity:
            lines.append(f"ANGVEL_FRAME = {options.ref_frame_b}")
        lines += ["META_STOP", "", "DATA_START"]
        for sample in segment:
            values = list(sample.orientation)
            if options.angular_velocity:
                values += [math.degrees(w) for w in sample.angular_velocity_body]
            lines.append(" ".join([format_epoch(start, sample.t_ns)] + [_number(v) for v in values]))
        lines += ["DATA_STOP", ""]
    return "\n".join(lines)


def read_attitude_samples(reader: BagReader) -> list[AttitudeSample]:
    """The recording's states in log order (the ``~/state`` topic, found by its role)."""
    topic = reader.find_topic("state", _STATE_TYPE)
    if topic is None:
        raise ValueError(f"{reader.path}: no {_STATE_TYPE} topic (~/state) in the recording")
    samples = []
    for _message, state in reader.decoded([topic]):
        q = quaternion_to_array(state.orientation)
        w = vector3_to_array(state.angular_velocity_body)
        t_ns = int(state.header.stamp.sec) * 1_000_000_000 + int(state.header.stamp.nanosec)
        samples.append(
            AttitudeSample(
                t_ns, (float(q[0]), float(q[1]), float(q[2]), float(q[3])), (float(w[0]), float(w[1]), float(w[2]))
            )
        )
    return samples


def write_aem(
    path: str | os.PathLike[str],
    out: str | os.PathLike[str] | None = None,
    options: AemOptions = AemOptions(),
    creation_date: _dt.datetime | None = None,
) -> Path:
    """Write the AEM of the recording at ``path`` to ``out`` (default: beside it, ``.aem``); its path."""
    reader = BagReader(path)
    scene_record = reader.metadata.get("scene", {})
    epoch, world, body, name = DEFAULT_EPOCH, "world", "body", None
    if "text" in scene_record:
        scene = parse_scene_text(scene_record["text"], source=scene_record.get("file", "<recorded scene>"))
        epoch, world, body, name = scene.epoch, scene.frames.world, scene.frames.body, scene.name
    if options.object_name is None and name:
        options = replace(options, object_name=re.sub(r"[^A-Z0-9_\-./]", "_", name.upper()))
    samples = read_attitude_samples(reader)
    comments = [f"attitude history of the rigid_rot_sim recording {Path(path).name}"]
    if name:
        comments.append(f"scene {name}")
    text = format_aem(
        samples,
        epoch=epoch,
        options=options,
        world_frame=world,
        body_frame=body,
        comments=comments,
        creation_date=creation_date,
    )
    target = Path(out) if out is not None else Path(path).with_suffix(".aem")
    target.write_text(text, encoding="ascii")
    return target
