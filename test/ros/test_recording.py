"""The node's recording, an observer of the simulator: every kind of event replays bit for bit in resim."""

from pathlib import Path

import pytest
import yaml

pytest.importorskip("rigid_rot_msgs.msg")
from rigid_rot_msgs.msg import RigidBodyState
from rigid_rot_sim import conversions
from rigid_rot_sim.recording.resim import resimulate
from rigid_rot_sim.recording.session import RunRecorder
from rigid_rot_sim.ros.recording import NodeRecording
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import load_scene

SCENE = Path(__file__).resolve().parents[2] / "config" / "scenes" / "torque_driven.yaml"


def test_every_event_kind_is_recorded_and_replayed_bit_for_bit(tmp_path):
    bag = tmp_path / "events.mcap"
    sim = Simulator(load_scene(SCENE), method="rk4")
    run = RunRecorder(
        bag,
        scene_text=SCENE.read_text(),
        scene_file=str(SCENE),
        parameters={},
        integrator={"method": sim.stepper.method, "dt": sim.clock.dt, "options": sim.stepper.options},
        events_topic="/rigid_rot_sim/sim_events",
    )
    run.add_topic("/rigid_rot_sim/state", RigidBodyState, role="state")
    sim.add_observer(NodeRecording(run, sim, None))

    def publish():
        run.record("/rigid_rot_sim/state", conversions.snapshot_to_state(sim.snapshot(), "odom", "base_link"))

    script = [
        (50, lambda: sim.receive_torque("~/torque", (0.0, 0.0, 0.003), "base_link", 0.0)),
        (120, lambda: sim.apply_torque((0.001, 0.0, 0.0), "odom", 0.05)),
        (200, lambda: sim.set_integrator(dt=0.0005)),  # a dt change mid-run
        (300, lambda: sim.set_state((0.1, 0.0, 0.0, 1.0), (0.2, -0.1, 0.3))),
        (400, lambda: sim.submit_torque("~/torque", (0.0, 0.002, 0.0), "body", sim.clock.t + 0.01)),
        (500, lambda: sim.set_integrator(method="lie_rk4")),  # an integrator change mid-run
        (600, sim.reset),
        (650, lambda: sim.receive_torque("~/torque", (0.001, 0.001, 0.0), "odom", 0.0)),
    ]
    k = 0
    for at, action in script:
        while k < at:
            sim.advance(10)
            k += 10
            publish()
        action()
        publish()
    for _ in range(20):
        sim.advance(10)
        publish()
    run.close()

    report = resimulate(bag)
    assert report.events == len(script)
    assert report.identical, report.format()
    assert "BIT-EXACT" in report.verdict


def test_rejected_commands_record_no_event(tmp_path):
    from rigid_rot_sim.recording.reader import BagReader
    from rigid_rot_sim.run.simulator import CommandRejected

    bag = tmp_path / "rejected.mcap"
    sim = Simulator(load_scene(SCENE), method="rk4")
    with RunRecorder(
        bag,
        scene_text=SCENE.read_text(),
        scene_file=str(SCENE),
        parameters={},
        integrator={"method": sim.stepper.method, "dt": sim.clock.dt},
        events_topic="/e/sim_events",
    ) as run:
        sim.add_observer(NodeRecording(run, sim, None))
        with pytest.raises(CommandRejected):
            sim.receive_torque("~/torque", (float("inf"), 0.0, 0.0), "base_link", 0.0)
    assert BagReader(bag).counts().get("/e/sim_events", 0) == 0


def test_tf_and_the_latched_tf_static_are_recorded_as_published(tmp_path):
    from rigid_rot_sim.recording.reader import BagReader

    bag = tmp_path / "tf.mcap"
    _record_half_a_second(bag)
    reader = BagReader(bag)
    assert reader.complete
    assert reader.counts()["/tf_static"] == 1 and reader.counts()["/tf"] == 26  # 50 Hz over 0.5 s, both ends
    assert reader.topics["/tf_static"].type_name == "tf2_msgs/msg/TFMessage"
    (offered,) = yaml.safe_load(reader.topics["/tf_static"].channel_metadata["offered_qos_profiles"])
    assert offered["durability"] == 1 and offered["depth"] == 1  # transient local, as published
    ((_, static),) = reader.decoded(["/tf_static"])
    assert static.transforms[0].child_frame_id == "base_link_principal"


def _record_half_a_second(bag: Path, check_node=None) -> None:
    """An in-process node on from_point_masses, recorded to ``bag`` for 0.5 s of sim time as fast as it goes."""
    import rclpy

    from rigid_rot_sim.ros.node import RigidRotSimNode

    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = RigidRotSimNode(
            context=context,
            parameter_overrides=[
                rclpy.parameter.Parameter("scene", value="from_point_masses"),
                rclpy.parameter.Parameter("record_path", value=str(bag)),
                rclpy.parameter.Parameter("real_time_factor", value=0.0),
                rclpy.parameter.Parameter("duration", value=0.5),
            ],
        )
        if check_node is not None:
            check_node(node)
        while not node.finished:
            node.run.tick()
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
