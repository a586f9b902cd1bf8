"""Send one actuator command to a running node and report its verdict: the body of ``rigid-rot wheels`` and
``rigid-rot mtb``.

Waits up to ``--wait`` s for the node's subscription (exit 1 on stderr when nobody subscribes), publishes the
command once (reliable, volatile: the node's command QoS), waits for the node to acknowledge it, and listens
``--confirm`` s on the node's ``~/rejected`` (:class:`~rigid_rot_sim.cli.rejections.RejectionWatch`): a refusal
raises ValueError with the node's reason, which the ``rigid-rot`` entry point prints as one line and exit 2.
An actuator's rejection echoes the message's frame_id (empty here) and a zero torque, which is how the watch
tells it is ours. The header stamp is left zero: the command takes effect when the node receives it.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

from rigid_rot_sim.cli.argtypes import nonnegative_number, positive_number
from rigid_rot_sim.cli.ros_args import add_ros_args, rclpy_args

#: Seconds to listen for a refusal after the node acknowledged the command.
DEFAULT_CONFIRM = 1.0


def add_common_arguments(parser: argparse.ArgumentParser, topic: str) -> None:
    """``--topic``, ``--wait``, ``--confirm`` and ``--ros-args``, as ``rigid-rot torque`` has them."""
    parser.add_argument("--topic", default=topic, help=f"command topic (default {topic})")
    parser.add_argument(
        "--wait", type=positive_number, default=5.0, help="seconds to wait for a subscriber (default 5)"
    )
    parser.add_argument(
        "--confirm",
        type=nonnegative_number,
        default=DEFAULT_CONFIRM,
        help=f"seconds to listen to the node's ~/rejected after the command (default {DEFAULT_CONFIRM:g})",
    )
    add_ros_args(parser)


def send(args: argparse.Namespace, node_name: str, message_type: Any, message: Any, what: str) -> int:
    """Publish ``message`` once on ``args.topic``; 0 when delivered and not refused, 1 when nobody subscribes."""
    import rclpy

    from rigid_rot_sim.cli.rejections import RejectionWatch, command_publisher, spin_until
    from rigid_rot_sim.ros.qos import COMMAND_QOS

    rclpy.init(args=rclpy_args(args))
    node = rclpy.create_node(node_name)
    try:
        topic = node.resolve_topic_name(args.topic)
        watch = RejectionWatch(node, topic)

        publisher = command_publisher(node, watch, message_type, COMMAND_QOS, args.wait)
        if publisher is None:
            print(
                f"rigid-rot {args.command}: no subscriber on {topic} after {args.wait:g} s "
                "(is the node running, with this actuator in its scene?)",
                file=sys.stderr,
            )
            return 1
        publisher.publish(message)
        watch.sent("", (0.0, 0.0, 0.0))
        publisher.wait_for_all_acked(rclpy.duration.Duration(seconds=2.0))
        if watch.watched:
            spin_until(node, lambda: bool(watch.rejections), time.monotonic() + args.confirm)
        if watch.rejections:
            peer, reason = watch.rejections[0]
            raise ValueError(f"{peer} rejected the command on {publisher.topic_name}: {reason}")
        unwatched = "" if watch.watched else " (not confirmed: no ~/rejected of the subscriber to watch)"
        print(f"rigid-rot {args.command}: {what} on {publisher.topic_name}{unwatched}")
        return 0
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
