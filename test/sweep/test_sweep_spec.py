"""Sweep specs: the shipped ones load; bad ones give one line naming file, key and problem, exit 2."""

from pathlib import Path

import pytest

from rigid_rot_sim.cli import main
from rigid_rot_sim.sweep.spec import SweepSpecError, load_sweep_spec, parse_sweep_text

SWEEPS = Path(__file__).resolve().parents[2] / "config" / "sweeps"

GOOD = """
scene: free_tumble
seed: 1
samples: 4
duration: 1.0
grid: {method: [rk4], dt: [0.01]}
dispersions:
  principal_moments: {relative: 0.02}
"""


@pytest.mark.parametrize("path", sorted(SWEEPS.glob("*.yaml")), ids=lambda p: p.stem)
@pytest.mark.parametrize("quick", [False, True])
def test_shipped_specs_load(path, quick):
    spec = load_sweep_spec(path, quick=quick)
    assert spec.n_runs >= 1 and spec.duration > 0
    assert spec.text == path.read_text()


def test_quick_overrides_apply():
    full = load_sweep_spec(SWEEPS / "stability_map.yaml")
    quick = load_sweep_spec(SWEEPS / "stability_map.yaml", quick=True)
    assert quick.samples < full.samples and quick.duration < full.duration and quick.dts != full.dts
    assert quick.methods == full.methods  # untouched keys stay


def test_a_good_spec_parses_with_defaults():
    spec = parse_sweep_text(GOOD, "good.yaml")
    assert spec.name == "good" and spec.scene.name == "free_tumble"
    assert spec.grid == [("rk4", 0.01, None)] and spec.n_runs == 4
    assert spec.dispersions.principal_moments.size == (0.02, 0.02, 0.02)


BAD = [
    ("unknown top-level key", GOOD + "sample_count: 3\n", "bad.yaml: sample_count: unknown key"),
    ("negative sample count", GOOD.replace("samples: 4", "samples: -5"), "bad.yaml: samples: must be >= 1, got -5"),
    (
        "unknown dispersion key",
        GOOD.replace("principal_moments: {relative: 0.02}", "principal_moments: {relative: 0.02, sigma: 1}"),
        "bad.yaml: dispersions.principal_moments.sigma: unknown key",
    ),
    (
        "moment made non-positive",
        GOOD.replace("relative: 0.02", "relative: 0.3"),
        "bad.yaml: dispersions.principal_moments.relative: 0.3 (normal, cut at 4 sigma) can make moment 1",
    ),
    (
        "triangle inequality broken at the extremes",
        # free_tumble is 0.8, 1.2, 1.5: 0.8 (1 - 0.4) + 1.2 (1 - 0.4) = 1.2 < 1.5 (1 + 0.4)
        GOOD.replace("relative: 0.02}", "relative: 0.4, distribution: uniform}"),
        "bad.yaml: dispersions.principal_moments.relative: [0.4, 0.4, 0.4] (uniform) can break the triangle inequality",
    ),
    (
        "not a batch method",
        GOOD.replace("method: [rk4]", "method: [rk4, exact]"),
        "bad.yaml: grid.method[1]: must be a batch method",
    ),
    ("non-positive dt", GOOD.replace("dt: [0.01]", "dt: [0.01, 0.0]"), "bad.yaml: grid.dt[1]: must be > 0"),
    (
        "unknown scene",
        GOOD.replace("scene: free_tumble", "scene: no_such_scene"),
        "bad.yaml: scene: scene 'no_such_scene' not found",
    ),
    (
        "topic-driven scene",
        GOOD.replace("scene: free_tumble", "scene: torque_driven"),
        "bad.yaml: scene: topic_inputs: not run by the sweep path (scene torque_driven;",
    ),
    (
        "heavy top",
        GOOD.replace("scene: free_tumble", "scene: heavy_top"),
        "bad.yaml: scene: gravity: not run by the sweep path (scene heavy_top;",
    ),
    (
        "a batch method for a wheel scene",
        GOOD.replace("scene: free_tumble", "scene: wheel_slew"),
        "bad.yaml: grid.method[0]: must be a gyrostat method (the engine per sample) for scene wheel_slew "
        "(gyrostat_rk4, dopri5), got 'rk4'",
    ),
    (
        "torque noise on a wheel scene",
        GOOD.replace("scene: free_tumble", "scene: wheel_slew").replace("[rk4]", "[gyrostat_rk4]")
        + "  torque_noise: {sigma: 1.0e-3}\n",
        "bad.yaml: dispersions.torque_noise: maps onto no key of scene wheel_slew",
    ),
    ("unknown metric", GOOD + "metric: pointing\n", "bad.yaml: metric: unknown metric 'pointing'"),
    ("not YAML", "scene: [unclosed\n", "bad.yaml: not valid YAML"),
]


@pytest.mark.parametrize("text, expected", [(t, e) for _, t, e in BAD], ids=[name for name, _, _ in BAD])
def test_bad_spec_is_one_line_naming_file_key_and_problem(tmp_path, capsys, text, expected):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(SweepSpecError) as info:
        load_sweep_spec(path)
    assert str(info.value).startswith(expected), str(info.value)
    # the command line: one line on stderr, exit code 2, nothing run
    assert main(["sweep", str(path), "--out", str(tmp_path / "out"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("rigid-rot sweep: error: " + expected), err
    assert not (tmp_path / "out").exists()


def test_missing_file_is_one_line(tmp_path, capsys):
    assert main(["sweep", str(tmp_path / "nope.yaml")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot read sweep spec" in err


@pytest.mark.parametrize("command", ["sweep", "report", "stability"])
def test_zero_workers_is_one_line(tmp_path, capsys, command):
    path = tmp_path / "good.yaml"
    path.write_text(GOOD)
    args = [command, str(path)] if command == "sweep" else [command]
    try:
        code = main(args + ["--workers", "0", "--out", str(tmp_path / "out"), "--no-progress"])
    except SystemExit as exc:  # refused by argparse itself
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--workers" in err and "0" in err, err
    assert not (tmp_path / "out").exists()


def test_yaml_1_2_numbers_are_numbers_in_a_sweep_spec():
    text = GOOD.replace("dt: [0.01]", "dt: [1e-2]").replace("duration: 1.0", "duration: 1e0")
    spec = parse_sweep_text(text, "s.yaml")
    assert spec.grid == [("rk4", 0.01, None)] and spec.duration == 1.0
