"""End to end over DDS: ``~/simulate_steps`` (simulation_interfaces/action/SimulateSteps) and
``~/step_with_torque``, driven from this process against the node in a subprocess.

The action: a goal is stepped with feedback, a long goal is canceled, a goal while playing is
aborted with RESULT_OPERATION_FAILED (as the .action says), a second goal while one runs is
rejected, and the feedback topic carries the upstream 1.5.1 type hash. The node keeps
publishing ~/state while it steps (outputs are due as at any other step).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from test_node_e2e import SCENES, stamp
from test_vendored_interfaces import UPSTREAM_1_5_1_ACTION

ACTION = "/rigid_rot_sim/simulate_steps"
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6  # action_msgs/msg/GoalStatus


@pytest.fixture
def sim_node(launch_node):
    return launch_node(
        "--ros-args",
        "-p",
        f"scene:={SCENES / 'torque_driven.yaml'}",
        "-p",
        "real_time_factor:=0.0",
        "-p",
        "start_paused:=true",
        "-p",
        "integrator:=rk4",
        name="simulate_steps",
    )


def _reply(collector, request, process, what: str, resend: float = 5.0, timeout: float = 60.0):
    """The first reply to ``request()`` (a function returning a future), sent again every ``resend`` s.

    A fresh server's Fast DDS drops its reply when it has not yet matched the client's reply
    reader (ros2/rmw_fastrtps#704, see conftest.Collector.call); an action has three such
    services (send_goal, cancel_goal, get_result). Only idempotent requests are resent here.
    """
    futures = [request()]
    deadline, again = time.monotonic() + timeout, time.monotonic() + resend
    while not any(f.done() for f in futures):
        if time.monotonic() > deadline:
            raise AssertionError(f"no reply for {what} within {timeout} s\n{process.log()}")
        if time.monotonic() > again:
            futures.append(request())
            again = time.monotonic() + resend
        process.check_alive()
        collector.executor.spin_once(timeout_sec=0.05)
    return next(f for f in futures if f.done()).result()


def test_simulate_steps_goal_feedback_cancel_and_refusals(sim_node, collector):
    from rclpy.action import ActionClient
    from simulation_interfaces.action import SimulateSteps
    from simulation_interfaces.msg import Result, SimulationState
    from simulation_interfaces.srv import GetSimulationState, SetSimulationState

    from rigid_rot_msgs.msg import RigidBodyState
    from rigid_rot_sim.ros.qos import STATE_QOS

    states = collector.subscribe(RigidBodyState, "/rigid_rot_sim/state", STATE_QOS)
    client = ActionClient(collector.node, SimulateSteps, ACTION)
    collector.spin_until(lambda: client.server_is_ready(), 60.0, sim_node, "the action server")
    feedback = []

    def send(steps: int):
        """A goal's handle. Sent once: a lost reply is waited for, not resent (a goal is not idempotent)."""
        return _reply(
            collector,
            lambda: client.send_goal_async(SimulateSteps.Goal(steps=steps), feedback_callback=feedback.append),
            sim_node,
            f"a goal of {steps} steps",
            resend=math.inf,
        )

    def result(goal):
        return _reply(collector, goal.get_result_async, sim_node, "a goal's result")

    # warm-up: goals of one step until one is answered (each one answered or not is a step, or a
    # refusal while another runs), so that the reply paths of the three services are matched
    warm = _reply(collector, lambda: client.send_goal_async(SimulateSteps.Goal(steps=1)), sim_node, "a first goal")
    assert warm.accepted and result(warm).status == SUCCEEDED

    # a goal: all its steps, OK, still paused; ~/state went on at its rate (100 Hz: every 10 steps)
    count = len(states)
    goal = send(500)
    assert goal.accepted
    done = result(goal)
    assert done.status == SUCCEEDED and done.result.result.result == Result.RESULT_OK
    # 500 steps after the warm-up's 1 (or a few): the newest state (reliable, keep last) is at t >= 0.5 s
    collector.spin_until(
        lambda: states[count:] and stamp(states[-1]) >= 0.5 - 1e-9, 30.0, sim_node, "the state at the goal's end"
    )
    stamps = [stamp(msg) for msg in states[count:]]
    assert all(a < b for a, b in zip(stamps, stamps[1:], strict=False))
    assert all(abs(t * 100 - round(t * 100)) < 1e-6 for t in stamps)  # due every 10th step (100 Hz at dt 1 ms)
    state = collector.call(
        GetSimulationState, "get_simulation_state", GetSimulationState.Request(), process=sim_node, idempotent=True
    )
    assert state.state.state == SimulationState.STATE_PAUSED

    # the feedback topic is the standard type, with the upstream hash
    infos = collector.node.get_publishers_info_by_topic(f"{ACTION}/_action/feedback")  # (and earlier tests' nodes)
    assert infos and {str(info.topic_type_hash) for info in infos} == {
        UPSTREAM_1_5_1_ACTION["action/SimulateSteps_FeedbackMessage"]
    }

    # cancel a long goal once its feedback arrives; a second goal meanwhile is rejected
    feedback.clear()
    long_goal = send(10**9)
    assert long_goal.accepted
    collector.spin_until(lambda: len(feedback) >= 3, 30.0, sim_node, "feedback")
    received = [(f.feedback.completed_steps, f.feedback.remaining_steps) for f in feedback]
    assert all(a[0] < b[0] and a[0] + a[1] == 10**9 for a, b in zip(received, received[1:], strict=False))
    assert not send(5).accepted
    cancel = _reply(collector, long_goal.cancel_goal_async, sim_node, "the cancel")
    assert len(cancel.goals_canceling) == 1
    canceled = result(long_goal)
    assert canceled.status == CANCELED and "canceled after" in canceled.result.result.error_message

    # while playing: aborted with RESULT_OPERATION_FAILED and the reason
    set_state = SetSimulationState.Request(state=SimulationState(state=SimulationState.STATE_PLAYING))
    assert (
        collector.call(SetSimulationState, "set_simulation_state", set_state, process=sim_node).result.result
        == Result.RESULT_OK
    )
    refused = result(send(5))
    assert refused.status == ABORTED and refused.result.result.result == Result.RESULT_OPERATION_FAILED
    assert "paused" in refused.result.result.error_message
    client.destroy()


def test_step_with_torque_replies_with_the_state_after_its_steps(sim_node, collector):
    from geometry_msgs.msg import Vector3

    from rigid_rot_msgs.srv import Step, StepWithTorque

    # a refused request changes nothing, so it may be resent until answered (a fresh server: see _reply)
    refused = collector.call(
        StepWithTorque, "step_with_torque", StepWithTorque.Request(steps=0), process=sim_node, idempotent=True
    )
    assert not refused.success and "steps must be >= 1" in refused.message
    request = StepWithTorque.Request(torque=Vector3(z=0.004), frame_id="base_link", steps=100)
    reply = collector.call(StepWithTorque, "step_with_torque", request, process=sim_node)
    while not reply.success:  # out of the request's 0.25 s wall budget (a cold start, a loaded machine)
        assert "within the 0.25 s budget" in reply.message, reply.message
        rest = 100 - round(stamp(reply.state) / 0.001)
        reply = collector.call(Step, "step", Step.Request(steps=rest), process=sim_node)
    # from rest about the principal z axis (I_z = 0.04 kg m^2): omega_z = 0.004 * 0.1 / 0.04 exactly (rk4: linear)
    assert stamp(reply.state) == pytest.approx(0.1, abs=1e-12)
    assert reply.state.angular_velocity_body.z == pytest.approx(0.01, rel=1e-12)
    assert reply.state.torque_body.z == 0.004
