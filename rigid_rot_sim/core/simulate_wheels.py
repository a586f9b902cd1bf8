"""The wheel inputs of ``simulate``: wheels, initial wheel speeds and motor-torque schedules, checked.

:func:`rigid_rot_sim.core.simulate.simulate` runs a gyrostat (reaction wheels, gravity gradient)
with a method of :data:`~rigid_rot_sim.core.integrators.gyrostat.GYROSTAT_METHODS`; this module
turns its wheel arguments into what the integrator takes. Wheel motor torques change only at step
boundaries, as in the run engine: a segment starting at ``s`` seconds acts from step
``k = step_at_or_after(s, dt)`` on (the rule of :mod:`rigid_rot_sim.core.steps`), each value clamped
to its wheel's max_torque. With the same wheels, schedule, method and dt, ``simulate`` integrates
the states of the run engine's :class:`~rigid_rot_sim.run.simulator.Simulator` on the scene bit for
bit (principal frame); its body-frame samples are the integrator's quaternion as is, where the
Simulator's snapshot reports the one with w >= 0, and for a non-principal inertia the rotation to
the body frame may round differently in the last bit.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rigid_rot_sim.core import validation
from rigid_rot_sim.core.arrays import ArrayLike
from rigid_rot_sim.core.steps import step_at_or_after
from rigid_rot_sim.core.wheels import WheelModel, hub_inertia

__all__ = ["wheel_torque_events", "checked_wheels", "checked_wheel_speeds"]


def wheel_torque_events(wheels: WheelModel, wheel_torque: Any, dt: float) -> list[tuple[int, np.ndarray]]:
    """``(step, motor torques N*m)`` events of a constant or scheduled ``wheel_torque`` on the grid of ``dt``.

    Each value is clamped to its wheel's max_torque; ValueError for a wrong number of values,
    a non-finite one, or segment starts that are not finite and increasing.
    """
    if wheel_torque is None:
        return []
    if _is_schedule(wheel_torque):
        pairs = [(s.start, s.torques) if hasattr(s, "torques") else tuple(s) for s in wheel_torque]
    else:
        pairs = [(0.0, wheel_torque)]
    events = []
    previous = -math.inf
    for i, pair in enumerate(pairs):
        if len(pair) != 2:
            raise ValueError(f"wheel_torque[{i}] must be a (start_s, torques) pair, got {pair!r}")
        start = validation.finite_scalar(f"wheel_torque[{i}] start", pair[0])
        if not start > previous:
            raise ValueError(f"wheel_torque[{i}] start {start:g} s must be later than the previous segment's")
        previous = start
        values = np.array(pair[1], dtype=float).reshape(-1)
        if values.size != wheels.count:
            raise ValueError(
                f"wheel_torque[{i}]: {values.size} torque(s) for {wheels.count} wheel(s) [{', '.join(wheels.names)}]"
            )
        if not np.all(np.isfinite(values)):
            raise ValueError(f"wheel_torque[{i}]: torques must be finite, got {values.tolist()}")
        events.append(
            (max(step_at_or_after(start, dt), 0), np.minimum(np.maximum(values, -wheels.max_torque), wheels.max_torque))
        )
    return events


def _is_schedule(wheel_torque: Any) -> bool:
    """A sequence of segments (pairs or objects with ``start`` and ``torques``), not a flat vector of torques."""
    if isinstance(wheel_torque, np.ndarray):
        return wheel_torque.dtype == object or wheel_torque.ndim > 1
    try:
        first = next(iter(wheel_torque))
    except (TypeError, StopIteration):
        return False
    return hasattr(first, "torques") or (not isinstance(first, (str, bytes)) and hasattr(first, "__len__"))


def checked_wheels(wheels: Any, moments: np.ndarray, body: Any) -> WheelModel | None:
    """The wheels with axes in the principal frame (as the run engine rotates them); ValueError if not wheels
    or if they leave no body (``I - sum J g g^T`` not positive definite)."""
    if wheels is None:
        return None
    if not isinstance(wheels, WheelModel):
        raise ValueError(
            f"wheels must be a WheelModel (rigid_rot_sim.core.wheels.wheel_model), got {type(wheels).__name__}"
        )
    principal = dataclasses.replace(wheels, axes=np.ascontiguousarray(body.vector_to_principal(wheels.axes)))
    if wheels.count and not float(np.linalg.eigvalsh(hub_inertia(moments, principal))[0]) > 0.0:
        raise ValueError(
            "wheels: the inertia less the wheels' spin inertias (I - sum J g g^T) must be positive "
            "definite: the inertia includes the wheels"
        )
    return principal


def checked_wheel_speeds(wheels: WheelModel | None, wheel_speeds0: ArrayLike | None) -> np.ndarray:
    """Initial wheel speeds (rad/s, default 0); ValueError for a wrong count, a non-finite one, one beyond max_speed."""
    n_wheels = 0 if wheels is None else wheels.count
    if wheel_speeds0 is None:
        return np.zeros(n_wheels)
    speeds = np.array(wheel_speeds0, dtype=float).reshape(-1)
    if wheels is None or speeds.size != n_wheels:
        raise ValueError(f"wheel_speeds0 has {speeds.size} value(s) for {n_wheels} wheel(s)")
    beyond = ~np.isfinite(speeds) | (np.abs(speeds) > wheels.max_speed)
    if np.any(beyond):
        i = int(np.flatnonzero(beyond)[0])
        raise ValueError(
            f"wheel_speeds0[{i}] = {speeds[i]} rad/s must be finite and within max_speed {wheels.max_speed[i]:g} rad/s"
        )
    return speeds
