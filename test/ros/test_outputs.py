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
