"""CCSDS AEM 2.0 export, read back by a reader of the standard's KVN grammar written here.

The grammar and orders below are transcribed from CCSDS 504.0-B-2: table 4-2 (header),
table 4-3 (metadata), table 4-4 (data lines), 6.7 (KVN), 6.8.4 (numbers), 6.8.9 (time tags),
annex F2 (the quaternion from A to B: X_B = M_BA X_A).
"""

from __future__ import annotations

import datetime as dt
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_resim import COMMANDS, record_like_the_node

from rigid_rot_sim.recording.aem import AemOptions, AttitudeSample, format_aem, parse_epoch, write_aem
from rigid_rot_sim.recording.reader import BagReader

#: Table 4-2, in order: (keyword, mandatory).
HEADER = [
    ("CCSDS_AEM_VERS", True),
    ("COMMENT", False),
    ("CLASSIFICATION", False),
    ("CREATION_DATE", True),
    ("ORIGINATOR", True),
    ("MESSAGE_ID", False),
]
#: Table 4-3, in order (META_START/META_STOP delimit it).
METADATA = [
    ("COMMENT", False),
    ("OBJECT_NAME", True),
    ("OBJECT_ID", True),
    ("CENTER_NAME", False),
    ("REF_FRAME_A", True),
    ("REF_FRAME_B", True),
    ("TIME_SYSTEM", True),
    ("START_TIME", True),
    ("USEABLE_START_TIME", False),
    ("USEABLE_STOP_TIME", False),
    ("STOP_TIME", True),
    ("ATTITUDE_TYPE", True),
    ("EULER_ROT_SEQ", False),
    ("ANGVEL_FRAME", False),
    ("INTERPOLATION_METHOD", False),
    ("INTERPOLATION_DEGREE", False),
]
#: Table 4-4: values per data line after the epoch.
DATA_VALUES = {"QUATERNION": 4, "QUATERNION/ANGVEL": 7, "QUATERNION/DERIVATIVE": 8}
EPOCH = re.compile(r"^\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}(\.\d+)?Z?$")  # 6.8.9, calendar form
NUMBER = re.compile(r"^[+-]?(\d+\.\d+|\d\.\d+[eE][+-]?\d+)$")  # 6.8.4.1 fixed / 6.8.4.2 floating point


def _keyword_line(line: str) -> tuple[str, str]:
    if line.startswith("COMMENT"):
        return "COMMENT", line[len("COMMENT") :].strip()
    keyword, equals, value = line.partition("=")
    assert equals, f"not a KVN line: {line!r}"
    keyword, value = keyword.strip(), value.strip()
    assert keyword == keyword.upper() and " " not in keyword, keyword  # 6.7.3
    assert value, f"{keyword}: empty value (6.8.7)"
    return keyword, value


def _in_table_order(keywords: list[str], table: list[tuple[str, bool]]) -> None:
    order = [name for name, _ in table]
    positions = [order.index(k) for k in keywords]  # ValueError: a keyword the table does not allow (4.2.2.5)
    assert positions == sorted(positions), f"order {keywords} is not the table's (6.7.8)"
    for name, mandatory in table:
        assert not mandatory or name in keywords, f"mandatory {name} missing"
    assert all(keywords.count(k) == 1 for k in keywords if k != "COMMENT"), keywords


def _number(text: str) -> float:
    assert NUMBER.match(text), f"{text!r} is not a CCSDS number"
    digits = re.sub(r"[eE].*", "", text).replace("-", "").replace("+", "").replace(".", "")
    assert len(digits) <= 16, f"{text!r}: more than 16 digits (6.8.4)"
    value = float(text)
    assert not (value == 0.0 and text.startswith("-")), "-0 is not a valid value (6.8.5)"
    return value


def read_aem(text: str) -> dict:
    """Parse an AEM in KVN: header, then segments of metadata and data; assert the grammar."""
    lines = [line.strip() for line in text.splitlines()]
    lines = [line for line in lines if line]
    assert lines[0].startswith("CCSDS_AEM_VERS"), "the first non-blank line is the version (4.2.2.3)"
    i, header = 0, []
    while lines[i] != "META_START":
        header.append(_keyword_line(lines[i]))
        i += 1
    _in_table_order([k for k, _ in header], HEADER)
    segments = []
    while i < len(lines):
        assert lines[i] == "META_START"
        i += 1
        meta = []
        while lines[i] != "META_STOP":
            meta.append(_keyword_line(lines[i]))
            i += 1
        _in_table_order([k for k, _ in meta], METADATA)
        values = {k: v for k, v in meta if k != "COMMENT"}
        i += 1
        assert lines[i] == "DATA_START", lines[i]
        i += 1
        rows = []
        width = DATA_VALUES[values["ATTITUDE_TYPE"]]
        while lines[i] != "DATA_STOP":
            fields = lines[i].split()
            assert EPOCH.match(fields[0]), fields[0]
            assert len(fields) == 1 + width, lines[i]
            rows.append((fields[0], [_number(f) for f in fields[1:]]))
            i += 1
        i += 1
        epochs = [row[0] for row in rows]
        assert epochs == sorted(epochs) and len(set(epochs)) == len(epochs), "increasing, unrepeated (4.2.4.8.1)"
        assert values["START_TIME"] == epochs[0] and values["STOP_TIME"] == epochs[-1]
        segments.append({"meta": values, "comments": [v for k, v in meta if k == "COMMENT"], "rows": rows})
    return {"header": dict(header), "segments": segments}


def _seconds_after(epoch: str, tag: str) -> float:
    whole, ns = parse_epoch(epoch)
    tag_whole, tag_ns = parse_epoch(tag)
    return (tag_whole - whole).total_seconds() + (tag_ns - ns) / 1e9


def _recorded_states(path: Path) -> list:
    reader = BagReader(path)
    topic = reader.find_topic("state", "rigid_rot_msgs/msg/RigidBodyState")
    return [state for _, state in reader.decoded([topic])]


@pytest.mark.parametrize(
    "scene, commands, angvel",
    [
        ("free_tumble", {}, False),
        ("free_tumble", {}, True),
        ("torque_driven", COMMANDS, True),  # a slew by torque commands
    ],
)
def test_export_round_trips_the_recording(tmp_path, scene, commands, angvel):
    bag = tmp_path / "run.mcap"
    record_like_the_node(bag, scene, 600, 10, commands, method="rk4")
    out = write_aem(bag, tmp_path / "run.aem", AemOptions(angular_velocity=angvel))
    parsed = read_aem(out.read_text(encoding="ascii"))
    assert parsed["header"]["CCSDS_AEM_VERS"] == "2.0"
    dt.datetime.fromisoformat(parsed["header"]["CREATION_DATE"])
    (segment,) = parsed["segments"]
    meta = segment["meta"]
    assert (meta["REF_FRAME_A"], meta["REF_FRAME_B"], meta["TIME_SYSTEM"]) == ("EME2000", "SC_BODY_1", "UTC")
    assert meta["ATTITUDE_TYPE"] == ("QUATERNION/ANGVEL" if angvel else "QUATERNION")
    assert ("ANGVEL_FRAME" in meta) == angvel
    assert any("'odom'" in c for c in segment["comments"]) and any("'base_link'" in c for c in segment["comments"])
    states = _recorded_states(bag)
    assert len(segment["rows"]) == len(states)
    for (tag, values), state in zip(segment["rows"], states, strict=True):
        t = state.header.stamp.sec + state.header.stamp.nanosec * 1e-9
        assert _seconds_after("2000-01-01T12:00:00Z", tag) == pytest.approx(t, abs=1e-9)
        q = [state.orientation.x, state.orientation.y, state.orientation.z, state.orientation.w]
        np.testing.assert_allclose(values[:4], q, rtol=1e-15, atol=1e-16)  # 16 digits printed
        if angvel:
            w = state.angular_velocity_body
            np.testing.assert_allclose(values[4:], np.degrees([w.x, w.y, w.z]), rtol=1e-15, atol=1e-300)


def test_quaternion_is_the_standards_a_to_b():
    """Annex F2.2: B = A turned +90 deg about z; X_A = [1, 0, 0] has X_B = [0, -1, 0] (M_BA X_A)."""
    from scipy.spatial.transform import Rotation

    # a body turned +90 deg about the world z axis: our q rotates body -> world
    q = Rotation.from_euler("z", 90, degrees=True).as_quat()
    text = format_aem([AttitudeSample(0, tuple(q), (0.0, 0.0, 0.0))])
    q1, q2, q3, qc = read_aem(text)["segments"][0]["rows"][0][1]
    assert (q1, q2, q3) == (0.0, 0.0, pytest.approx(math.sqrt(0.5))) and qc == pytest.approx(math.sqrt(0.5))
    m_ba = np.array(
        [
            [q1**2 - q2**2 - q3**2 + qc**2, 2 * (q1 * q2 + q3 * qc), 2 * (q1 * q3 - q2 * qc)],
            [2 * (q1 * q2 - q3 * qc), -(q1**2) + q2**2 - q3**2 + qc**2, 2 * (q2 * q3 + q1 * qc)],
            [2 * (q1 * q3 + q2 * qc), 2 * (q2 * q3 - q1 * qc), -(q1**2) - q2**2 + q3**2 + qc**2],
        ]
    )
    np.testing.assert_allclose(m_ba @ [1.0, 0.0, 0.0], [0.0, -1.0, 0.0], atol=1e-15)


def test_time_going_back_starts_a_new_segment_and_repeats_are_dropped():
    q = (0.0, 0.0, 0.0, 1.0)
    samples = [AttitudeSample(t, q, (0.0, 0.0, 0.0)) for t in (0, 10, 10, 20)]
    samples.append(AttitudeSample(5, q, (0.0, 0.0, 0.0)))  # a reset: time goes back
    samples.append(AttitudeSample(5, (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0)))  # set_state at the same time
    parsed = read_aem(format_aem(samples, epoch="2026-11-24T23:59:59.5Z"))
    assert [len(s["rows"]) for s in parsed["segments"]] == [3, 1, 1]
    assert parsed["segments"][0]["rows"][1][0] == "2026-11-24T23:59:59.500000010"
    assert parsed["segments"][1]["meta"]["START_TIME"] == "2026-11-24T23:59:59.500000005"


def test_epoch_from_the_scene_and_day_rollover(tmp_path):
    text = format_aem(
        [AttitudeSample(1_500_000_000, (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0))], epoch="2026-12-31T23:59:59.25"
    )
    assert read_aem(text)["segments"][0]["rows"][0][0] == "2027-01-01T00:00:00.750000000"


@pytest.mark.parametrize(
    "options, message",
    [
        (AemOptions(ref_frame_a="odom"), "REF_FRAME_A"),
        (AemOptions(ref_frame_b="base_link"), "REF_FRAME_B"),
        (AemOptions(object_id="a b"), "OBJECT_ID"),
    ],
)
def test_invalid_options_are_refused(options, message):
    with pytest.raises(ValueError, match=message):
        format_aem([AttitudeSample(0, (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0))], options=options)


def test_cli_writes_the_file_and_refuses_bad_input_in_one_line(tmp_path):
    bag = tmp_path / "run.mcap"
    record_like_the_node(bag, "free_tumble", 100, 10, {}, method="rk4")
    exe = [str(Path(sys.executable).parent / "rigid-rot")]
    done = subprocess.run(exe + ["export", "aem", str(bag), "--angvel"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    parsed = read_aem((tmp_path / "run.aem").read_text(encoding="ascii"))
    assert parsed["segments"][0]["meta"]["OBJECT_NAME"] == "FREE_TUMBLE"
    bad = subprocess.run(
        exe + ["export", "aem", str(bag), "--ref-frame-a", "odom"], capture_output=True, text=True, timeout=120
    )
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "REF_FRAME_A" in bad.stderr
