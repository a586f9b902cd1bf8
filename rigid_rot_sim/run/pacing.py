"""Pacing a run: wall clock against sim time, outputs due per step, slices of bounded wall time.

Plain classes, no ROS, every clock injected, so the rules are tested with a fake clock
(``test/run/test_pacing.py``); the ROS node's run loop (``rigid_rot_sim.ros.run_loop``) calls
:meth:`RunDriver.tick` at each turn and waits :meth:`RunDriver.next_wait` for the next, and
``~/step`` calls :meth:`RunDriver.run`.

* :class:`Pacer`: the real-time factor r. At r > 0 the run is due at step
  ``r * (wall time since the anchor)`` after the anchor's sim time; a backlog of more than
  ``MAX_BACKLOG_WALL`` of wall time is dropped (the run re-anchors). r = 0: as fast as possible.
* :class:`OutputSchedule`: each output's period in whole steps (from its rate in Hz of sim
  time) and the outputs due at a step.
* :class:`StepCost`: wall time per physics step, so that a slice holds the executor for
  about its budget whatever a step costs (taylor at |ω| dt = 25 rad needs ~0.2 s per step).
* :class:`RunDriver`: advances the :class:`~rigid_rot_sim.run.simulator.Simulator` in
  slices up to the next due output, the paced target, the wall deadline or the duration,
  and tells its observers (:class:`~rigid_rot_sim.run.observer.SimulationObserver`) which
  outputs are due at each step, with the state there.

The states never depend on r, the rates or the slices (the Simulator's determinism notes):
pacing decides only *when* (wall clock) a step is computed.

>>> cost = StepCost()
>>> cost.record(steps=100, wall=0.01)
>>> cost.steps_within(0.002)
20
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rigid_rot_sim.core import limits

if TYPE_CHECKING:  # annotations only
    from rigid_rot_sim.run.observer import SimulationObserver
    from rigid_rot_sim.run.simulator import Simulator

__all__ = ["OutputSchedule", "Pacer", "Progress", "RunDriver", "StepCost", "falling_behind_message"]

#: Most wall time (s) one timer tick spends stepping, so the executor serves commands between.
MAX_TICK_WALL = 0.02
#: Most steps between two checks of the wall-clock deadline (fewer when steps are slow: StepCost).
MAX_CHUNK = 256
#: Wall-clock timer period bounds (s).
MIN_TICK = 0.001
MAX_TICK = 0.02
#: At r > 0, a backlog beyond this much wall time is dropped (the run re-anchors), with a warning.
MAX_BACKLOG_WALL = 0.5
#: The physics is blamed for falling behind only when it alone needs more than 1 / PHYSICS_SHARE of the
#: wall time at the real-time factor (it can run less than PHYSICS_SHARE times as fast as asked).
PHYSICS_SHARE = 2.0
#: Wall time (s) after a step's due time that its tick is timed for (float rounding never wakes it early).
DUE_MARGIN = 2e-6
#: Steps to the next due output when no output is scheduled at all.
NEVER = 10**9

Clock = Callable[[], float]


class StepCost:
    """Running estimate (s of wall time) of one physics step; starts optimistic."""

    #: Weight of the newest measurement (an exponential moving average over ~5 slices).
    SMOOTHING = 0.2

    def __init__(self, initial: float = 20e-6) -> None:
        self.per_step = initial

    def record(self, steps: int, wall: float) -> None:
        """Fold in a slice of ``steps`` steps that took ``wall`` s."""
        if steps <= 0 or not math.isfinite(wall) or wall < 0.0:
            return
        sample = wall / steps
        # a slower step counts at once (the next slice must not overrun), a faster one gradually
        self.per_step = sample if sample > self.per_step else self.per_step + self.SMOOTHING * (sample - self.per_step)

    def steps_within(self, budget: float) -> int:
        """How many steps fit in ``budget`` s of wall time (at least 1)."""
        if budget <= 0.0:
            return 1
        return max(1, int(budget / max(self.per_step, 1e-9)))


def falling_behind_message(
    real_time_factor: float,
    behind_wall: float,
    method: str,
    dt: float,
    per_step: float,
    omega: float,
    torque: float,
    spent: tuple[float, float, float] | None = None,
) -> str:
    """Why the run cannot keep its pace, measured: the physics, or the rest of the machine.

    ``per_step``: the CPU time of one step (the time the process waited for a core never counts as
    the physics'). The physics is named (with the integrator advice) only when one step of ``method``
    takes more than ``1 / PHYSICS_SHARE`` of its wall-time budget at this real-time factor. Otherwise
    the time went elsewhere, and ``spent`` (wall s of the window, CPU s in the physics, CPU s in the
    outputs and commands) says where: what is left was not the run's (the process waited for a core,
    or a service held the run).
    """
    pace = dt / per_step if per_step > 0.0 else math.inf
    head = f"cannot keep up with real_time_factor {real_time_factor:g} ({behind_wall:.2f} s of wall time behind): "
    if pace < PHYSICS_SHARE * real_time_factor:
        return head + (
            f"{method} needs {per_step * 1e3:.3g} ms of wall time per {dt:g} s step "
            f"(at most {pace:.3g}x real time) at |omega| = {omega:.3g} rad/s, |torque| = {torque:.3g} N*m; "
            "dropping the backlog (a smaller torque, max_torque or another integrator helps)"
        )
    text = head + (
        f"not the physics ({method} needs {per_step * 1e6:.3g} µs of CPU time per {dt:g} s step, {pace:.3g}x real time)"
    )
    if spent is not None:
        wall, physics, node_side = spent
        elsewhere = max(0.0, wall - physics - node_side)
        load = os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan
        text += (
            f": of the last {wall:.2f} s of wall time the run used {physics:.3f} s of CPU stepping and "
            f"{node_side:.3f} s on its outputs and commands; the other {elsewhere:.2f} s it did not run "
            f"(the process waited for a core, or a service held the run; load average {load:.1f} on "
            f"{os.cpu_count()} cores)"
        )
    return text + "; dropping the backlog (a less busy machine, or fewer or slower outputs, helps)"


class Pacer:
    """Wall clock against sim time at ``real_time_factor`` r (sim s per wall s; 0: as fast as possible).

    ``clock`` returns wall seconds (a monotonic clock; a fake one in tests).
    """

    def __init__(self, real_time_factor: float, clock: Clock = time.monotonic) -> None:
        self.real_time_factor = float(real_time_factor)
        self.clock = clock
        self._anchor_wall = clock()
        self._anchor_t = 0.0

    def anchor(self, t: float) -> None:
        """Restart pacing from sim time ``t`` (s) now: after a pause, a reset, a new r."""
        self._anchor_wall = self.clock()
        self._anchor_t = t

    def wall_at(self, t: float) -> float:
        """The wall time (clock s) at which sim time ``t`` is due (r > 0)."""
        return self._anchor_wall + (t - self._anchor_t) / self.real_time_factor

    def tick_period(self, dt: float) -> float:
        """Wall seconds between two timer ticks: one step of wall time, within [MIN_TICK, MAX_TICK]."""
        if self.real_time_factor <= 0.0:
            return MIN_TICK
        return min(max(dt / self.real_time_factor, MIN_TICK), MAX_TICK)

    def target_step(self, sim: Simulator, now: float) -> tuple[int | None, float | None]:
        """The step the run is due at ``now`` (None: unbounded) and the backlog dropped (wall s) or None.

        The backlog is how late the next step is (wall time since it fell due); one of more than
        ``MAX_BACKLOG_WALL`` is dropped: the run re-anchors half a tick before ``now``, so it goes
        on at pace from where it is.
        """
        r = self.real_time_factor
        if r <= 0.0:
            return None, None
        target_t = self._anchor_t + (now - self._anchor_wall) * r
        # how late the next step is (it is due once target_t reaches its end): a long step is not a backlog
        # while it is not due (dt 10 s at r = 1 is 10 s of wall time between two steps, on pace)
        behind_wall = (target_t - sim.clock.t - sim.clock.dt) / r
        dropped = None
        if behind_wall > MAX_BACKLOG_WALL:
            dropped = behind_wall
            self._anchor_wall = now - MAX_TICK_WALL * 0.5
            self._anchor_t = sim.clock.t
            target_t = sim.clock.t + MAX_TICK_WALL * 0.5 * r
        return max(sim.clock.step_at_or_before(target_t), sim.clock.k), dropped


class OutputSchedule:
    """Each output's period in steps; which outputs are due at a step.

    ``periods`` maps an output name to its period (steps >= 1). An output is due at the
    steps that are multiples of its period.
    """

    def __init__(self, periods: Mapping[str, int] | None = None) -> None:
        self.periods: dict[str, int] = dict(periods or {})

    @staticmethod
    def period_steps(rate: float, dt: float) -> int:
        """Whole steps of ``dt`` s per period of ``rate`` Hz (at least 1: an output faster than the
        steps is due at every step).

        ValueError unless ``rate`` is > 0 within :func:`~rigid_rot_sim.core.limits.check_rate`'s
        range and ``dt`` > 0 is finite: the period must be a finite positive whole number of steps.
        """
        if rate == 0.0:
            raise ValueError("rate 0 Hz: the output is not scheduled (it has no period)")
        limits.check_rate(rate)
        steps = 1.0 / (rate * dt) if math.isfinite(dt) and dt > 0.0 else math.nan
        if not math.isfinite(steps):
            raise ValueError(f"rate {rate!r} Hz at dt {dt!r} s: the period is not a finite number of steps")
        return max(1, int(round(steps)))

    @classmethod
    def from_rates(cls, rates: Mapping[str, float], dt: float) -> OutputSchedule:
        """The schedule of the outputs with a rate > 0 (Hz of sim time) at step ``dt`` (s)."""
        return cls({name: cls.period_steps(rate, dt) for name, rate in rates.items() if rate > 0.0})

    def set_rates(self, rates: Mapping[str, float], dt: float) -> None:
        """New periods for the scheduled outputs (after a rate or dt change); others stay unscheduled."""
        for name in self.periods:
            self.periods[name] = self.period_steps(rates[name], dt)

    def due(self, step: int, force: bool = False, rest: bool = False) -> list[str]:
        """The outputs due at ``step``: all with ``force``; with ``rest`` those *not* due there."""
        return [name for name, n in self.periods.items() if force or (step % n != 0 if rest else step % n == 0)]

    def next_due(self, step: int) -> int:
        """The first step after ``step`` at which some output is due (``step + NEVER`` if none)."""
        periods = self.periods.values()
        return min(((step // n) + 1) * n for n in periods) if periods else step + NEVER


@dataclass
class Progress:
    """What a slice of the run came to, for the node to log."""

    #: Steps done.
    steps: int = 0
    #: The falling-behind warning when a backlog was dropped (r > 0), else None.
    falling_behind: str | None = None
    #: Why the run stopped (the Simulator's failure), else None.
    failure: str | None = None
    #: True when the duration was reached in this slice.
    finished: bool = False
    #: Lockstep: why a turn timed out and what the run did (paused or holding), else None.
    lockstep_timeout: str | None = None


class RunDriver:
    """Advances ``sim`` in slices and tells its observers the outputs due at each step.

    ``duration`` (s of sim time, None: unbounded) ends the run: every output is published
    once more on the final state (those not due there), then :attr:`finished` is set.
    """

    def __init__(
        self,
        sim: Simulator,
        schedule: OutputSchedule,
        pacer: Pacer,
        duration: float | None = None,
        observers: Iterable[SimulationObserver] = (),
    ) -> None:
        self.sim = sim
        self.schedule = schedule
        self.pacer = pacer
        self.clock = pacer.clock
        self.duration = duration
        self.step_cost = StepCost()
        #: CPU time (s) of this thread, for what the run itself costs: a step's wall time also holds the
        #: time the process waited for a core, which must never be blamed on the physics.
        self.cpu_clock: Clock = time.thread_time
        #: Running estimate of one physics step in CPU time (the falling-behind warning's physics figure).
        self.physics_cost = StepCost()
        self.finished = False
        self.observers: list[SimulationObserver] = list(observers)
        #: Called between two chunks of steps (the node takes its commands there); returns how many came.
        self.between_chunks: Callable[[], int] | None = None
        self._warm = False
        #: Since the run was last on pace: [wall start, CPU s stepping, CPU s on outputs and commands].
        self._spent = [self.clock(), 0.0, 0.0]

    def publish_due(self, force: bool = False, rest: bool = False) -> None:
        """Report the outputs due at the current step (see :meth:`OutputSchedule.due`)."""
        step = self.sim.clock.k
        names: Sequence[str] = self.schedule.due(step, force, rest)
        if not names:
            return
        snapshot = self.sim.snapshot()
        for observer in self.observers:
            observer.outputs_due(step, snapshot, names)

    def restart(self) -> None:
        """After a reset: not finished, paced from the current (initial) state."""
        self.finished = False
        self.pacer.anchor(self.sim.clock.t)

    def next_wait(self) -> float | None:
        """Wall time (s) until the run next needs a tick: the next due output (or the end) at r > 0, 0 at
        r = 0, None when paused or finished (nothing is due until something changes).

        Steps between two outputs are computed at the next output's tick: the states do not depend
        on when they are computed, and a command that arrives in between wakes the run, which first
        steps to the step due at that wall time.
        """
        sim = self.sim
        if sim.paused or self.finished:
            return None
        r = self.pacer.real_time_factor
        if r <= 0.0:
            return 0.0
        k = sim.clock.k
        stop = self.schedule.next_due(k)
        if self.duration is not None:
            stop = min(stop, sim.clock.step_at_or_after(self.duration))
        due = self.pacer.wall_at(sim.clock.t + (stop - k) * sim.clock.dt) + DUE_MARGIN
        return max(0.0, due - self.clock())

    def tick(self, budget: float = MAX_TICK_WALL) -> Progress:
        """One tick: step to the paced target (r > 0) or as far as ``budget`` s of wall time allows."""
        sim = self.sim
        if sim.paused or self.finished:
            return Progress()
        now = self.clock()
        target, dropped = self.pacer.target_step(sim, now)
        behind = None
        if dropped is not None:
            snapshot = sim.snapshot()
            behind = falling_behind_message(
                self.pacer.real_time_factor,
                dropped,
                sim.stepper.method,
                sim.clock.dt,
                self.physics_cost.per_step,
                math.hypot(*snapshot.angular_velocity_body.tolist()),
                math.hypot(*snapshot.torque_body.tolist()),
                (now - self._spent[0], self._spent[1], self._spent[2]),
            )
            self._spent = [now, 0.0, 0.0]
        progress = self.run(target, now + budget)
        progress.falling_behind = behind
        if target is not None and sim.clock.k >= target:
            self._spent = [self.clock(), 0.0, 0.0]  # on pace: the window of a next warning starts here
        return progress

    def run(self, target: int | None, deadline: float | None) -> Progress:
        """Step (reporting what is due) up to step ``target`` (None: unbounded) or the wall ``deadline``."""
        sim = self.sim
        start = sim.clock.k
        end_step = sim.clock.step_at_or_after(self.duration) if self.duration is not None else None
        first = True
        while True:
            k = sim.clock.k
            if end_step is not None and k >= end_step:
                self.publish_due(rest=True)  # every output ends on the final state, none twice
                self.finished = True
                return Progress(steps=k - start, finished=True)
            stop = min(self.schedule.next_due(k), k + MAX_CHUNK)
            if deadline is not None:  # as many steps as the measured cost per step lets fit
                stop = min(stop, k + self.step_cost.steps_within(deadline - self.clock()))
            if target is not None:
                stop = min(stop, target)
            if end_step is not None:
                stop = min(stop, end_step)
            if stop <= k:
                break
            if not first and self.between_chunks is not None:
                # only between two chunks that both step; the caller takes what came before and after the call.
                # Never after the last chunk: a lockstep answer to the state just published would be taken
                # here, unseen by the caller's turn, which would then wait for it (issue 27b).
                self.between_chunks()
            first = False
            began, cpu_began = self.clock(), self.cpu_clock()
            steps = sim.advance_to(stop)
            stepped, cpu_stepped = self.clock(), self.cpu_clock()
            if self._warm:
                self.step_cost.record(steps, stepped - began)
                self.physics_cost.record(steps, cpu_stepped - cpu_began)
            else:  # the first chunk loads the compiled kernels: not a step's cost, and the pace starts after it
                self._warm = True
                self.pacer.anchor(sim.clock.t)
            if sim.failure is not None:
                self.publish_due(force=True)
                return Progress(steps=sim.clock.k - start, failure=sim.failure)
            self.publish_due()
            self._spent[1] += cpu_stepped - cpu_began
            self._spent[2] += self.cpu_clock() - cpu_stepped
            if deadline is not None and self.clock() >= deadline:
                break
        return Progress(steps=sim.clock.k - start)
