"""Every subcommand that creates a ROS node takes --ros-args; its errors go to stderr.

Real processes (the installed ``rigid-rot``) on the session's private DDS domain.
"""

import os
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "recording"))
from test_resim import COMMANDS, record_like_the_node  # noqa: E402

RIGID_ROT = str(Path(sys.executable).with_name("rigid-rot"))


def rigid_rot(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([RIGID_ROT, *argv], capture_output=True, text=True, timeout=60, env=os.environ)


def test_torque_resolves_its_topic_in_the_ros_args_namespace_and_reports_no_subscriber_on_stderr():
    done = rigid_rot(
        "torque", "0", "0", "0.01", "--topic", "torque", "--wait", "0.3", "--ros-args", "-r", "__ns:=/nobody_here"
    )
    assert done.returncode == 1
    assert done.stdout == ""
    assert done.stderr.strip().splitlines() == [
        "rigid-rot torque: no subscriber on /nobody_here/torque after 0.3 s (is the node running?)"
    ]


def test_replay_takes_ros_args(tmp_path):
    bag = tmp_path / "commands.mcap"
    record_like_the_node(bag, "torque_driven", 400, 10, COMMANDS)
    done = rigid_rot("replay", str(bag), "--wait", "0.2", "--rate", "20", "--ros-args", "-r", "__node:=replayer_test")
    assert done.returncode == 0, done.stderr
    assert "replayed 3 messages" in done.stdout  # received at steps 0, 100, 300 (1 ms steps)
    # paced by the log times, which are sim times: 0.3 s of sim time at rate 20 takes at least 15 ms
    wall = float(done.stdout.split(" in ", 1)[1].split(" s:", 1)[0])
    assert wall >= 0.3 / 20


def test_inertia_ros_args_need_the_service():
    done = rigid_rot("inertia", "--mass", "1", "0", "0", "0", "--ros-args", "-r", "__ns:=/x")
    assert done.returncode == 2 and done.stdout == ""
    assert "--ros-args needs --service" in done.stderr


def test_run_passes_the_ros_args_as_given_and_its_options_as_overrides_that_win():
    from rigid_rot_sim.cli import build_parser
    from rigid_rot_sim.cli.run import node_arguments

    args = build_parser("run").parse_args(
        ["run", "free_tumble", "--record", "x.mcap", "--record-log-time", "wall", "--ros-args", "-p", "body_frame:=sat"]
    )
    argv, overrides = node_arguments(args)
    assert argv == ["rigid_rot_sim_node", "--ros-args", "-p", "body_frame:=sat"]
    values = {o.name: o.value for o in overrides}
    assert values["record_log_time"] == "wall" and values["record_path"] == os.path.abspath("x.mcap")
    assert values["scene"].endswith("free_tumble.yaml") and "duration" not in values  # only what was given
