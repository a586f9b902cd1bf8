"""Sim time of a run as a count of fixed steps: the step boundaries every change lands on.

The time of step boundary k is computed from the integer counter, never accumulated:
``t = t_epoch + (k - k_epoch) * dt``, with ``t_epoch = k_epoch = 0`` until dt changes at
run time (:meth:`StepClock.change_dt` starts a new epoch at the current boundary). Which
boundary a time lands on is :mod:`rigid_rot_sim.core.steps`' rule (re-exported here), the
one the scene's schedules and the sweep use too.

>>> clock = StepClock(0.1)
>>> clock.k = 3
>>> clock.step_at_or_after(0.3)  # 0.3 / 0.1 = 2.9999999999999996 counts as on boundary 3
3
>>> clock.change_dt(0.25)
>>> clock.time_of_step(5)
0.8
"""

from __future__ import annotations

import numpy as np

from rigid_rot_sim.core import steps
from rigid_rot_sim.core.steps import BOUNDARY_SLACK, step_at_or_after, step_at_or_before, time_of_step

__all__ = ["StepClock", "BOUNDARY_SLACK", "step_at_or_after", "step_at_or_before", "time_of_step"]


class StepClock:
    """Step counter ``k`` and step ``dt`` (s > 0) of a run, with the epoch of the last dt change."""

    def __init__(self, dt: float) -> None:
        self.dt = float(dt)
        self.k = 0
        self.k_epoch = 0
        self.t_epoch = 0.0

    def reset(self) -> None:
        """Back to step 0 at t = 0 (dt kept)."""
        self.k = 0
        self.k_epoch = 0
        self.t_epoch = 0.0

    def change_dt(self, dt: float) -> None:
        """Step ``dt`` s from the current boundary on; t stays exact (a new epoch starts here)."""
        self.t_epoch = self.t
        self.k_epoch = self.k
        self.dt = float(dt)

    @property
    def t(self) -> float:
        """Sim time of the current step boundary, s."""
        return self.time_of_step(self.k)

    def time_of_step(self, k: int) -> float:
        """Sim time (s) of step boundary k."""
        return steps.time_of_step(k, self.dt, t0=self.t_epoch, k0=self.k_epoch)

    def times_of_next_steps(self, n: int) -> np.ndarray:
        """Sim times (s) of the boundaries k + 1 .. k + n, each exactly :meth:`time_of_step`."""
        # steps.time_of_step's formula, t0 + (k - k0) * dt, over an array of k
        return self.t_epoch + (np.arange(self.k + 1, self.k + n + 1) - self.k_epoch) * self.dt

    def step_at_or_after(self, t: float) -> int:
        """The first step boundary at or after sim time t (s), never before the current one."""
        return max(steps.step_at_or_after(t, self.dt, t0=self.t_epoch, k0=self.k_epoch), self.k)

    def step_at_or_before(self, t: float) -> int:
        """The last step boundary at or before sim time t (s) (may be in the past)."""
        return steps.step_at_or_before(t, self.dt, t0=self.t_epoch, k0=self.k_epoch)
