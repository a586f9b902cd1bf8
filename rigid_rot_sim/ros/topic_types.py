"""Publishers of another type on the node's command topics, named in the log.

DDS matches a publisher with a subscription only when their types agree: a publisher of
``Vector3Stamped`` on a ``WrenchStamped`` command topic delivers nothing, and neither side
says so. The ROS graph knows every endpoint's type, so :class:`WrongTypeWatch` reads it on a
steady timer (``Node.get_publishers_info_by_topic`` reads the node's local copy of the graph:
no waiting, nothing sent) and warns once per publisher found with another type, naming its
node, its type and the type the topic takes. A publisher that leaves and comes back is named
again.
"""

from __future__ import annotations

from collections.abc import Sequence

from rclpy.clock import Clock
from rclpy.clock_type import ClockType
from rclpy.node import Node
from rclpy.subscription import Subscription

__all__ = ["WATCH_PERIOD", "WrongTypeWatch", "message_type_name"]

#: Wall seconds between two looks at the graph.
WATCH_PERIOD = 1.0


def message_type_name(msg_type: type) -> str:
    """``pkg/msg/Type`` of a generated rclpy message class, as the graph names types."""
    return f"{msg_type.__module__.split('.', 1)[0]}/msg/{msg_type.__name__}"


class WrongTypeWatch:
    """Warns about publishers on the topics of ``subscriptions`` whose type differs from theirs.

    No timer when there is no subscription. :meth:`check` returns the warnings it logged.
    """

    def __init__(self, node: Node, subscriptions: Sequence[Subscription], period: float = WATCH_PERIOD) -> None:
        self.node = node
        self.logger = node.get_logger()
        self.expected = {sub.topic_name: message_type_name(sub.msg_type) for sub in subscriptions}
        #: (topic, publisher node, its type) warned about and still on the graph.
        self.named: set[tuple[str, str, str]] = set()
        self.timer = (
            node.create_timer(period, self.check, clock=Clock(clock_type=ClockType.STEADY_TIME))
            if self.expected
            else None
        )

    def check(self) -> list[str]:
        """Look at the graph once; warn about each wrong-type publisher not named yet."""
        found: set[tuple[str, str, str]] = set()
        warnings: list[str] = []
        for topic, expected in self.expected.items():
            for info in self.node.get_publishers_info_by_topic(topic):
                if info.topic_type == expected:
                    continue
                peer = f"{info.node_namespace.rstrip('/')}/{info.node_name}"
                key = (topic, peer, info.topic_type)
                found.add(key)
                if key not in self.named:
                    warnings.append(
                        f"{topic}: a publisher of {info.topic_type} (node {peer}) is on this command topic, which "
                        f"takes {expected}: DDS delivers none of its messages (publish {expected})"
                    )
        for warning in warnings:
            self.logger.warning(warning)
        self.named = found
        return warnings
