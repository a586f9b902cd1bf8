"""WrongTypeWatch reads the graph: a publisher of another type on a command topic is named once
while it stays, and again when it comes back (issue 29)."""

import time

import pytest
import rclpy
from geometry_msgs.msg import Vector3Stamped, WrenchStamped

from rigid_rot_sim.ros.topic_types import WrongTypeWatch, message_type_name

TOPIC = "/typed_test/torque"


@pytest.fixture
def nodes():
    """The watched node and a peer, each in a context (a DDS participant) of its own: one participant
    refuses two types on one topic."""
    contexts = [rclpy.Context(), rclpy.Context()]
    for context in contexts:
        rclpy.init(context=context)
    watched = rclpy.create_node("watched", context=contexts[0])
    peer = rclpy.create_node("peer", namespace="/elsewhere", context=contexts[1])
    try:
        yield watched, peer
    finally:
        watched.destroy_node()
        peer.destroy_node()
        for context in contexts:
            rclpy.try_shutdown(context=context)


def checks_until(watch: WrongTypeWatch, condition, timeout: float = 30.0) -> list[str]:
    """Call ``watch.check()`` until its result satisfies ``condition`` (the graph updates asynchronously)."""
    deadline = time.monotonic() + timeout
    while True:
        warnings = watch.check()
        if condition(warnings):
            return warnings
        assert time.monotonic() < deadline, f"graph never showed it (last check: {warnings}, named: {watch.named})"
        time.sleep(0.05)


def test_message_type_name_is_the_graphs_spelling():
    assert message_type_name(WrenchStamped) == "geometry_msgs/msg/WrenchStamped"


def test_a_wrong_type_publisher_is_named_once_while_it_stays_and_again_when_it_comes_back(nodes):
    watched, peer = nodes
    subscription = watched.create_subscription(WrenchStamped, TOPIC, lambda msg: None, 10)
    watch = WrongTypeWatch(watched, [subscription])
    assert watch.timer is not None and watch.check() == []
    right = watched.create_publisher(WrenchStamped, TOPIC, 10)  # the right type: never named
    wrong = peer.create_publisher(Vector3Stamped, TOPIC, 10)
    warnings = checks_until(watch, bool)
    assert warnings == [
        f"{TOPIC}: a publisher of geometry_msgs/msg/Vector3Stamped (node /elsewhere/peer) is on this command topic, "
        "which takes geometry_msgs/msg/WrenchStamped: DDS delivers none of its messages "
        "(publish geometry_msgs/msg/WrenchStamped)"
    ]
    assert watch.check() == []  # named once while it stays
    peer.destroy_publisher(wrong)
    checks_until(watch, lambda _: not watch.named)
    wrong = peer.create_publisher(Vector3Stamped, TOPIC, 10)
    assert len(checks_until(watch, bool)) == 1  # back: named again
    watched.destroy_publisher(right)


def test_no_command_topic_no_timer(nodes):
    watched, _ = nodes
    watch = WrongTypeWatch(watched, [])
    assert watch.timer is None and watch.check() == []
