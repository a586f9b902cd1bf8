"""What a new ROS 2 user meets first (issue 40), from outside: real processes on the session's domain."""

from __future__ import annotations

import os
import subprocess
import sys
import time
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


def _wait_for_log(process, text: str, timeout: float = 60.0) -> str:
    """The process's log once it holds ``text`` (AssertionError with the log after ``timeout`` s)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        process.check_alive()
        log = process.log()
        if text in log:
            return log
        time.sleep(0.1)  # the log is a file another process writes: nothing to wait on but its content
    raise AssertionError(f"no {text!r} in the log within {timeout} s:\n{process.log()}")


def test_two_nodes_on_clock_each_name_the_other(launch_node):
    """Two bodies in two namespaces, both with /clock: each warns, naming the other's node."""
    nodes = {
        ns: launch_node("--ros-args", "-r", f"__ns:=/{ns}", "-p", "scene:=free_tumble", name=ns) for ns in ("a", "b")
    }
    for ns, other in (("a", "b"), ("b", "a")):
        log = _wait_for_log(nodes[ns], f"/clock: node /{other}/rigid_rot_sim publishes it too")
        assert "rates.clock:=0" in log
        assert f"/{ns}/rigid_rot_sim publishes" not in log  # its own publisher, on the graph all along: no word


def test_torque_is_done_once_the_node_answered_every_command_not_after_a_fixed_window(launch_node):
    """``--confirm 30`` is a bound, not a window: done as soon as the node accepted each command (issue 40)."""
    node = launch_node("--ros-args", "-p", "scene:=torque_driven", "-p", "integrator:=rk4", name="answering")
    _wait_for_log(node, "duration unbounded")
    start = time.monotonic()
    done = rigid_rot("torque", "0", "0", "0.004", "--duration", "0.2", "--confirm", "30", "--wait", "60", timeout=120)
    elapsed = time.monotonic() - start
    assert done.returncode == 0, done.stdout + done.stderr
    assert "then zero" in done.stdout and "answered" not in done.stdout and "not confirmed" not in done.stdout
    # before: a fixed --confirm window (30 s) after a 2 s wait for DDS acknowledgements; now the node's
    # ~/sim_events answers within a turn. 20 s leaves room for a loaded machine's start-up and discovery.
    assert elapsed < 20.0, f"{elapsed:.1f} s"
    node.check_alive()


def test_the_controller_says_why_the_node_refuses_its_commands(launch_node):
    """rigid-rot-controller watches the node's ~/rejected: a wrong frame_id is named, not a silent loop."""
    node = launch_node("--ros-args", "-p", "scene:=torque_driven", "-p", "integrator:=rk4", name="sim")
    controller = launch_node(
        "--ros-args", "-p", "frame_id:=not_a_frame", name="controller", module="rigid_rot_sim.ros.controller"
    )
    log = _wait_for_log(controller, "the node rejected this controller's command on")
    assert "not_a_frame" in log  # the node's reason names the frame
    node.check_alive()


def test_a_subnormal_real_time_factor_is_refused_in_one_line():
    """5e-324 passes the descriptor's range (0 to 1000) but would never reach a step: refused, exit 2."""
    done = rigid_rot("run", "free_tumble", "--realtime-factor", "5e-324")
    assert done.returncode == 2 and done.stdout == "", done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "real_time_factor must be 0 (as fast as possible) or from 1e-06" in lines[0], lines


def test_start_up_line_says_a_rate_above_the_step_rate_and_a_refused_apply_torque_is_logged_once(
    launch_node, collector
):
    from geometry_msgs.msg import Vector3

    from rigid_rot_msgs.srv import ApplyTorque

    node = launch_node(
        "--ros-args", "-p", "scene:=torque_driven", "-p", "dt:=0.001", "-p", "rates.state:=5000.0", name="rates"
    )
    log = _wait_for_log(node, "duration unbounded")
    assert "~/state 1000 Hz (every step; 5000 Hz asked)" in log  # what it publishes: one state per step
    request = ApplyTorque.Request(torque=Vector3(z=0.001), frame_id="no_such_frame")
    request.duration.sec = 1
    reply = collector.call(ApplyTorque, "apply_torque", request, process=node)
    assert not reply.success and "no_such_frame" in reply.message
    # the reply comes after the callback's logging: the refusal is in the log once, not twice
    lines = [line for line in node.log().splitlines() if "no_such_frame" in line]
    assert len(lines) == 1, lines
