"""Steps of a paused run that carry their own input: the engine side of ``~/step_with_torque``.

An optimiser or a learning client wants "this torque over the next N steps, then the state"
in one call, with no other input slipping in between. :func:`torque_for_steps` schedules
the torque over exactly those steps; the caller then steps them
(:meth:`~rigid_rot_sim.run.pacing.RunDriver.run`), all within one executor callback.

Why it equals a topic command followed by a step, bit for bit: the torque acting over a
step is the sum of what the inputs hold and what is applied
(:class:`~rigid_rot_sim.run.commands.CommandSchedule`), accumulated from 0.0 in the same
order, so one applied torque τ gives the same 0.0 + τ as one held command τ; a world-frame
torque is re-expressed in the body frame at every step boundary either way. The difference
is the end: the applied torque stops on the boundary after the last step, while a topic
input holds its command until a newer one replaces it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # annotations only
    from rigid_rot_sim.run.commands import TorqueCommand
    from rigid_rot_sim.run.simulator import Simulator

__all__ = ["torque_for_steps"]


def torque_for_steps(sim: Simulator, torque: Any, frame_id: str, steps: int) -> TorqueCommand:
    """Apply ``torque`` (N*m, in ``frame_id``; empty = the body frame) from the current step boundary k
    for exactly ``steps`` steps: it acts over steps k .. k + steps - 1 and ends on boundary k + steps.

    Nothing is stepped here. ValueError if ``steps`` is not an integer >= 1;
    :class:`~rigid_rot_sim.run.commands.CommandRejected` (a ValueError, observers told) for a torque
    or frame that ``apply_torque`` refuses. Recorded as an applied torque, so a re-simulation
    reproduces it.
    """
    if isinstance(steps, bool) or int(steps) != steps or steps < 1:
        raise ValueError(f"steps must be an integer >= 1, got {steps}")
    k = sim.clock.k
    # the end time is that of boundary k + steps computed from the step counter; the schedule
    # rounds t_k + duration back onto that boundary (within the clock's BOUNDARY_SLACK)
    duration = sim.clock.time_of_step(k + int(steps)) - sim.clock.t
    return sim.apply_torque(torque, frame_id, duration)
