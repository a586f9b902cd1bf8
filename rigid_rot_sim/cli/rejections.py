"""What the node said about a command-sending CLI's commands: its ``~/rejected``, watched from outside.

A command that reaches the node may still be refused (a frame the scene does not name, a torque
above ``commands.max_torque``, a stamp lockstep cannot use): the node then publishes a
``rigid_rot_msgs/RejectedCommand`` on ``<node>/rejected`` with the reason. A CLI that only
published would report success; :class:`RejectionWatch` subscribes to the ``~/rejected`` of
every node the graph shows subscribed to the command topic (the graph names each subscriber's
node) and keeps the rejections of this CLI's own commands: those on its topic that echo a
frame_id and a torque it sent. (RejectedCommand carries no sender, so an identical command of
another publisher at the same time would be taken for ours.)

The node also says what it accepted: a ``torque`` event on its live ``~/sim_events`` for each
command it scheduled (:mod:`rigid_rot_sim.ros.sim_events`). The watch subscribes to those too,
volatile (the topic's latched history is of earlier commands), so that a CLI knows when the
node has answered every command it sent (:meth:`RejectionWatch.answered`) instead of listening
for a fixed time.

``rigid-rot torque`` uses it; its module docstring says how long it listens.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from typing import Any

from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import QoSProfile

from rigid_rot_sim.core import limits

__all__ = ["REJECTED_TYPE", "RejectionWatch", "resolve_source", "spin_until", "command_publisher"]

REJECTED_TYPE = "rigid_rot_msgs/msg/RejectedCommand"
EVENTS_TYPE = "diagnostic_msgs/msg/DiagnosticStatus"
#: Most seconds to wait, once the node subscribes, for its ~/rejected to be on the graph and matched.
REJECTED_DISCOVERY = 2.0


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
        #: Fully qualified ~/sim_events topics watched -> their subscription.
        self.events: dict[str, Any] = {}
        #: How many of this CLI's commands the nodes accepted (their ``torque`` events), and sent.
        self.accepted = 0
        self.count = 0

    def discover(self) -> None:
        """Subscribe to the ~/rejected of each node now subscribed to the command topic."""
        from diagnostic_msgs.msg import DiagnosticStatus
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        from rigid_rot_msgs.msg import RejectedCommand  # generated, untyped
        from rigid_rot_sim.ros.qos import REJECTED_QOS

        # volatile: the node's latched history holds earlier commands' events, not ours
        EVENTS_QOS = QoSProfile(
            depth=1000, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE
        )

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
            events = f"{peer}/sim_events"
            if any(p.topic_type == EVENTS_TYPE for p in self.node.get_publishers_info_by_topic(events)):
                self.events[events] = self.node.create_subscription(
                    DiagnosticStatus, events, self._event_listener(info.node_namespace, info.node_name), EVENTS_QOS
                )

    def ready(self) -> bool:
        """Every watched ~/rejected and ~/sim_events is matched with its node's publisher."""
        return all(sub.get_publisher_count() > 0 for sub in (*self.watched.values(), *self.events.values()))

    def sent(self, frame_id: str, torque: Iterable[float]) -> None:
        """Remember a command published (its frame_id and torque, N*m)."""
        self._sent.add((limits.clip_text(frame_id), tuple(float(v) for v in torque)))
        self.count += 1

    def answered(self) -> bool:
        """The nodes accepted or refused every command sent (False when no ~/sim_events is watched)."""
        return bool(self.events) and self.accepted + len(self.rejections) >= self.count

    def _event_listener(self, namespace: str, name: str) -> Callable[[Any], None]:
        return lambda msg: self._event(msg, namespace, name)

    def _event(self, msg: Any, namespace: str, name: str) -> None:
        from rigid_rot_sim.recording.events import EVENT_PREFIX

        if msg.name != f"{EVENT_PREFIX}torque":
            return
        values = {str(kv.key): str(kv.value) for kv in msg.values}
        if resolve_source(values.get("source", ""), namespace, name) != self.topic:
            return
        try:
            torque = tuple(float(values[f"torque_{i}"]) for i in range(3))
        except (KeyError, ValueError):
            return
        if any(torque == sent for _, sent in self._sent):
            self.accepted += 1

    def _listener(self, namespace: str, name: str, peer: str) -> Callable[[Any], None]:
        return lambda msg: self._received(msg, namespace, name, peer)

    def _received(self, msg: Any, namespace: str, name: str, peer: str) -> None:
        if resolve_source(msg.source, namespace, name) != self.topic:
            return
        torque = (float(msg.torque.x), float(msg.torque.y), float(msg.torque.z))
        if (msg.header.frame_id, torque) in self._sent:
            self.rejections.append((peer, msg.reason))


def spin_until(node: Node, condition: Callable[[], bool], until: float) -> bool:
    """Spin ``node`` until ``condition()`` holds (True) or the monotonic time ``until`` (False)."""
    import rclpy

    while not condition():
        left = until - time.monotonic()
        if left <= 0.0:
            return False
        rclpy.spin_once(node, timeout_sec=min(left, 0.05))
    return True


def command_publisher(
    node: Node, watch: RejectionWatch, message_type: type, qos: QoSProfile, wait: float
) -> Publisher | None:
    """The command writer on ``watch.topic``, created once the node's ~/rejected is watched; None when no
    subscriber matched it within ``wait`` s.

    The node's ~/rejected is matched with this CLI's reader before the command writer exists: the node then
    learns of the reader a discovery round before it can take (and refuse) a command. ~/rejected keeps no
    history, so a refusal published before the node had the reader would reach nobody.
    """

    def watching() -> bool:
        watch.discover()
        return bool(watch.watched) and watch.ready()

    deadline = time.monotonic() + wait
    if spin_until(node, lambda: node.count_subscribers(watch.topic) > 0, deadline):
        spin_until(node, watching, time.monotonic() + REJECTED_DISCOVERY)  # a subscriber without ~/rejected: unwatched
    publisher = node.create_publisher(message_type, watch.topic, qos)
    matched = spin_until(node, lambda: publisher.get_subscription_count() > 0, max(deadline, time.monotonic() + 1.0))
    return publisher if matched else None
