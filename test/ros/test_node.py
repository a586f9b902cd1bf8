"""In-process tests of the simulation node: what it builds, parameters, services, rejections.

Each test creates the node with ``parameter_overrides`` in an rclpy context of its own
(domain id private to this test run, localhost discovery) and talks to it from a client
node in the same executor.
"""

import math
import os
import time
from pathlib import Path

import pytest

# test/conftest.py has set the session's ROS_DOMAIN_ID and localhost discovery.
import rclpy
from builtin_interfaces.msg import Duration
from geometry_msgs.msg import Vector3, WrenchStamped
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from std_srvs.srv import SetBool, Trigger

from rigid_rot_msgs.msg import RejectedCommand, RigidBodyState
from rigid_rot_msgs.srv import ApplyTorque, ComputeInertia, SetState, Step
from rigid_rot_sim.ros.node import RigidRotSimNode
from rigid_rot_sim.ros.qos import COMMAND_QOS, REJECTED_QOS, STATE_QOS

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "config" / "scenes"


@pytest.fixture
def context():
    ctx = rclpy.Context()
    # the session's second domain: no e2e test's node (same name) is on this graph
    rclpy.init(context=ctx, domain_id=int(os.environ["RIGID_ROT_SIM_IN_PROCESS_DOMAIN_ID"]))
    yield ctx
    rclpy.shutdown(context=ctx)


class Harness:
    """The node under test, a client node and one executor for both."""

    def __init__(self, ctx, scene: str | None, **params):
        overrides = [Parameter(name, value=value) for name, value in params.items()]
        if scene is not None:
            overrides.insert(0, Parameter("scene", value=str(SCENES / f"{scene}.yaml")))
        self.node = RigidRotSimNode(context=ctx, parameter_overrides=overrides)
        self.client = rclpy.create_node("test_client", context=ctx)
        self.executor = SingleThreadedExecutor(context=ctx)
        self.executor.add_node(self.node)
        self.executor.add_node(self.client)

    def call(self, srv_type, name: str, request, timeout: float = 10.0):
        client = self.client.create_client(srv_type, f"/rigid_rot_sim/{name}")
        assert client.wait_for_service(timeout_sec=timeout)
        future = client.call_async(request)
        self.executor.spin_until_future_complete(future, timeout_sec=timeout)
        assert future.done(), f"{name}: no reply in {timeout} s"
        return future.result()

    def spin_until(self, condition, timeout: float = 60.0) -> bool:
        # generous: returns as soon as the condition holds; a cold numba cache compiles on the first step
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if condition():
                return True
            self.executor.spin_once(timeout_sec=0.02)
        return condition()

    def published_topics(self) -> dict[str, list[str]]:
        return dict(self.client.get_publisher_names_and_types_by_node("rigid_rot_sim", "/"))

    def close(self):
        self.executor.shutdown()
        self.client.destroy_node()
        self.node.destroy_node()


@pytest.fixture
def harness(context):
    made = []

    def make(scene, **params):
        h = Harness(context, scene, **params)
        made.append(h)
        return h

    yield make
    for h in made:
        h.close()


def test_without_scene_only_compute_inertia_is_served(harness):
    h = harness(None)
    assert h.node.run is None
    request = ComputeInertia.Request(masses=[1.0, 1.0])
    request.positions = [_point(0.5, 0, 0), _point(-0.5, 0, 0)]
    response = h.call(ComputeInertia, "compute_inertia", request)
    assert response.success and response.symmetry == "linear"
    services = dict(h.client.get_service_names_and_types_by_node("rigid_rot_sim", "/"))
    assert "/rigid_rot_sim/compute_inertia" in services and "/rigid_rot_sim/set_state" not in services


def _point(x, y, z):
    from geometry_msgs.msg import Point

    return Point(x=float(x), y=float(y), z=float(z))


def test_torque_free_scene_builds_no_subscription_and_picks_exact(harness):
    h = harness("free_tumble", real_time_factor=0.0)
    assert h.node.run.sim.stepper.method == "exact"
    assert h.node.run.inputs.subscriptions == []
    subscriptions = dict(h.client.get_subscriber_names_and_types_by_node("rigid_rot_sim", "/"))
    assert not any("torque" in topic for topic in subscriptions)
    assert h.spin_until(lambda: "/rigid_rot_sim/state" in h.published_topics())
    topics = h.published_topics()
    for topic in (
        "/rigid_rot_sim/state",
        "/rigid_rot_sim/orientation",
        "/rigid_rot_sim/angular_velocity",
        "/rigid_rot_sim/angular_momentum",
        "/rigid_rot_sim/mass_properties",
        "/rigid_rot_sim/rejected",
        "/clock",
    ):
        assert topic in topics, topic
    assert "/rigid_rot_sim/top_state" not in topics
    assert h.node.run.recording is None


def test_top_scene_builds_top_state_and_torque_scene_subscribes(harness):
    top = harness("heavy_top", real_time_factor=0.0)
    assert top.spin_until(lambda: "/rigid_rot_sim/top_state" in top.published_topics())
    assert top.node.run.sim.stepper.method == "exact_split"
    top.close()
    driven = harness("torque_driven", real_time_factor=0.0)
    assert [s.topic_name for s in driven.node.run.inputs.subscriptions] == ["/rigid_rot_sim/torque"]
    assert driven.node.run.sim.stepper.method == "taylor"


def test_parameters_are_validated_and_applied(harness):
    h = harness("torque_driven", real_time_factor=0.0)
    node = h.node
    refused = node.set_parameters([Parameter("integrator", value="magic")])[0]
    assert not refused.successful and "unknown integrator 'magic'" in refused.reason
    assert node.run.sim.stepper.method == "taylor" and node.get_parameter("integrator").value == "auto"
    for bad_dt in (-0.001, 0.0):
        result = node.set_parameters([Parameter("dt", value=bad_dt)])[0]
        assert not result.successful and result.reason
    assert node.run.sim.clock.dt == 0.001
    assert not node.set_parameters([Parameter("scene", value="other.yaml")])[0].successful
    refused_rate = node.set_parameters([Parameter("rates.top_state", value=10.0)])[0]
    assert not refused_rate.successful and "not built" in refused_rate.reason
    ok = node.set_parameters([Parameter("integrator", value="rk4"), Parameter("dt", value=0.002)])[0]
    assert ok.successful
    assert node.run.sim.stepper.method == "rk4" and node.run.sim.clock.dt == 0.002
    assert node.set_parameters([Parameter("real_time_factor", value=2.0)])[0].successful
    assert node.run.driver.pacer.real_time_factor == 2.0
    assert node.set_parameters([Parameter("rates.state", value=25.0)])[0].successful
    assert node.run.driver.schedule.periods["state"] == 20  # 25 Hz at dt = 2 ms
    # the run continues
    k = node.run.sim.clock.k
    assert h.spin_until(lambda: node.run.sim.clock.k > k + 100)


def test_params_file_overrides_the_scene(context, tmp_path):
    params = tmp_path / "params.yaml"
    params.write_text(
        "rigid_rot_sim:\n  ros__parameters:\n"
        f"    scene: {SCENES / 'torque_driven.yaml'}\n    integrator: rk4\n    dt: 0.0005\n"
        "    real_time_factor: 0.0\n    rates:\n      state: 200.0\n      clock: 0.0\n"
    )
    node = RigidRotSimNode(context=context, cli_args=["--ros-args", "--params-file", str(params)])
    try:
        assert (
            node.run.sim.stepper.method == "rk4"
            and node.run.sim.clock.dt == 0.0005
            and node.run.driver.pacer.real_time_factor == 0.0
        )
        assert node.run.driver.schedule.periods["state"] == 10 and "clock" not in node.run.driver.schedule.periods
    finally:
        node.destroy_node()


def test_pause_step_reset_set_state_services(harness):
    h = harness("free_tumble", real_time_factor=1.0)
    states = []
    h.client.create_subscription(RigidBodyState, "/rigid_rot_sim/state", states.append, STATE_QOS)
    refused = h.call(Step, "step", Step.Request(steps=5))
    assert not refused.success and "not paused" in refused.message
    assert h.call(SetBool, "pause", SetBool.Request(data=True)).success
    k = h.node.run.sim.clock.k
    h.spin_until(lambda: False, timeout=0.2)
    assert h.node.run.sim.clock.k == k  # paused: no steps
    zero = h.call(Step, "step", Step.Request(steps=0))
    assert not zero.success
    stepped = h.call(Step, "step", Step.Request(steps=25))
    assert stepped.success and h.node.run.sim.clock.k == k + 25
    t = stepped.state.header.stamp.sec + stepped.state.header.stamp.nanosec * 1e-9
    assert t == pytest.approx((k + 25) * 0.01, abs=1e-9)
    request = SetState.Request()
    request.orientation.w = 2.0  # normalised by the simulator
    request.angular_velocity = Vector3(x=0.0, y=0.0, z=1.5)
    assert h.call(SetState, "set_state", request).success
    snap = h.node.run.sim.snapshot()
    assert snap.orientation.tolist() == [0.0, 0.0, 0.0, 1.0] and snap.angular_velocity_body.tolist() == [0.0, 0.0, 1.5]
    bad = SetState.Request()
    bad.orientation.w = 0.0  # all-zero quaternion (the message default is w = 1)
    response = h.call(SetState, "set_state", bad)
    assert not response.success and "orientation" in response.message
    bad_omega = SetState.Request()
    bad_omega.orientation.w = 1.0
    bad_omega.angular_velocity.x = math.nan
    assert not h.call(SetState, "set_state", bad_omega).success
    assert h.call(Trigger, "reset", Trigger.Request()).success
    assert h.node.run.sim.clock.k == 0
    assert h.node.run.sim.snapshot().angular_velocity_body.tolist() == [0.3, 0.2, 2.0]
    assert h.call(SetBool, "pause", SetBool.Request(data=False)).success
    assert h.spin_until(lambda: h.node.run.sim.clock.k > 5)


def test_apply_torque_service_and_rejections(harness):
    h = harness("torque_driven", real_time_factor=0.0, integrator="rk4")
    rejected = []
    h.client.create_subscription(RejectedCommand, "/rigid_rot_sim/rejected", rejected.append, REJECTED_QOS)
    request = ApplyTorque.Request(torque=Vector3(z=0.004), frame_id="", duration=Duration(sec=0, nanosec=100_000_000))
    response = h.call(ApplyTorque, "apply_torque", request)
    assert response.success, response.message
    bad = ApplyTorque.Request(torque=Vector3(z=0.004), frame_id="map", duration=Duration(sec=1))
    response = h.call(ApplyTorque, "apply_torque", bad)
    assert not response.success and "neither the body frame" in response.message
    zero = ApplyTorque.Request(torque=Vector3(z=0.004), duration=Duration())
    assert not h.call(ApplyTorque, "apply_torque", zero).success
    # bad topic commands: published on ~/rejected with the reason, no effect on the state
    publisher = h.client.create_publisher(WrenchStamped, "/rigid_rot_sim/torque", COMMAND_QOS)
    assert h.spin_until(lambda: publisher.get_subscription_count() > 0)
    nan_cmd = WrenchStamped()
    nan_cmd.header.frame_id = "base_link"
    nan_cmd.wrench.torque.x = math.nan
    force_cmd = WrenchStamped()
    force_cmd.header.frame_id = "base_link"
    force_cmd.wrench.torque.z = 1.0
    force_cmd.wrench.force.x = 2.0
    publisher.publish(nan_cmd)
    publisher.publish(force_cmd)
    assert h.spin_until(lambda: len(rejected) >= 4)
    reasons = [r.reason for r in rejected]
    sources = {r.source for r in rejected}
    assert any("neither the body frame" in r for r in reasons)
    assert any("non-finite torque.x" in r for r in reasons) and any("non-zero force" in r for r in reasons)
    assert sources == {"/rigid_rot_sim/apply_torque", "/rigid_rot_sim/torque"}
    assert h.spin_until(lambda: h.node.run.sim.clock.t > 0.5)
    # only the 0.1 s applied torque acted: omega_z = 0.004 * 0.1 / 0.04
    assert h.node.run.sim.snapshot().angular_velocity_body[2] == pytest.approx(0.01, rel=1e-9)


def test_start_paused_waits_for_resume(harness):
    h = harness("free_tumble", real_time_factor=0.0, start_paused=True)
    h.spin_until(lambda: False, timeout=0.3)
    assert h.node.run.sim.paused and h.node.run.sim.clock.k == 0
    assert h.call(SetBool, "pause", SetBool.Request(data=False)).success
    assert h.spin_until(lambda: h.node.run.sim.clock.k > 100)


def test_duration_reached_finishes(harness):
    h = harness("free_tumble", real_time_factor=0.0, duration=0.5)
    assert h.spin_until(lambda: h.node.finished)
    assert h.node.run.sim.clock.t == pytest.approx(0.5, abs=1e-12) and h.node.run.sim.clock.k == 50


def test_rep105_frames_by_default_on_every_output_and_recorded_tf(harness, tmp_path):
    from geometry_msgs.msg import InertiaStamped, QuaternionStamped, Vector3Stamped
    from tf2_msgs.msg import TFMessage

    from rigid_rot_sim.recording.reader import BagReader
    from rigid_rot_sim.ros.qos import LATCHED_QOS, TF_QOS

    bag = tmp_path / "frames.mcap"
    h = harness("free_tumble", real_time_factor=0.0, duration=0.2, record_path=str(bag))
    got: dict[str, list] = {}
    for topic, msg_type, qos in (
        ("state", RigidBodyState, STATE_QOS),
        ("orientation", QuaternionStamped, STATE_QOS),
        ("angular_velocity", Vector3Stamped, STATE_QOS),
        ("angular_momentum", Vector3Stamped, STATE_QOS),
        ("mass_properties", InertiaStamped, LATCHED_QOS),
    ):
        got[topic] = []
        h.client.create_subscription(msg_type, f"/rigid_rot_sim/{topic}", got[topic].append, qos)
    got["tf"] = []
    h.client.create_subscription(TFMessage, "/tf", got["tf"].append, TF_QOS)
    h.node.run.sim.pause(True)
    publishers = [p for name, p in h.node.run.outputs.publishers.items() if name in got]
    assert h.spin_until(lambda: all(p.get_subscription_count() > 0 for p in publishers))
    assert h.call(Trigger, "reset", Trigger.Request()).success  # republishes every output at t = 0, matched now
    assert h.spin_until(lambda: all(got.values()))
    assert (got["state"][0].header.frame_id, got["state"][0].child_frame_id) == ("odom", "base_link")
    assert got["orientation"][0].header.frame_id == "odom" and got["angular_momentum"][0].header.frame_id == "odom"
    assert got["angular_velocity"][0].header.frame_id == "base_link"
    assert got["mass_properties"][0].header.frame_id == "base_link"
    transform = got["tf"][0].transforms[0]
    assert (transform.header.frame_id, transform.child_frame_id) == ("odom", "base_link")
    assert (
        "/rigid_rot_sim/imu" not in h.published_topics() and "imu" not in h.node.run.outputs.publishers
    )  # not asked for
    h.node.run.sim.pause(False)
    assert h.spin_until(lambda: h.node.finished)
    h.node.run.recording.close()
    frames = {
        (m.transforms[0].header.frame_id, m.transforms[0].child_frame_id) for _, m in BagReader(bag).decoded(["/tf"])
    }
    assert frames == {("odom", "base_link")}


def test_frame_parameters_override_the_scene_and_bad_names_are_refused(context):
    scene = str(SCENES / "heavy_top.yaml")  # frames {world: world, body: top} in the file
    node = RigidRotSimNode(context=context, parameter_overrides=[Parameter("scene", value=scene)])
    try:
        assert (node.run.scene.frames.world, node.run.scene.frames.body) == (
            "world",
            "top",
        ) and node.run.sim.frames == node.run.scene.frames
    finally:
        node.destroy_node()
    node = RigidRotSimNode(
        context=context,
        parameter_overrides=[
            Parameter("scene", value=scene),
            Parameter("world_frame", value="map"),
            Parameter("body_frame", value="base_link"),
        ],
    )
    try:
        assert (node.run.scene.frames.world, node.run.scene.frames.body) == (
            "map",
            "base_link",
        ) and node.run.sim.frames == node.run.scene.frames
    finally:
        node.destroy_node()
    for world, body, reason in (("map", "map", "must differ"), ("", "base_link", "non-empty")):
        with pytest.raises(ValueError, match=reason):
            RigidRotSimNode(
                context=context,
                parameter_overrides=[
                    Parameter("scene", value=scene),
                    Parameter("world_frame", value=world),
                    Parameter("body_frame", value=body),
                ],
            )
    with pytest.raises(ValueError, match="record_log_time must be one of sim, wall"):
        RigidRotSimNode(
            context=context,
            parameter_overrides=[Parameter("scene", value=scene), Parameter("record_log_time", value="gps")],
        )


def test_recording_without_the_mcap_package_is_disabled_with_a_message(context, tmp_path, monkeypatch, capfd):
    import sys

    for name in [
        n
        for n in sys.modules
        if n in ("mcap", "rigid_rot_sim.ros.recording") or n.startswith(("mcap.", "rigid_rot_sim.recording."))
    ]:
        parent, _, child = name.rpartition(".")
        if parent in sys.modules and hasattr(sys.modules[parent], child):
            # undone after the test: the package attribute points at the original module again
            monkeypatch.setattr(sys.modules[parent], child, sys.modules[name])
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "mcap", None)  # import mcap -> ImportError, as when it is not installed
    node = RigidRotSimNode(
        context=context,
        parameter_overrides=[
            Parameter("scene", value=str(SCENES / "free_tumble.yaml")),
            Parameter("record_path", value=str(tmp_path / "x.mcap")),
        ],
    )
    try:
        assert node.run.recording is None and node.run.sim is not None and not (tmp_path / "x.mcap").exists()
        assert "recording disabled: mcap is not installed" in capfd.readouterr().err
        k = node.run.sim.clock.k  # the run itself goes on
        node.run.sim.advance_to(k + 3)
        assert node.run.sim.clock.k == k + 3
    finally:
        node.destroy_node()


def test_without_simulation_interfaces_the_node_runs_without_the_standard_services(context, monkeypatch):
    from rigid_rot_sim.ros import simulation_services

    monkeypatch.setattr(simulation_services, "AVAILABLE", False)  # as on an install without the package
    # a node name of its own, so that no other test's node can answer the graph query below
    node = RigidRotSimNode(
        context=context,
        cli_args=["--ros-args", "-r", "__node:=rigid_rot_plain"],
        parameter_overrides=[Parameter("scene", value=str(SCENES / "free_tumble.yaml"))],
    )
    probe = rclpy.create_node("probe_plain", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(probe)
    try:
        assert node.run.simulation_services is None

        def services():
            return dict(probe.get_service_names_and_types_by_node("rigid_rot_plain", "/"))

        deadline = time.monotonic() + 30.0
        while not {"/rigid_rot_plain/step", "/rigid_rot_plain/apply_torque"} <= set(services()):
            assert time.monotonic() < deadline, services()
            executor.spin_once(timeout_sec=0.05)
        assert not any(
            name.endswith(("_simulation", "_simulation_state", "_simulator_features")) for name in services()
        )
    finally:
        executor.shutdown()
        probe.destroy_node()
        node.destroy_node()


def test_integer_values_for_double_parameters_are_stored_as_floats(context, tmp_path):
    """`ros2 param set /rigid_rot_sim real_time_factor 2` (an INTEGER over SetParameters), `-p x:=1`
    and a params file with integers all give DOUBLE parameters."""
    from rcl_interfaces.msg import Parameter as ParameterMsg
    from rcl_interfaces.msg import ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    params = tmp_path / "params.yaml"
    params.write_text(
        "rigid_rot_sim:\n  ros__parameters:\n"
        f"    scene: {SCENES / 'torque_driven.yaml'}\n    real_time_factor: 0\n    duration: 5\n"
        "    rates:\n      state: 50\n"
    )
    node = RigidRotSimNode(context=context, cli_args=["--ros-args", "--params-file", str(params), "-p", "dt:=1"])
    client = rclpy.create_node("param_client", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(client)
    try:
        for name, value in (("real_time_factor", 0.0), ("duration", 5.0), ("rates.state", 50.0), ("dt", 1.0)):
            stored = node.get_parameter(name)
            assert stored.type_ == Parameter.Type.DOUBLE and stored.value == value and isinstance(stored.value, float)
        assert (
            node.run.driver.pacer.real_time_factor == 0.0
            and node.run.driver.duration == 5.0
            and node.run.sim.clock.dt == 1.0
        )
        # what `ros2 param set` sends: the SetParameters service of the node, an INTEGER value
        service = client.create_client(SetParameters, "/rigid_rot_sim/set_parameters")
        assert service.wait_for_service(timeout_sec=30.0)
        request = SetParameters.Request(
            parameters=[
                ParameterMsg(
                    name="real_time_factor", value=ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=2)
                )
            ]
        )
        future = service.call_async(request)
        executor.spin_until_future_complete(future, timeout_sec=30.0)
        (result,) = future.result().results
        assert result.successful, result.reason
        stored = node.get_parameter("real_time_factor")
        assert (
            stored.type_ == Parameter.Type.DOUBLE
            and stored.value == 2.0
            and node.run.driver.pacer.real_time_factor == 2.0
        )
        # the ranges still apply, and other types are still refused
        assert not node.set_parameters([Parameter("real_time_factor", value=5000)])[0].successful
        assert not node.set_parameters([Parameter("dt", value="fast")])[0].successful
        assert node.set_parameters([Parameter("rates.state", value=20)])[0].successful
        assert (
            node.get_parameter("rates.state").value == 20.0 and node.run.driver.schedule.periods["state"] == 1
        )  # dt = 1 s
    finally:
        executor.shutdown()
        client.destroy_node()
        node.destroy_node()


def test_output_qos_from_parameters_and_scene(harness, context, tmp_path):
    from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

    from rigid_rot_sim.ros.qos import TF_QOS

    h = harness("free_tumble", real_time_factor=0.0, **{"qos.reliability": "best_effort", "qos.depth": 1000})
    for name in ("state", "orientation", "angular_velocity", "angular_momentum"):
        profile = h.node.run.outputs.publishers[name].qos_profile
        assert profile.reliability == ReliabilityPolicy.BEST_EFFORT and profile.depth == 1000
        assert profile.durability == DurabilityPolicy.VOLATILE
    assert h.node.run.outputs.publishers["tf"].qos_profile.depth == TF_QOS.depth  # /tf keeps tf2's profile
    assert h.node.run.outputs.publishers["tf"].qos_profile.reliability == ReliabilityPolicy.RELIABLE
    assert not h.node.set_parameters([Parameter("qos.depth", value=5)])[0].successful  # read only
    h.close()

    scene = tmp_path / "scene.yaml"
    scene.write_text((SCENES / "free_tumble.yaml").read_text() + "qos: {reliability: reliable, depth: 3}\n")
    node = RigidRotSimNode(context=context, parameter_overrides=[Parameter("scene", value=str(scene))])
    try:
        profile = node.run.outputs.publishers["state"].qos_profile
        assert profile.reliability == ReliabilityPolicy.RELIABLE and profile.depth == 3
        assert node.get_parameter("qos.depth").value == 3
    finally:
        node.destroy_node()
    with pytest.raises(ValueError, match="qos.reliability must be one of reliable, best_effort, got 'sometimes'"):
        RigidRotSimNode(
            context=context,
            parameter_overrides=[
                Parameter("scene", value="free_tumble"),
                Parameter("qos.reliability", value="sometimes"),
            ],
        )


def test_tf_static_carries_the_principal_frame_only_where_it_differs(harness):
    from rigid_rot_sim.core.inertia import principal_frame, principal_orientation

    h = harness("from_point_masses", real_time_factor=0.0)
    (transform,) = h.node.run.outputs.static_transforms
    assert (transform.header.frame_id, transform.child_frame_id) == ("base_link", "base_link_principal")
    tensor = h.node.run.scene.body.inertia_array
    r = transform.transform.rotation
    assert [r.x, r.y, r.z, r.w] == principal_orientation(principal_frame(tensor)[1]).tolist()
    t = transform.transform.translation
    assert [t.x, t.y, t.z] == list(h.node.run.scene.body.center_of_mass)
    # by topic, not by node name: a node of an earlier test with the same name may linger in the graph
    assert h.spin_until(
        lambda: any(info.node_name == "rigid_rot_sim" for info in h.client.get_publishers_info_by_topic("/tf_static"))
    )
    h.close()
    top = harness("heavy_top", real_time_factor=0.0)  # principal moments about the pivot, centre of mass on z
    (shifted,) = top.node.run.outputs.static_transforms
    assert shifted.transform.rotation.w == 1.0
    assert shifted.transform.translation.z == top.node.run.scene.body.center_of_mass[2] > 0.0
    top.close()
    plain = harness("torque_driven", real_time_factor=0.0)
    assert plain.node.run.outputs.static_transforms == [] and "tf_static" not in plain.node.run.outputs.publishers


@pytest.mark.parametrize(
    "override,expected",
    [
        ("qos.depth:=2.5", "'qos.depth' to '2.5' of type 'DOUBLE', expecting type 'INTEGER'"),
        ("qos.reliability:=sometimes", "qos.reliability must be one of reliable, best_effort, got 'sometimes'"),
        ("dt:=fast", "'dt' to 'fast' of type 'STRING', expecting type 'DOUBLE'"),
    ],
)
def test_bad_start_up_parameters_exit_2_with_one_line(override, expected):
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, "-m", "rigid_rot_sim.ros.node", "--ros-args", "-p", "scene:=free_tumble", "-p", override],
        capture_output=True,
        text=True,
        timeout=120,
    )
    output = (done.stdout + done.stderr).strip()
    assert done.returncode == 2 and expected in output and "Traceback" not in output, output


def test_a_destroyed_node_leaves_the_graph(harness):
    """Nothing the node made (its SimulateSteps action server included) keeps it alive after destroy_node."""
    h = harness("free_tumble", real_time_factor=0.0)

    def ours() -> int:  # a node of an earlier test (same name) may still be listed: count them
        return h.client.get_node_names_and_namespaces().count(("rigid_rot_sim", "/"))

    assert h.spin_until(lambda: ours() >= 1)
    before = ours()
    h.executor.remove_node(h.node)
    h.node.destroy_node()
    assert h.spin_until(lambda: ours() == before - 1, timeout=10.0), "the node is still on the graph after destroy_node"


def test_a_lockstep_answer_that_comes_while_the_turn_steps_is_never_left_undecided(harness):
    """The controller answers each state before the node has finished the turn that published it (a fast
    controller): the answer must not be taken inside the stepping and then left waiting for the next look
    (POLL_WALL) with the turn answered but not decided. After every turn the answer to the state it published
    is still in the reader, so the loop's wait wakes at once, and the next turn goes on."""
    h = harness("closed_loop_lockstep")
    run = h.node.run
    run.loop.detach()  # the turns are run here, one by one
    turns = run.lockstep.turns
    publisher = h.client.create_publisher(WrenchStamped, "/rigid_rot_sim/torque", COMMAND_QOS)
    deadline = time.monotonic() + 30.0
    while publisher.get_subscription_count() == 0:
        assert time.monotonic() < deadline, "the node's torque subscription never matched"
        time.sleep(0.01)

    with run.intake.waiting() as wait:
        wait(0.0)  # the start-up's wake-up

        def answer(stamp_ns: int) -> None:
            """Publish the answer and return once it is in the node's reader (not taken)."""
            msg = WrenchStamped()
            msg.header.frame_id = "base_link"
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
            msg.wrench.torque.z = 1e-3
            publisher.publish(msg)
            until = time.monotonic() + 10.0
            while not wait(0.1):
                assert time.monotonic() < until, "the answer never reached the node's reader"

        class Controller:
            def published(self, name, topic, data, msg):
                if name == "state":  # answered before the node goes on
                    answer(msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec)

        answer(0)  # turn 0's state was published at start-up
        run.outputs.listeners.append(Controller())
        until = time.monotonic() + 60.0
        while turns.turns < 5:
            assert time.monotonic() < until, f"only {turns.turns} turns in 60 s"
            wait_s = run.turn()
            if turns.waiting:  # the turn stands on a boundary: its answer is not taken yet, and the loop wakes at once
                assert turns.missing() == ["~/torque"], "an answer was taken but its turn left undecided"
                assert wait_s is not None and wait_s > 0.0
                assert wait(0.0), "the answer to the state just published is in the reader"
            else:  # a slice cut by SLICE_WALL (the first one loads the kernels): at rtf 0 the next turn comes at once
                assert wait_s == 0.0
    assert turns.timeouts == 0 and run.sim.clock.k >= 5 * turns.period_steps
