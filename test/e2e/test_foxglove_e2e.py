"""The Foxglove live server and ``rigid-rot view``, seen by a ws-protocol client (as the Foxglove app).

What the node streams must be what it publishes over DDS: the same ~/state bytes at the same
sim times, and the body scene drawn from that state.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import foxglove  # noqa: F401  (the viewer extra: make setup installs it, so these tests always run)
from e2e_helpers import WAIT
from foxglove_client import FoxgloveClient

from rigid_rot_sim.core.inertia import equivalent_box, principal_frame
from rigid_rot_sim.recording.definitions import dynamic_decoder
from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.run.body_view import body_view
from rigid_rot_sim.scene.scene import load_scene
from rigid_rot_sim.share import resolve_scene

STATE_TYPE = "rigid_rot_msgs/msg/RigidBodyState"
PORT = re.compile(r"Foxglove live server ws://127\.0\.0\.1:(\d+)")


def _port_from_log(process, timeout: float = WAIT) -> int:
    deadline = time.monotonic() + timeout
    while (match := PORT.search(process.log())) is None:
        process.check_alive()
        assert time.monotonic() < deadline, f"no Foxglove start-up line\n{process.log()}"
        time.sleep(0.1)
    return int(match.group(1))


def _arrow_tip(arrow: dict) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    pose = arrow["pose"]
    q = [pose["orientation"][k] for k in "xyzw"]
    tail = np.array([pose["position"][k] for k in "xyz"])
    return tail + Rotation.from_quat(q).apply([arrow["shaft_length"] + arrow["head_length"], 0.0, 0.0])


def _check_scene_entity(update: dict, state, view) -> None:
    body, momentum = update["entities"]
    (cube,) = body["cubes"]
    sides = sorted(cube["size"][k] for k in "xyz")
    assert sides == pytest.approx(sorted(view.box_sides), rel=1e-12)
    omega = np.array([state.angular_velocity_body.x, state.angular_velocity_body.y, state.angular_velocity_body.z])
    L = np.array([state.angular_momentum_world.x, state.angular_momentum_world.y, state.angular_momentum_world.z])
    np.testing.assert_allclose(_arrow_tip(body["arrows"][0]), view.box_center + view.omega_scale * omega, atol=1e-9)
    np.testing.assert_allclose(_arrow_tip(momentum["arrows"][0]), view.momentum_scale * L, atol=1e-9)
    assert (body["frame_id"], momentum["frame_id"]) == ("base_link", "odom")


def test_live_server_streams_what_the_node_publishes(tmp_path, launch_node, ros_node, collector):
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    from rigid_rot_msgs.msg import RigidBodyState

    bag = tmp_path / "live.mcap"
    node = launch_node(
        "--ros-args",
        "-p",
        "scene:=free_tumble",
        "-p",
        "foxglove:=127.0.0.1:0",
        "-p",
        "rates.markers:=10.0",
        "-p",
        f"record_path:={bag}",
    )
    port = _port_from_log(node)
    dds: list[bytes] = []
    ros_node.create_subscription(
        RigidBodyState,
        "/rigid_rot_sim/state",
        dds.append,
        QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE),
        raw=True,
    )
    client = FoxgloveClient(f"ws://127.0.0.1:{port}")
    try:
        client.until(
            lambda: client.channel_of("/rigid_rot_sim/state") and client.channel_of("/rigid_rot_sim/body_scene"),
            WAIT,
            "the state and scene channels",
            node.check_alive,
        )
        state_channel = client.channel_of("/rigid_rot_sim/state")
        assert (state_channel["encoding"], state_channel["schemaName"]) == ("cdr", STATE_TYPE)
        assert state_channel["schemaEncoding"] == "ros2msg"
        assert client.channel_of("/rigid_rot_sim/body_scene")["schemaName"] == "foxglove.SceneUpdate"
        client.subscribe("/rigid_rot_sim/state", "/rigid_rot_sim/body_scene")
        decode = dynamic_decoder(STATE_TYPE, state_channel["schema"])

        def common() -> set[bytes]:
            return {payload for _, payload in client.received("/rigid_rot_sim/state")} & set(dds)

        deadline = time.monotonic() + WAIT
        while len(common()) < 20:
            assert time.monotonic() < deadline, "fewer than 20 states both over DDS and over Foxglove"
            node.check_alive()
            client.pump(0.2)
            collector.executor.spin_once(timeout_sec=0.05)
        view = body_view(load_scene(resolve_scene("free_tumble")))
        scenes = {t: json.loads(payload) for t, payload in client.received("/rigid_rot_sim/body_scene")}
        checked = 0
        for t_ns, payload in client.received("/rigid_rot_sim/state"):
            state = decode(payload)
            stamp = state.header.stamp.sec * 1_000_000_000 + state.header.stamp.nanosec
            assert t_ns == stamp  # the log time is the sim time it was published at
            if payload in dds and t_ns in scenes:
                _check_scene_entity(scenes[t_ns], state, view)
                checked += 1
        assert checked >= 10
        # the server's time moves to each state's time as it streams it: every time it broadcast is the time of
        # a state it streams (the SDK sends its time and data messages apart, so the state may come just after)
        assert client.times
        last_time = max(client.times)

        def state_times() -> set[int]:
            return {t for t, _ in client.received("/rigid_rot_sim/state")}

        client.until(lambda: max(state_times()) >= last_time, WAIT, "the state at the last time", node.check_alive)
        assert last_time in state_times()
        assert client.channel_of("/rigid_rot_sim/markers")["schemaName"] == "visualization_msgs/msg/MarkerArray"
    finally:
        client.close()
    assert node.stop() == 0
    _check_recorded_markers(bag, view)


def _check_recorded_markers(bag: Path, view) -> None:
    """~/markers is in the recording and decodes with rosbags (an independent reader)."""
    from rosbags.highlevel import AnyReader

    with AnyReader([bag]) as reader:
        connections = [c for c in reader.connections if c.topic == "/rigid_rot_sim/markers"]
        assert connections and connections[0].msgtype == "visualization_msgs/msg/MarkerArray"
        arrays = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=connections)]
    assert len(arrays) >= 2
    box, omega, momentum = arrays[-1].markers
    assert sorted([box.scale.x, box.scale.y, box.scale.z]) == pytest.approx(sorted(view.box_sides), rel=1e-12)
    assert (box.header.frame_id, omega.header.frame_id, momentum.header.frame_id) == ("base_link", "base_link", "odom")
    assert len(omega.points) == len(momentum.points) == 2


def test_box_has_the_bodys_principal_moments():
    scene = load_scene(resolve_scene("spacecraft_slew"))  # an inertia tensor with products of inertia
    mass, _, tensor = scene.mass_properties_about_com()
    moments, _ = principal_frame(tensor)
    a, b, c = equivalent_box(moments, mass=12.0)
    m = 12.0
    np.testing.assert_allclose(
        [m * (b**2 + c**2) / 12, m * (a**2 + c**2) / 12, m * (a**2 + b**2) / 12], moments, rtol=1e-12
    )


def test_view_serves_a_recording(tmp_path):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "recording"))
    from test_resim import record_like_the_node

    bag = tmp_path / "run.mcap"
    record_like_the_node(bag, "free_tumble", 400, 10, {}, method="rk4")
    command = [
        str(Path(sys.executable).parent / "rigid-rot"),
        "view",
        str(bag),
        "--foxglove",
        "127.0.0.1:0",
        "--speed",
        "0.5",
    ]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        line = process.stdout.readline()
        match = re.search(r"ws://127\.0\.0\.1:(\d+)", line)
        assert match, line
        client = FoxgloveClient(f"ws://127.0.0.1:{match.group(1)}")
        client.until(lambda: client.channel_of("/rigid_rot_sim/state") is not None, WAIT, "the state channel")
        assert "playbackControl" in client.server_info["capabilities"]  # play/pause/seek from the app
        end = client.server_info["dataEndTime"]
        assert end["sec"] * 1_000_000_000 + end["nsec"] == max(m.log_time_ns for m in BagReader(bag).messages())
        client.subscribe("/rigid_rot_sim/state", "/rigid_rot_sim/body_scene")
        client.until(lambda: len(client.received("/rigid_rot_sim/state")) >= 5, WAIT, "5 recorded states")
        recorded = {m.log_time_ns: m.data for m in BagReader(bag).messages(["/rigid_rot_sim/state"])}
        for t_ns, payload in client.received("/rigid_rot_sim/state"):
            assert recorded[t_ns] == payload  # the recorded bytes at their recorded times
        client.close()
    finally:
        process.send_signal(2)
        output, _ = process.communicate(timeout=10)
    assert process.returncode == 0, output
    # the player is a real ServerListener: the SDK finds every callback it calls (subscribe, unsubscribe)
    assert "Callback failed" not in output and "AttributeError" not in output, output


def test_view_once_starts_playing_when_a_client_subscribes(tmp_path):
    """A client that connects after the recording's own duration still gets all of it, then the close."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "recording"))
    from test_resim import record_like_the_node

    bag = tmp_path / "run.mcap"
    record_like_the_node(bag, "free_tumble", 400, 10, {}, method="rk4")
    recorded = [m.log_time_ns for m in BagReader(bag).messages(["/rigid_rot_sim/state"])]
    command = [str(Path(sys.executable).parent / "rigid-rot"), "view", str(bag), "--foxglove", "127.0.0.1:0", "--once"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        line = process.stdout.readline()
        match = re.search(r"ws://127\.0\.0\.1:(\d+)", line)
        assert match, line
        # longer than the whole recording at speed 1: a player that started with the server has ended
        time.sleep(2.0 + (recorded[-1] - recorded[0]) / 1e9)
        assert process.poll() is None, "view --once ended before any client connected"
        client = FoxgloveClient(f"ws://127.0.0.1:{match.group(1)}")
        client.until(lambda: client.channel_of("/rigid_rot_sim/state") is not None, WAIT, "the state channel")
        client.subscribe("/rigid_rot_sim/state")
        client.until(lambda: len(client.received("/rigid_rot_sim/state")) == len(recorded), WAIT, "every state")
        assert [t for t, _ in client.received("/rigid_rot_sim/state")] == recorded
        client.close()
        output, _ = process.communicate(timeout=WAIT)  # --once: it ends by itself after the last message
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 0, output
    assert "Callback failed" not in output, output


def test_a_client_that_connects_late_gets_the_latched_mass_properties(launch_node, ros_node, collector):
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    from rigid_rot_msgs.msg import RigidBodyState

    node = launch_node("--ros-args", "-p", "scene:=free_tumble", "-p", "foxglove:=127.0.0.1:0")
    port = _port_from_log(node)
    states: list = []
    ros_node.create_subscription(
        RigidBodyState,
        "/rigid_rot_sim/state",
        states.append,
        QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE),
    )
    # long after start-up, when ~/mass_properties went out once
    collector.spin_until(lambda: len(states) >= 20, WAIT, node, "20 states over DDS")
    topic = "/rigid_rot_sim/mass_properties"
    for _ in range(2):  # the first client, then one more after it: each gets it on subscribing
        _latched_reaches(FoxgloveClient(f"ws://127.0.0.1:{port}"), topic, node)
    assert node.stop() == 0


def _latched_reaches(client: FoxgloveClient, topic: str, node) -> None:
    try:
        client.until(lambda: client.channel_of(topic) is not None, WAIT, f"the channel {topic}", node.check_alive)
        client.subscribe(topic)
        client.until(lambda: len(client.received(topic)) >= 1, WAIT, f"the latched {topic}", node.check_alive)
        assert client.channel_of(topic)["schemaName"] == "geometry_msgs/msg/InertiaStamped"
    finally:
        client.close()
