"""``rigid-rot torque X Y Z``: publish torque commands (geometry_msgs/WrenchStamped) to a running node.

    rigid-rot torque 0 0 0.01                       # once, body frame
    rigid-rot torque 0 0 0.01 --duration 2 --rate 50 --frame world
    rigid-rot torque --zero                         # clear: publish a zero torque

The simplest client of the simulation node (ros2cli is not always installed). X Y Z are
the torque in N*m, expressed in ``--frame`` (header.frame_id: the scene's body or world
frame name, default ``base_link``, the REP 105 body frame); the force is zero and the stamp is left zero, so the node
applies each command at the sim time it arrives. With ``--duration S`` the command is
repeated at ``--rate`` Hz (wall clock) for S seconds and followed by a zero torque, which
also keeps inputs with a hold timeout alive meanwhile. Waits up to ``--wait`` s for the
node's subscription first; exit code 1 (message on stderr) when nobody subscribes.

The node may refuse a command it received (a ``--frame`` the scene does not name, a torque
above ``commands.max_torque``): it says so on its ``~/rejected``, which this command watches
(:mod:`.rejections`). A refused command ends it with the node's reason as one line on stderr
and exit code 2 (with ``--duration``, at the first refusal, after a zero torque). Having sent,
it waits until the node has answered every command (accepted, on its live ``~/sim_events``, or
refused), at most ``--confirm`` s (default 1): done within a few hundredths of a second of the
last command, not after a fixed window. A node without ``~/sim_events`` (no ``mcap`` packages)
is listened to for ``--confirm`` s after it acknowledged the last command; a refusal later than
that goes unseen.
``--ros-args`` passes remappings, a namespace or parameters to ROS, as with ``ros2 run``.
"""

from __future__ import annotations

import argparse
import sys
import time

from rigid_rot_sim.cli.argtypes import finite_number, nonnegative_number, positive_number
from rigid_rot_sim.cli.ros_args import add_ros_args, rclpy_args

DEFAULT_TOPIC = "/rigid_rot_sim/torque"
#: Most seconds to wait for the node's answer to the commands (a fixed window without ~/sim_events).
DEFAULT_CONFIRM = 1.0


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "torque", help="publish WrenchStamped torque commands to a running node", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("torque", nargs="*", type=finite_number, metavar="X Y Z", help="torque, N*m (omit with --zero)")
    parser.add_argument(
        "--frame", default="base_link", help="header.frame_id: the scene's body or world frame (default base_link)"
    )
    parser.add_argument("--duration", type=positive_number, help="repeat for this many wall seconds, then send zero")
    parser.add_argument(
        "--rate", type=positive_number, default=20.0, help="repeat rate with --duration, Hz (default 20)"
    )
    parser.add_argument("--topic", default=DEFAULT_TOPIC, help=f"command topic (default {DEFAULT_TOPIC})")
    parser.add_argument("--zero", action="store_true", help="publish a zero torque (clears a held command)")
    parser.add_argument(
        "--wait", type=positive_number, default=5.0, help="seconds to wait for a subscriber (default 5)"
    )
    parser.add_argument(
        "--confirm",
        type=nonnegative_number,
        default=DEFAULT_CONFIRM,
        help=f"most seconds to wait for the node's answer after the last command (default {DEFAULT_CONFIRM:g})",
    )
    add_ros_args(parser)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    if args.zero:
        if args.torque and any(args.torque):
            raise ValueError("--zero takes no torque values")
        torque = (0.0, 0.0, 0.0)
    elif len(args.torque) != 3:
        raise ValueError(f"give three torque components X Y Z (N*m), got {len(args.torque)}")
    else:
        torque = tuple(args.torque)

    import rclpy
    from geometry_msgs.msg import WrenchStamped

    from rigid_rot_sim.conversions import array_to_vector3
    from rigid_rot_sim.ros.qos import COMMAND_QOS

    def message(values) -> WrenchStamped:
        msg = WrenchStamped()
        msg.header.frame_id = args.frame
        msg.wrench.torque = array_to_vector3(values)
        return msg

    from rigid_rot_sim.cli.rejections import RejectionWatch, command_publisher, spin_until

    rclpy.init(args=rclpy_args(args))
    node = rclpy.create_node("rigid_rot_torque")
    try:
        topic = node.resolve_topic_name(args.topic)
        watch = RejectionWatch(node, topic)

        publisher = command_publisher(node, watch, WrenchStamped, COMMAND_QOS, args.wait)
        if publisher is None:
            print(
                f"rigid-rot torque: no subscriber on {topic} after {args.wait:g} s (is the node running?)",
                file=sys.stderr,
            )
            return 1

        def send(values) -> None:
            publisher.publish(message(values))
            watch.sent(args.frame, values)

        sent = 0
        if args.duration is None:
            send(torque)
            sent = 1
        else:
            period = 1.0 / args.rate
            start = time.monotonic()
            while time.monotonic() - start < args.duration and not watch.rejections:
                send(torque)
                sent += 1
                spin_until(node, lambda: bool(watch.rejections), start + min(sent * period, args.duration))
            send((0.0, 0.0, 0.0))
        if watch.events:  # the node's answer to every command: as soon as it is in
            spin_until(node, watch.answered, time.monotonic() + args.confirm)
        else:  # reliable delivery: the node has every command, then a moment for its verdict
            publisher.wait_for_all_acked(rclpy.duration.Duration(seconds=2.0))
            if watch.watched:
                spin_until(node, lambda: bool(watch.rejections), time.monotonic() + args.confirm)
        if watch.rejections:
            peer, reason = watch.rejections[0]
            raise ValueError(
                f"{peer} rejected the command on {publisher.topic_name} "
                f"({len(watch.rejections)} of {sent + (args.duration is not None)} refused): {reason}"
            )
        if not watch.watched:
            unwatched = " (not confirmed: no ~/rejected of the subscriber to watch)"
        elif watch.events and not watch.answered():
            unwatched = f" (the node answered {watch.accepted} of {watch.count} within --confirm {args.confirm:g} s)"
        else:
            unwatched = ""
        print(
            f"rigid-rot torque: {sent} command(s) {list(torque)} N*m in frame {args.frame!r} on {publisher.topic_name}"
            + (", then zero" if args.duration is not None else "")
            + unwatched
        )
        return 0
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
