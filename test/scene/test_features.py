"""Every scene field is run or refused by every path: the classification of scene/features.py is complete."""

from __future__ import annotations

import dataclasses
import types
import typing
from pathlib import Path

import pytest

from rigid_rot_sim.scene import features
from rigid_rot_sim.scene.features import FEATURE_FIELDS, FEATURES, PATHS, SETTINGS, features_of, refuse_unhonoured
from rigid_rot_sim.scene.scene import Scene, load_scene, parse_scene_text

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"


def _dataclass_in(hint: typing.Any) -> type | None:
    """The dataclass a field's type holds (itself, optional, or a tuple of it), else None."""
    if dataclasses.is_dataclass(hint):
        return hint  # type: ignore[return-value]
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType, tuple):
        for arg in typing.get_args(hint):
            found = _dataclass_in(arg)
            if found is not None:
                return found
    return None


def _unclassified(cls: type, prefix: str = "") -> list[str]:
    """Dotted fields of ``cls`` (recursively into dataclasses) classified nowhere."""
    classified = {**FEATURE_FIELDS, **SETTINGS}
    missing = []
    for name, hint in typing.get_type_hints(cls).items():
        if name not in {f.name for f in dataclasses.fields(cls)}:  # type: ignore[arg-type]
            continue
        path = f"{prefix}{name}"
        if path in classified:
            continue
        inner = _dataclass_in(hint)
        if inner is None:
            missing.append(path)
        else:
            missing += _unclassified(inner, f"{path}.")
    return missing


def _all_paths(cls: type, prefix: str = "") -> set[str]:
    out = set()
    for name, hint in typing.get_type_hints(cls).items():
        if name not in {f.name for f in dataclasses.fields(cls)}:  # type: ignore[arg-type]
            continue
        out.add(f"{prefix}{name}")
        inner = _dataclass_in(hint)
        if inner is not None:
            out |= _all_paths(inner, f"{prefix}{name}.")
    return out


def test_every_scene_field_is_a_feature_or_a_setting():
    assert _unclassified(Scene) == [], "classify these fields in scene/features.py (FEATURE_FIELDS or SETTINGS)"


def test_the_walk_goes_through_spacecraft_wheels_and_sensors():
    paths = _all_paths(Scene)
    assert {"spacecraft.wheels.coulomb", "spacecraft.gravity_gradient.radius", "sensors.gyro.rate"} <= paths


def test_a_new_field_classified_nowhere_fails_the_walk():
    @dataclasses.dataclass(frozen=True)
    class Grown(Scene):
        magnetorquers: tuple[float, ...] = ()

    assert _unclassified(Grown) == ["magnetorquers"]


def test_every_classified_field_exists_and_names_a_feature():
    paths = _all_paths(Scene)
    assert sorted(set(FEATURE_FIELDS) - paths) == []
    assert sorted(set(SETTINGS) - paths) == []
    assert set(FEATURE_FIELDS) & set(SETTINGS) == set()
    assert set(FEATURE_FIELDS.values()) <= set(FEATURES)
    for path, honoured in PATHS.items():
        assert honoured <= set(FEATURES), path
        assert {"body", "initial"} <= honoured, path


def test_every_feature_is_read_from_some_field():
    read = set(FEATURE_FIELDS.values()) | {"schedules.world"}  # a schedule's frame picks body or world
    assert read == set(FEATURES)


@pytest.mark.parametrize("path", sorted(PATHS))
@pytest.mark.parametrize("scene", sorted(p.name for p in SCENES.glob("*.yaml")))
def test_a_path_refuses_a_shipped_scene_by_its_first_unrun_feature_or_runs_it(scene, path):
    loaded = load_scene(str(SCENES / scene))
    unrun = [key for key in features_of(loaded) if key not in PATHS[path]]
    if not unrun:
        refuse_unhonoured(loaded, path)
        return
    with pytest.raises(ValueError) as caught:
        refuse_unhonoured(loaded, path)
    message = str(caught.value)
    assert message.startswith(f"{unrun[0]}: ") and "\n" not in message


def test_features_of_a_scene():
    scene = parse_scene_text(
        "body: {principal_moments: [1, 2, 3]}\n"
        "torque_inputs:\n  - schedule: {frame: world, segments: [{start: 0, torque: [0, 0, 1]}]}\n"
        "actuators:\n  reaction_wheels:\n"
        "    - {name: w, axis: [0, 0, 1], inertia: 0.01, max_torque: 0.1, max_speed: 100,\n"
        "       friction: {viscous: 1.0e-4}}\n"
        "integrator: {method: gyrostat_rk4, dt: 0.01}\n"
    )
    assert features_of(scene) == (
        "body",
        "initial",
        "schedules.world",
        "spacecraft.wheels",
        "spacecraft.wheels.friction",
    )
    assert features.MEASUREMENTS <= set(FEATURES)


def test_each_path_checks_its_declaration_before_any_work(monkeypatch):
    """A feature taken off a path's declaration is refused there by name: the engine, the sweep."""
    from rigid_rot_sim.run.simulator import Simulator
    from rigid_rot_sim.sweep.spec import SweepSpecError, parse_sweep_text

    scene = load_scene(str(SCENES / "gravity_gradient_satellite.yaml"))
    for path in ("engine", "sweep"):
        monkeypatch.setitem(PATHS, path, PATHS[path] - {"spacecraft.gravity_gradient"})
    with pytest.raises(ValueError, match=r"^spacecraft\.gravity_gradient: not run by the engine path"):
        Simulator(scene)
    spec = "scene: gravity_gradient_satellite\nseed: 1\nsamples: 1\ngrid: {method: [gyrostat_rk4], dt: [1.0]}\n"
    with pytest.raises(SweepSpecError, match=r"^g\.yaml: scene: spacecraft\.gravity_gradient: not run by the sweep"):
        parse_sweep_text(spec, "g.yaml")
