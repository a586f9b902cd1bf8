"""Complete message definitions and type hashes (rigid_rot_sim.recording.definitions)."""

import json
import sys
from pathlib import Path

import pytest

from rigid_rot_sim.recording import definitions

SHARE = Path(sys.prefix) / "share"


def test_complete_definition_lists_each_dependency_once_after_80_equals():
    text = definitions.complete_definition("geometry_msgs/msg/WrenchStamped")
    blocks = text.split("=" * 80 + "\n")
    assert blocks[0].strip().endswith("Wrench wrench")
    names = [b.splitlines()[0] for b in blocks[1:]]
    assert names == [
        "MSG: std_msgs/msg/Header",
        "MSG: builtin_interfaces/msg/Time",
        "MSG: geometry_msgs/msg/Wrench",
        "MSG: geometry_msgs/msg/Vector3",
    ]
    # separator lines are exactly 80 '=' and nothing else
    for line in text.splitlines():
        assert set(line) != {"="} or len(line) == 80


def test_project_types_resolve_with_their_dependencies():
    text = definitions.complete_definition("rigid_rot_msgs/RejectedCommand")
    assert "MSG: geometry_msgs/msg/Vector3" in text
    assert "MSG: std_msgs/msg/Header" in text
    assert text.startswith("# A torque command or request the simulator refused")


def test_field_types_skip_constants_primitives_and_comments():
    text = (
        "uint8 MODE=1  # const\nstring<=8 name\nint32[<=5] a\nPoint[] points  # nested\n"
        "std_msgs/Header header\n# geometry_msgs/Pose commented\n"
    )
    assert definitions.field_types(text, "geometry_msgs") == ["geometry_msgs/msg/Point", "std_msgs/msg/Header"]


def test_bad_type_name_is_a_value_error_and_unknown_type_a_lookup_error():
    with pytest.raises(ValueError, match="type_name"):
        definitions.normalize_type_name("not a type")
    with pytest.raises(LookupError, match="no_such_msgs/msg/Thing"):
        definitions.msg_text("no_such_msgs/msg/Thing")


def test_installed_type_hash_matches_rosidl_json():
    expected = json.loads((SHARE / "geometry_msgs/msg/Vector3Stamped.json").read_text())["type_hashes"][0]
    assert definitions.type_hash("geometry_msgs/msg/Vector3Stamped") == expected["hash_string"]


def test_hash_procedure_for_embedded_types_reproduces_an_installed_hash():
    # PoseArray has the same shape as TFMessage (an unbounded sequence of a nested type):
    # hashing its individual description the way TFMessage is hashed must give rosidl's hash.
    installed = json.loads((SHARE / "geometry_msgs/msg/PoseArray.json").read_text())
    individual = installed["type_description_msg"]["type_description"]
    assert definitions.hash_from_description(individual) == installed["type_hashes"][0]["hash_string"]
    assert definitions.type_hash("tf2_msgs/msg/TFMessage").startswith("RIHS01_")


def test_tf_message_roundtrips_through_the_dynamic_encoder():
    encode = definitions.dynamic_encoder("tf2_msgs/msg/TFMessage")
    decode = definitions.dynamic_decoder(
        "tf2_msgs/msg/TFMessage", definitions.complete_definition("tf2_msgs/msg/TFMessage")
    )
    transform = {
        "header": {"stamp": {"sec": 3, "nanosec": 250}, "frame_id": "world"},
        "child_frame_id": "body",
        "transform": {
            "translation": {"x": 0.0, "y": 0.0, "z": 0.0},
            "rotation": {"x": 0.5, "y": -0.5, "z": 0.5, "w": 0.5},
        },
    }
    decoded = decode(encode({"transforms": [transform]}))
    (out,) = decoded.transforms
    assert (out.header.stamp.sec, out.header.stamp.nanosec, out.child_frame_id) == (3, 250, "body")
    assert (out.transform.rotation.x, out.transform.rotation.w) == (0.5, 0.5)
