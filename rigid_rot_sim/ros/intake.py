"""The node's command intake: every command topic, taken by the run loop in arrival order, never by the executor.

Why (issue 27, docs/architecture.md "The node loop"): a command subscription handed to rclpy's
executor competes with the stepping for the executor's turn; under the old two-thread
``MultiThreadedExecutor`` it lost nearly every turn to the 1 ms stepping timer (same mutually
exclusive group, timers yielded first, a refused handler returns without taking), so for long
stretches nothing was taken, and the reader's keep-last history overwrote what arrived beyond
its depth: commands were lost before any callback saw them, silently.

Here a command subscription belongs to :data:`~.rclpy_internals.TAKEN_BY_THE_RUN_LOOP`, a callback
group no executor ever runs (``can_execute`` is False: the executor does not even wait on it). The run
loop (:mod:`rigid_rot_sim.ros.run_loop`) waits on the subscriptions itself and, before and
between its steps, calls :meth:`CommandIntake.drain`: every message each reader holds is taken,
the messages of all topics are handed on in the order DDS received them (the reception
timestamp), each to its topic's handler. What arrives while a slice steps waits in the reader's
history, keep last ``commands.qos_depth`` (reliable; the run loop drains at least every
``run_loop.SLICE_WALL`` of wall time, so the depth holds ``depth / SLICE_WALL`` commands per
second).

Nothing is dropped silently: every message carries its publisher's sequence number, so a gap
(messages the reader's history overwrote when more than ``depth`` arrived between two drains,
or that the publisher's own history overwrote before delivery) is counted and reported, on
``~/rejected`` (one RejectedCommand per gap, with the count in its reason) and in the log.

A new command topic plugs in at one place: :meth:`CommandIntake.subscribe` with the message
type, the topic, its QoS and a handler ``handler(msg, received_ns)``; ``~/torque`` inputs
(:mod:`.inputs`) and ``~/wheel_torque`` (:mod:`.wheel_inputs`) are subscribed that way.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Protocol

from rclpy.guard_condition import GuardCondition
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.subscription import Subscription

from rigid_rot_sim.ros import rclpy_internals
from rigid_rot_sim.ros.rclpy_internals import TAKEN_BY_THE_RUN_LOOP, Handler


class CommandDoor(Protocol):
    """A part of the node's run that takes commands through the intake (:mod:`.parts`): its subscriptions
    and who hears each command as received (the recording); says what it built for the start-up line."""

    subscriptions: list[Subscription]
    listeners: list[Any]

    def describe(self) -> tuple[list[str], list[str]]: ...


#: Publishers told apart per topic (a new one beyond these forgets the oldest).
MAX_STREAMS = 64

#: ``lost(topic, count, why)``: ``count`` commands on ``topic`` never reached the handler.
LostReport = Callable[[str, int, str], None]


def _never_called(msg: Any) -> None:  # the executor never runs a TAKEN_BY_THE_RUN_LOOP member
    raise AssertionError("a command subscription is taken by the run loop, not by an executor")


@dataclass
class Door:
    """One command topic: its subscription, the handler of its messages, the publishers' sequence numbers."""

    subscription: Subscription
    handler: Handler
    topic: str
    depth: int
    #: The last publication sequence number of each publisher seen (publishers are told apart by
    #: their numbering: a message continues the stream it follows most closely).
    streams: list[int] = field(default_factory=list)
    taken: int = 0
    lost: int = 0
    #: Count and report sequence gaps (False for a topic whose keep-last drops are by design: /clock).
    counts_gaps: bool = True

    def gap(self, sequence: int | None) -> int:
        """Messages missing before the one numbered ``sequence`` from its publisher (0: none)."""
        if sequence is None or sequence <= 0:
            return 0
        below = [i for i, last in enumerate(self.streams) if last < sequence]
        if not below:  # a publisher not seen before (or restarted): it starts a stream
            self.streams.append(sequence)
            del self.streams[:-MAX_STREAMS]
            return 0
        i = max(below, key=lambda j: self.streams[j])
        missing = sequence - self.streams[i] - 1
        self.streams[i] = sequence
        return missing


class CommandIntake:
    """The command topics of ``node``, drained in arrival order by the run loop (see the module)."""

    def __init__(self, node: Node, lost: LostReport | None = None) -> None:
        self.node = node
        self.context = node.context
        self.doors: list[Door] = []
        self.report_lost = lost
        self.listeners: list[Callable[[str, Any, int], None]] = []
        #: Wakes the run loop (its wait) from another thread: a service changed the run.
        self.guard = GuardCondition(None, TAKEN_BY_THE_RUN_LOOP, context=self.context)

    @property
    def subscriptions(self) -> list[Subscription]:
        return [door.subscription for door in self.doors]

    def subscribe(self, msg_type: Any, topic: str, handler: Handler, qos: QoSProfile) -> Subscription:
        """A command topic: ``handler(msg, received_ns)`` gets each message, in arrival order, from the run loop."""
        subscription = self.node.create_subscription(
            msg_type, topic, _never_called, qos, callback_group=TAKEN_BY_THE_RUN_LOOP
        )
        self.doors.append(Door(subscription, handler, subscription.topic_name, qos.depth))
        return subscription

    def adopt(self, subscription: Subscription, handler: Handler) -> None:
        """A subscription made elsewhere in :data:`TAKEN_BY_THE_RUN_LOOP` (rclpy's own /clock, with
        ``use_sim_time``): drained with the others, its keep-last drops not counted (not a command)."""
        depth = subscription.qos_profile.depth
        self.doors.append(Door(subscription, handler, subscription.topic_name, depth, counts_gaps=False))

    def wake(self) -> None:
        """Wake the run loop now (thread-safe)."""
        self.guard.trigger()

    def drain(self) -> int:
        """Take every message the readers hold and hand each on, all topics in reception order; how many."""
        pending: list[tuple[int, int, Door, Any]] = []
        for door in list(self.doors):
            taken = missing = 0

            def take(msg: Any, info: dict[str, Any], door: Door = door) -> None:
                nonlocal taken, missing
                taken += 1
                if door.counts_gaps:
                    missing += door.gap(info.get("publication_sequence_number"))
                pending.append((rclpy_internals.received_ns(info), len(pending), door, msg))

            if not rclpy_internals.take_all(door.subscription, take):  # destroyed meanwhile (/clock)
                self.doors.remove(door)
                continue
            door.taken += taken
            if missing:  # a full history overflowed; else a publisher's own history dropped them
                self._lost(door, missing, full=taken >= door.depth)
        if len(self.doors) > 1:
            pending.sort(key=lambda item: (item[0], item[1]))
        for received_ns, _, door, msg in pending:
            door.handler(msg, received_ns)
        return len(pending)

    def losses(self) -> str:
        """How many commands each topic that lost some took and lost ("" when none lost: a bound was never hit)."""
        return "; ".join(f"{d.topic}: {d.lost} lost of {d.taken + d.lost}" for d in self.doors if d.lost)

    def _lost(self, door: Door, count: int, full: bool) -> None:
        door.lost += count
        why = (
            f"{count} command(s) lost before the node could take them: more than the queue depth "
            f"({door.depth}, commands.qos_depth) arrived between two takes (the run stepping, or the process "
            "not running: a busy machine)"
            if full
            else f"{count} command(s) from a publisher never arrived (its own history overwrote them before delivery)"
        )
        if self.report_lost is not None:
            self.report_lost(door.topic, count, why)

    @contextmanager
    def waiting(self) -> Iterator[Callable[[float | None], bool]]:
        """A wait on the command topics and the wake-up, for the run loop: ``wait(timeout_s)`` (None:
        until something arrives) returns True when something is ready. The entities stay in use
        (not destroyable) inside the ``with``."""
        with rclpy_internals.waiting(self.context, self.subscriptions, self.guard) as wait:
            yield wait

    def destroy(self) -> None:
        self.guard.destroy()


__all__ = ["TAKEN_BY_THE_RUN_LOOP", "CommandDoor", "CommandIntake", "Door"]
