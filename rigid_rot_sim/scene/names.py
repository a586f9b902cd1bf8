"""Syntax checks of ROS names, without rclpy: scenes are validated before any node exists.

The rules are those of ``rcl_validate_topic_name`` (design article "Topic and Service name
mapping to DDS"), without substitutions (``{node}``): a scene names its topics literally.

* non-empty, at most :data:`~rigid_rot_sim.core.limits.MAX_NAME_LENGTH` characters;
* only ASCII letters, digits, ``_``, ``/`` and a leading ``~`` (the node's private namespace);
* ``~`` only as the first character and then followed by ``/`` (or alone);
* no empty token (``//``), no trailing ``/``;
* no token starting with a digit.

>>> check_topic_name("~/torque")
'~/torque'
>>> check_topic_name("9torque")
Traceback (most recent call last):
...
ValueError: topic name '9torque': a name token must not start with a digit ('9torque')
"""

from __future__ import annotations

import re

from rigid_rot_sim.core import limits

__all__ = ["check_topic_name", "check_frame_id"]

_ALLOWED = re.compile(r"[A-Za-z0-9_/~]*")


def check_topic_name(name: str) -> str:
    """Return ``name`` if it is a valid ROS 2 topic name (relative, absolute or ``~/``); ValueError naming the rule."""
    label = f"topic name {limits.clip_text(repr(name), 80)}"
    if not isinstance(name, str) or not name:
        raise ValueError(f"{label}: must be a non-empty string")
    if len(name) > limits.MAX_NAME_LENGTH:
        raise ValueError(f"{label}: longer than {limits.MAX_NAME_LENGTH} characters")
    bad = _ALLOWED.fullmatch(name) is None
    if bad:
        char = next(c for c in name if not _ALLOWED.fullmatch(c))
        raise ValueError(f"{label}: character {char!r} not allowed (letters, digits, '_', '/', a leading '~/')")
    if "~" in name[1:] or (name.startswith("~") and name not in ("~",) and not name.startswith("~/")):
        raise ValueError(f"{label}: '~' is allowed only as the leading '~/' (the node's namespace)")
    if name.endswith("/") and name != "/":
        raise ValueError(f"{label}: must not end with '/'")
    if name == "/":
        raise ValueError(f"{label}: names no topic")
    if "//" in name:
        raise ValueError(f"{label}: must not contain '//' (an empty token)")
    for token in name.split("/"):
        if token[:1].isdigit():
            raise ValueError(f"{label}: a name token must not start with a digit ({token!r})")
    return name


def check_frame_id(name: str, what: str = "frame_id") -> str:
    """Return ``name`` if it is a usable frame name.

    At most MAX_NAME_LENGTH characters, no whitespace or control characters.
    """
    if len(name) > limits.MAX_NAME_LENGTH:
        raise ValueError(f"{what} of {len(name)} characters exceeds the limit of {limits.MAX_NAME_LENGTH}")
    if any(c.isspace() or not c.isprintable() for c in name):
        raise ValueError(f"{what} {limits.clip_text(repr(name), 80)} contains whitespace or control characters")
    return name
