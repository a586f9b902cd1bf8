"""``simulate`` for a gyrostat: a body with reaction wheels, under gravity gradient and a constant torque.

:func:`rigid_rot_sim.core.simulate.simulate` hands a call with ``wheels``, ``wheel_speeds0``,
``wheel_torque`` or ``orbit`` to :func:`simulate_gyrostat`, which runs a method of
:data:`~rigid_rot_sim.core.integrators.gyrostat.GYROSTAT_METHODS` on the same time grid as
``simulate`` (full steps of dt, then one shorter step landing on t_end) and returns a
:class:`~rigid_rot_sim.core.simulate.Trajectory` that carries the wheel speeds, its energy and
world momentum those of body and wheels (eqs. (1), (6) of :mod:`rigid_rot_sim.core.wheels`).

Wheel motor torques change only at step boundaries, as in the run engine: a segment starting at
``s`` seconds acts from step ``k = step_at_or_after(s, dt)`` on (the rule of
:mod:`rigid_rot_sim.core.steps`), each value clamped to its wheel's max_torque. With the same
wheels, schedule, method and dt, the states are those of the run engine's
:class:`~rigid_rot_sim.run.simulator.Simulator` on the scene, bit for bit.

Example: a wheel on the body's z axis driven by 0.05 N*m for 10 s; body and wheel trade momentum.

>>> import numpy as np
>>> from rigid_rot_sim.core.wheels import wheel_model
>>> rw = wheel_model(np.diag([10.0, 12.0, 15.0]), ["rw_z"], [[0, 0, 1]], [0.5], [0.1], [1000.0])
>>> traj = simulate_gyrostat((10.0, 12.0, 15.0), (0.0, 0.0, 0.2), 10.0, 0.01, "rk4", wheels=rw,
...                          wheel_speeds0=[10.0], wheel_torque=[0.05])
>>> traj.wheel_speeds.shape, round(float(traj.omega[-1, 2]), 9)    # (I3 - J) dw/dt = -u
((1001, 1), 0.165517241)
>>> bool(np.allclose(traj.L_world, [0.0, 0.0, 15.0 * 0.2 + 0.5 * 10.0], rtol=0, atol=1e-12))
True
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rigid_rot_sim.core import validation
from rigid_rot_sim.core.integrators.gyrostat import get_gyrostat_method
from rigid_rot_sim.core.simulate import (
    Trajectory,
    attitude,
    checked_save_every,
    principal_torque,
    rigid_body,
    step_grid,
)
from rigid_rot_sim.core.steps import step_at_or_after
from rigid_rot_sim.core.wheels import NO_ORBIT, OrbitModel, WheelModel, hub_inertia

__all__ = ["simulate_gyrostat", "wheel_torque_events"]


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
            raise ValueError(f"wheel_torque[{i}]: {values.size} torque(s) for {wheels.count} wheel(s) "
                             f"[{', '.join(wheels.names)}]")
        if not np.all(np.isfinite(values)):
            raise ValueError(f"wheel_torque[{i}]: torques must be finite, got {values.tolist()}")
        events.append((max(step_at_or_after(start, dt), 0), np.minimum(np.maximum(values, -wheels.max_torque),
                                                                       wheels.max_torque)))
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


def _checked_wheels(wheels: Any, moments: np.ndarray, body: Any) -> WheelModel | None:
    """The wheels with axes in the principal frame (as the run engine rotates them); ValueError if not wheels
    or if they leave no body (``I - sum J g g^T`` not positive definite)."""
    if wheels is None:
        return None
    if not isinstance(wheels, WheelModel):
        raise ValueError(f"wheels must be a WheelModel (rigid_rot_sim.core.wheels.wheel_model), got {type(wheels).__name__}")
    principal = dataclasses.replace(wheels, axes=np.ascontiguousarray(body.vector_to_principal(wheels.axes)))
    if wheels.count and not float(np.linalg.eigvalsh(hub_inertia(moments, principal))[0]) > 0.0:
        raise ValueError("wheels: the inertia less the wheels' spin inertias (I - sum J g g^T) must be positive "
                         "definite: the inertia includes the wheels")
    return principal


def simulate_gyrostat(
    inertia: Any, omega0: Any, t_end: float, dt: float, method: str, q0: Any = (0.0, 0.0, 0.0, 1.0),
    torque: Any = None, *, save_every: int = 1, wheels: WheelModel | None = None, wheel_speeds0: Any = None,
    wheel_torque: Any = None, orbit: OrbitModel | None = None, **options: Any,
) -> Trajectory:
    """:func:`~rigid_rot_sim.core.simulate.simulate` with reaction wheels and the gravity gradient.

    Parameters as :func:`~rigid_rot_sim.core.simulate.simulate`'s; ``method`` is ``rk4`` or
    ``dopri5`` (ValueError naming them otherwise), ``torque`` None or a constant body-frame
    vector (N*m). ``wheel_speeds0`` or ``wheel_torque`` need ``wheels``; a wheel speed beyond its
    max_speed is refused.
    """
    body, is_principal = rigid_body(inertia)
    omega0 = validation.finite_vector("omega0", omega0)
    q0 = attitude(q0)
    t_end = validation.nonnegative_scalar("t_end", t_end)
    dt = validation.positive_scalar("dt", dt)
    save_every = checked_save_every(save_every)
    integrator_class = get_gyrostat_method(method)
    if orbit is not None and not isinstance(orbit, OrbitModel):
        raise ValueError(f"orbit must be an OrbitModel (rigid_rot_sim.core.wheels.orbit_model), got {type(orbit).__name__}")
    if wheels is None and (wheel_speeds0 is not None or wheel_torque is not None):
        raise ValueError("wheel_speeds0 and wheel_torque need wheels")
    moments = body.principal_moments
    wheels_p = _checked_wheels(wheels, moments, body)
    n_wheels = 0 if wheels is None else wheels.count
    speeds0 = np.zeros(n_wheels)
    if wheel_speeds0 is not None:
        speeds0 = np.array(wheel_speeds0, dtype=float).reshape(-1)
        if speeds0.size != n_wheels:
            raise ValueError(f"wheel_speeds0 has {speeds0.size} value(s) for {n_wheels} wheel(s)")
        beyond = ~np.isfinite(speeds0) | (np.abs(speeds0) > wheels.max_speed)  # type: ignore[union-attr]
        if np.any(beyond):
            i = int(np.flatnonzero(beyond)[0])
            raise ValueError(f"wheel_speeds0[{i}] = {speeds0[i]} rad/s must be finite and within max_speed "
                             f"{wheels.max_speed[i]:g} rad/s")  # type: ignore[union-attr]
    events = [] if wheels is None else wheel_torque_events(wheels, wheel_torque, dt)

    if is_principal:
        q0_p, omega0_p = q0, omega0
    else:
        q0_p = body.attitude_to_principal(q0)
        omega0_p = body.vector_to_principal(omega0)
    integrator = integrator_class(
        moments, dt, principal_torque(body, torque, is_principal), wheels=wheels_p,
        orbit=NO_ORBIT if orbit is None else orbit, q0=q0_p, omega0=omega0_p, wheel_speeds0=speeds0, **options,
    )

    n_full, last = step_grid(t_end, dt)
    n_saves = n_full // save_every
    tail = n_full > n_saves * save_every or last > 0.0
    n_rows = n_saves + 1 + tail
    t = np.arange(n_rows) * (save_every * dt)
    q_p = np.empty((n_rows, 4))
    omega_p = np.empty((n_rows, 3))
    speeds = np.empty((n_rows, n_wheels))
    q_p[0], omega_p[0], speeds[0] = q0_p, omega0_p, speeds0

    k, row, pending = 0, 1, 0
    while True:
        while pending < len(events) and events[pending][0] <= k:  # the commands due at this boundary
            integrator.set_wheel_commands(events[pending][1])
            pending += 1
        if k >= n_full:
            break
        stop = min(n_full, row * save_every if row <= n_saves else n_full,
                   events[pending][0] if pending < len(events) else n_full)
        integrator.advance(stop - k)
        k = stop
        if row <= n_saves and k == row * save_every:
            q_p[row], omega_p[row], speeds[row] = integrator.q, integrator.omega, integrator.wheel_speeds
            row += 1
    if last > 0.0:
        integrator.dt = last
        integrator.advance(1)
    if tail:
        q_p[-1], omega_p[-1], speeds[-1] = integrator.q, integrator.omega, integrator.wheel_speeds
    if n_full or tail:
        t[-1] = t_end

    if is_principal:
        q_body, omega_body = q_p, omega_p
    else:
        q_body = body.attitude_from_principal(q_p)
        omega_body = body.vector_from_principal(omega_p)
    return Trajectory(
        t=t, q=q_body, omega=omega_body, method=method, principal_moments=moments, q_principal=q_p,
        omega_principal=omega_p, wheel_speeds=speeds if wheels is not None else None, wheels_principal=wheels_p,
    )
