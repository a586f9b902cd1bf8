"""run.pacing without DDS: slices sized by the cost of a step, pacing, backlog drop, pause, due outputs.

The run driver is tested on a fake clock and a fake simulator whose steps cost fake wall time.
"""

from types import SimpleNamespace

import numpy as np
import pytest

from rigid_rot_sim.run.clock import StepClock
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.run.pacing import (
    MAX_BACKLOG_WALL,
    MAX_TICK,
    MAX_TICK_WALL,
    MIN_TICK,
    OutputSchedule,
    Pacer,
    RunDriver,
    StepCost,
    falling_behind_message,
)


def test_a_slow_step_shrinks_the_slice_at_once_and_a_fast_one_gradually():
    cost = StepCost(initial=20e-6)
    assert cost.steps_within(0.02) in (999, 1000)  # 0.02 / 20e-6 in floating point
    cost.record(steps=1, wall=0.2)  # taylor at 25 000 rad per step
    assert cost.steps_within(0.02) == 1  # never more than one such step per slice
    cost.record(steps=100, wall=0.002)
    assert 20e-6 < cost.per_step < 0.2
    for _ in range(100):
        cost.record(steps=100, wall=0.002)
    assert cost.per_step == pytest.approx(20e-6, rel=1e-3)
    assert cost.steps_within(-1.0) == 1
    cost.record(steps=0, wall=1.0)  # nothing done: nothing learnt
    assert cost.per_step == pytest.approx(20e-6, rel=1e-3)


def test_the_falling_behind_warning_says_why():
    message = falling_behind_message(1.0, 0.8, "taylor", 0.001, 0.19, 2.5e7, 1e6)
    assert "taylor needs 190 ms of wall time per 0.001 s step" in message
    assert "|omega| = 2.5e+07 rad/s" in message and "|torque| = 1e+06 N*m" in message
    assert "max_torque" in message


def test_the_falling_behind_warning_never_blames_a_physics_that_keeps_up():
    # the physics alone could run 196x real time: the time went elsewhere, and the warning says where
    message = falling_behind_message(1.0, 0.8, "taylor", 0.001, 0.001 / 196, 2.5, 0.1, spent=(1.3, 0.0066, 0.05))
    assert "not the physics" in message and "196x real time" in message
    assert "used 0.007 s of CPU stepping and 0.050 s on its outputs and commands; the other 1.24 s" in message
    assert "integrator" not in message and "max_torque" not in message


# ---------------------------------------------------------------- Pacer, OutputSchedule, RunDriver (fake clock)


class FakeClock:
    """Wall seconds that move only when told to (or when the fake simulator steps)."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


class FakeSim:
    """The Simulator's stepping API on a real step clock; each step costs ``step_wall`` s of the fake wall clock."""

    def __init__(self, wall: FakeClock, dt: float = 0.01, step_wall: float = 0.0, fail_at: int | None = None) -> None:
        self.wall, self.step_wall, self.fail_at = wall, step_wall, fail_at
        self.clock = StepClock(dt)
        self.stepper = SimpleNamespace(method="rk4")
        self.paused = False
        self.failure = None
        self.slices: list[tuple[int, int]] = []

    def advance_to(self, k: int) -> int:
        start = self.clock.k
        end = k if self.fail_at is None else min(k, self.fail_at)
        self.clock.k = end
        self.wall.now += (end - start) * self.step_wall
        self.slices.append((start, end))
        if self.fail_at is not None and end == self.fail_at:
            self.failure = "NonFiniteStateError: test"
            self.paused = True
        return end - start

    def snapshot(self):
        return SimpleNamespace(t=self.clock.t, angular_velocity_body=np.array([3.0, 4.0, 0.0]), torque_body=np.zeros(3))


class Due(SimulationObserver):
    def __init__(self) -> None:
        self.calls: list[tuple[int, tuple[str, ...]]] = []

    def outputs_due(self, step, snapshot, names):
        assert snapshot.t == pytest.approx(step * 0.01)
        self.calls.append((step, tuple(names)))


def driver(clock, sim, rtf=0.0, periods=None, duration=None):
    due = Due()
    run = RunDriver(sim, OutputSchedule(periods or {}), Pacer(rtf, clock), duration, observers=[due])
    run.pacer.anchor(sim.clock.t)
    return run, due


def test_output_schedule_periods_due_and_next_due():
    assert OutputSchedule.period_steps(25.0, 0.002) == 20 and OutputSchedule.period_steps(1e6, 0.01) == 1
    schedule = OutputSchedule.from_rates({"state": 50.0, "clock": 100.0, "imu": 0.0}, 0.01)
    assert schedule.periods == {"state": 2, "clock": 1}  # rate 0: not scheduled
    assert schedule.due(4) == ["state", "clock"] and schedule.due(5) == ["clock"]
    assert schedule.due(5, rest=True) == ["state"] and schedule.due(5, force=True) == ["state", "clock"]
    assert schedule.next_due(4) == 5
    schedule.set_rates({"state": 10.0, "clock": 20.0}, 0.01)
    assert schedule.periods == {"state": 10, "clock": 5} and schedule.next_due(7) == 10
    assert OutputSchedule().next_due(7) == 7 + 10**9 and OutputSchedule().due(0, force=True) == []


def test_tick_period_follows_one_step_of_wall_time_within_bounds():
    clock = FakeClock()
    assert Pacer(0.0, clock).tick_period(0.01) == MIN_TICK
    assert Pacer(1.0, clock).tick_period(0.005) == 0.005
    assert Pacer(1.0, clock).tick_period(1.0) == MAX_TICK and Pacer(1e6, clock).tick_period(0.001) == MIN_TICK


def test_paced_run_reaches_the_step_due_by_the_wall_clock_and_reports_due_outputs():
    clock = FakeClock()
    sim = FakeSim(clock)
    run, due = driver(clock, sim, rtf=2.0, periods={"state": 5})
    clock.now += 0.1  # 0.2 s of sim time at r = 2: step 20
    progress = run.tick()
    assert sim.clock.k == 20 and progress.steps == 20 and progress.falling_behind is None
    assert [step for step, _ in due.calls] == [5, 10, 15, 20]  # slices stop at each due output
    assert run.tick().steps == 0  # no wall time passed: nothing due


def test_a_backlog_beyond_the_limit_is_dropped_with_the_reason():
    clock = FakeClock()
    sim = FakeSim(clock)
    run, _ = driver(clock, sim, rtf=1.0)
    clock.now += MAX_BACKLOG_WALL + 0.3  # e.g. the process was stopped
    progress = run.tick()
    assert progress.falling_behind is not None and "cannot keep up with real_time_factor 1" in progress.falling_behind
    # the fake steps cost nothing: the 0.8 s were lost elsewhere, and the warning says so
    assert "not the physics" in progress.falling_behind and "the other 0.80 s it did not run" in progress.falling_behind
    # re-anchored: only half a tick of sim time ahead, not the 0.8 s missed
    assert sim.clock.k == sim.clock.step_at_or_before(MAX_TICK_WALL * 0.5) == 1
    clock.now += 0.05
    assert run.tick().falling_behind is None and sim.clock.k == 6  # paced again from the new anchor


def test_slices_hold_the_executor_about_the_budget_whatever_a_step_costs():
    clock = FakeClock()
    sim = FakeSim(clock, step_wall=0.004)  # 4 ms per step: 5 steps fit in MAX_TICK_WALL
    run, _ = driver(clock, sim, rtf=0.0)
    run.step_cost.per_step = 0.004
    began = clock.now
    run.tick()  # as fast as possible: stops at the deadline
    assert sim.clock.k == 5 and clock.now - began == pytest.approx(MAX_TICK_WALL)
    sim.step_wall = 0.2  # a step suddenly 50x slower (taylor at a huge |omega| dt)
    began = clock.now
    run.tick()
    assert clock.now - began <= MAX_TICK_WALL + 5 * 0.2  # the first slice, sized on the old cost
    began, steps = clock.now, sim.clock.k
    run.tick()
    assert sim.clock.k - steps == 1 and clock.now - began == pytest.approx(0.2)  # at most one slow step


def test_a_paused_run_does_not_step_and_resumes_from_a_new_anchor():
    clock = FakeClock()
    sim = FakeSim(clock)
    run, _ = driver(clock, sim, rtf=1.0)
    sim.paused = True
    clock.now += 0.3
    assert run.tick().steps == 0 and sim.clock.k == 0
    sim.paused = False
    run.pacer.anchor(sim.clock.t)  # as ~/pause data=false does
    clock.now += 0.1
    assert run.tick().falling_behind is None and sim.clock.k == 10  # the paused time is not caught up


def test_the_duration_ends_the_run_with_every_output_on_the_final_state_once():
    clock = FakeClock()
    sim = FakeSim(clock)
    run, due = driver(clock, sim, rtf=0.0, periods={"state": 4, "clock": 1}, duration=0.1)
    progress = run.tick()
    assert progress.finished and run.finished and sim.clock.k == 10
    assert due.calls[-2:] == [(10, ("clock",)), (10, ("state",))]  # due ones, then the rest: none twice
    assert run.tick().steps == 0 and len(due.calls) == 11  # finished: nothing more
    run.restart()  # after a reset
    assert not run.finished


def test_a_failure_stops_the_slice_and_reports_every_output():
    clock = FakeClock()
    sim = FakeSim(clock, fail_at=7)
    run, due = driver(clock, sim, rtf=0.0, periods={"state": 5, "clock": 1})
    progress = run.tick()
    assert progress.failure == "NonFiniteStateError: test" and sim.clock.k == 7
    assert due.calls[-1] == (7, ("state", "clock"))
    assert run.tick().steps == 0  # paused by the failure


def test_a_step_request_runs_to_its_target_within_its_budget():
    clock = FakeClock()
    sim = FakeSim(clock, step_wall=0.001)
    run, _ = driver(clock, sim)
    sim.paused = True
    assert run.run(25, clock() + 0.25).steps == 25 and sim.clock.k == 25
    sim.step_wall = 0.1
    run.step_cost.per_step = 0.1
    assert run.run(50, clock() + 0.25).steps < 25  # stopped short at the budget; the reply says so


def test_the_next_tick_is_due_when_the_next_output_is_and_never_while_paused():
    clock = FakeClock()
    sim = FakeSim(clock)  # dt 0.01
    run, due = driver(clock, sim, rtf=2.0, periods={"state": 5}, duration=0.07)
    assert run.next_wait() == pytest.approx(5 * 0.01 / 2.0, abs=1e-5)  # step 5 is due at 0.025 s of wall time
    clock.now += 0.01
    assert run.next_wait() == pytest.approx(0.015, abs=1e-5)  # the steps before it wait for it (no tick for them)
    clock.now += 0.015
    run.tick()
    assert sim.clock.k == 5 and run.next_wait() == pytest.approx(2 * 0.01 / 2.0, abs=1e-5)  # then the end, step 7
    sim.paused = True
    assert run.next_wait() is None  # paused: nothing is due until something changes
    sim.paused = False
    run.pacer.real_time_factor = 0.0
    assert run.next_wait() == 0.0  # as fast as possible: at once
    clock.now += 1.0
    run.tick()
    assert run.finished and run.next_wait() is None


def test_a_run_loop_takes_its_commands_between_the_chunks_of_a_long_call():
    clock = FakeClock()
    sim = FakeSim(clock)
    run, _ = driver(clock, sim, rtf=0.0, periods={"state": 4})
    calls: list[int] = []
    run.between_chunks = lambda: calls.append(sim.clock.k) or 0
    run.run(12, None)  # three chunks: 0-4, 4-8, 8-12
    # between two chunks only: none before the first (the caller took them just before), none after the
    # last (the caller takes them just after: in lockstep, the answer to the state published last)
    assert calls == [4, 8]
    calls.clear()
    run.run(16, None)  # one chunk: nothing taken inside the call
    assert calls == []


@pytest.mark.parametrize("duration", [10.000000005, 10.0, 9.995])
def test_the_node_simulate_and_the_sweep_take_the_same_number_of_steps(duration):
    """One duration rule (core/steps.step_grid): the run engine ends on step_at_or_after(duration), simulate()
    takes the same count with a shorter last step; 10.000000005 s at dt 0.01 is the review's disagreeing case."""
    from rigid_rot_sim.core.simulate import simulate
    from rigid_rot_sim.core.steps import step_grid
    from rigid_rot_sim.run.simulator import Simulator
    from rigid_rot_sim.scene.scene import parse_scene_text

    dt = 0.01
    scene = parse_scene_text(f"body: {{principal_moments: [1.0, 2.0, 3.0]}}\nintegrator: {{method: rk4, dt: {dt}}}\n")
    sim = Simulator(scene)
    clock = FakeClock()
    run = RunDriver(sim, OutputSchedule({}), Pacer(0.0, clock), duration)
    run.pacer.anchor(sim.clock.t)
    while not run.tick().finished:
        pass
    trajectory = simulate([1.0, 2.0, 3.0], [0.0, 0.0, 0.0], t_end=duration, dt=dt, method="rk4", save_every=1)
    n_full, last = step_grid(duration, dt)  # what the sweep's chunks take
    assert sim.clock.k == len(trajectory.t) - 1 == n_full + (last > 0.0)
    assert trajectory.t[-1] == duration


def test_a_long_step_on_pace_is_not_a_backlog():
    """dt 10 s at r = 1: 10 s of wall time between two steps is the pace, not falling behind (issue 40)."""
    clock = FakeClock()
    sim = FakeSim(clock, dt=10.0)
    run, _ = driver(clock, sim, rtf=1.0)
    warnings = []
    for _ in range(350):  # 35 s of wall time in 0.1 s ticks
        clock.now += 0.1
        warnings.append(run.tick().falling_behind)
    assert warnings == [None] * 350
    assert sim.clock.k == 3  # each 10 s step done when it fell due


def test_a_late_long_step_is_still_a_backlog():
    clock = FakeClock()
    sim = FakeSim(clock, dt=10.0)
    run, _ = driver(clock, sim, rtf=1.0)
    clock.now += 10.0 + MAX_BACKLOG_WALL + 0.2  # the first step fell due 0.7 s ago (the process was stopped)
    assert "cannot keep up" in (run.tick().falling_behind or "")
