"""In-process tests of the node's stepping services over DDS: ``~/step_with_torque`` against a
topic command followed by ``~/step`` (bit for bit), and the ``~/simulate_steps`` action.

The node and the client node share one executor (as in test_node.py); the e2e test
(test/e2e/test_simulate_steps_e2e.py) drives the action from another process.
"""

import math
import struct

import pytest
from geometry_msgs.msg import Vector3, WrenchStamped
from rclpy.action import ActionClient
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import Result, SimulatorFeatures
from simulation_interfaces.srv import GetSimulatorFeatures
from std_srvs.srv import SetBool
from test_node import Harness, context  # noqa: F401 (the fixture)

from rigid_rot_msgs.msg import RejectedCommand
from rigid_rot_msgs.srv import Step, StepWithTorque
from rigid_rot_sim.ros.qos import COMMAND_QOS, REJECTED_QOS
from rigid_rot_sim.run.observer import SimulationObserver


def _complete(h, response, start: int, steps: int):
    """The reply after ``steps`` steps from ``start``: a request that ran out of its wall budget
    (a loaded machine) says so and is finished with ~/step, as the service's reply advises."""
    while not response.success:
        assert "within the 0.25 s budget" in response.message, response.message
        rest = start + steps - h.node.run.sim.clock.k
        response = h.call(Step, "step", Step.Request(steps=rest))
    return response


class _Accepted(SimulationObserver):
    """The commands the simulator accepted (the node's own observer interface, as the recorder uses)."""

    def __init__(self) -> None:
        self.commands = []

    def command_accepted(self, step, command) -> None:
        self.commands.append(command)


def _state_bits(state) -> bytes:
    """Every float of a RigidBodyState and its stamp, as their exact bits."""
    fields = [state.orientation.x, state.orientation.y, state.orientation.z, state.orientation.w]
    for vector in (
        state.angular_velocity_body,
        state.angular_velocity_world,
        state.angular_momentum_body,
        state.angular_momentum_world,
        state.torque_body,
    ):
        fields += [vector.x, vector.y, vector.z]
    fields += [state.kinetic_energy, state.energy_drift, state.angular_momentum_drift]
    stamp = struct.pack("<iI", state.header.stamp.sec, state.header.stamp.nanosec)
    return struct.pack(f"<{len(fields)}d", *fields) + stamp


@pytest.fixture
def harness(context):  # noqa: F811
    made = []

    def make(scene, **params):
        made.append(Harness(context, scene, **params))
        return made[-1]

    yield make
    for h in made:
        if not getattr(h, "closed", False):
            h.close()


def _close(h) -> None:
    h.close()
    h.closed = True


@pytest.mark.parametrize("frame", ["base_link", "odom"])
def test_step_with_torque_equals_a_topic_command_then_step_bit_for_bit(harness, frame):
    torque = Vector3(x=0.0021, y=-0.0034, z=0.0113)
    spin = dict(real_time_factor=0.0, start_paused=True, integrator="rk4")
    topic = harness("torque_driven", **spin)
    # the same first state for both: a tumbling body (set through the simulator, as ~/set_state does)
    topic.node.run.sim.set_state([0.1, -0.2, 0.3, 0.9], [0.4, -1.1, 2.3])
    publisher = topic.client.create_publisher(WrenchStamped, "/rigid_rot_sim/torque", COMMAND_QOS)
    assert topic.spin_until(lambda: publisher.get_subscription_count() > 0)
    command = WrenchStamped()
    command.header.frame_id = frame
    command.wrench.torque = torque
    accepted = _Accepted()
    topic.node.run.sim.add_observer(accepted)
    publisher.publish(command)  # unstamped: acts from the sim time at receipt (paused: now)
    assert topic.spin_until(lambda: accepted.commands)
    assert accepted.commands[0].step == 0 and accepted.commands[0].source == "~/torque"
    by_topic = _complete(topic, topic.call(Step, "step", Step.Request(steps=300)), 0, 300)
    topic_steps = topic.node.run.sim.clock.k
    _close(topic)  # one node named rigid_rot_sim at a time

    atomic = harness("torque_driven", **spin)
    atomic.node.run.sim.set_state([0.1, -0.2, 0.3, 0.9], [0.4, -1.1, 2.3])
    response = atomic.call(
        StepWithTorque, "step_with_torque", StepWithTorque.Request(torque=torque, frame_id=frame, steps=300)
    )
    response = _complete(atomic, response, 0, 300)
    assert atomic.node.run.sim.clock.k == topic_steps == 300
    assert _state_bits(response.state) == _state_bits(by_topic.state)
    assert response.state.torque_body.z != 0.0
    # the torque acted over exactly those steps: the next step is torque-free
    after = atomic.call(Step, "step", Step.Request(steps=1))
    assert [after.state.torque_body.x, after.state.torque_body.y, after.state.torque_body.z] == [0.0, 0.0, 0.0]


def test_step_with_torque_refusals_apply_and_step_nothing(harness):
    h = harness("torque_driven", real_time_factor=0.0, integrator="rk4")
    rejected = []
    h.client.create_subscription(RejectedCommand, "/rigid_rot_sim/rejected", rejected.append, REJECTED_QOS)
    playing = h.call(StepWithTorque, "step_with_torque", StepWithTorque.Request(torque=Vector3(z=0.01), steps=5))
    assert not playing.success and "not paused" in playing.message
    assert h.call(SetBool, "pause", SetBool.Request(data=True)).success
    k = h.node.run.sim.clock.k
    for request, reason in [
        (StepWithTorque.Request(torque=Vector3(z=0.01), steps=0), "steps must be >= 1"),
        (StepWithTorque.Request(torque=Vector3(z=0.01), steps=10**6), "exceeds the limit"),
        (StepWithTorque.Request(torque=Vector3(z=0.01), frame_id="map", steps=5), "neither the body frame"),
        (StepWithTorque.Request(torque=Vector3(z=math.nan), steps=5), "non-finite torque.z"),
        (StepWithTorque.Request(torque=Vector3(z=5.0), steps=5), "exceeds max_torque"),
    ]:
        response = h.call(StepWithTorque, "step_with_torque", request)
        assert not response.success and reason in response.message, response.message
    sim = h.node.run.sim
    assert sim.clock.k == k and sim.snapshot().angular_velocity_body.tolist() == [0.0, 0.0, 0.0]
    assert h.spin_until(lambda: len(rejected) >= 3)  # the torque refusals are published with their reason
    assert {r.source for r in rejected} == {"/rigid_rot_sim/step_with_torque"}
    h.call(Step, "step", Step.Request(steps=5))
    assert h.node.run.sim.snapshot().angular_velocity_body.tolist() == [0.0, 0.0, 0.0]  # nothing left applied


def _send_goal(h, client, steps, feedback):
    assert client.wait_for_server(timeout_sec=10.0)
    future = client.send_goal_async(SimulateSteps.Goal(steps=steps), feedback_callback=feedback.append)
    h.executor.spin_until_future_complete(future, timeout_sec=10.0)
    return future.result()


def _result(h, goal_handle):
    future = goal_handle.get_result_async()
    h.executor.spin_until_future_complete(future, timeout_sec=60.0)
    assert future.done()
    return future.result()


def test_simulate_steps_action_feedback_at_a_bounded_rate_cancel_and_refusal(harness, monkeypatch):
    import time

    from rclpy.action.server import ServerGoalHandle

    from rigid_rot_sim.ros.simulate_steps import FEEDBACK_RATE

    published = []  # every feedback the server sends (DDS may drop older ones: keep-last depth 10)
    send = ServerGoalHandle.publish_feedback
    monkeypatch.setattr(
        ServerGoalHandle,
        "publish_feedback",
        lambda self, message: (
            published.append((message.completed_steps, message.remaining_steps, time.monotonic())),
            send(self, message),
        )[1],
    )
    h = harness("free_tumble", real_time_factor=0.0, start_paused=True)
    features = h.call(GetSimulatorFeatures, "get_simulator_features", GetSimulatorFeatures.Request()).features
    assert SimulatorFeatures.STEP_SIMULATION_ACTION in features.features
    client = ActionClient(h.client, SimulateSteps, "/rigid_rot_sim/simulate_steps")
    feedback = []
    steps = 20_000
    goal = _send_goal(h, client, steps, feedback)
    assert goal.accepted
    done = _result(h, goal)
    assert done.status == 4 and done.result.result.result == Result.RESULT_OK  # GoalStatus.STATUS_SUCCEEDED
    assert h.node.run.sim.clock.k == steps and h.node.run.sim.paused
    # feedback after complete steps, in order, the first after the first step and always the last;
    # at most FEEDBACK_RATE per second of wall time, not one per step
    assert [p[:2] for p in published[:1] + published[-1:]] == [(1, steps - 1), (steps, 0)]
    assert all(a[0] < b[0] and a[0] + a[1] == steps for a, b in zip(published, published[1:], strict=False))
    intervals = [b[2] - a[2] for a, b in zip(published[:-2], published[1:-1], strict=True)]
    assert all(gap >= 1.0 / FEEDBACK_RATE - 1e-3 for gap in intervals)  # the last one may come sooner
    assert len(published) < steps / 10
    # (what the client received of those depends on when its feedback reader matched: checked below)

    # cancel: a long goal, canceled once it has started; it stops before the next step
    feedback.clear()
    goal = _send_goal(h, client, 10**9, feedback)
    assert goal.accepted
    assert h.spin_until(lambda: len(feedback) >= 3, timeout=30.0)
    received = [(f.feedback.completed_steps, f.feedback.remaining_steps) for f in feedback]
    assert all(a[0] < b[0] and a[0] + a[1] == 10**9 for a, b in zip(received, received[1:], strict=False))
    cancel = goal.cancel_goal_async()
    h.executor.spin_until_future_complete(cancel, timeout_sec=10.0)
    assert len(cancel.result().goals_canceling) == 1
    canceled = _result(h, goal)
    assert canceled.status == 5 and "canceled after" in canceled.result.result.error_message  # STATUS_CANCELED
    stopped_at = h.node.run.sim.clock.k
    h.spin_until(lambda: False, timeout=0.2)
    assert h.node.run.sim.clock.k == stopped_at < 10**9 and h.node.run.sim.paused

    # refused while playing: aborted with RESULT_OPERATION_FAILED, as the .action says
    assert h.call(SetBool, "pause", SetBool.Request(data=False)).success
    goal = _send_goal(h, client, 5, feedback)
    refused = _result(h, goal)
    assert refused.status == 6 and refused.result.result.result == Result.RESULT_OPERATION_FAILED  # STATUS_ABORTED
    assert "paused" in refused.result.result.error_message
    client.destroy()


def test_a_run_driven_by_step_with_torque_resimulates_bit_exact(harness, tmp_path):
    from rigid_rot_sim.recording.resim import resimulate

    bag = tmp_path / "step_with_torque.mcap"
    h = harness("torque_driven", real_time_factor=0.0, start_paused=True, integrator="rk4", record_path=str(bag))
    h.node.run.sim.set_state([0.1, -0.2, 0.3, 0.9], [0.4, -1.1, 2.3])
    start = 0
    for torque, frame, steps in [
        (Vector3(z=0.004), "base_link", 200),
        (Vector3(x=-0.002, y=0.003), "odom", 150),
        (Vector3(y=0.001), "", 77),
    ]:
        request = StepWithTorque.Request(torque=torque, frame_id=frame, steps=steps)
        _complete(h, h.call(StepWithTorque, "step_with_torque", request), start, steps)
        start += steps
    assert h.node.run.sim.clock.k == 427
    _close(h)  # the recording is complete
    report = resimulate(bag)
    assert report.identical and "BIT-EXACT" in report.verdict, report.format()
