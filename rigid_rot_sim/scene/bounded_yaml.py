"""YAML for input files, bounded: size, nesting depth, collection sizes; no aliases.

A plain ``yaml.safe_load`` runs no code from tags, but it expands aliases (a few lines of
"billion laughs" become gigabytes), recurses once per nesting level (RecursionError on
deep nesting) and reads files of any size. :func:`load_bounded` first walks the parser's
event stream, which is flat and cheap, and refuses the document at the first event beyond
a limit; only a document within every limit is then built. Errors are
:class:`BoundedYAMLError` (a ValueError) with a one-line message. Numbers are read as YAML 1.2
reads them (``1e-3`` is a float, as in a ROS params file), not as YAML 1.1's string.

>>> load_bounded("a: [1, 2]")
{'a': [1, 2]}
>>> load_bounded("dt: 1e-3")  # YAML 1.2 (a string in YAML 1.1)
{'dt': 0.001}
>>> load_bounded("a: &x [1]\\nb: *x")
Traceback (most recent call last):
...
rigid_rot_sim.scene.bounded_yaml.BoundedYAMLError: line 2: YAML aliases (*x) are not accepted; write the value out
"""

from __future__ import annotations

import os
import re
from typing import Any

import yaml

from rigid_rot_sim.core import limits

__all__ = ["BoundedYAMLError", "load_bounded", "read_bounded", "read_input", "load_input"]

# libyaml's parser where PyYAML was built with it (the PyPI wheels, Debian's python3-yaml)
_BaseLoader: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)

#: YAML 1.2's core-schema floats that YAML 1.1 (PyYAML's resolver) reads as strings: an exponent
#: without a dot or without a signed exponent (``1e-3``, ``1E5``, ``2.5e3``, ``.5e-3``), as ROS params
#: files, ``-p`` and JSON Schema read them. YAML 1.1's own forms keep their meaning.
YAML12_FLOAT = re.compile(r"^[-+]?(?:\.[0-9]+|[0-9][0-9_]*(?:\.[0-9_]*)?)[eE][-+]?[0-9]+$")


class _Loader(_BaseLoader):  # type: ignore[misc]  # PyYAML's loaders are untyped classes
    """The safe loader, with YAML 1.2's floats (:data:`YAML12_FLOAT`) resolved as floats."""


_Loader.add_implicit_resolver("tag:yaml.org,2002:float", YAML12_FLOAT, list("-+0123456789."))


class BoundedYAMLError(ValueError):
    """The text is not valid YAML, or exceeds a limit of :mod:`rigid_rot_sim.core.limits`."""


def _line(event: Any) -> str:
    mark = getattr(event, "start_mark", None)
    return f"line {mark.line + 1}: " if mark is not None else ""


def _yaml_error(exc: yaml.YAMLError) -> BoundedYAMLError:
    if isinstance(exc, yaml.MarkedYAMLError):
        mark = exc.problem_mark or exc.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        what = exc.problem or exc.context or "invalid YAML"
        return BoundedYAMLError(limits.one_line(f"not valid YAML: {where}{what}"))
    return BoundedYAMLError(limits.one_line(f"not valid YAML: {exc}"))


def check_events(text: str, *, max_depth: int = limits.MAX_YAML_DEPTH, max_items: int = limits.MAX_YAML_ITEMS) -> None:
    """Walk the YAML events of ``text``; BoundedYAMLError at the first alias, too deep a
    nesting or too long a collection (and for invalid YAML)."""
    counts: list[int] = []  # items so far in each open collection (mapping: keys + values)
    kinds: list[bool] = []  # True for a mapping
    documents = 0
    try:
        for event in yaml.parse(text, Loader=_Loader):
            if isinstance(event, yaml.AliasEvent):
                raise BoundedYAMLError(
                    f"{_line(event)}YAML aliases (*{limits.clip_text(str(event.anchor), 40)}) are not accepted; "
                    "write the value out"
                )
            if isinstance(event, yaml.DocumentStartEvent):
                documents += 1
                if documents > 1:
                    raise BoundedYAMLError(f"{_line(event)}more than one YAML document")
            if isinstance(event, (yaml.ScalarEvent, yaml.SequenceStartEvent, yaml.MappingStartEvent)) and counts:
                counts[-1] += 1
                limit = 2 * max_items if kinds[-1] else max_items
                if counts[-1] > limit:
                    what = "mapping has more than" if kinds[-1] else "list has more than"
                    raise BoundedYAMLError(f"{_line(event)}{what} {max_items} items (limit)")
            if isinstance(event, (yaml.SequenceStartEvent, yaml.MappingStartEvent)):
                if len(counts) >= max_depth:
                    raise BoundedYAMLError(f"{_line(event)}nested deeper than {max_depth} levels (limit)")
                counts.append(0)
                kinds.append(isinstance(event, yaml.MappingStartEvent))
            elif isinstance(event, (yaml.SequenceEndEvent, yaml.MappingEndEvent)):
                counts.pop()
                kinds.pop()
    except yaml.YAMLError as exc:
        raise _yaml_error(exc) from None


def load_bounded(text: str, *, max_bytes: int = limits.MAX_SCENE_BYTES) -> Any:
    """Parse ``text`` (YAML, safe tags only) within the limits; BoundedYAMLError otherwise."""
    size = len(text.encode("utf-8", errors="replace"))
    if size > max_bytes:
        raise BoundedYAMLError(f"{size} bytes, more than the limit of {max_bytes} bytes")
    check_events(text)
    try:
        return yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as exc:  # e.g. an unknown tag (!!python/object): never constructed
        raise _yaml_error(exc) from None


def read_bounded(path: str | os.PathLike[str], *, max_bytes: int = limits.MAX_SCENE_BYTES) -> str:
    """The UTF-8 text of the file at ``path``, read no further than ``max_bytes``.

    OSError for a file that cannot be read, BoundedYAMLError for one too large or not UTF-8.
    """
    with open(path, "rb") as f:
        data = f.read(max_bytes + 1)
    if len(data) > max_bytes:
        raise BoundedYAMLError(f"larger than the limit of {max_bytes} bytes")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise BoundedYAMLError(f"not UTF-8 text (byte {exc.start})") from None


def read_input(path: str, what: str, error_class: type[ValueError]) -> str:
    """:func:`read_bounded` for a loader: its errors as one ``error_class`` line naming ``path``
    (``<path>: cannot read <what>: <reason>``)."""
    try:
        return read_bounded(path)
    except OSError as exc:
        raise error_class(f"{path}: cannot read {what}: {exc.strerror}") from None
    except BoundedYAMLError as exc:
        raise error_class(f"{path}: {exc}") from None


def load_input(text: str, source: str, error_class: type[ValueError]) -> Any:
    """:func:`load_bounded` for a loader: its errors as one ``error_class`` line naming the file."""
    try:
        return load_bounded(text)
    except BoundedYAMLError as exc:
        raise error_class(f"{os.path.basename(source)}: {exc}") from None
