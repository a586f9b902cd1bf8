"""No silent failure on the command path (issue 29): a refused ``rigid-rot torque`` exits 2 with the
node's reason; a publisher of another type on a command topic is named in the node's log.

The node runs in its own process (conftest's ``launch_node``); the CLI in another; the wrong-type
publisher in this test process. Every wait is on a condition with a timeout.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

from e2e_helpers import WAIT  # beside this file

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"
TORQUE_TOPIC = "/rigid_rot_sim/torque"
CLI = str(Path(sys.executable).with_name("rigid-rot"))


def torque_driven(launch_node, name: str):
    """torque_driven (commands in the header's frame, max_torque 1 N*m), rk4, once its state flows."""
    return launch_node(
        "--ros-args", "-p", f"scene:={SCENES / 'torque_driven.yaml'}", "-p", "integrator:=rk4", name=name
    )


def rigid_rot(ros_env, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([CLI, *args], env=ros_env, capture_output=True, text=True, timeout=120)


def one_error_line(done: subprocess.CompletedProcess) -> str:
    """The refusal: exit 2, one line on stderr, nothing on stdout."""
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and done.stdout == "", done.stdout + done.stderr
    return lines[0]


def test_rigid_rot_torque_exits_2_with_the_nodes_reason_when_its_commands_are_refused(launch_node, ros_env):
    node = torque_driven(launch_node, "refusing")
    # each refused command: the CLI listens for the verdict until it comes (--confirm is that wait's bound, and
    # the default 1 s after the acknowledgement is shorter than a loaded machine's path through the node)
    refused = ("--wait", "60", "--confirm", str(WAIT))
    # a frame the scene does not name: the node refuses it on ~/rejected (before: "1 command(s)", exit 0)
    line = one_error_line(rigid_rot(ros_env, "torque", "0", "0", "0.004", "--frame", "body", *refused))
    assert line.startswith(f"rigid-rot torque: error: /rigid_rot_sim rejected the command on {TORQUE_TOPIC} (1 of 1")
    assert "'body'" in line and "base_link" in line, line  # the node's reason names the frame and the known ones
    # above commands.max_torque (1 N*m)
    line = one_error_line(rigid_rot(ros_env, "torque", "0", "0", "5", *refused))
    assert "max_torque" in line, line
    # repeated: it stops at the first refusal, long before the 100 commands of 5 s at 20 Hz
    line = one_error_line(rigid_rot(ros_env, "torque", "0", "0", "5", "--duration", "5", *refused))
    sent = int(line.split(" refused)")[0].split(" of ")[-1])
    assert 1 <= sent < 100, line
    # an accepted command still succeeds, with the count it sent
    done = rigid_rot(ros_env, "torque", "0", "0", "0.004", "--frame", "base_link", "--wait", "60")
    assert done.returncode == 0 and "1 command(s) [0.0, 0.0, 0.004]" in done.stdout, done.stdout + done.stderr
    assert "not confirmed" not in done.stdout
    node.check_alive()


def test_a_publisher_of_another_type_on_a_command_topic_is_named_in_the_log(launch_node, ros_node):
    from geometry_msgs.msg import Vector3Stamped

    node = torque_driven(launch_node, "typed")
    publisher = ros_node.create_publisher(Vector3Stamped, TORQUE_TOPIC, 10)
    expected = (
        f"{TORQUE_TOPIC}: a publisher of geometry_msgs/msg/Vector3Stamped (node {ros_node.get_fully_qualified_name()}) "
        "is on this command topic, which takes geometry_msgs/msg/WrenchStamped"
    )
    deadline = time.monotonic() + WAIT
    while expected not in node.log():
        node.check_alive()
        assert time.monotonic() < deadline, f"no warning naming the publisher\n{node.log()}"
        time.sleep(0.1)
    assert node.log().count(expected) == 1  # named once while it stays
    ros_node.destroy_publisher(publisher)
