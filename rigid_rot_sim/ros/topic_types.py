"""Publishers of another type on the node's command topics, named in the log.

DDS matches a publisher with a subscription only when their types agree: a publisher of
``Vector3Stamped`` on a ``WrenchStamped`` command topic delivers nothing, and neither side
says so. The ROS graph knows every endpoint's type, so :class:`WrongTypeWatch` reads it on a
steady timer (``Node.get_publishers_info_by_topic`` reads the node's local copy of the graph:
no waiting, nothing sent) and warns once per publisher found with another type, naming its
node, its type and the type the topic takes (a publisher whose node the graph does not learn
within ``NAME_GRACE`` s, e.g. a plain DDS participant, is named as such). A publisher that
leaves and comes back is named again.

:class:`RivalPublisherWatch` reads the same graph for another node publishing a topic that
must have one publisher: the node's ``/clock``. Two simulations in two namespaces both publish
``/clock``; every ``use_sim_time`` node then sees two interleaved timelines, its time jumping
back several times a second (a tf2 listener clears its buffer each time), and DDS says nothing.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

from rclpy.clock import Clock
from rclpy.clock_type import ClockType
from rclpy.node import Node
from rclpy.subscription import Subscription

__all__ = ["WATCH_PERIOD", "RivalPublisherWatch", "WrongTypeWatch", "message_type_name"]

#: Wall seconds between two looks at the graph.
WATCH_PERIOD = 1.0
#: Wall seconds to wait for the node name of a publisher the graph shows without one.
NAME_GRACE = 3.0
#: The node name the graph gives an endpoint whose node it does not know (yet).
UNKNOWN_NODE_NAME = "_NODE_NAME_UNKNOWN_"


def _peer_name(info: Any, unnamed_for: float) -> str | None:
    """How to name the node of endpoint ``info``; None while the graph may still learn it.

    An endpoint is on the graph a moment before its node's name (ROS discovery info), so one
    without a name is named as a bare DDS participant only after ``NAME_GRACE`` s.
    """
    if info.node_name != UNKNOWN_NODE_NAME:
        return f"node {info.node_namespace.rstrip('/')}/{info.node_name}"
    return "a DDS participant that names no ROS node" if unnamed_for >= NAME_GRACE else None


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
                peer = _peer_name(info, now - self._unnamed_since.setdefault(key, now))
                if peer is None:
                    continue
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


class RivalPublisherWatch:
    """Warns once per publisher of ``topic`` that belongs to another node (``advice`` ends the line).

    For a topic the node publishes and that must have one publisher (``/clock``). A publisher
    that leaves and comes back is named again. :meth:`check` returns the warnings it logged.
    """

    def __init__(self, node: Node, topic: str, advice: str, period: float = WATCH_PERIOD) -> None:
        self.node = node
        self.topic = node.resolve_topic_name(topic)
        self.advice = advice
        self.logger = node.get_logger()
        self.clock = time.monotonic
        self.named: set[bytes] = set()
        self._unnamed_since: dict[bytes, float] = {}
        self.timer = node.create_timer(period, self.check, clock=Clock(clock_type=ClockType.STEADY_TIME))

    def _ours(self, info: Any) -> bool:
        return bool(info.node_name == self.node.get_name() and info.node_namespace == self.node.get_namespace())

    def check(self) -> list[str]:
        """Look at the graph once; warn about each other publisher not named yet."""
        now = self.clock()
        found: set[bytes] = set()
        warnings: list[str] = []
        for info in self.node.get_publishers_info_by_topic(self.topic):
            if self._ours(info):
                continue
            key = bytes(info.endpoint_gid)
            found.add(key)
            if key in self.named:
                continue
            peer = _peer_name(info, now - self._unnamed_since.setdefault(key, now))
            if peer is None:
                continue
            warnings.append(f"{self.topic}: {peer} publishes it too: {self.advice}")
            self.named.add(key)
        for warning in warnings:
            self.logger.warning(warning)
        self.named &= found
        self._unnamed_since = {key: t for key, t in self._unnamed_since.items() if key in found}
        return warnings
