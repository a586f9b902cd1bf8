"""Every command-line error is one line on stderr, at most MAX_ERROR_CHARS, exit code 2, nothing on
stdout (issue 9, item 7): before, 152 of 163 refused scenes printed on stdout, YAML errors took
several lines and an alias bomb gave a 17 MB message."""

import subprocess
import sys
from pathlib import Path

import pytest

from rigid_rot_sim import cli
from rigid_rot_sim.core import limits

REPO = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
MINIMAL = "body: {principal_moments: [1.0, 2.0, 2.5]}\n"
BOMB = 'a: &a "' + "x" * 100 + '"\nb: &b [*a, *a, *a, *a, *a, *a, *a, *a]\nc: &c [*b, *b, *b, *b, *b, *b, *b, *b]\n'

BAD_SCENES = {
    "deep": MINIMAL + "description: " + "[" * 3000 + "]" * 3000 + "\n",
    "bomb": MINIMAL + BOMB,
    "dt": MINIMAL + "integrator: {dt: 20}\n",
    "topic": MINIMAL + "torque_inputs: [{topic: 9torque}]\n",
    "bigint": "body: {principal_moments: [1, 2, " + "9" * 400 + "]}\n",
    "yaml": "body: [1, 2\n  ]]: x\n",
}


def assert_one_line_error(completed: subprocess.CompletedProcess, expected: str) -> None:
    assert completed.returncode == 2, completed
    assert completed.stdout == "", completed.stdout
    lines = [line for line in completed.stderr.splitlines() if "[rcl]" not in line]
    assert len(lines) == 1, completed.stderr
    assert len(lines[0]) <= limits.MAX_ERROR_CHARS and expected in lines[0], lines[0]


@pytest.mark.parametrize("name", sorted(BAD_SCENES))
def test_node_start_up_errors_are_one_line_on_stderr(tmp_path, name):
    scene = tmp_path / f"{name}.yaml"
    scene.write_text(BAD_SCENES[name])
    completed = subprocess.run(
        [str(BIN / "rigid_rot_sim_node"), "--ros-args", "-p", f"scene:={scene}"],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    assert_one_line_error(completed, f"rigid_rot_sim: error: {name}.yaml: ")


def test_parameter_outside_its_range_and_bad_ros_arguments_are_one_line(tmp_path):
    scene = REPO / "config" / "scenes" / "free_tumble.yaml"
    completed = subprocess.run(
        [str(BIN / "rigid-rot"), "run", str(scene), "--ros-args", "-p", "real_time_factor:=5000.0"],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    assert_one_line_error(completed, "real_time_factor")
    completed = subprocess.run(
        [str(BIN / "rigid_rot_sim_node"), "--ros-args", "-p", "bad"],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    assert_one_line_error(completed, "bad ROS arguments")


def test_inertia_overflow_and_bad_body_files_are_one_line(tmp_path, capsys):
    # before: success with an infinite total mass
    code = cli.main(["inertia", "--mass", "1e308", "0", "0", "0", "--mass", "1e308", "1", "0", "0"])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and "total_mass overflows" in err and err.count("\n") == 1
    body = tmp_path / "bomb.yaml"
    body.write_text("point_masses:\n  masses: [1]\n  positions: [[0, 0, 0]]\n" + BOMB)
    code = cli.main(["inertia", str(body)])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and "YAML aliases" in err and err.count("\n") == 1
    assert len(err) <= limits.MAX_ERROR_CHARS + 1
    huge = tmp_path / "huge.yaml"
    huge.write_text("point_masses:\n  masses: [" + ", ".join(["1"] * 20_000) + "]\n  positions: []\n")
    code = cli.main(["inertia", str(huge)])
    out, err = capsys.readouterr()
    assert code == 2 and "more than 10000 items" in err and err.count("\n") == 1


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["mtb", "mtq_x"], "expected NAME=DIPOLE"),
        (["mtb", "mtq_x=nan"], "expected NAME=DIPOLE"),
        (["mtb", "a=1", "a=2"], "a rod is named twice"),
        (["wheels"], "give one motor torque per wheel"),
        (["wheels", "1", "--zero", "2"], "--zero N takes no torque values"),
    ],
)
def test_actuator_commands_refuse_bad_arguments_in_one_line(args, expected):
    completed = subprocess.run(
        [str(BIN / "rigid-rot"), *args], capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL
    )
    assert_one_line_error(completed, expected)
