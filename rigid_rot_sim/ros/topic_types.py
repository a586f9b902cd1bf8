"""Publishers of another type on the node's command topics, named in the log.

DDS matches a publisher with a subscription only when their types agree: a publisher of
``Vector3Stamped`` on a ``WrenchStamped`` command topic delivers nothing, and neither side
says so. The ROS graph knows every endpoint's type, so :class:`WrongTypeWatch` reads it on a
steady timer (``Node.get_publishers_info_by_topic`` reads the node's local copy of the graph:
no waiting, nothing sent) and warns once per publisher found with another type, naming its
node, its type and the type the topic takes (a publisher whose node the graph does not learn
within ``NAME_GRACE`` s, e.g. a plain DDS participant, is named as such). A publisher that
leaves and comes back is named again.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

from rclpy.clock import Clock
from rclpy.clock_type import ClockType
from rclpy.node import Node
from rclpy.subscription import Subscription

__all__ = ["WATCH_PERIOD", "WrongTypeWatch", "message_type_name"]

#: Wall seconds between two looks at the graph.
WATCH_PERIOD = 1.0
#: Wall seconds to wait for the node name of a publisher the graph shows without one.
NAME_GRACE = 3.0
#: The node name the graph gives an endpoint whose node it does not know (yet).
UNKNOWN_NODE_NAME = "_NODE_NAME_UNKNOWN_"


def message_type_name(msg_type: Any) -> str:
    """``pkg/msg/Type`` of a generated rclpy message class, as the graph names types."""
    return f"{msg_type.__module__.split('.', 1)[0]}/msg/{msg_type.__name__}"


class WrongTypeWatch:
    """Warns about publishers on the topics of ``subscriptions`` whose type differs from theirs.

    No timer when there is no subscription. :meth:`check` returns the warnings it logged.
    """

    def __init__(self, node: Node, subscriptions: Sequence[Subscription], period: float = WATCH_PERIOD) -> None:
        self.node = node
        self.logger = node.get_logger()
        self.clock = time.monotonic
        self.expected = {sub.topic_name: message_type_name(sub.msg_type) for sub in subscriptions}
        #: (topic, endpoint gid) of the publishers named and still on the graph.
        self.named: set[tuple[str, bytes]] = set()
        #: (topic, endpoint gid) -> when first seen, of those whose node the graph does not know yet.
        self._unnamed_since: dict[tuple[str, bytes], float] = {}
        self.timer = (
            node.create_timer(period, self.check, clock=Clock(clock_type=ClockType.STEADY_TIME))
            if self.expected
            else None
        )

    def check(self) -> list[str]:
        """Look at the graph once; warn about each wrong-type publisher not named yet."""
        now = self.clock()
        found: set[tuple[str, bytes]] = set()
        warnings: list[str] = []
        for topic, expected in self.expected.items():
            for info in self.node.get_publishers_info_by_topic(topic):
                if info.topic_type == expected:
                    continue
                key = (topic, bytes(info.endpoint_gid))
                found.add(key)
                if key in self.named:
                    continue
                # an endpoint is on the graph a moment before its node's name (ROS discovery info)
                unknown = info.node_name == UNKNOWN_NODE_NAME
                if unknown and now - self._unnamed_since.setdefault(key, now) < NAME_GRACE:
                    continue
                peer = (
                    "a DDS participant that names no ROS node"
                    if unknown
                    else f"node {info.node_namespace.rstrip('/')}/{info.node_name}"
                )
                warnings.append(
                    f"{topic}: a publisher of {info.topic_type} ({peer}) is on this command topic, which "
                    f"takes {expected}: DDS delivers none of its messages (publish {expected})"
                )
                self.named.add(key)
        for warning in warnings:
            self.logger.warning(warning)
        self.named &= found
        self._unnamed_since = {key: t for key, t in self._unnamed_since.items() if key in found}
        return warnings
