"""``rigid-rot wheels`` drives a running node's wheels; refused, it exits 2 with the node's reason (one line).

The node runs in its own process (conftest's ``launch_node``), the CLI in another. Every wait is on a condition
with a timeout.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"
WHEEL_TOPIC = "/rigid_rot_sim/wheel_torque"
CLI = str(Path(sys.executable).with_name("rigid-rot"))


def rigid_rot(ros_env, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([CLI, *args], env=ros_env, capture_output=True, text=True, timeout=120)


def test_rigid_rot_wheels_sets_the_torques_or_exits_2_with_the_nodes_reason(launch_node, ros_env):
    node = launch_node("--ros-args", "-p", f"scene:={SCENES / 'wheel_slew.yaml'}", name="wheels")
    # two values for the scene's three wheels: the node refuses it on ~/rejected, the CLI says why
    refused = rigid_rot(ros_env, "wheels", "0.001", "0.0", "--wait", "60", "--confirm", "5")
    assert refused.returncode == 2 and refused.stdout == "", refused.stdout + refused.stderr + node.log()
    lines = refused.stderr.strip().splitlines()
    assert len(lines) == 1, refused.stderr
    assert lines[0].startswith(f"rigid-rot wheels: error: /rigid_rot_sim rejected the command on {WHEEL_TOPIC}: ")
    assert "2 torque(s) for 3 wheel(s)" in lines[0], lines[0]
    done = rigid_rot(ros_env, "wheels", "0.001", "0.0", "-0.001", "--wait", "60")
    assert done.returncode == 0, done.stdout + done.stderr
    assert f"wheel torques [0.001, 0.0, -0.001] N*m on {WHEEL_TOPIC}" in done.stdout
    assert "not confirmed" not in done.stdout
    node.check_alive()
