"""The rigid-rot dispatcher and its inertia subcommand (no ROS: the library path only)."""

import argparse
import importlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rigid_rot_sim import cli
from rigid_rot_sim.cli import inertia as inertia_cli
from rigid_rot_sim.core.inertia import mass_properties, principal_orientation

REPO = Path(__file__).resolve().parents[2]
SAMPLE_BODY = REPO / "config" / "bodies" / "sample_body.yaml"
RIGID_ROT = Path(sys.executable).parent / "rigid-rot"


def run_cli(capsys, *argv):
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def sample_expected():
    body = inertia_cli.load_body_file(SAMPLE_BODY)
    return body, mass_properties(body.masses, body.positions, body.origin)


# --- the dispatcher -------------------------------------------------------------------------


def parsers_without_handler(parser, path):
    """Paths of parsers that can be reached but set no handler (nested subcommands allowed)."""
    if callable(parser.get_default("handler")):
        return []
    nested = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not nested:
        return [path]
    return [
        missing
        for action in nested
        for name, child in action.choices.items()
        for missing in parsers_without_handler(child, f"{path} {name}")
    ]


@pytest.mark.parametrize("name", cli.SUBCOMMANDS)
def test_every_registered_subcommand_has_a_parser_and_handler(name):
    importlib.import_module(f"rigid_rot_sim.cli.{name}")
    parser = cli.build_parser(only=name)
    subparsers = next(a for a in parser._actions if a.dest == "command")
    assert name in subparsers.choices
    assert parsers_without_handler(subparsers.choices[name], name) == []


def test_full_parser_lists_every_subcommand(capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["--help"])
    assert exit_info.value.code == 0
    out = capsys.readouterr().out
    for name in cli.SUBCOMMANDS:
        assert name in out


@pytest.mark.parametrize("argv", [[], ["no-such-command"], ["inertia", "--mass", "1", "0", "0"]])
def test_bad_arguments_give_one_line_and_exit_code_2(capsys, argv):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "error:" in err


def test_inertia_does_not_import_rclpy():
    # rclpy takes a second to import; the library path of `rigid-rot inertia` must not pay for it
    code = (
        "import sys; from rigid_rot_sim.cli import main; "
        f"rc = main(['inertia', {str(SAMPLE_BODY)!r}, '--json']); "
        "assert rc == 0; assert 'rclpy' not in sys.modules, 'rclpy imported'; "
        "assert 'matplotlib' not in sys.modules"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr


# --- rigid-rot inertia ----------------------------------------------------------------------


def test_json_of_the_sample_body_matches_the_library(capsys):
    body, expected = sample_expected()
    code, out, _ = run_cli(capsys, "inertia", str(SAMPLE_BODY), "--json")
    assert code == 0
    data = json.loads(out)
    assert data["name"] == "sample_satellite" and data["frame_id"] == "base_link"
    assert data["count"] == len(body.masses)
    assert data["total_mass"] == pytest.approx(18.4)
    np.testing.assert_allclose(data["center_of_mass"], expected.center_of_mass, rtol=1e-15)
    np.testing.assert_allclose(data["inertia_origin"], expected.inertia_origin, rtol=1e-15)
    np.testing.assert_allclose(data["inertia_com"], expected.inertia_com, rtol=1e-15)
    np.testing.assert_allclose(data["principal_moments"], expected.principal_moments, rtol=1e-15)
    np.testing.assert_allclose(data["principal_axes"], expected.principal_axes, rtol=1e-15)
    np.testing.assert_allclose(data["principal_orientation"], principal_orientation(expected.principal_axes))
    assert data["symmetry"] == expected.symmetry == "asymmetric"


def test_table_shows_the_numbers_with_units(capsys):
    _, expected = sample_expected()
    code, out, _ = run_cli(capsys, "inertia", str(SAMPLE_BODY))
    assert code == 0
    assert "total mass             18.4 kg" in out
    assert "symmetry               asymmetric" in out
    moments_line = next(line for line in out.splitlines() if "principal moments" in line)
    printed = [float(v) for v in moments_line.split()[2:5]]
    np.testing.assert_allclose(printed, expected.principal_moments, rtol=1e-8)


def test_mass_options_and_origin(capsys):
    # unit masses at x = 0 and x = 2: inertia about (0, 0, 1) by hand
    code, out, _ = run_cli(
        capsys,
        "inertia",
        "--mass",
        "1",
        "0",
        "0",
        "0",
        "--mass",
        "1",
        "2",
        "0",
        "0",
        "--origin",
        "0",
        "0",
        "1",
        "--json",
    )
    assert code == 0
    data = json.loads(out)
    np.testing.assert_allclose(data["center_of_mass"], [1.0, 0.0, 0.0])
    # d1 = (0, 0, -1), d2 = (2, 0, -1): Ixx = 1 + 1, Iyy = 1 + 5, Izz = 0 + 4, Ixz = -(0 + 2*-1) = 2
    np.testing.assert_allclose(data["inertia_origin"], [[2, 0, 2], [0, 6, 0], [2, 0, 4]], atol=1e-15)
    assert data["symmetry"] == "linear"


def test_origin_option_overrides_the_file(capsys):
    _, out_default = run_cli(capsys, "inertia", str(SAMPLE_BODY), "--json")[0:2]
    code, out, _ = run_cli(capsys, "inertia", str(SAMPLE_BODY), "--origin", "1", "2", "3", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["origin"] == [1.0, 2.0, 3.0]
    assert data["inertia_com"] == json.loads(out_default)["inertia_com"]
    assert data["inertia_origin"] != json.loads(out_default)["inertia_origin"]


@pytest.mark.parametrize(
    "argv, expected_message",
    [
        (["inertia"], "no masses"),
        (["inertia", "--mass", "-1", "0", "0", "0"], "masses[0] must be > 0"),
        (["inertia", "--mass", "1", "0", "0", "0", "--mass", "nan", "0", "0", "0"], "masses[1] must be finite"),
        (["inertia", "--mass", "1", "0", "inf", "0"], "positions[0] must be finite"),
        (["inertia", "does-not-exist.yaml"], "does-not-exist.yaml"),
        (["inertia", str(SAMPLE_BODY), "--mass", "1", "0", "0", "0"], "not both"),
        (["inertia", "--mass", "1", "0", "0", "0", "--compare"], "--compare needs --service"),
    ],
)
def test_bad_input_is_one_line_naming_the_problem(capsys, argv, expected_message):
    code, out, err = run_cli(capsys, *argv)
    assert code == 2
    assert out == ""
    assert len(err.strip().splitlines()) == 1
    assert err.startswith("rigid-rot inertia: error: ")
    assert expected_message in err


@pytest.mark.parametrize(
    "text, expected_message",
    [
        ("- 1\n- 2\n", "must be a mapping"),
        ("point_masses: {masses: [1.0]}\n", "point_masses must be a mapping with masses and positions"),
        ("point_masses: {masses: [1.0], positions: [[0, 0]]}\n", "point_masses.positions must be a list of [x, y, z]"),
        ("point_masses: {masses: [a], positions: [[0, 0, 0]]}\n", "point_masses.masses must be a list of numbers"),
        ("point_masses: {masses: [1.0, 2.0], positions: [[0, 0, 0]]}\n", "positions has 1 points but masses has 2"),
        ("point_masses: {masses: [1.0], positions: [[0, 0, 0]]}\norigin: [0, 0]\n", "origin must have shape"),
        ("point_masses: {masses: [1.0], positions: [[0, 0, 0]]}\ncolour: red\n", "unknown key 'colour'"),
        ("point_masses: [1, 2\n", "not valid YAML"),
    ],
)
def test_bad_body_file_names_the_problem(capsys, tmp_path, text, expected_message):
    path = tmp_path / "body.yaml"
    path.write_text(text)
    code, _, err = run_cli(capsys, "inertia", str(path))
    assert code == 2
    assert len(err.strip().splitlines()) == 1
    assert expected_message in err


def test_console_script_is_installed_and_reports_bad_input():
    ok = subprocess.run(
        [str(RIGID_ROT), "inertia", str(SAMPLE_BODY), "--json"], capture_output=True, text=True, timeout=60
    )
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["symmetry"] == "asymmetric"
    bad = subprocess.run(
        [str(RIGID_ROT), "inertia", "--mass", "0", "0", "0", "0"], capture_output=True, text=True, timeout=60
    )
    assert bad.returncode == 2
    assert bad.stderr.strip() == "rigid-rot inertia: error: masses[0] must be > 0 kg, got 0.0"
