"""End to end: live /tf and /tf_static as any DDS participant sees them.

The node runs a shipped scene given by name (found through the ament index); this process
checks the endpoints' type name and RIHS01 type hash (what `ros2 topic info -v /tf` shows on
a Jazzy system), their QoS (TransformBroadcaster / StaticTransformBroadcaster), the world ->
body transform against ~/orientation at the same stamps, bit for bit, and the latched
body -> principal-axes transform against the inertia core.
"""

import numpy as np
import pytest
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from rigid_rot_sim.core.inertia import mass_properties, principal_frame, principal_orientation
from rigid_rot_sim.scene.scene import load_scene
from rigid_rot_sim.share import resolve_scene

#: `ros2 topic info -v /tf` on ROS 2 Jazzy (tf2_msgs/msg/TFMessage).
TF_TYPE_HASH = "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"
WAIT = 60.0
STATE_BEST_EFFORT = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)


def stamp(msg) -> float:
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


def endpoints(collector, topic: str, process) -> list:
    """The publishers of ``topic`` in the graph (a node of an earlier test may linger briefly)."""
    collector.spin_until(
        lambda: collector.node.get_publishers_info_by_topic(topic), WAIT, process, f"a publisher on {topic}"
    )
    return collector.node.get_publishers_info_by_topic(topic)


def test_tf_and_tf_static_are_live_with_the_upstream_type_hash_and_match_the_orientation(launch_node, collector):
    from geometry_msgs.msg import QuaternionStamped
    from tf2_msgs.msg import TFMessage

    from rigid_rot_sim.ros.qos import STATE_QOS, TF_QOS, TF_STATIC_QOS

    node = launch_node("--ros-args", "-p", "scene:=from_point_masses", name="tf")
    scene = load_scene(resolve_scene("from_point_masses"))
    world, body, principal = scene.frames.world, scene.frames.body, scene.frames.principal

    for topic, durability in (("/tf", DurabilityPolicy.VOLATILE), ("/tf_static", DurabilityPolicy.TRANSIENT_LOCAL)):
        for info in endpoints(collector, topic, node):
            assert info.topic_type == "tf2_msgs/msg/TFMessage"
            assert str(info.topic_type_hash) == TF_TYPE_HASH, topic
            assert info.qos_profile.reliability == ReliabilityPolicy.RELIABLE
            assert info.qos_profile.durability == durability

    tf = collector.subscribe(TFMessage, "/tf", TF_QOS)
    orientation = collector.subscribe(QuaternionStamped, "/rigid_rot_sim/orientation", STATE_QOS)
    static = collector.subscribe(TFMessage, "/tf_static", TF_STATIC_QOS)  # latched: a late subscriber gets it

    def common_stamps() -> set[float]:
        return {stamp(t) for m in tf for t in m.transforms} & {stamp(q) for q in orientation}

    collector.spin_until(
        lambda: len(common_stamps()) >= 3 and static, WAIT, node, "/tf and ~/orientation at common stamps"
    )
    by_stamp = {stamp(q): q for q in orientation}
    compared = 0
    for message in tf:
        (transform,) = message.transforms  # the moving frame only: fixed ones are on /tf_static
        assert (transform.header.frame_id, transform.child_frame_id) == (world, body)
        t = transform.transform
        assert (t.translation.x, t.translation.y, t.translation.z) == (0.0, 0.0, 0.0)
        if stamp(transform) in by_stamp:
            q = by_stamp[stamp(transform)].quaternion
            assert (t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w) == (q.x, q.y, q.z, q.w)  # bit for bit
            compared += 1
    assert compared >= 3

    (latched,) = static[0].transforms
    assert (latched.header.frame_id, latched.child_frame_id) == (body, principal)
    props = mass_properties(scene.body.masses, scene.body.positions)
    shift = latched.transform.translation
    np.testing.assert_allclose([shift.x, shift.y, shift.z], props.center_of_mass, rtol=1e-12, atol=1e-15)
    r = latched.transform.rotation
    expected = principal_orientation(principal_frame(props.inertia_com)[1])
    np.testing.assert_allclose([r.x, r.y, r.z, r.w], expected, rtol=1e-12, atol=1e-12)
    assert np.linalg.norm(props.principal_axes - principal_frame(props.inertia_com)[1]) == pytest.approx(0.0, abs=1e-12)
    # the start-up line names what was built, with rates and QoS
    log = node.log()
    assert "/tf 50 Hz (reliable, depth 100)" in log and "~/state 100 Hz (reliable, depth 10)" in log
    assert f"/tf_static {body} -> {principal} (reliable, depth 1, transient local)" in log


def test_no_tf_static_when_the_body_axes_are_principal_and_qos_parameters_apply(launch_node, collector):
    from rigid_rot_msgs.msg import RigidBodyState

    node = launch_node(
        "--ros-args",
        "-p",
        "scene:=free_tumble",
        "-p",
        "qos.reliability:=best_effort",
        "-p",
        "qos.depth:=500",
        name="no_static",
    )
    collector.spin_until(
        lambda: any(
            i.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT
            for i in collector.node.get_publishers_info_by_topic("/rigid_rot_sim/state")
        ),
        WAIT,
        node,
        "a best-effort publisher of ~/state",
    )
    states = collector.subscribe(RigidBodyState, "/rigid_rot_sim/state", STATE_BEST_EFFORT)
    collector.spin_until(lambda: states, WAIT, node, "a best-effort state")
    assert all(i.qos_profile.reliability == ReliabilityPolicy.RELIABLE for i in endpoints(collector, "/tf", node))
    assert "~/state 50 Hz (best effort, depth 500)" in node.log()
    assert "left out" in node.log() and "/tf_static (the body axes are the principal axes" in node.log()
