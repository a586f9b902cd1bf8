"""``~/simulate_steps``: the standard ``simulation_interfaces/action/SimulateSteps`` action.

SimulateSteps.action (1.5.1): "Assuming the simulation is paused, simulate a finite number of
steps and return to paused state. The action returns feedback after each complete step."
A goal is stepped by a timer of the node, in slices of at most ``run.pacing.MAX_TICK_WALL``
of wall time, one physics step at a time with a feedback (``completed_steps``,
``remaining_steps``) after each, so that the executor serves topics, services and cancel
requests between slices and the run's outputs are published as at any other step. The
timer sits in the node's default (mutually exclusive) callback group with every other
callback that touches the simulator; the goal's execute coroutine only waits for the outcome.

Outcomes (``Result.result``):

* ``RESULT_OK``, goal succeeded: every step done; the simulation is still paused.
* ``RESULT_OK``, goal canceled: a cancel request is honoured before the next step; the
  message says how many steps were done.
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


@dataclass
class _Goal:
    """The goal being stepped: its handle, steps asked for and done, and the outcome to come."""

    handle: Any
    steps: int
    done: int
    outcome: Future


class SimulateStepsAction:
    """The action server on ``node``; ``services`` is the node's :class:`SimulationServices`."""

    def __init__(self, node: Any, services: Any, action_type: Any, ok: int, failed: int) -> None:
        self.node = node
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
            ACTION_NAME,
            execute_callback=self.execute,
            goal_callback=self.on_goal,
            cancel_callback=lambda goal_handle: CancelResponse.ACCEPT,
        )

    def on_goal(self, request: Any) -> GoalResponse:
        if self.goal is not None:
            self.node.get_logger().warning(
                f"{ACTION_NAME}: goal of {request.steps} steps rejected: a goal of {self.goal.steps} steps "
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
            self.node.get_logger().error(f"{ACTION_NAME} failed: {exc!r}")
            goal.outcome.set_result(("abort", self.failed, f"internal error: {exc!r}"))
        if goal.outcome.done():
            self.timer.cancel()

    def _step_slice(self, goal: _Goal) -> None:
        run, sim = self.run, self.run.sim
        feedback = self.action_type.Feedback()
        deadline = time.monotonic() + MAX_TICK_WALL
        while True:
            if goal.handle.is_cancel_requested:
                goal.outcome.set_result(("cancel", self.ok, f"canceled after {goal.done} of {goal.steps} steps"))
                return
            if not sim.paused or run.finished:
                why = "the run reached its duration" if run.finished else "the simulation was resumed (playing)"
                goal.outcome.set_result(("abort", self.failed, f"{why} after {goal.done} of {goal.steps} steps"))
                return
            progress = run.run(sim.step_index + 1, None)
            self.actions.report(progress)
            goal.done += progress.steps
            if sim.failure is not None:
                goal.outcome.set_result(
                    ("abort", self.failed, f"stopped after {goal.done} of {goal.steps} steps: {sim.failure}")
                )
                return
            if progress.steps:
                feedback.completed_steps = goal.done
                feedback.remaining_steps = goal.steps - goal.done
                goal.handle.publish_feedback(feedback)
            if goal.done >= goal.steps:
                goal.outcome.set_result(("succeed", self.ok, ""))
                return
            if time.monotonic() >= deadline:
                return

    def _finish(self, goal_handle: Any, end: str, code: int, message: str, done: int, steps: int) -> Any:
        getattr(goal_handle, {"succeed": "succeed", "cancel": "canceled", "abort": "abort"}[end])()
        if end != "succeed":
            self.node.get_logger().warning(f"{ACTION_NAME} ({steps} steps) {end}: {message}")
        result = self.action_type.Result()
        result.result.result = code
        result.result.error_message = message
        return result

    def destroy(self) -> None:
        self.server.destroy()
        self.timer.destroy()
