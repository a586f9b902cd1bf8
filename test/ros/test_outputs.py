"""The node's one publishing path: what reaches the wire is already in the recording."""

import pytest
import rclpy

from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.ros.node import RigidRotSimNode

STATE_TOPIC = "/rigid_rot_sim/state"


def test_a_publish_interrupted_on_the_wire_is_already_recorded(tmp_path):
    # SIGTERM while the node starts raises KeyboardInterrupt wherever Python is: right after
    # the message went out, the file must hold it (a subscriber saw it)
    bag = tmp_path / "interrupted.mcap"
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = RigidRotSimNode(
            context=context,
            parameter_overrides=[
                rclpy.parameter.Parameter("scene", value="free_tumble"),
                rclpy.parameter.Parameter("record_path", value=str(bag)),
                rclpy.parameter.Parameter("real_time_factor", value=0.0),
            ],
        )
        state_publisher = node.run.outputs.publishers["state"]
        sent = []

        def publish_then_interrupt(data):
            sent.append(data)
            raise KeyboardInterrupt  # as the start-up signal handler does

        state_publisher.publish = publish_then_interrupt
        with pytest.raises(KeyboardInterrupt):
            node.run.driver.publish_due(force=True)
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    assert len(sent) == 1
    reader = BagReader(bag)
    assert reader.complete
    recorded = [message.data for message in reader.messages([STATE_TOPIC])]
    assert len(recorded) == 2  # the start-up state and the one interrupted on the wire
    assert recorded[-1] == sent[0]  # the very bytes that went out


def test_the_refilled_messages_carry_the_bytes_of_fresh_ones():
    # ~/state, ~/angular_velocity and ~/angular_momentum reuse one message each (refilled at each
    # publish): what goes out must be, byte for byte, what a message built anew would carry
    from rclpy.serialization import serialize_message

    from rigid_rot_sim.ros.outputs import OUTPUTS, REFILLED

    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = RigidRotSimNode(
            context=context,
            parameter_overrides=[
                rclpy.parameter.Parameter("scene", value="torque_driven"),
                rclpy.parameter.Parameter("real_time_factor", value=0.0),
            ],
        )
        outputs, sim = node.run.outputs, node.run.sim
        assert set(REFILLED) <= set(outputs.refilled)
        sent: dict[str, list[bytes]] = {name: [] for name in REFILLED}
        for name in REFILLED:
            outputs.publishers[name].publish = lambda msg, name=name: sent[name].append(serialize_message(msg))
        expected: dict[str, list[bytes]] = {name: [] for name in REFILLED}
        sim.submit_torque("~/torque", [0.001, -0.002, 0.003], frame="body", effective_time=0.0)
        for steps in (0, 7, 300):
            if steps:
                sim.advance(steps)
            snapshot = sim.snapshot()
            outputs.outputs_due(sim.clock.k, snapshot, list(REFILLED))
            for name in REFILLED:
                expected[name].append(serialize_message(OUTPUTS[name][1](snapshot, outputs)))
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    for name in REFILLED:
        assert sent[name] == expected[name], name
        assert len(set(sent[name])) == 3, f"{name}: the three states differ, so must their messages"
