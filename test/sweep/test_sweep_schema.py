"""The sweep spec schema: exported as committed, valid, bounded, described; its errors name the key."""

import json
import re
from pathlib import Path

import pytest
from jsonschema import Draft202012Validator

from rigid_rot_sim.scene import schema
from rigid_rot_sim.sweep.schema import SWEEP_SCHEMA
from rigid_rot_sim.sweep.spec import SweepSpecError, parse_sweep_text

ROOT = Path(__file__).resolve().parents[2]
EXPORTED = ROOT / "config" / "schema" / "sweep.schema.json"
GOOD = "scene: free_tumble\nseed: 1\nsamples: 4\nduration: 1.0\ngrid: {method: [rk4], dt: [0.01]}\n"


def test_the_committed_json_is_the_schema():
    # regenerate with: python -m rigid_rot_sim.sweep.schema > config/schema/sweep.schema.json
    assert EXPORTED.read_text() == schema.dump(SWEEP_SCHEMA)


def test_it_is_valid_bounded_and_described():
    Draft202012Validator.check_schema(json.loads(EXPORTED.read_text()))
    for item in schema.iter_schemas(SWEEP_SCHEMA):
        if item.get("type") == "number":
            assert "maximum" in item and ("minimum" in item or "exclusiveMinimum" in item), item
        for name, value in item.get("properties", {}).items():
            assert value.get("description"), name


@pytest.mark.parametrize("path", sorted((ROOT / "config" / "sweeps").glob("*.yaml")), ids=lambda p: p.stem)
def test_shipped_specs_name_the_schema_for_editors(path):
    match = re.fullmatch(r"# yaml-language-server: \$schema=(\S+)", path.read_text().splitlines()[0])
    assert match and (path.parent / match.group(1)).resolve() == EXPORTED


@pytest.mark.parametrize(
    "text, expected",
    [
        ("seed: 1\n", "w.yaml: scene: missing"),
        (GOOD + "quick: {samples: 0}\n", "w.yaml: quick.samples: must be >= 1, got 0"),
        (GOOD + "quick: {grid: {dt: [-1]}}\n", "w.yaml: quick.grid.dt[0]: must be > 0, got -1"),
        (
            GOOD + "dispersions: {initial_omega: {sigma: [1, 2]}}\n",
            "w.yaml: dispersions.initial_omega.sigma: must be a list of 3 numbers, got [1, 2]",
        ),
        (GOOD + "dispersions: {torque_noise: {interval: 1}}\n", "w.yaml: dispersions.torque_noise: needs sigma"),
        (GOOD + "nominal: {method: rk4}\n", "w.yaml: nominal: needs dt"),
        (GOOD + "seed: 1.5\n".replace("seed", "checkpoints"), "w.yaml: checkpoints: must be an integer, got 1.5"),
        (GOOD + "energy_tolerance: .nan\n", "w.yaml: energy_tolerance: must be finite, got nan"),
        (GOOD + "events: [first_flip, wobble]\n", "w.yaml: events[1]: unknown event 'wobble'"),
    ],
)
def test_errors_are_one_line_naming_the_key(text, expected):
    with pytest.raises(SweepSpecError) as info:
        parse_sweep_text(text, source="/any/w.yaml")
    message = str(info.value)
    assert message.startswith(expected) and "\n" not in message, message


def test_quick_overrides_merge_into_the_grid():
    spec = parse_sweep_text(
        GOOD + "grid: {method: [rk4, splitting], dt: [0.01]}\nquick: {samples: 2, grid: {dt: [0.1]}}\n", quick=True
    )
    assert spec.samples == 2 and spec.dts == (0.1,) and spec.methods == ("rk4", "splitting")
