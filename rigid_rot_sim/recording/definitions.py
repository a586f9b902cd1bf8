"""Complete message definitions and type hashes, as MCAP schemas and rosbag2 store them.

A ``ros2msg`` schema is the .msg text of the top-level type, then for every type it
depends on (recursively, each once, in order of first use) a line of exactly 80 ``=``,
a line ``MSG: pkg/msg/Type`` and that type's .msg text (rosbag2
``docs/message_definition_encoding.md``). Definitions are read from the installed
interface packages (``<prefix>/share/<pkg>/msg/<Type>.msg`` for every prefix on
``AMENT_PREFIX_PATH`` and the running interpreter's prefix, i.e. the venv). The type
hash (REP 2011, ``RIHS01_...``) is read from the ``.json`` type description that rosidl
installs next to each .msg.

``tf2_msgs/msg/TFMessage`` is embedded here, because ``/tf`` is recorded even where the
tf2_msgs package is not installed (it is not on PyPI); its hash is computed from its
type description with rosidl's own hashing function.
"""

from __future__ import annotations

import json
import os
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

SEPARATOR = "=" * 80

PRIMITIVE_TYPES = frozenset(
    {
        "bool",
        "byte",
        "char",
        "float32",
        "float64",
        "int8",
        "uint8",
        "int16",
        "uint16",
        "int32",
        "uint32",
        "int64",
        "uint64",
        "string",
        "wstring",
    }
)

EMBEDDED_DEFINITIONS: dict[str, str] = {
    "tf2_msgs/msg/TFMessage": "geometry_msgs/TransformStamped[] transforms\n",
}

# The individual type description of each embedded type (REP 2011 field type ids:
# 145 = nested type, unbounded sequence), used to compute its hash.
_EMBEDDED_TYPE_DESCRIPTIONS: dict[str, dict] = {
    "tf2_msgs/msg/TFMessage": {
        "type_name": "tf2_msgs/msg/TFMessage",
        "fields": [
            {
                "name": "transforms",
                "type": {
                    "type_id": 145,
                    "capacity": 0,
                    "string_capacity": 0,
                    "nested_type_name": "geometry_msgs/msg/TransformStamped",
                },
                "default_value": "",
            }
        ],
    },
}

_SOURCE_TREE = Path(__file__).resolve().parents[2]
_TYPE_NAME = re.compile(r"^([A-Za-z][A-Za-z0-9_]*)/(?:msg/)?([A-Za-z][A-Za-z0-9_]*)$")


@dataclass(frozen=True)
class MessageType:
    """What a recording needs to know about a message type.

    ``name`` is ``pkg/msg/Type``; ``definition`` the complete ``ros2msg`` text;
    ``hash`` the RIHS01 type hash, or ``""`` when it cannot be determined.
    """

    name: str
    definition: str
    hash: str


def normalize_type_name(type_name: str) -> str:
    """Return ``pkg/msg/Type`` for ``pkg/Type`` or ``pkg/msg/Type``; ValueError otherwise."""
    match = _TYPE_NAME.match(type_name.strip())
    if not match:
        raise ValueError(f"type_name must look like 'pkg/msg/Type', got {type_name!r}")
    return f"{match.group(1)}/msg/{match.group(2)}"


def prefixes() -> list[Path]:
    """Install prefixes searched for interface packages, in order of precedence."""
    found: list[Path] = []
    for entry in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        if entry and Path(entry) not in found:
            found.append(Path(entry))
    if Path(sys.prefix) not in found:
        found.append(Path(sys.prefix))
    return found


def _interface_file(type_name: str, suffix: str) -> Path | None:
    package, _, name = type_name.split("/")
    for prefix in prefixes():
        candidate = prefix / "share" / package / "msg" / f"{name}{suffix}"
        if candidate.is_file():
            return candidate
    # rigid_rot_msgs before `make setup` has installed it: its sources sit next to us.
    candidate = _SOURCE_TREE / package / "msg" / f"{name}{suffix}"
    if suffix == ".msg" and candidate.is_file():
        return candidate
    return None


@cache
def msg_text(type_name: str) -> str:
    """The .msg text of one type (not its dependencies); LookupError when not found."""
    type_name = normalize_type_name(type_name)
    path = _interface_file(type_name, ".msg")
    if path is not None:
        return path.read_text(encoding="utf-8")
    if type_name in EMBEDDED_DEFINITIONS:
        return EMBEDDED_DEFINITIONS[type_name]
    searched = ", ".join(str(p / "share") for p in prefixes())
    raise LookupError(f"no .msg file for {type_name} (searched {searched})")


def field_types(text: str, package: str) -> list[str]:
    """Message types (``pkg/msg/Type``) of the fields of a .msg text, in order of appearance.

    Constants, primitive fields and comments are skipped; a type without a package
    refers to ``package``.
    """
    found: list[str] = []
    for raw_line in text.splitlines():
        line = raw_line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split(None, 1)
        if len(parts) < 2 or "=" in parts[1].split(None, 1)[0]:
            continue  # malformed, or a constant such as `uint8 MODE=1`
        type_token = re.sub(r"\[.*\]$", "", parts[0])
        type_token = type_token.split("<=", 1)[0]
        if type_token in PRIMITIVE_TYPES:
            continue
        name = normalize_type_name(type_token if "/" in type_token else f"{package}/{type_token}")
        if name not in found:
            found.append(name)
    return found


@cache
def complete_definition(type_name: str) -> str:
    """The ``ros2msg`` schema text of ``type_name`` with all its dependencies."""
    top = normalize_type_name(type_name)
    order: list[str] = []

    def visit(name: str) -> None:
        for dependency in field_types(msg_text(name), name.split("/", 1)[0]):
            if dependency != top and dependency not in order:
                order.append(dependency)
                visit(dependency)

    visit(top)
    parts = [msg_text(top).rstrip("\n")]
    for dependency in order:
        parts.append(f"{SEPARATOR}\nMSG: {dependency}\n{msg_text(dependency).rstrip(chr(10))}")
    return "\n".join(parts) + "\n"


def _installed_type_description(type_name: str) -> dict | None:
    path = _interface_file(type_name, ".json")
    if path is None:
        return None
    return json.loads(path.read_text(encoding="utf-8"))


def hash_from_description(individual: dict) -> str:
    """RIHS01 hash of a type from its individual type description (REP 2011).

    The descriptions of the types it refers to are read from the installed packages;
    ``""`` when one of them, or rosidl's hashing module, is not available.
    """
    type_name = individual["type_name"]
    try:
        from rosidl_generator_type_description import (
            calculate_type_hash,
            extract_full_type_description,
        )
    except ImportError:
        return ""
    lookup = {type_name: individual}
    for field in individual["fields"]:
        nested = field["type"]["nested_type_name"]
        if not nested:
            continue
        installed = _installed_type_description(nested)
        if installed is None:
            return ""
        described = installed["type_description_msg"]
        lookup[nested] = described["type_description"]
        for referenced in described["referenced_type_descriptions"]:
            lookup[referenced["type_name"]] = referenced
    return calculate_type_hash(extract_full_type_description(type_name, lookup))


@cache
def type_hash(type_name: str) -> str:
    """The RIHS01 hash of a type, or ``""`` when neither installed nor computable."""
    type_name = normalize_type_name(type_name)
    installed = _installed_type_description(type_name)
    if installed is not None:
        for entry in installed.get("type_hashes", []):
            if entry.get("type_name") == type_name:
                return str(entry["hash_string"])
        return ""
    if type_name in _EMBEDDED_TYPE_DESCRIPTIONS:
        return hash_from_description(_EMBEDDED_TYPE_DESCRIPTIONS[type_name])
    return ""


def message_type(type_name: str) -> MessageType:
    """Name, complete definition and hash of a message type (LookupError if unknown)."""
    name = normalize_type_name(type_name)
    return MessageType(name=name, definition=complete_definition(name), hash=type_hash(name))


@cache
def dynamic_encoder(type_name: str) -> Callable[[Any], bytes]:
    """CDR encoder built from the complete definition (no generated Python type needed).

    The encoder takes nested mappings or objects with the field names, e.g.
    ``{"transforms": [{"header": {...}, "child_frame_id": "body", "transform": {...}}]}``.
    """
    from mcap_ros2._dynamic import serialize_dynamic

    name = normalize_type_name(type_name)
    return serialize_dynamic(name, complete_definition(name))[name]


@cache
def dynamic_decoder(type_name: str, definition: str) -> Callable[[bytes], Any]:
    """CDR decoder for a type from its complete ``ros2msg`` definition text."""
    from mcap_ros2._dynamic import generate_dynamic

    name = normalize_type_name(type_name)
    return generate_dynamic(name, definition)[name]
