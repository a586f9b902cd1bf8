"""Tests for rigid_rot_sim.core.steps: which step boundary a sim time lands on."""

import doctest
import math

import pytest

from rigid_rot_sim.core import steps
from rigid_rot_sim.core.steps import step_at_or_after, step_at_or_before, time_of_step


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
