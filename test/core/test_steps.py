"""Tests for rigid_rot_sim.core.steps: which step boundary a sim time lands on."""

import doctest
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigid_rot_sim.core import steps
from rigid_rot_sim.core.steps import step_at_or_after, step_at_or_before, step_grid, time_of_step


def test_the_module_examples_run():
    assert doctest.testmod(steps, raise_on_error=True).attempted > 0


@pytest.mark.parametrize("dt", [0.03, 0.009, 0.1, 0.001, 0.3, 1.0 / 3.0])
def test_the_time_of_a_boundary_lands_on_that_boundary(dt):
    for k in range(0, 5000, 7):
        t = time_of_step(k, dt)
        assert step_at_or_after(t, dt) == k and step_at_or_before(t, dt) == k
        # a time a tenth of a step away lands on the neighbouring boundary on its side
        assert step_at_or_after(t + 0.1 * dt, dt) == k + 1 and step_at_or_before(t + 0.1 * dt, dt) == k
        assert step_at_or_after(t - 0.1 * dt, dt) == k and step_at_or_before(t - 0.1 * dt, dt) == k - 1


def test_a_decimal_time_counts_as_on_the_boundary_its_ratio_rounds_to():
    assert 30 * 0.03 < 0.9 and step_at_or_after(0.9, 0.03) == 30 and step_at_or_before(0.9, 0.03) == 30
    assert 0.3 / 0.1 < 3 and step_at_or_after(0.3, 0.1) == 3 and step_at_or_before(0.3, 0.1) == 3
    assert 0.9 / 0.009 > 100 and step_at_or_after(0.9, 0.009) == 100 and step_at_or_before(0.9, 0.009) == 100
    assert step_at_or_after(0.0, 0.01) == 0


def test_an_epoch_shifts_the_grid():
    # boundary 3 at t = 0.3, then steps of 0.25 s
    assert time_of_step(5, 0.25, t0=0.3, k0=3) == 0.8
    assert step_at_or_after(0.8, 0.25, t0=0.3, k0=3) == 5
    assert step_at_or_after(0.81, 0.25, t0=0.3, k0=3) == 6
    assert step_at_or_before(0.79, 0.25, t0=0.3, k0=3) == 4
    assert math.isclose(time_of_step(3, 0.25, t0=0.3, k0=3), 0.3)


# the review's two durations where simulate() and the sweep (relative grid tolerance) took one step
# fewer than the node (absolute BOUNDARY_SLACK), before the one rule
REVIEW_CASES = [(10.000000005, 0.01, 1001), (100.00000005, 1e-4, 1_000_001)]


@pytest.mark.parametrize(("duration", "dt", "steps_taken"), REVIEW_CASES)
def test_a_duration_just_off_the_grid_takes_one_more_step_on_every_path(duration, dt, steps_taken):
    n_full, last = step_grid(duration, dt)
    assert last > 0.0 and n_full + 1 == steps_taken  # simulate() and the sweep: a short last step
    assert step_at_or_after(duration, dt) == steps_taken  # the node's end step (RunDriver.run)


def test_a_duration_on_the_grid_takes_its_full_steps_and_no_short_one():
    assert step_grid(1.0, 0.1) == (10, 0.0)  # 1.0 / 0.1 is 10 up to rounding
    assert step_grid(0.9, 0.03) == (30, 0.0)  # 30 * 0.03 < 0.9, yet on the grid
    assert step_grid(0.0, 0.1) == (0, 0.0)
    n, last = step_grid(0.03, 0.1)
    assert n == 0 and last == pytest.approx(0.03)


@settings(max_examples=400, deadline=None)
@given(
    steps=st.integers(min_value=0, max_value=2_000_000),
    dt=st.floats(min_value=1e-5, max_value=1.0),
    offset=st.one_of(st.just(0.0), st.floats(min_value=-0.999, max_value=0.999)),
)
def test_simulate_the_sweep_and_the_node_take_the_same_number_of_steps(steps, dt, offset):
    duration = (steps + offset) * dt
    if duration < 0.0:
        duration = 0.0
    n_full, last = step_grid(duration, dt)
    assert n_full + (last > 0.0) == step_at_or_after(duration, dt)
    assert 0.0 <= last < dt * (1.0 + 1e-9)
    if last > 0.0:  # the short last step ends on the duration
        assert math.isclose(time_of_step(n_full, dt) + last, duration, rel_tol=1e-12, abs_tol=1e-15)
