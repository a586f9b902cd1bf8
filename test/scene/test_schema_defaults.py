"""Schema defaults have one meaning: a key left out parses as the key written with its schema default.

The JSON Schemas (``scene_schema.SCENE_SCHEMA``, ``sweep.schema.SWEEP_SCHEMA``) state each default for
editors and the docs; the parsers and dataclasses apply their own. For every ``default`` of a key whose
section the minimal document has (or an optional section that parses with that key alone), the minimal
document and the same document with the key written out must parse to the same value.
"""

from __future__ import annotations

import copy
import dataclasses
from typing import Any

import pytest

from rigid_rot_sim.scene.scene import parse_scene
from rigid_rot_sim.scene.scene_schema import SCENE_SCHEMA
from rigid_rot_sim.sweep.schema import SWEEP_SCHEMA
from rigid_rot_sim.sweep.spec import parse_sweep_spec

MINIMAL_SCENE: dict[str, Any] = {"body": {"principal_moments": [1.0, 2.0, 3.0]}}
MINIMAL_SWEEP: dict[str, Any] = {
    "scene": "free_tumble",
    "seed": 1,
    "samples": 2,
    "grid": {"method": ["rk4"], "dt": [0.01]},
    "duration": 1.0,
}


def defaults(schema: dict[str, Any], path: tuple[str, ...] = ()) -> list[tuple[tuple[str, ...], Any]]:
    """(key path, default) of every default under object properties (arrays and alternatives not entered)."""
    found = []
    for key, sub in schema.get("properties", {}).items():
        if "default" in sub:
            found.append(((*path, key), sub["default"]))
        if sub.get("type") == "object" or "properties" in sub:
            found += defaults(sub, (*path, key))
    return found


def with_key(document: dict[str, Any], path: tuple[str, ...], value: Any) -> dict[str, Any]:
    changed = copy.deepcopy(document)
    node = changed
    for key in path[:-1]:
        node = node.setdefault(key, {})
        if not isinstance(node, dict):
            raise TypeError(path)
    node[path[-1]] = value
    return changed


def comparable(document: Any) -> Any:
    """The parsed document without what records the input itself (its text and source)."""
    fields = {f.name for f in dataclasses.fields(document)}
    return dataclasses.replace(document, **{name: "" for name in ("text", "source") if name in fields})


SCENE_DEFAULTS = defaults(SCENE_SCHEMA)
SWEEP_DEFAULTS = defaults(SWEEP_SCHEMA)


def _check(parse, minimal: dict[str, Any], path: tuple[str, ...], value: Any) -> bool:
    """True when compared; False when the key's section cannot stand with this key alone."""
    base_doc = minimal if len(path) == 1 or path[0] in minimal else with_key(minimal, path[:-1], {})
    try:  # an optional section: compare the section with the key against the section left empty
        base = parse(base_doc)
    except (ValueError, TypeError):
        return False
    try:
        written = parse(with_key(base_doc, path, value))
    except ValueError:
        return False
    assert comparable(written) == comparable(base), f"{'.'.join(path)}: default {value!r} is not the parser's"
    return True


def test_every_scene_default_that_can_stand_alone_is_the_parsers():
    compared = [path for path, value in SCENE_DEFAULTS if _check(parse_scene, MINIMAL_SCENE, path, value)]
    # 30 of 35 stand alone in their section (gravity_gradient.mu and orbit.inclination, star_tracker.rate
    # and lockstep.timeout/on_timeout need companion keys)
    assert len(SCENE_DEFAULTS) >= 30 and len(compared) >= 30, (len(SCENE_DEFAULTS), compared)


def test_every_sweep_default_that_can_stand_alone_is_the_parsers():
    compared = [path for path, value in SWEEP_DEFAULTS if _check(parse_sweep_spec, MINIMAL_SWEEP, path, value)]
    assert len(compared) >= 4, (SWEEP_DEFAULTS, compared)


@pytest.mark.parametrize("path", ["integrator.dt", "real_time_factor", "qos.depth"])
def test_the_reviews_restated_defaults_are_among_those_compared(path):
    """The defaults the review found written two or three times are checked, not filtered out."""
    wanted = tuple(path.split("."))
    value = dict(SCENE_DEFAULTS)[wanted]
    assert _check(parse_scene, MINIMAL_SCENE, wanted, value)
