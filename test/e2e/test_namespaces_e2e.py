"""End to end: two simulated bodies side by side, the ROS way (composition by namespace).

Two nodes of the same name run on one domain with ``--ros-args -r __ns:=/sat1`` and
``/sat2``, each with its own scene frames: each has its own topics, services and /tf child
of the shared world frame, and a command or a service call addressed to one never reaches
the other.
"""

from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[2]
WAIT = 60.0


def stamp(msg) -> float:
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


def write_scene(directory: Path, body_frame: str) -> Path:
    scene = yaml.safe_load((REPO / "config" / "scenes" / "torque_driven.yaml").read_text())
    scene["name"] = body_frame
    scene["frames"] = {"world": "world", "body": body_frame}
    scene["integrator"] = {"method": "rk4", "dt": 0.001}
    scene["torque_inputs"][0]["hold"] = "hold"
    path = directory / f"{body_frame}.yaml"
    path.write_text(yaml.safe_dump(scene, sort_keys=False))
    return path


def test_two_namespaced_nodes_run_side_by_side_without_cross_talk(launch_node, collector, tmp_path):
    from geometry_msgs.msg import WrenchStamped
    from std_srvs.srv import SetBool
    from tf2_msgs.msg import TFMessage

    from rigid_rot_msgs.msg import RigidBodyState
    from rigid_rot_msgs.srv import Step
    from rigid_rot_sim.ros.qos import COMMAND_QOS, STATE_QOS, TF_QOS

    nodes = {
        # /clock comes from one simulator only; `rates.clock:=0` (an integer) also checks that
        # double parameters take integers on the command line
        "sat1": launch_node(
            "--ros-args", "-r", "__ns:=/sat1", "-p", f"scene:={write_scene(tmp_path, 'sat1_body')}", name="sat1"
        ),
        "sat2": launch_node(
            "--ros-args",
            "-r",
            "__ns:=/sat2",
            "-p",
            f"scene:={write_scene(tmp_path, 'sat2_body')}",
            "-p",
            "rates.clock:=0",
            name="sat2",
        ),
    }
    states = {ns: collector.subscribe(RigidBodyState, f"/{ns}/rigid_rot_sim/state", STATE_QOS) for ns in nodes}
    tf = collector.subscribe(TFMessage, "/tf", TF_QOS)
    publisher = collector.node.create_publisher(WrenchStamped, "/sat1/rigid_rot_sim/torque", COMMAND_QOS)
    collector.spin_until(
        lambda: all(states.values()) and publisher.get_subscription_count() > 0,
        WAIT,
        None,
        "states of both nodes and sat1's torque subscription",
    )
    for ns, process in nodes.items():  # each node subscribes to its own torque topic only (graph data: awaited)
        collector.spin_until(
            lambda ns=ns: collector.node.count_subscribers(f"/{ns}/rigid_rot_sim/torque") >= 1,
            WAIT,
            process,
            f"/{ns}/rigid_rot_sim/torque's subscriber",
        )
        assert collector.node.count_subscribers(f"/{ns}/rigid_rot_sim/torque") == 1
    collector.spin_until(  # node names reach the graph with the participants' data, a little after the endpoints
        lambda: (
            {("rigid_rot_sim", "/sat1"), ("rigid_rot_sim", "/sat2")}
            <= set(collector.node.get_node_names_and_namespaces())
        ),
        WAIT,
        None,
        "both nodes in the graph",
    )

    # each body is a child of the shared world frame on /tf, with its own attitude
    def tf_children() -> dict[str, set[float]]:
        children: dict[str, set[float]] = {}
        for message in tf:
            for transform in message.transforms:
                children.setdefault((transform.header.frame_id, transform.child_frame_id), set()).add(stamp(transform))
        return {child: stamps for (parent, child), stamps in children.items() if parent == "world"}

    def tf_matches_state(ns: str) -> bool:
        state_stamps = {stamp(m) for m in states[ns]}
        return bool(tf_children().get(f"{ns}_body", set()) & state_stamps)

    collector.spin_until(
        lambda: tf_matches_state("sat1") and tf_matches_state("sat2"),
        WAIT,
        None,
        "a /tf transform of each body at a stamp of its own ~/state",
    )
    assert {"sat1_body", "sat2_body"} <= set(tf_children())
    for ns in nodes:
        by_stamp = {stamp(m): m.orientation for m in states[ns]}
        for message in tf:
            for transform in message.transforms:
                if transform.child_frame_id == f"{ns}_body" and stamp(transform) in by_stamp:
                    q, r = by_stamp[stamp(transform)], transform.transform.rotation
                    assert (r.x, r.y, r.z, r.w) == (q.x, q.y, q.z, q.w)

    # a torque command to sat1 acts on sat1 only
    command = WrenchStamped()
    command.header.frame_id = "sat1_body"
    command.wrench.torque.z = 0.004
    publisher.publish(command)
    collector.spin_until(lambda: states["sat1"][-1].angular_velocity_body.z > 0.0, WAIT, nodes["sat1"], "sat1 to turn")
    later = stamp(states["sat2"][-1]) + 1.0
    collector.spin_until(lambda: stamp(states["sat2"][-1]) >= later, WAIT, nodes["sat2"], "1 s more of sat2")
    assert all(m.angular_velocity_body.z == 0.0 and m.angular_velocity_body.x == 0.0 for m in states["sat2"])
    assert all(m.header.frame_id == "world" and m.child_frame_id == "sat2_body" for m in states["sat2"])
    assert all(m.child_frame_id == "sat1_body" for m in states["sat1"])

    # services are per node: pausing sat1 leaves sat2 running
    paused = collector.call(
        SetBool, "/sat1/rigid_rot_sim/pause", SetBool.Request(data=True), process=nodes["sat1"], idempotent=True
    )
    assert paused.success, paused.message
    assert collector.call(Step, "/sat1/rigid_rot_sim/step", Step.Request(steps=1), process=nodes["sat1"]).success
    refused = collector.call(Step, "/sat2/rigid_rot_sim/step", Step.Request(steps=1), process=nodes["sat2"])
    assert not refused.success and "not paused" in refused.message
    later = stamp(states["sat2"][-1]) + 0.5
    collector.spin_until(lambda: stamp(states["sat2"][-1]) >= later, WAIT, nodes["sat2"], "sat2 to run on")
    for process in nodes.values():
        process.check_alive()
