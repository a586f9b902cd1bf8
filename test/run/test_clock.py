"""Tests for rigid_rot_sim.run.clock: sim time from the step count, boundaries, dt changes."""

import doctest

from rigid_rot_sim.run import clock as clock_module
from rigid_rot_sim.run.clock import StepClock


def test_the_module_examples_run():
    assert doctest.testmod(clock_module, raise_on_error=True).attempted > 0


def test_time_is_computed_from_the_count_not_accumulated():
    clock = StepClock(0.01)
    clock.k = 1000
    assert clock.t == 1000 * 0.01
    total = 0.0
    for _ in range(1000):
        total += 0.01
    assert total != clock.t  # what accumulating would have given


def test_boundaries_round_to_the_grid_with_a_slack_of_rounding():
    clock = StepClock(0.1)
    clock.k = 1
    assert clock.step_at_or_after(0.3) == 3 and clock.step_at_or_before(0.3) == 3
    assert clock.step_at_or_after(0.31) == 4 and clock.step_at_or_before(0.39) == 3
    assert clock.step_at_or_after(0.0) == 1  # never before the current boundary
    assert clock.step_at_or_before(0.0) == 0  # may be in the past


def test_a_dt_change_starts_an_epoch_and_reset_ends_it():
    clock = StepClock(0.1)
    clock.k = 4
    t = clock.t
    clock.change_dt(0.5)
    assert clock.t == t and clock.time_of_step(6) == t + 2 * 0.5
    assert clock.step_at_or_after(t + 0.75) == 6
    clock.reset()
    assert (clock.k, clock.t, clock.dt) == (0, 0.0, 0.5)


def test_times_of_next_steps_are_the_times_of_those_steps():
    clock = StepClock(0.1)
    clock.k = 7
    clock.change_dt(0.03)
    clock.k = 11
    assert clock.times_of_next_steps(5).tolist() == [clock.time_of_step(k) for k in range(12, 17)]
