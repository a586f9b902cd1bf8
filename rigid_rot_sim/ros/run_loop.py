"""The node loop: one turn steps the run to the paced time, takes every command, steps what they released.

Design (docs/architecture.md, "The node loop"; issue 27):

* **One turn** (``turn``, :meth:`rigid_rot_sim.ros.node.SceneRun.turn`): step the run up to the step
  due now (at most :data:`SLICE_WALL` of wall time), drain the command topics in arrival order
  (:meth:`~rigid_rot_sim.ros.intake.CommandIntake.drain`; they act from the step due now), and, in
  lockstep, step again when a command came (the turn it answered goes on at once). It returns the
  wall time until the run needs the next turn: the next due output, the end of the run, a lockstep timeout, 0 at
  ``real_time_factor`` 0, or None (paused, finished: only a command or a service wakes it).
* **Waking**: the next turn comes when that time is up, a command arrives (the loop waits on the
  command subscriptions themselves), or a service, parameter change or action changed the run
  (:class:`RunCallbackGroup` wakes the loop after each). Nothing fires for nothing: a paused node
  waits on its inputs, with one look every :data:`POLL_WALL` (SIGINT, a change made by a direct call).
* **Who runs it**: :func:`rigid_rot_sim.ros.node_process.run_until_finished` (``rigid-rot run``, the console
  script) runs :meth:`RunLoop.spin` on the main thread, beside an executor thread that serves the
  services, parameters and actions; neither path waits for the other except for the
  :class:`RunLock` (one holder of the run at a time, a service first). Any other executor that
  spins the node (tests, a composed process) runs the same turns: :class:`RunLoop` is also an
  rclpy ``Waitable`` of the node, with a one-shot steady timer for the next turn.
* **rclpy's internals**: the waits and takes the loop needs beyond rclpy's public API are in
  :mod:`rigid_rot_sim.ros.rclpy_internals`, each use with the public API it stands in for.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.clock import Clock
from rclpy.clock_type import ClockType
from rclpy.node import Node
from rclpy.subscription import Subscription
from rclpy.timer import Timer
from rclpy.waitable import NumberOfEntities, Waitable

from rigid_rot_sim.ros import rclpy_internals
from rigid_rot_sim.ros.intake import CommandIntake
from rigid_rot_sim.ros.rclpy_internals import TAKEN_BY_THE_RUN_LOOP

#: Most wall time (s) a turn steps before the commands are taken again.
SLICE_WALL = 0.002
#: Longest wait (s) of the run loop: SIGINT / SIGTERM are seen within it; the pacer's backlog check.
POLL_WALL = 0.1

Turn = Callable[[], "float | None"]


class RunLock:
    """The run has one holder at a time: the run loop or one executor callback; a waiting callback goes first."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._changed = threading.Condition()
        self._waiting = 0

    def acquire(self) -> None:
        """For an executor callback: wait for the run loop's turn to end."""
        with self._changed:
            self._waiting += 1
        self._lock.acquire()
        with self._changed:
            self._waiting -= 1
            self._changed.notify_all()

    def release(self) -> None:
        self._lock.release()

    @contextmanager
    def for_a_turn(self) -> Iterator[None]:
        """For the run loop: a callback waiting for the run gets it first (Python's lock is not fair)."""
        if self._waiting:
            with self._changed:
                self._changed.wait_for(lambda: self._waiting == 0, timeout=POLL_WALL)
        with self._lock:
            yield


class RunCallbackGroup(MutuallyExclusiveCallbackGroup):
    """The node's default group: its callbacks run one at a time, each holding the :class:`RunLock`,
    and wake the run loop when done (a service or parameter may have paused, stepped, retimed the run)."""

    def __init__(self, lock: RunLock) -> None:
        super().__init__()
        self.lock = lock
        self.wake: Callable[[], None] = lambda: None

    def beginning_execution(self, entity: Any) -> bool:
        if not super().beginning_execution(entity):
            return False
        self.lock.acquire()
        return True

    def ending_execution(self, entity: Any) -> None:
        self.lock.release()
        super().ending_execution(entity)
        if not isinstance(entity, (Subscription, RunLoop)):  # /clock (use_sim_time) changes nothing in the run
            self.wake()


def _not_called() -> None:
    raise AssertionError("the run loop's timer is taken by the RunLoop, never called")


class RunLoop(Waitable):
    """The run's turns for ``node``: :meth:`spin` on a thread of its own, or as a Waitable of any executor."""

    def __init__(self, node: Node, intake: CommandIntake, turn: Turn) -> None:
        super().__init__(node.default_callback_group)
        self.intake = intake
        self.turn = turn
        # one-shot: armed for the next turn by each turn (executor use only); steady, never /clock
        self.timer = Timer(
            _not_called,  # the Waitable takes the timer itself; it is no node's timer
            TAKEN_BY_THE_RUN_LOOP,
            int(POLL_WALL * 1e9),
            Clock(clock_type=ClockType.STEADY_TIME),
            context=node.context,
            autostart=False,
        )
        self._indices: rclpy_internals.WaitSetIndices = ([], 0, 0)
        node.add_waitable(self)

    # ---------------------------------------------------------------- on a thread of its own

    def detach(self) -> None:
        """From now on no executor runs the turns (call before an executor spins the node): :meth:`spin` does."""
        self.callback_group = TAKEN_BY_THE_RUN_LOOP
        self.timer.cancel()

    def spin(self, lock: RunLock, keep_going: Callable[[], bool]) -> None:
        """Turns until ``keep_going()`` is False: wait for the next turn's time, a command or a wake-up."""
        self.detach()
        wait_s: float | None = 0.0
        with self.intake.waiting() as wait:
            while keep_going():
                wait(POLL_WALL if wait_s is None else min(wait_s, POLL_WALL))
                if not keep_going():
                    break
                with lock.for_a_turn():
                    wait_s = self.turn()

    # ---------------------------------------------------------------- as an rclpy Waitable

    def _arm(self, wait_s: float | None) -> None:
        # None (paused, finished) waits POLL_WALL, as spin does: a change made by a direct call is seen
        if wait_s is not None and wait_s <= 0.0:
            self.timer.cancel()
            self.intake.wake()
        else:
            self.timer.timer_period_ns = max(1, int(min(POLL_WALL if wait_s is None else wait_s, POLL_WALL) * 1e9))
            self.timer.reset()

    def get_num_entities(self) -> NumberOfEntities:
        return NumberOfEntities(len(self.intake.doors), 1, 1, 0, 0, 0)

    def add_to_wait_set(self, wait_set: Any) -> None:
        self._indices = rclpy_internals.add_to_wait_set(
            wait_set, self.intake.subscriptions, self.intake.guard, self.timer
        )

    def is_ready(self, wait_set: Any) -> bool:
        return rclpy_internals.is_ready(wait_set, self._indices, self.timer)

    def take_data(self) -> bool:
        rclpy_internals.take_timer(self.timer)
        return True

    async def execute(self, taken_data: Any) -> None:
        self._arm(self.turn())  # the executor holds the run lock (RunCallbackGroup) around this

    def destroy(self) -> None:
        """The timer and the wake-up (idempotent; the subscriptions go with the node)."""
        self.timer.destroy()
        self.intake.destroy()


__all__ = ["POLL_WALL", "SLICE_WALL", "RunCallbackGroup", "RunLock", "RunLoop"]
