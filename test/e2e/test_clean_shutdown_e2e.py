"""End to end (issue 27 / 29): a node run and the controller end with nothing on stderr but their own lines.

The old two-thread executor printed ``The following exception was never retrieved: cannot use
Destroyable because destruction was requested`` at the end of every run (a task on a worker thread
triggered the executor's guard condition after ``executor.shutdown()`` destroyed it;
docs/architecture.md, "The node loop"). Here every line a process writes to stderr must be one of its
own log lines (``[LEVEL] [stamp] [name]: ...``): no traceback, no rclpy task noise. Checked for a run
that reaches its duration, for a run stopped by SIGINT while commands come in, and for
``rigid-rot-controller`` stopped by SIGINT while it answers states.
"""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time

LOG_LINE = re.compile(r"^\[(DEBUG|INFO|WARN|ERROR|FATAL)\] \[\d+\.\d+\] \[[\w./]+\]: ")
TIMEOUT = 60.0


def _start(module: str, *ros_args: str, env) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", module, "--ros-args", *ros_args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
        env=env,
    )


def _finish(process: subprocess.Popen, interrupt: bool) -> str:
    """Its stderr after it exited with code 0 (SIGINT first with ``interrupt``)."""
    if interrupt:
        process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=TIMEOUT)
    assert process.returncode == 0, err
    return err


def _only_own_lines(err: str, name: str) -> None:
    lines = err.splitlines()
    assert lines, "no log line at all"
    strays = [line for line in lines if not LOG_LINE.match(line)]
    assert not strays, f"{name} wrote lines of others to stderr: {strays}"
    assert "never retrieved" not in err and "Traceback" not in err


def _wait_for(condition, process: subprocess.Popen, what: str) -> None:
    deadline = time.monotonic() + TIMEOUT
    while not condition():
        assert process.poll() is None, f"exited while waiting for {what}"
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.05)


def test_a_run_to_its_duration_ends_clean(ros_env):
    node = _start("rigid_rot_sim.ros.node", "-p", "scene:=torque_driven", "-p", "duration:=1.0", env=ros_env)
    _only_own_lines(_finish(node, interrupt=False), "the node")


def test_an_interrupted_run_and_the_controller_end_clean(ros_env, ros_node):
    from rigid_rot_msgs.msg import RigidBodyState

    states: list[object] = []
    ros_node.create_subscription(RigidBodyState, "/rigid_rot_sim/state", states.append, 10)
    node = _start("rigid_rot_sim.ros.node", "-p", "scene:=torque_driven", env=ros_env)
    controller = _start(
        "rigid_rot_sim.ros.controller", "-p", "target:=[0.0, 0.0, 0.5, 0.8660254037844386]", env=ros_env
    )
    from rclpy.executors import SingleThreadedExecutor

    executor = SingleThreadedExecutor(context=ros_node.context)
    executor.add_node(ros_node)
    try:

        def answered() -> bool:  # the controller's commands reach the node: its state carries a torque
            executor.spin_once(timeout_sec=0.05)
            return any(s.torque_body.z != 0.0 for s in states)  # type: ignore[attr-defined]

        _wait_for(answered, node, "the closed loop")
        err_node = _finish(node, interrupt=True)  # mid-loop: commands arriving, states going out
        err_controller = _finish(controller, interrupt=True)
    finally:
        executor.remove_node(ros_node)
        for process in (node, controller):
            if process.poll() is None:
                process.kill()
                process.wait()
    _only_own_lines(err_node, "the node")
    _only_own_lines(err_controller, "the controller")
