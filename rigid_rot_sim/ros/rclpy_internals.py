"""Every use of rclpy's internals in the node, in one module (issue 39): the node loop's seam to rclpy.

The node loop (:mod:`.run_loop`, :mod:`.intake`) waits on the command subscriptions and takes
their messages itself, between its steps, in arrival order (docs/architecture.md, "The node
loop"); rclpy's executors cannot: they take one message per wait and per callback, in their own
order. What that needs and rclpy 7.1.6 (ROS 2 Jazzy, the version installed) offers only inside its
executors is here, each use with the public API it stands in for. None of these has a public
replacement in any rclpy up to 7.1.6; each use can go, from the rclpy version that adds the
API named at it. The rest of the node uses public rclpy only (``Node``, ``Waitable``,
``CallbackGroup``, ``GuardCondition``, ``Timer``, the executors).

Why not an ``rclpy.executors.Executor`` subclass on public API alone: its public surface
(``spin_once``, ``wait_for_ready_callbacks``) hands out one ready callback per wait, so draining
every reader's history in reception order (the no-command-lost figures at 1000/s, benchmarks/
node_loop.py) needs the same private take and wait as here.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from typing import Any, Protocol

from rclpy.callback_groups import CallbackGroup
from rclpy.context import Context
from rclpy.exceptions import InvalidHandle
from rclpy.guard_condition import GuardCondition

# Internal: rclpy's C extension. Missing public API: a Python wait set (rclcpp's rclcpp::WaitSet);
# rclpy's own wait_for_message and executors use this one. Not needed from the rclpy version that
# adds a public ``rclpy.wait_set.WaitSet`` (none up to 7.1.6).
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

# Internal module, public class: the type of ``Node.get_logger()``, for annotations. Missing public API: the
# logger class under a public module (rclpy.logging has none); not needed from the rclpy version that exports it.
from rclpy.impl.rcutils_logger import RcutilsLogger as Logger
from rclpy.node import Node
from rclpy.subscription import Subscription
from rclpy.time_source import CLOCK_TOPIC
from rclpy.timer import Timer

#: ``handler(msg, received_ns)``: one message of a subscription the run loop takes.
Handler = Callable[[Any, int], None]


class _TakenByTheRunLoop(CallbackGroup):
    """A callback group no executor runs: its members are waited on and taken by the run loop.

    Internal behaviour relied on: rclpy's executors skip (and do not wait on) an entity whose group's
    ``can_execute`` is False (``Executor._wait_for_ready_callbacks``, 7.1.6). Missing public API: a
    way to keep a subscription out of every executor (rclcpp's ``automatically_add_to_executor_with_node
    = false``); not needed from the rclpy version that adds it (none up to 7.1.6)."""

    def can_execute(self, entity: Any) -> bool:
        return False

    def beginning_execution(self, entity: Any) -> bool:
        return False

    def ending_execution(self, entity: Any) -> None:
        pass


#: The group of every subscription, guard condition and timer the run loop takes (one instance).
TAKEN_BY_THE_RUN_LOOP = _TakenByTheRunLoop()


def take_all(subscription: Subscription, into: Callable[[Any, dict[str, Any]], None]) -> bool:
    """Hand ``into(msg, info)`` every message ``subscription``'s reader holds, oldest first; False (nothing
    taken) when the subscription was destroyed meanwhile (rclpy's /clock when use_sim_time turns false)."""
    handle = subscription.handle
    # Internal: ``Subscription.handle`` (the C handle) and its ``take_message``, as rclpy's
    # ``Executor._take_subscription`` calls it. Missing public API: a non-blocking take with the
    # message info on ``rclpy.subscription.Subscription`` (rclcpp's ``Subscription::take``); not
    # needed from the rclpy version that adds it (none up to 7.1.6).
    try:
        handle.__enter__()
    except InvalidHandle:
        return False
    try:
        while (got := handle.take_message(subscription.msg_type, subscription.raw)) is not None:
            into(*got)
    finally:
        handle.__exit__(None, None, None)
    return True


def received_ns(info: dict[str, Any]) -> int:
    """The reception time (ns, DDS's) in a message info of :func:`take_all`; now when the middleware gives none."""
    return int(info.get("received_timestamp") or time.time_ns())


@contextmanager
def waiting(
    context: Context, subscriptions: list[Subscription], guard: GuardCondition
) -> Iterator[Callable[[float | None], bool]]:
    """A wait on ``subscriptions`` and ``guard``: ``wait(timeout_s)`` (None: until something arrives) returns
    True when something is ready. The entities stay in use (not destroyable) inside the ``with``."""
    with ExitStack() as stack:
        # Internal: the C handles of the entities and the context, held for the wait set's lifetime, and
        # ``_rclpy.WaitSet`` (see the import). Missing public API: a Python wait set; as above.
        handles = [subscription.handle for subscription in subscriptions]
        guard_handle = guard.handle
        for handle in (*handles, guard_handle, context.handle):
            stack.enter_context(handle)
        wait_set = _rclpy.WaitSet(len(handles), 1, 0, 0, 0, 0, context.handle)

        def wait(timeout: float | None) -> bool:
            wait_set.clear_entities()
            for handle in handles:
                wait_set.add_subscription(handle)
            wait_set.add_guard_condition(guard_handle)
            wait_set.wait(-1 if timeout is None else max(0, int(timeout * 1e9)))
            return bool(wait_set.get_ready_entities("subscription")) or bool(
                wait_set.get_ready_entities("guard_condition")
            )

        yield wait


#: Where a Waitable's entities sit in an executor's wait set: the subscriptions, the guard, the timer.
WaitSetIndices = tuple[list[int], int, int]


def add_to_wait_set(
    wait_set: Any, subscriptions: list[Subscription], guard: GuardCondition, timer: Timer
) -> WaitSetIndices:
    """For ``Waitable.add_to_wait_set``: the subscriptions, the guard condition and the timer.

    Internal: the entities' C handles. ``Waitable`` is public, but it is handed rclpy's C wait set and
    can only add C handles to it (rclpy's own ActionServer does the same). Missing public API: adding
    entities to a Waitable's wait set by their Python objects; none up to 7.1.6."""
    subs = [wait_set.add_subscription(subscription.handle) for subscription in subscriptions]
    return subs, wait_set.add_guard_condition(guard.handle), wait_set.add_timer(timer.handle)


def is_ready(wait_set: Any, indices: WaitSetIndices, timer: Timer) -> bool:
    """For ``Waitable.is_ready``: a command, the wake-up, or the timer's time came (internals as above)."""
    subs, guard, timer_index = indices
    if any(wait_set.is_ready("subscription", i) for i in subs) or wait_set.is_ready("guard_condition", guard):
        return True
    return bool(wait_set.is_ready("timer", timer_index)) and timer.handle.is_timer_ready()


def take_timer(timer: Timer) -> None:
    """For ``Waitable.take_data``: rearm a timer that fired (a timer no executor runs).

    Internal: ``Timer.handle.call_timer`` as rclpy's ``Executor._take_timer`` calls it. Missing public
    API: a timer owned by a Waitable (rclpy's ``Timer`` has no public ``call``); none up to 7.1.6."""
    if timer.handle.is_timer_ready():
        timer.handle.call_timer()


class Adopter(Protocol):
    """Who takes rclpy's /clock subscription once the run loop exists (:class:`.intake.CommandIntake`)."""

    def adopt(self, subscription: Subscription, handler: Handler) -> None: ...


class ClockTakenByTheRunLoop(Node):
    """A Node whose own ``/clock`` subscription (rclpy's TimeSource makes it with ``use_sim_time`` true) is
    taken by the run loop between its turns: its messages (this node's own /clock, at its rate) never
    wake the executor. The node reads no ROS time; the ROS clock still follows /clock.

    Internal behaviour relied on: rclpy's ``TimeSource`` subscribes through ``Node.create_subscription``
    with no callback group (7.1.6). Missing public API: a TimeSource option for the callback group of
    its /clock subscription; not needed from the rclpy version that adds it (none up to 7.1.6)."""

    def __init__(self, name: str, **kwargs: Any) -> None:
        self._clock_subscriptions: list[tuple[Subscription, Handler]] = []
        self._clock_adopter: Adopter | None = None
        super().__init__(name, **kwargs)

    def create_subscription(
        self, msg_type: Any, topic: str, callback: Callable[[Any], None], qos_profile: Any, **kwargs: Any
    ) -> Subscription:
        if topic != CLOCK_TOPIC or kwargs.get("callback_group") is not None:
            return super().create_subscription(msg_type, topic, callback, qos_profile, **kwargs)
        subscription = super().create_subscription(
            msg_type, topic, callback, qos_profile, callback_group=TAKEN_BY_THE_RUN_LOOP, **kwargs
        )

        def handler(msg: Any, received_ns: int) -> None:
            callback(msg)

        self._clock_subscriptions.append((subscription, handler))
        if self._clock_adopter is not None:
            self._clock_adopter.adopt(subscription, handler)
        return subscription

    def hand_clock_to(self, adopter: Adopter | None) -> None:
        """/clock from now on to ``adopter`` (the run loop's intake); None: no run loop, the executor takes it."""
        self._clock_adopter = adopter
        for subscription, handler in self._clock_subscriptions:
            if adopter is not None:
                adopter.adopt(subscription, handler)
            else:
                subscription.callback_group = self.default_callback_group
                self.default_callback_group.add_entity(subscription)


__all__ = [
    "TAKEN_BY_THE_RUN_LOOP",
    "Logger",
    "ClockTakenByTheRunLoop",
    "add_to_wait_set",
    "is_ready",
    "received_ns",
    "take_all",
    "take_timer",
    "waiting",
]
