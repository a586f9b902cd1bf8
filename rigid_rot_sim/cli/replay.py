"""``rigid-rot replay BAG``: republish recorded torque commands to a live node.

The commands go out as recorded (same bytes: header stamps, frames and values), with the
original timing scaled by ``--rate``. ``--topics`` picks topics (default: the recording
node's torque inputs, else every WrenchStamped topic), ``--remap OLD:=NEW`` renames one
(a real robot's command topic onto the simulator's input), ``--clock`` publishes /clock
from the bag's time. The timing is the bag's log time: sim time for the simulator's own
recordings (the default), so a replay runs at the recorded sim pace. ``--ros-args`` passes
remappings, a namespace or parameters to ROS.
"""

from __future__ import annotations

from rigid_rot_sim.cli.ros_args import add_ros_args, rclpy_args


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "replay", help="republish recorded torque commands with their timing", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("bag", metavar="BAG.mcap")
    parser.add_argument("--rate", type=float, default=1.0, help="playback speed factor (default 1.0)")
    parser.add_argument("--topics", nargs="+", metavar="TOPIC", help="recorded topics to replay")
    parser.add_argument("--remap", action="append", default=[], metavar="OLD:=NEW", help="publish OLD on NEW")
    parser.add_argument("--clock", action="store_true", help="also publish /clock from the bag's time")
    parser.add_argument(
        "--wait",
        type=float,
        default=5.0,
        metavar="S",
        help="wait up to S seconds for subscribers before starting (default 5)",
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


def run(args) -> int:
    import rclpy

    from rigid_rot_sim.recording.replay import replay

    remap = _remaps(args.remap)
    rclpy.init(args=rclpy_args(args))
    try:
        report = replay(
            args.bag, rate=args.rate, topics=args.topics, remap=remap, clock=args.clock, wait_for_subscribers=args.wait
        )
    finally:
        rclpy.try_shutdown()
    total = sum(report.published.values())
    topics = ", ".join(f"{topic} ({n})" for topic, n in sorted(report.published.items())) or "none"
    print(
        f"replayed {total} messages in {report.wall_time:.3f} s: {topics}; "
        f"max lateness {report.max_lateness * 1e3:.2f} ms"
    )
    return 0
