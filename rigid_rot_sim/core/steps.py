"""Which fixed step a sim time lands on: the one rule for every change on a step grid.

A grid of fixed steps ``dt`` (s) has its boundary ``k0`` at time ``t0`` (s), so boundary
k is at ``t0 + (k - k0) * dt``, computed from the count, never accumulated. A change at
time t (a schedule segment, a command, a timeout) takes effect on the first boundary at
or after t; a time within :data:`BOUNDARY_SLACK` of a step of a boundary counts as on it,
since t / dt is rarely an exact integer in floating point.

The run engine's clock (:class:`rigid_rot_sim.run.clock.StepClock`), the scene's torque
schedules (:meth:`rigid_rot_sim.scene.scene.TorqueSchedule.change_steps`) and the sweep
all place changes with these functions, so they agree to the step.

A run's duration follows the same rule (:func:`step_grid`): a duration on the grid (within
:data:`BOUNDARY_SLACK` of a step of a boundary) takes that many full steps; a duration off
the grid takes one more step, which :func:`rigid_rot_sim.core.simulate.simulate` and the
sweep shorten to end exactly on the duration and the node (:class:`rigid_rot_sim.run.pacing.RunDriver`)
takes in full, ending at the next boundary. So all three take
``step_at_or_after(duration, dt)`` steps.

Two more rules live here, so that no caller spells them again (``test/test_one_home.py`` looks for
``round(... / dt)`` elsewhere): a *period* of whole steps (:func:`whole_steps`: the lockstep period of a
scene, checked to a relative :data:`PERIOD_RTOL` of the period), and the *nearest* step
(:func:`nearest_step`: a recorded stamp's step in a re-simulation; :func:`steps_over` the step count of
the analyses, which choose ``dt`` and then take the count nearest ``t_end / dt``, at least one).

>>> 30 * 0.03  # boundary 30 of a 0.03 s grid is not at 0.9 s, but 0.9 s lands on it
0.8999999999999999
>>> step_at_or_after(0.9, 0.03), step_at_or_after(0.3, 0.1)  # 0.3 / 0.1 = 2.9999999999999996
(30, 3)
>>> step_at_or_after(0.91, 0.03), step_at_or_before(0.91, 0.03)
(31, 30)
>>> time_of_step(5, 0.25, t0=0.3, k0=3)
0.8
>>> step_grid(1.0, 0.1), step_grid(0.25, 0.1)  # on the grid; off it: 2 full steps and one of ~0.05 s
((10, 0.0), (2, 0.04999999999999999))
>>> whole_steps(0.3, 0.1), whole_steps(0.25, 0.1)  # 0.25 s is not a whole number of 0.1 s steps
(3, None)
>>> nearest_step(0.26, 0.1), steps_over(0.01, 0.1)
(3, 1)
"""

from __future__ import annotations

import math

__all__ = [
    "BOUNDARY_SLACK",
    "PERIOD_RTOL",
    "nearest_step",
    "step_at_or_after",
    "step_at_or_before",
    "step_grid",
    "steps_over",
    "time_of_step",
    "whole_steps",
]

#: A time within this fraction of a step of a boundary counts as on it (t / dt is rarely an
#: exact integer in floating point: 0.3 / 0.1 = 2.9999999999999996).
BOUNDARY_SLACK = 1e-9

#: A period counts as a whole number n of steps when ``|n dt - period|`` is within this fraction of it.
PERIOD_RTOL = 1e-9


def step_at_or_after(t: float, dt: float, *, t0: float = 0.0, k0: int = 0) -> int:
    """The first boundary at or after sim time ``t`` (s) on the grid of step ``dt`` (s), boundary ``k0`` at ``t0``."""
    return k0 + math.ceil((t - t0) / dt - BOUNDARY_SLACK)


def step_at_or_before(t: float, dt: float, *, t0: float = 0.0, k0: int = 0) -> int:
    """The last boundary at or before sim time ``t`` (s) on the grid of step ``dt`` (s), boundary ``k0`` at ``t0``."""
    return k0 + math.floor((t - t0) / dt + BOUNDARY_SLACK)


def time_of_step(k: int, dt: float, *, t0: float = 0.0, k0: int = 0) -> float:
    """Sim time (s) of boundary ``k`` on the grid of step ``dt`` (s) with boundary ``k0`` at ``t0``."""
    return t0 + (k - k0) * dt


def step_grid(duration: float, dt: float) -> tuple[int, float]:
    """Full steps of ``dt`` (s) in a run of ``duration`` (s) from 0, and the length (s) of a last, shorter step.

    The last step is 0.0 when the duration is on the grid (within :data:`BOUNDARY_SLACK` of a step of a
    boundary); otherwise the run takes ``n + 1 = step_at_or_after(duration, dt)`` steps in all.
    """
    n = step_at_or_before(duration, dt)
    if step_at_or_after(duration, dt) == n:
        return n, 0.0
    return n, duration - n * dt


def whole_steps(period: float, dt: float) -> int | None:
    """Steps of ``dt`` (s) in ``period`` (s) when it is a whole number n >= 1 of them, else None.

    Whole: ``|n dt - period| <= PERIOD_RTOL * period`` for the nearest n (a lockstep turn lasts whole steps).
    """
    n = round(period / dt)
    if n < 1 or abs(n * dt - period) > PERIOD_RTOL * period:
        return None
    return int(n)


def nearest_step(t: float, dt: float, *, t0: float = 0.0, k0: int = 0) -> int:
    """The boundary nearest sim time ``t`` (s) on the grid of step ``dt`` (s), boundary ``k0`` at ``t0``."""
    return k0 + round((t - t0) / dt)


def steps_over(t_end: float, dt: float) -> int:
    """The step count nearest ``t_end / dt``, at least 1: the analyses' count of steps of about ``dt`` over ``t_end``.

    An estimate for a work or error figure, not a run's grid (that is :func:`step_grid`).
    """
    return max(1, round(t_end / dt))
