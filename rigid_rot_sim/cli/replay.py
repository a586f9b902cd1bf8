"""``rigid-rot replay BAG``: republish recorded torque commands to a live node.

The commands go out as recorded (same bytes: header stamps, frames and values), with the
original timing scaled by ``--rate``. ``--topics`` picks topics (default: the recording
node's torque inputs, else every WrenchStamped topic), ``--remap OLD:=NEW`` renames one
(a real robot's command topic onto the simulator's input), ``--clock [HZ]`` publishes /clock
from the bag's time (40 Hz without a value). The timing is the bag's log time, from the bag's
start, as ``ros2 bag play`` times it: sim time for the simulator's own recordings (the
default), so a replay runs at the recorded sim pace. ``--ros-args`` passes
remappings, a namespace or parameters to ROS.

Like ``rigid-rot torque``, it watches the ``~/rejected`` of the nodes it commands
(:mod:`.rejections`) and listens ``--confirm`` s after the last command was acknowledged: a
replayed command the node refuses makes the replay, once run to its end, report the node's
reason (the first one) as one line on stderr, exit code 2.
"""

from __future__ import annotations

import threading
import time
from typing import Any

from rigid_rot_sim.cli.argtypes import nonnegative_number
from rigid_rot_sim.cli.ros_args import add_ros_args, rclpy_args
from rigid_rot_sim.cli.torque import DEFAULT_CONFIRM
from rigid_rot_sim.recording.replay import CLOCK_RATE

#: A command as the node echoes it on ~/rejected: frame_id and torque (N*m).
Command = tuple[str, tuple[float, float, float]]


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "replay", help="republish recorded torque commands with their timing", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("bag", metavar="BAG.mcap")
    parser.add_argument("--rate", type=float, default=1.0, help="playback speed factor (default 1.0)")
    parser.add_argument("--topics", nargs="+", metavar="TOPIC", help="recorded topics to replay")
    parser.add_argument("--remap", action="append", default=[], metavar="OLD:=NEW", help="publish OLD on NEW")
    parser.add_argument(
        "--clock",
        type=nonnegative_number,
        nargs="?",
        const=CLOCK_RATE,
        default=0.0,
        metavar="HZ",
        help=f"also publish /clock from the bag's time, from its start, at HZ (default {CLOCK_RATE:g}, "
        "as ros2 bag play --clock)",
    )
    parser.add_argument(
        "--wait",
        type=float,
        default=5.0,
        metavar="S",
        help="wait up to S seconds for subscribers before starting (default 5)",
    )
    parser.add_argument(
        "--confirm",
        type=nonnegative_number,
        default=DEFAULT_CONFIRM,
        help=f"seconds to listen to the nodes' ~/rejected after the last command (default {DEFAULT_CONFIRM:g})",
    )
    add_ros_args(parser)
    parser.set_defaults(handler=run)


def _remaps(items: list[str]) -> dict[str, str]:
    remap = {}
    for item in items:
        old, sep, new = item.partition(":=")
        if not sep or not old or not new:
            raise ValueError(f"--remap must look like OLD:=NEW, got {item!r}")
        remap[old] = new
    return remap


def _commands(bag: str, topics: list[str] | None) -> dict[str, list[Command]]:
    """(frame_id, torque) of every command the replay publishes, by recorded topic."""
    from rigid_rot_sim.recording.reader import BagReader
    from rigid_rot_sim.recording.replay import select_topics

    reader = BagReader(bag)
    chosen = select_topics(reader, topics)
    commands: dict[str, list[Command]] = {topic: [] for topic in chosen}
    for message, decoded in reader.decoded(chosen):
        vector = decoded.wrench.torque if hasattr(decoded, "wrench") else getattr(decoded, "vector", None)
        if vector is not None:
            commands[message.topic].append((decoded.header.frame_id, (vector.x, vector.y, vector.z)))
    return commands


def _watch(node: Any, commands: dict[str, list[Command]], remap: dict[str, str], wait: float) -> list[Any]:
    """A RejectionWatch per replayed topic, watching once its subscribers' ~/rejected are matched
    (at most ``wait`` s for subscribers, then ``REJECTED_DISCOVERY`` s for their ~/rejected)."""
    from rigid_rot_sim.cli.rejections import REJECTED_DISCOVERY, RejectionWatch

    watches = []
    for topic, sent in commands.items():
        watch = RejectionWatch(node, node.resolve_topic_name(remap.get(topic, topic)))
        for frame_id, torque in sent:
            watch.sent(frame_id, torque)
        watches.append(watch)
    deadline = time.monotonic() + wait
    while time.monotonic() < deadline and not all(node.get_subscriptions_info_by_topic(w.topic) for w in watches):
        time.sleep(0.05)
    deadline = time.monotonic() + REJECTED_DISCOVERY
    while time.monotonic() < deadline:
        for watch in watches:
            watch.discover()
        if all(watch.watched and watch.ready() for watch in watches):
            break
        time.sleep(0.05)
    return watches


def run(args) -> int:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from rigid_rot_sim.recording.replay import replay

    remap = _remaps(args.remap)
    commands = _commands(args.bag, args.topics)
    rclpy.init(args=rclpy_args(args))
    node = rclpy.create_node("rigid_rot_replay")
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    # the watches' subscriptions are served here while the replay publishes from this thread
    spinning = threading.Thread(target=executor.spin, name="rejections", daemon=True)
    spinning.start()
    try:
        watches = _watch(node, commands, remap, args.wait)
        report = replay(
            args.bag,
            rate=args.rate,
            topics=args.topics,
            remap=remap,
            clock=args.clock,
            wait_for_subscribers=args.wait,
            node=node,
        )
        deadline = time.monotonic() + (args.confirm if any(w.watched for w in watches) else 0.0)
        while time.monotonic() < deadline and not any(w.rejections for w in watches):
            time.sleep(0.02)
    finally:
        executor.shutdown()
        spinning.join(timeout=2.0)
        node.destroy_node()
        rclpy.try_shutdown()
    total = sum(report.published.values())
    refused = [(watch.topic, *rejection) for watch in watches for rejection in watch.rejections]
    if refused:
        topic, peer, reason = refused[0]
        raise ValueError(
            f"{peer} rejected {len(refused)} of the {total} replayed commands (first on {topic}): {reason}"
        )
    topics = ", ".join(f"{topic} ({n})" for topic, n in sorted(report.published.items())) or "none"
    print(
        f"replayed {total} messages in {report.wall_time:.3f} s: {topics}; "
        f"max lateness {report.max_lateness * 1e3:.2f} ms"
    )
    return 0
