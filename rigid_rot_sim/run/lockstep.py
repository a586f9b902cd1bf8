"""Lockstep: the run waits at every controller turn for the commands that answer it. No ROS.

Contract (the scene's ``lockstep`` section, :class:`~rigid_rot_sim.scene.scene.LockstepSpec`):
turn k sits on step boundary ``k * n`` (``n = period / dt`` steps, so ``t_k = k * period``
from t_0 = 0). When the run reaches it, the outputs due there are published (the state
outputs are due exactly at the turns: :data:`TURN_OUTPUTS`), then the run waits until every
input of ``inputs`` has delivered one command stamped exactly ``t_k`` (compared in integer
nanoseconds, the resolution of a header stamp). Those commands act from t_k (their stamp is
their effective time), and the run advances to turn k + 1, no faster than the pacer allows
(real_time_factor 0: as soon as the last answer is in). A command on a lockstep input with any
other stamp, or a second one for the same turn, is rejected with the reason
(:meth:`Lockstep.admit`, the Simulator's command gate). After ``timeout`` s of wall time
without every answer: ``pause`` pauses the run with the reason, ``hold`` goes on to the next
turn with what each input holds.

How the other controls interact with turns:

* an unanswered turn publishes its state outputs again every ``RESEND_WALL`` s (a state sent
  before the controller's subscription matched is lost); a second answer is rejected;
* pause: the open turn stays open (commands for it are still accepted); the timeout clock
  restarts when the run resumes;
* step (while paused): advances as asked, through turns without waiting; landing on a
  turn boundary opens that turn;
* reset, set_state: the open turn closes (its state is gone); the run goes on from the new
  state, which the service publishes: at a turn boundary that turn opens again and waits
  for answers to the new state (same stamp).

States never depend on the wall clock: a turn's commands always act at t_k, and the run
never passes t_{k+1} without them (or without the timeout's decision, which is recorded).

>>> from types import SimpleNamespace as NS
>>> sim = NS(clock=NS(k=0, t=0.0, dt=0.01), paused=False)
>>> spec = NS(period=0.02, inputs=("~/torque",), timeout=1.0, on_timeout="pause")
>>> turns = Lockstep(spec, sim, clock=lambda: 0.0)
>>> turns.period_steps, turns.next_turn_step()
(2, 2)
"""

from __future__ import annotations

import enum
import math
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rigid_rot_sim.core.steps import whole_steps
from rigid_rot_sim.run.commands import CommandRejected
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.run.pacing import MAX_TICK_WALL, Progress

if TYPE_CHECKING:  # annotations only
    from rigid_rot_sim.run.pacing import RunDriver
    from rigid_rot_sim.run.simulator import Simulator

__all__ = ["Decision", "Lockstep", "TURN_OUTPUTS", "period_steps", "stamp_ns"]

#: The outputs that carry the body's state: in lockstep each is published exactly once per turn,
#: at t_k (its rate is replaced by the turn rate). /tf, /clock keep their rates.
TURN_OUTPUTS = ("state", "orientation", "angular_velocity", "angular_momentum", "top_state", "imu", "odom")


#: Wall seconds after which an unanswered turn publishes its state outputs again (same stamp, same
#: state): a state published before the controller's subscription was matched is lost (volatile
#: QoS), and the turn would wait for an answer to a message never received.
RESEND_WALL = 0.5


class Decision(enum.Enum):
    """What an open turn comes to at a tick."""

    WAIT = "wait"  # answers missing, time left
    RESEND = "resend"  # nothing answered for RESEND_WALL: publish the turn's state outputs again
    RELEASE = "release"  # every input answered: go on to the next turn
    HOLD = "hold"  # timed out, on_timeout hold: go on with what the inputs hold
    PAUSE = "pause"  # timed out, on_timeout pause


def stamp_ns(seconds: float) -> int:
    """A time (s) as the integer nanoseconds of its header stamp (as the outputs round it)."""
    return int(round(float(seconds) * 1e9))


def period_steps(period: float, dt: float) -> int:
    """Whole steps of ``dt`` in ``period`` (s); ValueError when the period is not a whole number of steps."""
    n = whole_steps(period, dt)
    if n is None:
        raise ValueError(f"lockstep.period {period:g} s is not a whole number of steps of dt {dt:g} s")
    return n


class Lockstep(SimulationObserver):
    """The turns of ``sim`` under ``spec`` (period s, inputs, timeout s of wall time, on_timeout).

    ``clock`` returns wall seconds (monotonic; a fake one in tests). Add it as an observer of
    the simulator (reset / set_state close the open turn) and set ``sim.command_gate`` to
    :meth:`admit`.
    """

    def __init__(self, spec: Any, sim: Simulator, clock: Callable[[], float] = time.monotonic) -> None:
        self.sim = sim
        self.spec = spec
        self.period_steps = period_steps(spec.period, sim.clock.dt)
        self.inputs = tuple(spec.inputs)
        self.timeout = float(spec.timeout)
        self.on_timeout = spec.on_timeout
        self.clock = clock
        #: Step of the open turn (None: no turn open), the inputs that answered it, and since when it waits.
        self.open_step: int | None = None
        self.answered: set[str] = set()
        self.waiting_since = self.sent_at = 0.0
        self._was_paused = False
        self._done_step: int | None = None  # the boundary whose turn was finished (not opened again)
        #: Turns completed, and those that timed out (counters for the logs and the benchmark).
        self.turns = 0
        self.timeouts = 0
        self.resends = 0
        self.first_released = 0.0  # wall time the first turn was released

    def summary(self) -> str:
        """Turns done and their pace since the first was released (for the log at the end of a run)."""
        wall = self.clock() - self.first_released
        pace = ""
        if wall > 0:
            pace = f", {self.turns / wall:.0f} turns/s, {self.turns * self.spec.period / wall:.1f}x real time"
        return (
            f"lockstep: {self.turns} turns in {wall:.3f} s of wall time since the first{pace}; "
            f"{self.timeouts} timed out, {self.resends} states sent again"
        )

    # ------------------------------------------------------------------ turns

    def next_turn_step(self) -> int:
        """The first turn boundary after the current step."""
        n = self.period_steps
        return (self.sim.clock.k // n + 1) * n

    def at_turn_boundary(self) -> bool:
        return self.sim.clock.k % self.period_steps == 0

    def _sync(self) -> None:
        """Start the bookkeeping of the turn the run stands on (once per turn; keeps early answers)."""
        if self.open_step != self.sim.clock.k:
            self.open_step = self.sim.clock.k
            self.answered = set()
            self.waiting_since = self.sent_at = self.clock()

    def close_turn(self) -> None:
        """Forget the open turn (reset, set_state): the boundary the run stands on opens anew."""
        self.open_step = None
        self.answered = set()
        self._done_step = None

    @property
    def waiting(self) -> bool:
        """The run stands on a turn boundary whose turn is not done: it waits for answers."""
        sim = self.sim
        return self.at_turn_boundary() and sim.clock.k != self._done_step and sim.failure is None

    def missing(self) -> list[str]:
        """The inputs that have not answered the open turn yet."""
        return [name for name in self.inputs if name not in self.answered]

    def decide(self) -> Decision:
        """What the open turn comes to now (call only while :attr:`waiting`)."""
        now = self.clock()
        if self.sim.paused:
            self._was_paused = True
        else:
            if self._was_paused:  # resumed: the timeout counts from now
                self._was_paused = False
                self.waiting_since = now
            if not self.missing():
                return Decision.RELEASE
            if now - self.waiting_since >= self.timeout:
                return Decision.PAUSE if self.on_timeout == "pause" else Decision.HOLD
        if not self.answered and now - self.sent_at >= min(RESEND_WALL, self.timeout / 4):
            self.sent_at = now  # also while paused: a controller may answer a paused turn
            return Decision.RESEND
        return Decision.WAIT

    def timeout_reason(self) -> str:
        """Why the open turn timed out (for ~/sim_events, the log and Simulator.fail)."""
        t = self.sim.clock.t
        return (
            f"lockstep: no command stamped {t:.9g} s (turn {self.sim.clock.k // self.period_steps}) on "
            f"{', '.join(self.missing())} within the timeout of {self.timeout:g} s of wall time"
        )

    def finish_turn(self) -> None:
        """The open turn is done (answered or held): the run may go on."""
        if self.turns == 0:
            self.first_released = self.clock()
        self.turns += 1
        self._done_step = self.sim.clock.k
        self.open_step = None
        self.answered = set()

    def next_decision(self) -> float:
        """Wall time (s) until the open turn's next decision (timeout or resend) is due (call while waiting)."""
        now = self.clock()
        due = [self.sent_at + min(RESEND_WALL, self.timeout / 4)] if not self.answered else []
        if not self.sim.paused:
            due.append(self.waiting_since + self.timeout)
        return max(0.0, min(due, default=now + RESEND_WALL) - now)

    def tick(self, run: RunDriver, budget: float = MAX_TICK_WALL) -> Progress:
        """One tick of a lockstep run (the node's timer, or as soon as a turn is answered).

        Opens the turn the run stands on, decides an open one (:meth:`decide`), and steps a
        released run towards the next turn, paced by ``run.pacer``, for at most
        ``MAX_TICK_WALL`` of wall time. Never waits: a turn still waiting returns at once.
        """
        sim = self.sim
        if run.finished:
            return Progress()
        note = None
        if self.waiting:
            self._sync()
            decision = self.decide()
            if decision is Decision.RESEND:
                self.resends += 1
                snapshot = sim.snapshot()
                names = [name for name in TURN_OUTPUTS if name in run.schedule.periods]
                for observer in run.observers:
                    observer.outputs_due(sim.clock.k, snapshot, names)
                return Progress()
            if decision is Decision.WAIT:
                return Progress()
            if decision is not Decision.RELEASE:
                self.timeouts += 1
                note = self.timeout_reason()
                action = "paused (~/pause data=false resumes the turn)" if decision is Decision.PAUSE else "holding"
                for observer in sim.observers:
                    observer.lockstep_timeout(sim.clock.k, note, decision.value)
                note = f"{note}: {action}"
                if decision is Decision.PAUSE:
                    sim.pause(True)
                    self._was_paused = True  # on resume the turn waits a whole timeout again
                    return Progress(lockstep_timeout=note)
            self.finish_turn()
        if sim.paused:
            return Progress(lockstep_timeout=note)
        now = run.clock()
        target, _ = run.pacer.target_step(sim, now)  # waiting for a controller is not falling behind
        stop = self.next_turn_step() if target is None else min(target, self.next_turn_step())
        progress = run.run(stop, now + budget)
        progress.lockstep_timeout = note
        if self.waiting:
            self._sync()  # the timeout counts from the publication of the turn's state
        return progress

    # ------------------------------------------------------------------ the command gate

    def admit(self, source: str, stamp: float | None) -> None:
        """The Simulator's command gate: CommandRejected unless ``source`` answers the open turn now.

        Inputs not listed in ``inputs`` pass. A listed input's command must carry the stamp of
        the open turn's state (t_k) and be its first for that turn.
        """
        if source not in self.inputs:
            return
        t = self.sim.clock.t
        k = self.sim.clock.k
        if not self.waiting:
            raise CommandRejected(
                source,
                f"lockstep: no turn is open at t = {t:.9g} s (turns every {self.spec.period:g} s; "
                "answer the state of a turn with its stamp)",
            )
        self._sync()
        turn = k // self.period_steps
        if stamp is None:
            stamp = 0.0  # a zero stamp reaches here as None: the stamp of turn 0
        if not math.isfinite(stamp) or stamp_ns(stamp) != stamp_ns(t):
            given = f"stamp {stamp:.9g} s"
            raise CommandRejected(
                source,
                f"lockstep: {given} is not the open turn's: turn {turn} waits for commands stamped {t:.9g} s "
                "(the stamp of the state it answers)",
            )
        if source in self.answered:
            raise CommandRejected(source, f"lockstep: turn {turn} (t = {t:.9g} s) was already answered on this input")
        self.answered.add(source)

    # ------------------------------------------------------------------ what the simulator reports

    def reset(self, step: int) -> None:
        self.close_turn()

    def state_set(self, step: int, orientation: Any, angular_velocity: Any) -> None:
        self.close_turn()
