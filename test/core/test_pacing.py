"""core.pacing: slices sized by the measured cost of a step (issue 9, items 4 and 9)."""

import pytest

from rigid_rot_sim.core.pacing import StepCost, falling_behind_message


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
