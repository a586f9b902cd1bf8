"""Wall-clock cost of physics steps, so that stepping never holds the node longer than a budget.

The node steps in slices between executor turns. A slice used to be a fixed number of
steps; but the wall time of one step depends on the method and the state (taylor at
|ω| dt = 25 rad needs ~0.2 s per step), so a fixed slice could block the executor for
seconds. :class:`StepCost` keeps a running estimate of the wall time per step and says how
many steps fit in what is left of a budget; the slices then hold the executor for about the
budget plus one step, whatever a step costs.

>>> cost = StepCost()
>>> cost.record(steps=100, wall=0.01)
>>> cost.steps_within(0.002)
20
"""

from __future__ import annotations

import math

__all__ = ["StepCost", "falling_behind_message"]


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
    real_time_factor: float, behind_wall: float, method: str, dt: float, per_step: float, omega: float, torque: float
) -> str:
    """Why the run cannot keep its pace: the wall time one step of the method takes now."""
    pace = dt / per_step if per_step > 0.0 else math.inf
    return (
        f"cannot keep up with real_time_factor {real_time_factor:g} ({behind_wall:.2f} s of wall time behind): "
        f"{method} needs {per_step * 1e3:.3g} ms of wall time per {dt:g} s step "
        f"(at most {pace:.3g}x real time) at |omega| = {omega:.3g} rad/s, |torque| = {torque:.3g} N*m; "
        "dropping the backlog (a smaller torque, max_torque or another integrator helps)"
    )
