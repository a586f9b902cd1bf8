"""Advance N gyrostats (bodies with reaction wheels) at once, in one compiled loop over the bodies.

Each body runs the single-body kernel :func:`rigid_rot_sim.core.integrators.gyrostat.rk4_advance`
(classical RK4 on ``(q, omega, Omega)``, the equations of :mod:`rigid_rot_sim.core.wheels`) from
its own state, with its own principal moments and motor commands and one wheel set shared by all
bodies (axes in the principal frame). So a body advanced here has the bits of the same body
advanced alone by :class:`~rigid_rot_sim.core.integrators.gyrostat.GyrostatRK4` with those
commands held, and there is no second copy of any formula. No orbit (no gravity gradient) and
no external torque but the optional constant ``torque_body``.

Arrays carry the body index first: principal moments ``(N, 3)`` kg*m^2 (wheels included, as
:func:`~rigid_rot_sim.core.wheels.wheel_model` defines them), attitudes ``(N, 4)`` scalar-last,
principal -> world, rates ``(N, 3)`` rad/s (principal frame), wheel speeds and motor commands
``(N, n)`` rad/s and N*m (commands already clamped to each wheel's max_torque by the caller; the
speed saturation and friction act inside, as in the single-body kernel).
"""

from __future__ import annotations

import numpy as np
from numba import prange

from rigid_rot_sim.core.arrays import ArrayLike
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.integrators.gyrostat import rk4_advance
from rigid_rot_sim.core.integrators.status import OK
from rigid_rot_sim.core.jit import compiled
from rigid_rot_sim.core.wheels import NO_ORBIT, WheelModel, hub_inertia

__all__ = ["advance_gyrostats", "hub_inverses"]

# Below this many body-steps a call runs serially: starting a parallel region costs up to a
# scheduler time slice when the cores are busy (as core/batch.py, whose threshold is 10x higher:
# a gyrostat RK4 step costs ~2 us, a rigid body's ~0.1 us; at 8192 bodies x 10 steps the parallel
# loop took half the serial time on the busy 2-core machine).
_PARALLEL_BODY_STEPS = 20_000


def _kernel(  # each body's steps and status into done[b], status[b]
    dt: float,
    k0: int,
    n_steps: int,
    y: np.ndarray,
    moments: np.ndarray,
    wheels: tuple[np.ndarray, ...],
    hub_inverse: np.ndarray,
    external: np.ndarray,
    orbit: np.ndarray,
    commands: np.ndarray,
    done: np.ndarray,
    status: np.ndarray,
) -> None:
    applied = np.empty(commands.shape[1])
    for b in range(y.shape[0]):
        done[b], status[b] = rk4_advance(
            0.0, k0, dt, n_steps, y[b], moments[b], wheels, hub_inverse[b], external[b], orbit, commands[b], applied
        )


def _kernel_parallel(
    dt: float,
    k0: int,
    n_steps: int,
    y: np.ndarray,
    moments: np.ndarray,
    wheels: tuple[np.ndarray, ...],
    hub_inverse: np.ndarray,
    external: np.ndarray,
    orbit: np.ndarray,
    commands: np.ndarray,
    done: np.ndarray,
    status: np.ndarray,
) -> None:
    for b in prange(y.shape[0]):
        applied = np.empty(commands.shape[1])
        done[b], status[b] = rk4_advance(
            0.0, k0, dt, n_steps, y[b], moments[b], wheels, hub_inverse[b], external[b], orbit, commands[b], applied
        )


_advance_serial = compiled(_kernel)
_advance_parallel = compiled(parallel=True)(_kernel_parallel)


def hub_inverses(principal_moments: ArrayLike, wheels: WheelModel) -> np.ndarray:
    """``inv(I - sum J g g^T)`` (N, 3, 3), 1/(kg*m^2), for each row of ``principal_moments`` (N, 3).

    Each matrix is inverted as :class:`~rigid_rot_sim.core.integrators.gyrostat.GyrostatIntegrator`
    inverts its own (the same bits); compute it once per inertia and pass it to :func:`advance_gyrostats`.
    """
    moments = np.asarray(principal_moments, dtype=float).reshape(-1, 3)
    return np.ascontiguousarray([np.linalg.inv(hub_inertia(row, wheels)) for row in moments])


def advance_gyrostats(
    principal_moments: ArrayLike,
    wheels: WheelModel,
    q: ArrayLike,
    omega: ArrayLike,
    wheel_speeds: ArrayLike,
    wheel_commands: ArrayLike,
    dt: float,
    n_steps: int,
    *,
    torque_body: ArrayLike | None = None,
    hub_inverse: ArrayLike | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Advance N gyrostats by ``n_steps`` RK4 steps of ``dt`` (s); returns new ``(q, omega, wheel_speeds)``.

    Parameters
    ----------
    principal_moments : array_like, (N, 3)
        kg*m^2, wheels included.
    wheels : WheelModel
        The wheel set of every body, axes in the principal frame.
    q, omega, wheel_speeds : array_like, (N, 4), (N, 3), (N, n)
        The states (q taken as it is: the single-body kernel normalises after each step).
    wheel_commands : array_like, (N, n)
        Motor torques (N*m), held over the run.
    torque_body : array_like, (N, 3), optional
        A constant external torque (N*m, principal frame).
    hub_inverse : array_like, (N, 3, 3), optional
        :func:`hub_inverses` of the moments (computed here when omitted).

    Raises
    ------
    ValueError
        Shapes that do not match, non-finite values, dt <= 0 or n_steps < 0.
    NonFiniteStateError
        A step produced a non-finite state (names the first body).
    """
    omega = np.array(omega, dtype=float, order="C", ndmin=2)
    n = omega.shape[0]
    count = wheels.count
    y = np.zeros((n, 7 + 2 * count))  # (q, omega, Omega, theta): the wheel angles start at 0 and are not returned
    y[:, :4] = np.asarray(q, dtype=float).reshape(n, 4)
    y[:, 4:7] = omega.reshape(n, 3)
    y[:, 7 : 7 + count] = np.asarray(wheel_speeds, dtype=float).reshape(n, count)
    moments = np.ascontiguousarray(np.asarray(principal_moments, dtype=float).reshape(n, 3))
    commands = np.ascontiguousarray(np.asarray(wheel_commands, dtype=float).reshape(n, count))
    external = np.zeros((n, 3)) if torque_body is None else np.array(torque_body, dtype=float).reshape(n, 3)
    inverse = hub_inverses(moments, wheels) if hub_inverse is None else np.asarray(hub_inverse, dtype=float)
    inverse = np.ascontiguousarray(inverse.reshape(n, 3, 3))
    for name, array in (("state", y), ("principal_moments", moments), ("wheel_commands", commands)):
        if not np.all(np.isfinite(array)):
            raise ValueError(f"{name} must be finite")
    if not (np.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be finite and > 0, got {dt}")
    if int(n_steps) != n_steps or n_steps < 0:
        raise ValueError(f"n_steps must be a non-negative integer, got {n_steps}")
    done = np.zeros(n, dtype=np.int64)
    status = np.zeros(n, dtype=np.int64)
    run = _advance_parallel if n > 1 and n * n_steps >= _PARALLEL_BODY_STEPS else _advance_serial
    run(
        float(dt),
        0,  # the first step's index (an argument: a literal 0 would compile rk4_advance a second time)
        int(n_steps),
        y,
        moments,
        wheels.compiled(),
        inverse,
        external,
        NO_ORBIT.compiled(),
        commands,
        done,
        status,
    )
    failed = np.flatnonzero(status != OK)
    if failed.size:
        b = int(failed[np.argmin(done[failed])])
        raise NonFiniteStateError(f"gyrostat rk4: non-finite state at step {int(done[b]) + 1} (body {b})")
    return y[:, :4].copy(), y[:, 4:7].copy(), y[:, 7 : 7 + count].copy()
