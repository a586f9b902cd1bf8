"""``rigid-rot wheels`` drives a running node's wheels; refused, it exits 2 with the node's reason (one line).

The node runs in its own process (conftest's ``launch_node``), the CLI in another. Every wait is on a condition
with a timeout.
"""

from __future__ import annotations

import subprocess
import sys
import time
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


ROD_TOPIC = "/rigid_rot_sim/magnetorquer_command"


def test_rigid_rot_mtb_commands_the_rods_by_name_or_exits_2_with_the_nodes_reason(launch_node, ros_env):
    scene = SCENES / "cubesat_detumble.yaml"
    node = launch_node("--ros-args", "-p", f"scene:={scene}", "-p", "real_time_factor:=1.0", name="rods")
    refused = rigid_rot(ros_env, "mtb", "mtq_w=0.1", "--wait", "60", "--confirm", "5")
    assert refused.returncode == 2 and refused.stdout == "", refused.stdout + refused.stderr + node.log()
    lines = refused.stderr.strip().splitlines()
    assert len(lines) == 1, refused.stderr
    assert lines[0].startswith(f"rigid-rot mtb: error: /rigid_rot_sim rejected the command on {ROD_TOPIC}: ")
    assert "unknown joint 'mtq_w' (the rods: mtq_x, mtq_y, mtq_z)" in lines[0], lines[0]
    done = rigid_rot(ros_env, "mtb", "mtq_x=0.5", "mtq_z=-0.1", "--wait", "60", "--confirm", "2")
    assert done.returncode == 0, done.stdout + done.stderr
    assert f"rod dipoles mtq_x=0.5, mtq_z=-0.1 A*m^2 on {ROD_TOPIC}" in done.stdout
    assert "not confirmed" not in done.stdout
    # 0.5 A*m^2 is beyond mtq_x's 0.2: clamped, and said once
    deadline = time.monotonic() + 30.0
    while "rod 'mtq_x' dipole clamped to its max_dipole" not in node.log():
        node.check_alive()
        assert time.monotonic() < deadline, node.log()
        time.sleep(0.1)
    node.check_alive()
