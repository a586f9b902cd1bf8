"""Which scheduled torque acts over which steps, and the one world -> body re-expression.

A scene's torque schedules (:class:`rigid_rot_sim.scene.scene.TorqueSchedule`) change the
torque on step boundaries (:meth:`~rigid_rot_sim.scene.scene.TorqueSchedule.change_steps`,
the rule of :mod:`rigid_rot_sim.core.steps`). :func:`stretches` cuts a run into the
:class:`Stretch` es between those boundaries, each with the sums of the body-frame and of
the world-frame schedules acting over it, added in schedule order from zero as the run
engine's :class:`~rigid_rot_sim.run.commands.CommandSchedule` adds them, so the sums have
its bits. A world-frame torque is re-expressed in the body frame at every step, from the
attitude at the start of the step: :func:`world_in_body`, used by the engine's stepper
(:meth:`rigid_rot_sim.run.stepper.Stepper.set_command_torque`) on floats and by the
sweep's chunks on columns (one body per row), with the same bits. :func:`stretch_at` finds the
stretch of a step; :func:`follows_attitude` says when a world-frame torque makes the body-frame
torque change at every step, not only where a stretch starts.

``test/sweep/test_sweep_matches_engine.py`` checks, for every shipped scene, that the
stretches start exactly where the engine's command schedule changes the torque.

>>> from rigid_rot_sim.scene.scene import ScheduleSegment, TorqueSchedule
>>> schedule = TorqueSchedule("body", (ScheduleSegment(0.0, (0.1, 0.0, 0.0)), ScheduleSegment(0.3, (0.0, 0.0, 0.0))))
>>> [(s.start, s.stop, s.body) for s in stretches((schedule,), 0.1, 5)]
[(0, 3, (0.1, 0.0, 0.0)), (3, 5, (0.0, 0.0, 0.0))]
>>> stretch_at(stretches((schedule,), 0.1, 5), 2).body, follows_attitude((schedule,))
((0.1, 0.0, 0.0), False)
"""

from __future__ import annotations

import bisect
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from rigid_rot_sim.core import frames
from rigid_rot_sim.scene.scene import TorqueSchedule

__all__ = ["Stretch", "stretches", "stretch_at", "follows_attitude", "world_in_body"]

Vector3 = tuple[float, float, float]


@dataclass(frozen=True)
class Stretch:
    """Steps ``start`` to ``stop`` (boundary indices, ``stop`` excluded) under constant scheduled torques.

    ``body``: the sum of the body-frame schedules (N*m, body frame); ``world``: the sum of the
    world-frame ones (N*m, world frame), None when no world-frame schedule exists.
    """

    start: int
    stop: int
    body: Vector3
    world: Vector3 | None


def change_steps(schedules: Sequence[TorqueSchedule], dt: float) -> list[int]:
    """Every step boundary (at step ``dt`` s) where some schedule's torque may change, sorted, unique."""
    return sorted({step for schedule in schedules for step in schedule.change_steps(dt)})


def stretches(schedules: Sequence[TorqueSchedule], dt: float, end_step: int) -> tuple[Stretch, ...]:
    """The run from boundary 0 to ``end_step`` cut where a schedule's torque changes (see the module)."""
    cuts = [0, *(k for k in change_steps(schedules, dt) if 0 < k < end_step), end_step]
    has_world = any(schedule.frame == "world" for schedule in schedules)
    out = []
    for start, stop in zip(cuts[:-1], cuts[1:], strict=True):
        body = [0.0, 0.0, 0.0]
        world = [0.0, 0.0, 0.0]
        for schedule in schedules:
            value = schedule.torque_at_step(start, dt)
            target = world if schedule.frame == "world" else body
            for i in range(3):
                target[i] += value[i]
        out.append(
            Stretch(start, stop, (body[0], body[1], body[2]), (world[0], world[1], world[2]) if has_world else None)
        )
    return tuple(out)


def stretch_at(timeline: Sequence[Stretch], k: int) -> Stretch:
    """The stretch of ``timeline`` (:func:`stretches`) that holds step ``k``."""
    return timeline[bisect.bisect_right([stretch.start for stretch in timeline], k) - 1]


def follows_attitude(schedules: Sequence[TorqueSchedule]) -> bool:
    """Whether a world-frame schedule holds a non-zero torque: then the body-frame torque may change at every step
    (re-expressed from the attitude at each boundary, :func:`world_in_body`), not only where a stretch starts."""
    return any(
        any(segment.torque) for schedule in schedules if schedule.frame == "world" for segment in schedule.segments
    )


def world_in_body(q_principal: Any, principal_from_body: Any, world: Any) -> Any:
    """A world-frame vector (N*m) in body coordinates at the attitude ``q_principal`` (principal -> world).

    Floats (the engine) or equal-length columns (the sweep, one body per row).
    """
    q_body = frames.attitude_from_principal(q_principal, principal_from_body)
    return frames.vector_in_body(q_body, world)
