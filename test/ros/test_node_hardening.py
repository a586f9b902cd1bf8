"""In-process tests of the node's limits and failure behaviour (issue 9): each reproduces a
reported failure first (the comment says what happened before) and asserts what holds now."""

import math
import time

import pytest
import rclpy
import test_node
from builtin_interfaces.msg import Duration
from geometry_msgs.msg import Point, Vector3, WrenchStamped
from rclpy.clock_type import ClockType
from rclpy.parameter import Parameter
from std_srvs.srv import SetBool, Trigger
from test_node import SCENES

from rigid_rot_msgs.msg import RejectedCommand, RigidBodyState
from rigid_rot_msgs.srv import ApplyTorque, ComputeInertia, SetState, Step
from rigid_rot_sim.core import limits
from rigid_rot_sim.ros.node import RigidRotSimNode
from rigid_rot_sim.ros.qos import COMMAND_QOS, REJECTED_QOS, STATE_QOS

# test_node's fixtures, used here by name
context = test_node.context
harness = test_node.harness

STATE_FIELDS = (
    "angular_velocity_body",
    "angular_velocity_world",
    "angular_momentum_body",
    "angular_momentum_world",
    "torque_body",
)


def finite_state(msg: RigidBodyState) -> bool:
    values = [msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w]
    for name in STATE_FIELDS:
        vector = getattr(msg, name)
        values += [vector.x, vector.y, vector.z]
    values += [msg.kinetic_energy, msg.potential_energy, msg.energy_drift, msg.angular_momentum_drift]
    return all(math.isfinite(v) for v in values)


def test_reset_after_a_failure_brings_the_run_back(harness):
    h = harness("torque_driven", real_time_factor=0.0, integrator="rk4", **{"commands.max_torque": 0.0})
    # before: 1e30 N*m overflowed, ~/reset answered success and the run stayed paused
    huge = ApplyTorque.Request(torque=Vector3(x=1e12), duration=Duration(sec=10))
    assert h.call(ApplyTorque, "apply_torque", huge).success
    assert h.spin_until(lambda: h.node.run.sim.failure is not None)
    assert h.node.run.sim.paused and "rotation limit" in h.node.run.sim.failure
    reply = h.call(Trigger, "reset", Trigger.Request())
    assert reply.success and "running" in reply.message, reply.message
    k = h.node.run.sim.clock.k
    assert h.spin_until(lambda: h.node.run.sim.clock.k > k + 100)
    # a pause asked for is kept by reset, and the reply says so
    assert h.call(SetBool, "pause", SetBool.Request(data=True)).success
    reply = h.call(Trigger, "reset", Trigger.Request())
    assert reply.success and "still paused" in reply.message and h.node.run.sim.paused


def test_compute_inertia_results_are_finite_or_refused_and_large_requests_are_refused(harness):
    h = harness("free_tumble", real_time_factor=1.0)
    states = []
    h.client.create_subscription(RigidBodyState, "/rigid_rot_sim/state", states.append, STATE_QOS)
    # before: success with an infinite mass, and NaN in inertia_origin
    overflow = ComputeInertia.Request(masses=[1e308, 1e308], positions=[Point(), Point(x=1.0)])
    reply = h.call(ComputeInertia, "compute_inertia", overflow)
    assert not reply.success and "total_mass overflows" in reply.message
    far = ComputeInertia.Request(masses=[1.0, 1.0], positions=[Point(), Point(x=1.0)], origin=Point(x=1e200, y=1e200))
    reply = h.call(ComputeInertia, "compute_inertia", far)
    assert not reply.success and "inertia_origin overflows" in reply.message
    # before: 1e6 masses took 8.7 s and stopped ~/state; beyond the limit now refused unconverted
    n = limits.MAX_POINT_MASSES + 1
    big = ComputeInertia.Request(masses=[1.0] * n, positions=[Point(x=float(i % 3)) for i in range(n)])
    start = time.monotonic()
    reply = h.call(ComputeInertia, "compute_inertia", big)
    assert not reply.success and f"more than the limit of {limits.MAX_POINT_MASSES}" in reply.message
    assert time.monotonic() - start < 10.0
    long_frame = ComputeInertia.Request(masses=[1.0], positions=[Point()], frame_id="f" * 100_000)
    reply = h.call(ComputeInertia, "compute_inertia", long_frame)
    assert not reply.success and "exceeds the limit of 256" in reply.message
    count = len(states)
    assert h.spin_until(lambda: len(states) > count)  # the state stream goes on


def test_huge_angular_velocity_is_refused_and_every_published_field_is_finite(harness):
    h = harness("torque_driven", real_time_factor=0.0, integrator="rk4")
    states = []
    h.client.create_subscription(RigidBodyState, "/rigid_rot_sim/state", states.append, STATE_QOS)
    request = SetState.Request(angular_velocity=Vector3(x=1e200))
    request.orientation.w = 1.0
    # before: accepted, then ~/state carried kinetic_energy = inf and energy_drift = nan
    reply = h.call(SetState, "set_state", request)
    assert not reply.success and "rad per step" in reply.message
    assert h.spin_until(lambda: len(states) > 20)
    assert all(finite_state(msg) for msg in states)


def test_step_requests_are_bounded_and_other_services_keep_answering(harness):
    h = harness("thin_rod", real_time_factor=1.0, integrator="taylor")
    assert h.call(SetBool, "pause", SetBool.Request(data=True)).success
    k = h.node.run.sim.clock.k
    # before: 1e9 steps never replied, every other service was dead and SIGTERM was ignored
    start = time.monotonic()
    reply = h.call(Step, "step", Step.Request(steps=1_000_000_000))
    assert not reply.success and f"exceeds the limit of {limits.MAX_STEPS_PER_REQUEST}" in reply.message
    assert h.node.run.sim.clock.k == k
    reply = h.call(Step, "step", Step.Request(steps=limits.MAX_STEPS_PER_REQUEST))
    elapsed = time.monotonic() - start
    done = h.node.run.sim.clock.k - k
    assert 0 < done <= limits.MAX_STEPS_PER_REQUEST
    if done < limits.MAX_STEPS_PER_REQUEST:  # stopped at the request's wall budget, and says so
        assert not reply.success and f"only {done} of" in reply.message
    else:
        assert reply.success
    assert elapsed < 10.0  # ~0.25 s of stepping plus DDS round trips on a loaded machine
    other = ComputeInertia.Request(masses=[1.0], positions=[Point()])
    assert h.call(ComputeInertia, "compute_inertia", other).success
    assert h.node.run.sim.paused and h.node.run.sim.clock.k == k + done  # no racing while paused


def test_use_sim_time_is_accepted_with_a_warning_and_the_timer_stays_steady(context, harness, capfd):
    h = harness("free_tumble", real_time_factor=1.0)
    assert h.node.run.loop.timer.clock.clock_type == ClockType.STEADY_TIME
    # a launch-wide use_sim_time:=true (Nav2 / Gazebo bringups) must not stop the node that is the clock
    result = h.node.set_parameters([Parameter("use_sim_time", value=True)])[0]
    assert result.successful
    assert h.node.get_parameter("use_sim_time").value is True
    k = h.node.run.sim.clock.k
    assert h.spin_until(lambda: h.node.run.sim.clock.k > k + 20)  # the steady-clock timer still paces the run
    node = RigidRotSimNode(
        context=context,
        parameter_overrides=[
            Parameter("scene", value=str(SCENES / "free_tumble.yaml")),
            Parameter("use_sim_time", value=True),
        ],
    )
    try:
        assert node.get_parameter("use_sim_time").value is True
        assert node.run.loop.timer.clock.clock_type == ClockType.STEADY_TIME
    finally:
        node.destroy_node()
    logged = capfd.readouterr().err
    assert logged.count("use_sim_time true accepted, but this node is the clock") == 2  # run time, start-up


def test_max_torque_and_long_frame_ids_are_rejected_on_the_rejected_topic(harness):
    h = harness("torque_driven", real_time_factor=0.0, integrator="rk4")
    assert h.node.get_parameter("commands.max_torque").value == 1.0  # from the shipped scene
    rejected = []
    h.client.create_subscription(RejectedCommand, "/rigid_rot_sim/rejected", rejected.append, REJECTED_QOS)
    publisher = h.client.create_publisher(WrenchStamped, "/rigid_rot_sim/torque", COMMAND_QOS)
    assert h.spin_until(lambda: publisher.get_subscription_count() > 0)

    def send(torque, frame_id="base_link"):
        msg = WrenchStamped()
        msg.header.frame_id = frame_id
        msg.wrench.torque = torque
        publisher.publish(msg)

    # before: 1e6 N*m slowed the run to 6 % of real time with nothing logged
    send(Vector3(x=1e6))
    assert h.spin_until(lambda: any("exceeds max_torque = 1 N*m" in m.reason for m in rejected))
    assert h.node.set_parameters([Parameter("commands.max_torque", value=1e7)])[0].successful
    assert h.node.run.sim.commands.max_torque == 1e7
    # before: a 1 MB frame_id was echoed twice into ~/rejected
    send(Vector3(z=0.001), frame_id="f" * 1_000_000)
    assert h.spin_until(lambda: any("exceeds the limit of 256" in m.reason for m in rejected))
    message = next(m for m in rejected if "exceeds the limit of 256" in m.reason)
    assert len(message.header.frame_id) < 400 and len(message.reason) < 200


def test_command_qos_depth_is_a_read_only_parameter(harness):
    h = harness("torque_driven", real_time_factor=0.0, **{"commands.qos_depth": 500})
    subscription = h.node.run.inputs.subscriptions[0]
    assert subscription.qos_profile.depth == 500
    assert not h.node.set_parameters([Parameter("commands.qos_depth", value=5)])[0].successful
    with pytest.raises(rclpy.exceptions.InvalidParameterValueException):
        harness("torque_driven", real_time_factor=0.0, **{"commands.qos_depth": 0})
