"""The scene schema: exported as committed, valid JSON Schema, bounded like the node's parameters,
described for editors, and its errors turned into one line naming the key."""

import copy
import dataclasses
import doctest
import json
import pickle
import re
from pathlib import Path

import pytest
from jsonschema import Draft202012Validator

from rigid_rot_sim.core import limits
from rigid_rot_sim.scene import schema
from rigid_rot_sim.scene.scene import DEFAULT_OUTPUT_RATES, OUTPUT_NAMES, OutputRates, SceneError, parse_scene_text
from rigid_rot_sim.scene.scene_schema import OUTPUTS, SCENE_SCHEMA

ROOT = Path(__file__).resolve().parents[2]
EXPORTED = ROOT / "config" / "schema" / "scene.schema.json"
MINIMAL = "body: {principal_moments: [1.0, 2.0, 3.0]}\n"


def test_the_committed_json_is_the_schema():
    # regenerate with: python -m rigid_rot_sim.scene.scene_schema > config/schema/scene.schema.json
    assert EXPORTED.read_text() == schema.dump(SCENE_SCHEMA)


def test_it_is_a_valid_draft_2020_12_schema():
    assert SCENE_SCHEMA["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    Draft202012Validator.check_schema(json.loads(EXPORTED.read_text()))


def test_every_number_is_bounded_on_both_sides():
    # a YAML integer of any size must meet a bound before anything converts it to a float
    numbers = [s for s in schema.iter_schemas(SCENE_SCHEMA) if s.get("type") in ("number", "integer")]
    assert len(numbers) > 20
    for item in numbers:
        assert "maximum" in item and ("minimum" in item or "exclusiveMinimum" in item), item


def test_every_key_is_described_for_editors():
    for item in schema.iter_schemas(SCENE_SCHEMA):
        for name, value in item.get("properties", {}).items():
            assert value.get("description"), name


@pytest.mark.parametrize(
    "path, bounds",
    [
        (("integrator", "dt"), limits.DT_RANGE),
        (("real_time_factor",), limits.REAL_TIME_FACTOR_RANGE),
        (("outputs", "state"), limits.RATE_RANGE),
        (("outputs", "odom"), limits.RATE_RANGE),
        (("commands", "max_torque"), limits.MAX_TORQUE_RANGE),
        (("commands", "qos_depth"), limits.COMMAND_DEPTH_RANGE),
        (("qos", "depth"), limits.QOS_DEPTH_RANGE),
    ],
)
def test_bounds_are_the_node_parameter_ranges(path, bounds):
    item = SCENE_SCHEMA
    for name in path:
        item = item["properties"][name]
    assert (item["minimum"], item["maximum"]) == bounds


def test_outputs_come_from_one_table():
    assert OUTPUT_NAMES == tuple(OUTPUTS) == tuple(OutputRates())
    assert DEFAULT_OUTPUT_RATES == dict(OutputRates())
    assert list(SCENE_SCHEMA["properties"]["outputs"]["properties"]) == list(OUTPUTS)
    assert OutputRates(imu=5.0)["imu"] == 5.0 and OutputRates({"odom": 2})["odom"] == 2.0


def test_output_rates_are_a_frozen_mapping():
    rates = OutputRates(imu=5.0)
    assert rates == OutputRates({"imu": 5.0}) != OutputRates() and hash(rates) == hash(OutputRates(imu=5.0))
    with pytest.raises(AttributeError):
        rates.imu = 1.0  # type: ignore[attr-defined]
    with pytest.raises(TypeError):
        rates["imu"] = 1.0  # type: ignore[index]
    with pytest.raises(KeyError, match="velocity"):
        OutputRates(velocity=1.0)
    assert pickle.loads(pickle.dumps(rates)) == rates and copy.deepcopy(rates) == rates


@pytest.mark.parametrize("path", sorted((ROOT / "config" / "scenes").glob("*.yaml")), ids=lambda p: p.stem)
def test_shipped_scenes_name_the_schema_for_editors(path):
    first = path.read_text().splitlines()[0]
    match = re.fullmatch(r"# yaml-language-server: \$schema=(\S+)", first)
    assert match, first
    assert (path.parent / match.group(1)).resolve() == EXPORTED


@pytest.mark.parametrize(
    "text, expected",
    [
        ("", "s.yaml: must be a mapping, got None"),
        ("body: 5\n", "s.yaml: body: must be a mapping, got 5"),
        (
            "body: {}\n",
            "s.yaml: body: must give exactly one of principal_moments, inertia_tensor, point_masses, got none",
        ),
        (
            "body: {inertia_tensor: [[1, 0, 0], [0, 1, 0]]}\n",
            "s.yaml: body.inertia_tensor: must be a list of 3 lists of 3 numbers",
        ),
        (
            "body: {inertia_tensor: [[1, 0, 0], [0, 1, 0], [0, 0, .inf]]}\n",
            "s.yaml: body.inertia_tensor[2][2]: must be finite, got inf",
        ),
        ("body: {point_masses: {masses: [1]}}\n", "s.yaml: body.point_masses: needs positions"),
        (MINIMAL + "torque_inputs: [{type: Twist}]\n", "s.yaml: torque_inputs[0]: needs topic"),
        (
            MINIMAL + "torque_inputs: [{topic: a, hold: 5}]\n",
            "s.yaml: torque_inputs[0].hold: must be 'hold' or {timeout: seconds}, got 5",
        ),
        (MINIMAL + "gravity: 5\n", "s.yaml: gravity: must be null, 'none' or a mapping, got 5"),
        (
            MINIMAL + "gravity: {acceleration: -1, mass: 1, center_of_mass: [0, 0, 1]}\n",
            "s.yaml: gravity.acceleration: must be > 0, got -1",
        ),
        (MINIMAL + "qos: {depth: 2.0}\n", "s.yaml: qos.depth: must be an integer from 1 to 100000, got 2.0"),
        (MINIMAL + "duration: abc\n", "s.yaml: duration: must be a number or null, got 'abc'"),
        (MINIMAL + "recording: '  '\n", "s.yaml: recording: must be a non-empty string or null, got '  '"),
        (MINIMAL + "description: '" + "x" * 5000 + "'\n", "s.yaml: description: longer than 4096 characters (limit)"),
        (
            MINIMAL + "integrator: {options: {tol: [1]}}\n",
            "s.yaml: integrator.options.tol: must be a number, a non-empty string",
        ),
        (
            MINIMAL + "torque_inputs: [" + ", ".join(["{topic: a}"] * 40) + "]\n",
            "s.yaml: torque_inputs: more than 32 items (limit)",
        ),
        (MINIMAL + "1: 2\n", "s.yaml: 1: unknown key (allowed: name, description, frames, body,"),
    ],
)
def test_schema_errors_are_one_line_naming_the_key(text, expected):
    with pytest.raises(SceneError) as info:
        parse_scene_text(text, source="/some/where/s.yaml")
    message = str(info.value)
    assert message.startswith(expected) and "\n" not in message, message


def test_null_sections_mean_their_defaults():
    scene = parse_scene_text(
        MINIMAL + "frames: ~\ninitial: ~\ntorque_inputs: ~\ngravity: none\nintegrator: ~\nduration: ~\n"
        "outputs: ~\nqos: ~\nrecording: ~\ncommands: ~\ndescription: ~\n"
    )
    default = parse_scene_text(MINIMAL)
    assert dataclasses.replace(scene, text="") == dataclasses.replace(default, text="")


def test_the_schema_module_examples_run():
    assert doctest.testmod(schema).failed == 0
