"""Replay: recorded torque commands go out byte for byte, in order, with their timing."""

import os
import threading
import time
from pathlib import Path

import pytest

rclpy = pytest.importorskip("rclpy")
pytest.importorskip("rigid_rot_msgs.msg")
from geometry_msgs.msg import WrenchStamped  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.serialization import deserialize_message  # noqa: E402
from test_resim import COMMANDS, record_like_the_node  # noqa: E402

from rigid_rot_sim.recording.bag_metadata import DURABILITY_TRANSIENT_LOCAL, QosProfile, offered_qos_yaml  # noqa: E402
from rigid_rot_sim.recording.reader import BagReader  # noqa: E402
from rigid_rot_sim.recording.replay import qos_from_metadata, replay, select_topics  # noqa: E402
from rigid_rot_sim.recording.writer import Recorder  # noqa: E402


@pytest.fixture
def ros_context():
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=os.getpid() % 100 + 1)
    yield context
    rclpy.try_shutdown(context=context)


def timed_bag(path: Path, gaps_s: list[float], lead_s: float = 0.0) -> None:
    """Torque commands at 1 s + the gaps (since the epoch); ``lead_s``: a message on another topic that
    far before the first command, which then starts the bag."""
    with Recorder(path) as recorder:
        recorder.add_topic("/robot/torque_cmd", "geometry_msgs/msg/WrenchStamped")
        t = 1_000_000_000
        if lead_s:
            recorder.add_topic("/robot/status", "geometry_msgs/msg/WrenchStamped")
            recorder.write_message("/robot/status", WrenchStamped(), t - int(lead_s * 1e9))
        for i, gap in enumerate(gaps_s):
            t += int(gap * 1e9)
            msg = WrenchStamped()
            msg.header.frame_id = "body"
            msg.header.stamp.sec = i
            msg.wrench.torque.z = float(i)
            recorder.write_message("/robot/torque_cmd", msg, t)


def test_replay_publishes_the_recorded_bytes_with_the_recorded_gaps(tmp_path, ros_context):
    bag = tmp_path / "cmds.mcap"
    gaps = [0.0, 0.2, 0.6, 0.2, 0.4]
    timed_bag(bag, gaps)
    listener = rclpy.create_node("listener", context=ros_context)
    publisher_node = rclpy.create_node("replayer", context=ros_context)
    received = []
    listener.create_subscription(WrenchStamped, "/sim/torque", lambda m: received.append((time.monotonic(), m)), 10)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(listener)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        report = replay(
            bag, rate=2.0, remap={"/robot/torque_cmd": "/sim/torque"}, node=publisher_node, wait_for_subscribers=10.0
        )
        deadline = time.monotonic() + 5.0
        while len(received) < len(gaps) and time.monotonic() < deadline:
            time.sleep(0.01)
    finally:
        executor.shutdown()
        listener.destroy_node()
        publisher_node.destroy_node()
    assert report.published == {"/sim/torque": len(gaps)}
    # same content, same order (compared decoded: CDR padding bytes carry no meaning)
    recorded = [deserialize_message(m.data, WrenchStamped) for m in BagReader(bag).messages()]
    assert [m for _, m in received] == recorded
    arrival = [t for t, _ in received]
    expected = [sum(gaps[1 : i + 1]) / 2.0 for i in range(len(gaps))]  # rate 2: half the gaps
    for i in range(1, len(gaps)):
        assert arrival[i] - arrival[0] == pytest.approx(expected[i], abs=0.06)


def test_default_topics_are_the_recorded_torque_inputs(tmp_path):
    bag = tmp_path / "run.mcap"
    record_like_the_node(bag, "torque_driven", 200, 10, COMMANDS)
    assert select_topics(BagReader(bag)) == ["/rigid_rot_sim/torque"]
    with pytest.raises(ValueError, match="/nope"):
        select_topics(BagReader(bag), ["/nope"])


def test_qos_is_rebuilt_from_the_recorded_profile():
    from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

    qos = qos_from_metadata(offered_qos_yaml([QosProfile(depth=3, durability=DURABILITY_TRANSIENT_LOCAL)]))
    assert (qos.depth, qos.durability, qos.reliability) == (
        3,
        DurabilityPolicy.TRANSIENT_LOCAL,
        ReliabilityPolicy.RELIABLE,
    )
    jazzy_form = "- history: keep_last\n  depth: 5\n  reliability: best_effort\n  durability: volatile\n"
    qos = qos_from_metadata(jazzy_form)
    assert (qos.depth, qos.reliability) == (5, ReliabilityPolicy.BEST_EFFORT)


def test_clock_follows_the_bag_time_at_the_replay_rate(tmp_path, ros_context):
    from rosgraph_msgs.msg import Clock

    bag = tmp_path / "cmds.mcap"
    timed_bag(bag, [0.0, 0.3, 0.3])  # log times 1.0, 1.3, 1.6 s since the epoch
    listener = rclpy.create_node("clock_listener", context=ros_context)
    publisher_node = rclpy.create_node("clock_replayer", context=ros_context)
    clocks = []
    listener.create_subscription(WrenchStamped, "/robot/torque_cmd", lambda m: None, 10)
    listener.create_subscription(Clock, "/clock", lambda m: clocks.append(m.clock.sec + m.clock.nanosec * 1e-9), 10)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(listener)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        report = replay(bag, rate=2.0, clock=100.0, node=publisher_node, wait_for_subscribers=10.0)
        # the newest /clock is never dropped (keep last): wait until the end of the bag's time arrives
        deadline = time.monotonic() + 30.0
        while not (clocks and clocks[-1] >= 1.5) and time.monotonic() < deadline:
            time.sleep(0.01)
    finally:
        executor.shutdown()
        listener.destroy_node()
        publisher_node.destroy_node()
    assert report.published == {"/robot/torque_cmd": 3}
    # how many of the 100 Hz clocks arrive depends on the machine's load; their values do not
    assert clocks and clocks == sorted(clocks)
    assert all(1.0 <= c <= 1.7 for c in clocks) and clocks[-1] >= 1.5  # bag time: 0.6 s of it, from 1.0 s


def test_replay_time_and_clock_start_at_the_bag_start_as_ros2_bag_play(tmp_path, ros_context):
    """rosbag2's player starts its clock at the bag's start (metadata starting_time), not at the first
    message it plays; ``--clock`` without a value is 40 Hz (ros2bag's play verb, Jazzy)."""
    from rosgraph_msgs.msg import Clock

    from rigid_rot_sim.recording.replay import CLOCK_RATE

    assert CLOCK_RATE == 40.0
    bag = tmp_path / "late.mcap"
    timed_bag(bag, [0.0, 0.2], lead_s=0.6)  # the bag starts at 0.4 s, the commands at 1.0 and 1.2 s
    assert BagReader(bag).start_time_ns == 400_000_000
    listener = rclpy.create_node("late_listener", context=ros_context)
    publisher_node = rclpy.create_node("late_replayer", context=ros_context)
    clocks = []
    listener.create_subscription(WrenchStamped, "/robot/torque_cmd", lambda m: None, 10)
    listener.create_subscription(Clock, "/clock", lambda m: clocks.append(m.clock.sec + m.clock.nanosec * 1e-9), 10)
    executor = SingleThreadedExecutor(context=ros_context)
    executor.add_node(listener)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    try:
        report = replay(
            bag, topics=["/robot/torque_cmd"], clock=CLOCK_RATE, node=publisher_node, wait_for_subscribers=10.0
        )
        deadline = time.monotonic() + 30.0
        while not (clocks and clocks[-1] >= 1.1) and time.monotonic() < deadline:
            time.sleep(0.01)
    finally:
        executor.shutdown()
        listener.destroy_node()
        publisher_node.destroy_node()
    assert report.published == {"/robot/torque_cmd": 2}
    assert report.wall_time >= 0.8  # from the bag's start (0.4 s) to the last command (1.2 s), at rate 1
    assert clocks and clocks == sorted(clocks)
    assert clocks[0] < 0.9, clocks[:3]  # the clock ran before the first command (1.0 s), from the bag's start
    assert all(c >= 0.4 for c in clocks)
