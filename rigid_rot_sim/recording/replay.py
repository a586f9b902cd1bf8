"""Replay recorded torque commands into a live node, with their original timing.

The recorded bytes are published as they are (``Publisher.publish`` of serialised CDR),
so header stamps, frames and values reach the node exactly as they were recorded, and a
bag from a real robot drives the simulator like the robot's controller did. Timing
follows the recorded receive times (MCAP log time), scaled by ``rate``: for the node's
own recordings these are sim times (``record_log_time`` ``sim``, the default), so the
replay runs at the recorded sim pace. As ``ros2 bag play`` (rosbag2's player, Jazzy), the
replay's time starts at the bag's start (its first message on any topic, not the first one
replayed): a command recorded 2 s into the bag goes out 2 s / ``rate`` after the start; and
``clock`` (Hz) publishes ``/clock`` from the bag's time, from the bag's start, like ``ros2 bag
play --clock [HZ]`` (whose rate is 40 Hz when given without a value: :data:`CLOCK_RATE`), which
then agrees with the recorded ``/clock``.

By default the topics replayed are the torque inputs the recording node had (its
``rigid_rot_sim`` metadata record), or else every WrenchStamped topic of the bag.
"""

from __future__ import annotations

import importlib
import os
import threading
import time
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import yaml

from rigid_rot_sim.recording.reader import BagReader

TORQUE_TYPES = ("geometry_msgs/msg/WrenchStamped", "geometry_msgs/msg/Vector3Stamped")
#: Hz of wall time: ``ros2 bag play --clock``'s rate when given without a value (ros2bag's ``const=40``).
CLOCK_RATE = 40.0


@dataclass(frozen=True)
class ReplayReport:
    """What :func:`replay` published: messages per (output) topic, wall time, worst lateness."""

    published: Mapping[str, int]
    wall_time: float
    max_lateness: float


def message_class(type_name: str) -> type:
    """The generated rclpy class of ``pkg/msg/Type`` (ImportError if not installed)."""
    package, _, name = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


def qos_from_metadata(offered_qos_profiles: str) -> Any:
    """An rclpy QoSProfile from a recorded ``offered_qos_profiles`` string (integer or string form)."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    profiles = yaml.safe_load(offered_qos_profiles) if offered_qos_profiles else None
    if not profiles:
        return QoSProfile(depth=10)
    first = profiles[0]

    def policy(enum: Any, value: Any, default: Any) -> Any:
        try:
            return enum(value) if isinstance(value, int) else enum[str(value).upper()]
        except (KeyError, ValueError):
            return default

    history = policy(HistoryPolicy, first.get("history"), HistoryPolicy.KEEP_LAST)
    if history not in (HistoryPolicy.KEEP_LAST, HistoryPolicy.KEEP_ALL):
        history = HistoryPolicy.KEEP_LAST
    return QoSProfile(
        history=history,
        depth=max(int(first.get("depth") or 10), 1),
        reliability=policy(ReliabilityPolicy, first.get("reliability"), ReliabilityPolicy.RELIABLE),
        durability=policy(DurabilityPolicy, first.get("durability"), DurabilityPolicy.VOLATILE),
    )


def select_topics(reader: BagReader, topics: Iterable[str] | None = None) -> list[str]:
    """The topics to replay: ``topics`` if given (each must be in the bag), else the torque inputs."""
    if topics:
        chosen = list(topics)
        missing = [t for t in chosen if t not in reader.topics]
        if missing:
            raise ValueError(f"topic(s) {missing} not in {reader.path} (it has {sorted(reader.topics)})")
        return chosen
    roles = reader.metadata.get("rigid_rot_sim", {})
    recorded_inputs = [topic for role, topic in roles.items() if role == "torque" or role.startswith("torque:")]
    if recorded_inputs:
        return sorted(set(recorded_inputs))
    return sorted(name for name, t in reader.topics.items() if t.type_name == TORQUE_TYPES[0])


def replay(
    path: str | os.PathLike[str],
    *,
    rate: float = 1.0,
    topics: Iterable[str] | None = None,
    remap: Mapping[str, str] | None = None,
    clock: float = 0.0,
    wait_for_subscribers: float = 5.0,
    node: Any = None,
    stop: threading.Event | None = None,
) -> ReplayReport:
    """Publish the recorded messages of ``topics`` with their recorded timing / ``rate``.

    ``node`` is an rclpy node to publish from (rclpy must be initialised); without one a
    node ``rigid_rot_replay`` is created in the default context and destroyed after.
    Before the first message, waits up to ``wait_for_subscribers`` s for every publisher
    to be matched (discovery takes a moment; messages published before it are lost).
    The replay's time starts at the bag's start; ``clock`` > 0: ``/clock`` at that many Hz
    of wall time. ``stop`` ends the replay early when set.
    """
    if not (rate > 0.0 and rate < float("inf")):
        raise ValueError(f"rate must be finite and > 0, got {rate}")
    if not (clock >= 0.0 and clock < float("inf")):
        raise ValueError(f"clock must be a finite rate >= 0 Hz, got {clock}")
    reader = BagReader(path)
    chosen = select_topics(reader, topics)
    remap = dict(remap or {})
    own_node = node is None
    if own_node:
        from rclpy.node import Node

        node = Node("rigid_rot_replay")
    stop = stop or threading.Event()
    publishers: dict[str, Any] = {}
    clock_thread = None
    try:
        for topic in chosen:
            info = reader.topics[topic]
            publishers[topic] = node.create_publisher(
                message_class(info.type_name),
                remap.get(topic, topic),
                qos_from_metadata(info.channel_metadata.get("offered_qos_profiles", "")),
            )
        deadline = time.monotonic() + wait_for_subscribers
        while time.monotonic() < deadline and not all(p.get_subscription_count() > 0 for p in publishers.values()):
            stop.wait(0.05)
        messages = list(reader.messages(chosen))
        published: Counter[str] = Counter()
        if not messages:
            return ReplayReport({}, 0.0, 0.0)
        bag_start = reader.start_time_ns
        first_ns = messages[0].log_time_ns if bag_start is None else min(bag_start, messages[0].log_time_ns)
        start = time.monotonic()
        if clock > 0.0:
            clock_thread = _start_clock(node, first_ns, start, rate, 1.0 / clock, stop)
        lateness = 0.0
        for message in messages:
            target = start + (message.log_time_ns - first_ns) / 1e9 / rate
            delay = target - time.monotonic()
            if delay > 0.0 and stop.wait(delay):
                break
            if stop.is_set():
                break
            publishers[message.topic].publish(message.data)
            published[remap.get(message.topic, message.topic)] += 1
            lateness = max(lateness, time.monotonic() - target)
        elapsed = time.monotonic() - start
        _wait_until_delivered(publishers.values())
        return ReplayReport(dict(published), elapsed, lateness)
    finally:
        stop.set()
        if clock_thread is not None:
            clock_thread.join(timeout=2.0)
        if own_node:
            node.destroy_node()


def _wait_until_delivered(publishers: Any, timeout_s: float = 5.0) -> None:
    """Block until reliable subscribers acknowledged every message, so that a replay that
    ends right after its last publish does not tear the node down with it still in flight."""
    from rclpy.duration import Duration

    for publisher in publishers:
        publisher.wait_for_all_acked(Duration(seconds=timeout_s))


def _start_clock(
    node: Any, first_ns: int, start: float, rate: float, period: float, stop: threading.Event
) -> threading.Thread:
    from rosgraph_msgs.msg import Clock

    publisher = node.create_publisher(Clock, "/clock", 10)

    def run() -> None:
        message = Clock()
        while not stop.is_set():
            now_ns = first_ns + int((time.monotonic() - start) * rate * 1e9)
            message.clock.sec, message.clock.nanosec = divmod(now_ns, 1_000_000_000)
            publisher.publish(message)
            stop.wait(period)

    thread = threading.Thread(target=run, name="replay-clock", daemon=True)
    thread.start()
    return thread
