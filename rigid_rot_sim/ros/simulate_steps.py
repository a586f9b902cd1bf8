"""``~/simulate_steps``: the standard ``simulation_interfaces/action/SimulateSteps`` action.

Served under the ``simulation_interfaces_namespace`` (``~``: ``~/simulate_steps``; ``/``:
``/simulate_steps``). SimulateSteps.action (1.5.1): "Assuming the simulation is paused, simulate
a finite number of steps and return to paused state. The action returns feedback after each
complete step." A feedback per physics step would cost more than the step itself (a DDS message
and a goal-handle call per 0.5 ms step: 3000 steps took 15.9 s with one per step, against 1.4 s
for 5000 without) and no client reads them at that rate, so the feedback is bounded: after a
complete step, at most :data:`FEEDBACK_RATE` times per second of wall time, and always after the
last step (also the last one before a cancel or an abort), so a client always sees the final
``completed_steps``. A goal is stepped by a timer of the node, in slices of at most
``run.pacing.MAX_TICK_WALL`` of wall time, each made of chunks of at most one feedback period,
so that the executor serves topics, services and cancel requests between slices and the run's
outputs are published as at any other step. The
timer sits in the node's default (mutually exclusive) callback group with every other
callback that touches the simulator; the goal's execute coroutine only waits for the outcome.

Outcomes (``Result.result``):

* ``RESULT_OK``, goal succeeded: every step done; the simulation is still paused.
* ``RESULT_OK``, goal canceled: a cancel request is honoured within one feedback period
  (1 / FEEDBACK_RATE s of wall time); the message says how many steps were done.
* ``RESULT_OPERATION_FAILED``, goal aborted: the simulation was not paused at the start, as
  the .action says (or was resumed, reset to playing, during the goal), ``steps`` was 0, a
  step failed (the reason of the run's failure), or the run reached its duration.

One goal at a time: a second goal while one runs is rejected (its client sees
``accepted == False``). ``~/step`` and the other services keep working between slices.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.clock import Clock
from rclpy.clock_type import ClockType
from rclpy.task import Future

from rigid_rot_sim.run.pacing import MAX_TICK_WALL, MIN_TICK

ACTION_NAME = "~/simulate_steps"
#: Most feedback messages per second of wall time (the last step's is always sent).
FEEDBACK_RATE = 50.0


@dataclass
class _Goal:
    """The goal being stepped: its handle, steps asked for and done, and the outcome to come."""

    handle: Any
    steps: int
    done: int
    outcome: Future
    #: ``done`` at the last feedback sent, and the wall time (monotonic, s) it was sent.
    sent: int = 0
    sent_at: float = -1.0


class SimulateStepsAction:
    """The action server on ``node``; ``services`` is the node's :class:`SimulationServices`."""

    def __init__(
        self, node: Any, services: Any, action_type: Any, ok: int, failed: int, name: str = ACTION_NAME
    ) -> None:
        self.node = node
        self.name = name
        self.services = services
        self.actions = services.actions  # the node's own services (RunServices): report, run
        self.run = services.run
        self.action_type = action_type
        self.ok, self.failed = ok, failed
        self.goal: _Goal | None = None
        self.timer = node.create_timer(MIN_TICK, self.step_slice, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.timer.cancel()  # runs only while a goal is stepped
        self.server = ActionServer(
            node,
            action_type,
            name,
            execute_callback=self.execute,
            goal_callback=self.on_goal,
            cancel_callback=lambda goal_handle: CancelResponse.ACCEPT,
        )

    def on_goal(self, request: Any) -> GoalResponse:
        if self.goal is not None:
            self.node.get_logger().warning(
                f"{self.name}: goal of {request.steps} steps rejected: a goal of {self.goal.steps} steps "
                f"is running ({self.goal.done} done)"
            )
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    async def execute(self, goal_handle: Any) -> Any:
        """Start stepping (or refuse), wait for the outcome; the result says OK or why not."""
        steps = int(goal_handle.request.steps)
        refusal = "another SimulateSteps goal is running" if self.goal is not None else self._refusal(steps)
        if refusal is not None:
            return self._finish(goal_handle, "abort", self.failed, refusal, 0, steps)
        self.services.stepping_started()
        goal = self.goal = _Goal(goal_handle, steps, 0, Future())
        self.timer.reset()
        try:
            end, code, message = await goal.outcome
        finally:
            self.timer.cancel()
            self.goal = None
        return self._finish(goal_handle, end, code, message, goal.done, steps)

    def _refusal(self, steps: int) -> str | None:
        run = self.run
        if steps < 1:
            return "steps must be >= 1"
        if run.finished:
            return "the run reached its duration and is stopping"
        if not run.sim.paused:
            return "stepping needs a paused simulation, it is playing: pause it first (SetSimulationState PAUSED)"
        return None

    def step_slice(self) -> None:
        """Timer: step the goal one step at a time, with a feedback after each, for at most MAX_TICK_WALL."""
        goal = self.goal
        if goal is None or goal.outcome.done():
            self.timer.cancel()
            return
        try:
            self._step_slice(goal)
        except Exception as exc:  # a callback must never raise: the goal ends with the reason
            self.node.get_logger().error(f"{self.name} failed: {exc!r}")
            goal.outcome.set_result(("abort", self.failed, f"internal error: {exc!r}"))
        if goal.outcome.done():
            self.timer.cancel()

    def _step_slice(self, goal: _Goal) -> None:
        run, sim = self.run, self.run.sim
        deadline = time.monotonic() + MAX_TICK_WALL
        period = 1.0 / FEEDBACK_RATE
        while True:
            if goal.handle.is_cancel_requested:
                self._end(goal, "cancel", self.ok, f"canceled after {goal.done} of {goal.steps} steps")
                return
            if not sim.paused or run.finished:
                why = "the run reached its duration" if run.finished else "the simulation was resumed (playing)"
                self._end(goal, "abort", self.failed, f"{why} after {goal.done} of {goal.steps} steps")
                return
            now = time.monotonic()
            chunk_end = min(deadline, max(now, goal.sent_at + period))  # up to the next feedback that is due
            progress = run.run(sim.clock.k + (goal.steps - goal.done), chunk_end)
            self.actions.report(progress)
            goal.done += progress.steps
            if sim.failure is not None:
                self._end(goal, "abort", self.failed, f"stopped after {goal.done} of {goal.steps} steps: {sim.failure}")
                return
            if goal.done >= goal.steps:
                self._end(goal, "succeed", self.ok, "")
                return
            if time.monotonic() - goal.sent_at >= period:
                self._feedback(goal)
            if time.monotonic() >= deadline:
                return

    def _feedback(self, goal: _Goal) -> None:
        """Send the goal's progress (once per value of ``done``)."""
        if goal.done == goal.sent:
            return
        feedback = self.action_type.Feedback()
        feedback.completed_steps = goal.done
        feedback.remaining_steps = goal.steps - goal.done
        goal.handle.publish_feedback(feedback)
        goal.sent, goal.sent_at = goal.done, time.monotonic()

    def _end(self, goal: _Goal, end: str, code: int, message: str) -> None:
        """The last feedback (the steps done, unless already sent), then the outcome."""
        self._feedback(goal)
        goal.outcome.set_result((end, code, message))

    def _finish(self, goal_handle: Any, end: str, code: int, message: str, done: int, steps: int) -> Any:
        getattr(goal_handle, {"succeed": "succeed", "cancel": "canceled", "abort": "abort"}[end])()
        if end != "succeed":
            self.node.get_logger().warning(f"{self.name} ({steps} steps) {end}: {message}")
        result = self.action_type.Result()
        result.result.result = code
        result.result.error_message = message
        return result

    def destroy(self) -> None:
        self.server.destroy()
        self.timer.destroy()
