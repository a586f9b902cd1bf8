"""What a new ROS 2 user meets first (issue 40), from outside: real processes on the session's domain."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
RIGID_ROT = str(Path(sys.executable).with_name("rigid-rot"))
EXAMPLE_PARAMS = str(REPO / "config" / "params" / "example.yaml")


def rigid_rot(*argv: str, timeout: float = 60.0) -> subprocess.CompletedProcess:
    return subprocess.run([RIGID_ROT, *argv], capture_output=True, text=True, timeout=timeout, env=os.environ)


def test_run_options_win_over_a_params_file(tmp_path):
    """The shipped params file sets scene torque_driven and duration 0 (unbounded): the command line's wins."""
    bag = tmp_path / "run.mcap"
    done = rigid_rot(
        "run", "free_tumble", "--duration", "0.5", "--record", str(bag), "--ros-args", "--params-file", EXAMPLE_PARAMS
    )
    assert done.returncode == 0, done.stderr
    assert "scene 'free_tumble'" in done.stderr and "duration 0.5 s" in done.stderr
    assert "duration reached: t = 0.5 s" in done.stderr
    assert "SCENE, --record, --duration override" in done.stderr  # said, not silent
    from rigid_rot_sim.recording.reader import BagReader

    metadata = BagReader(bag).metadata
    assert Path(metadata["scene"]["file"]).stem == "free_tumble", metadata["scene"]


def test_run_option_and_the_same_p_rule_are_refused_naming_both():
    done = rigid_rot("run", "free_tumble", "--duration", "0.5", "--ros-args", "-p", "duration:=3.0")
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.strip().splitlines() == [
        "rigid-rot run: error: --duration 0.5 and --ros-args -p duration:=3.0 both set the duration parameter: give one"
    ]
