"""What the node said about a command-sending CLI's commands: its ``~/rejected``, watched from outside.

A command that reaches the node may still be refused (a frame the scene does not name, a torque
above ``commands.max_torque``, a stamp lockstep cannot use): the node then publishes a
``rigid_rot_msgs/RejectedCommand`` on ``<node>/rejected`` with the reason. A CLI that only
published would report success; :class:`RejectionWatch` subscribes to the ``~/rejected`` of
every node the graph shows subscribed to the command topic (the graph names each subscriber's
node) and keeps the rejections of this CLI's own commands: those on its topic that echo a
frame_id and a torque it sent. (RejectedCommand carries no sender, so an identical command of
another publisher at the same time would be taken for ours.)

``rigid-rot torque`` uses it; its module docstring says how long it listens.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from rclpy.node import Node

from rigid_rot_sim.core import limits

__all__ = ["REJECTED_TYPE", "RejectionWatch", "resolve_source"]

REJECTED_TYPE = "rigid_rot_msgs/msg/RejectedCommand"


def resolve_source(source: str, node_namespace: str, node_name: str) -> str:
    """The fully qualified topic a RejectedCommand's ``source`` names (the node gives its topic input
    as the scene wrote it: ``~/torque``, ``cmd`` or ``/cmd``)."""
    namespace = node_namespace.rstrip("/")
    if source.startswith("~"):
        return f"{namespace}/{node_name}{source[1:]}"
    if source.startswith("/"):
        return source
    return f"{namespace}/{source}"


class RejectionWatch:
    """The rejections of the commands ``node`` sends on ``topic`` (fully qualified).

    Call :meth:`discover` while waiting for the command topic's subscribers, :meth:`ready` to
    know every watched ``~/rejected`` is matched (volatile: a rejection published before is
    lost), :meth:`sent` for each command published, and read :attr:`rejections`.
    """

    def __init__(self, node: Node, topic: str) -> None:
        self.node = node
        self.topic = topic
        #: Fully qualified ~/rejected topics watched -> their subscription.
        self.watched: dict[str, Any] = {}
        #: (frame_id, torque) of every command sent.
        self._sent: set[tuple[str, tuple[float, ...]]] = set()
        #: (node, reason) of each rejection of this CLI's commands, in arrival order.
        self.rejections: list[tuple[str, str]] = []

    def discover(self) -> None:
        """Subscribe to the ~/rejected of each node now subscribed to the command topic."""
        from rigid_rot_msgs.msg import RejectedCommand  # generated, untyped
        from rigid_rot_sim.ros.qos import REJECTED_QOS

        for info in self.node.get_subscriptions_info_by_topic(self.topic):
            peer = f"{info.node_namespace.rstrip('/')}/{info.node_name}"
            rejected = f"{peer}/rejected"
            if rejected in self.watched:
                continue
            if not any(p.topic_type == REJECTED_TYPE for p in self.node.get_publishers_info_by_topic(rejected)):
                continue  # not a rigid_rot_sim node (or its ~/rejected is not on the graph yet)
            self.watched[rejected] = self.node.create_subscription(
                RejectedCommand, rejected, self._listener(info.node_namespace, info.node_name, peer), REJECTED_QOS
            )

    def ready(self) -> bool:
        """Every watched ~/rejected is matched with its node's publisher."""
        return all(sub.get_publisher_count() > 0 for sub in self.watched.values())

    def sent(self, frame_id: str, torque: Iterable[float]) -> None:
        """Remember a command published (its frame_id and torque, N*m)."""
        self._sent.add((limits.clip_text(frame_id), tuple(float(v) for v in torque)))

    def _listener(self, namespace: str, name: str, peer: str) -> Callable[[Any], None]:
        return lambda msg: self._received(msg, namespace, name, peer)

    def _received(self, msg: Any, namespace: str, name: str, peer: str) -> None:
        if resolve_source(msg.source, namespace, name) != self.topic:
            return
        torque = (float(msg.torque.x), float(msg.torque.y), float(msg.torque.z))
        if (msg.header.frame_id, torque) in self._sent:
            self.rejections.append((peer, msg.reason))
