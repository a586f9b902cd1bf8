"""The command intake over real DDS in one process: arrival order across topics, every message taken,
and a history overflow counted and reported, never silent (rigid_rot_sim.ros.intake)."""

from __future__ import annotations

import os
import time

import pytest
import rclpy
from geometry_msgs.msg import Vector3Stamped, WrenchStamped
from rclpy.qos import QoSProfile

from rigid_rot_sim.ros.intake import CommandIntake, Door


@pytest.fixture
def nodes():
    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=int(os.environ["RIGID_ROT_SIM_IN_PROCESS_DOMAIN_ID"]))
    sim = rclpy.create_node("intake_sim", context=ctx)
    peer = rclpy.create_node("intake_peer", context=ctx)
    yield sim, peer
    peer.destroy_node()
    sim.destroy_node()
    rclpy.shutdown(context=ctx)


def _matched(publisher, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while publisher.get_subscription_count() == 0:
        assert time.monotonic() < deadline, "no match"
        time.sleep(0.01)
    time.sleep(0.2)


def _drain_until(intake: CommandIntake, count: int, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    with intake.waiting() as wait:
        while sum(door.taken for door in intake.doors) < count:
            assert time.monotonic() < deadline, f"{sum(d.taken for d in intake.doors)} of {count} taken"
            wait(0.1)
            intake.drain()


def test_every_message_of_every_topic_is_taken_in_arrival_order(nodes):
    sim, peer = nodes
    got: list[tuple[str, int, int]] = []
    intake = CommandIntake(sim)
    intake.subscribe(
        WrenchStamped, "/a", lambda m, ns: got.append(("a", int(m.header.frame_id), ns)), QoSProfile(depth=100)
    )
    intake.subscribe(
        Vector3Stamped, "/b", lambda m, ns: got.append(("b", int(m.header.frame_id), ns)), QoSProfile(depth=100)
    )
    pub_a = peer.create_publisher(WrenchStamped, "/a", 100)
    pub_b = peer.create_publisher(Vector3Stamped, "/b", 100)
    _matched(pub_a)
    _matched(pub_b)
    for i in range(60):  # interleaved, and nothing taken meanwhile: both histories hold them all
        msg = WrenchStamped() if i % 2 == 0 else Vector3Stamped()
        msg.header.frame_id = str(i)
        (pub_a if i % 2 == 0 else pub_b).publish(msg)
        time.sleep(0.001)
    _drain_until(intake, 60)
    assert [i for _, i, _ in got] == list(range(60))  # one drain, two topics, merged in the order received
    assert [ns for _, _, ns in got] == sorted(ns for _, _, ns in got)
    assert all(door.lost == 0 for door in intake.doors)
    intake.destroy()


def test_an_overflow_of_the_depth_is_counted_and_reported(nodes):
    sim, peer = nodes
    reports: list[tuple[str, int, str]] = []
    got: list[int] = []
    intake = CommandIntake(sim, lost=lambda topic, count, why: reports.append((topic, count, why)))
    intake.subscribe(WrenchStamped, "/c", lambda m, ns: got.append(int(m.header.frame_id)), QoSProfile(depth=5))
    publisher = peer.create_publisher(WrenchStamped, "/c", 100)
    _matched(publisher)
    first = WrenchStamped()
    first.header.frame_id = "0"
    publisher.publish(first)
    _drain_until(intake, 1)  # the publisher's numbering is known from here
    for i in range(1, 41):  # 40 more while nobody takes: the reader keeps the last 5
        msg = WrenchStamped()
        msg.header.frame_id = str(i)
        publisher.publish(msg)
    publisher.wait_for_all_acked(rclpy.duration.Duration(seconds=5.0))
    time.sleep(0.2)
    intake.drain()
    assert got == [0, 36, 37, 38, 39, 40]
    assert reports == [("/c", 35, reports[0][2])] and "more than the queue depth (5" in reports[0][2]
    assert intake.doors[0].lost == 35 and intake.doors[0].taken == 6
    intake.destroy()


def test_publishers_are_told_apart_by_their_numbering():
    door = Door(subscription=None, handler=lambda m, ns: None, topic="/t", depth=10)  # type: ignore[arg-type]
    # two publishers interleaved (1, 1, 2, 2, ...): no gap; then one skips two
    assert [door.gap(s) for s in (1, 1, 2, 2, 3, 3)] == [0, 0, 0, 0, 0, 0]
    assert door.gap(6) == 2 and door.gap(4) == 0
