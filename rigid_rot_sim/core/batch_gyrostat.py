"""Advance N gyrostats (bodies with reaction wheels) at once, compiled, in parallel over the cores.

Classical RK4 on ``(q, omega, Omega)``, the equations of :mod:`rigid_rot_sim.core.wheels`, each
body from its own state, with its own principal moments and motor commands and one wheel set
shared by all bodies (axes in the principal frame). Two layouts, the same bits: ``'per_body'``
runs the single-body kernel :func:`rigid_rot_sim.core.integrators.gyrostat.rk4_advance` body by
body; ``'soa'`` (the default, ~4x faster) re-writes its operations, in its order, for chunks of
bodies laid out for SIMD (``_rk4_soa_chunk``: the one deliberate second copy of the formula, as
:mod:`rigid_rot_sim.core.batch` has for rigid bodies, pinned bit for bit by
``test/core/test_batch_gyrostat.py``). So a body advanced here has the bits of the same body
advanced alone by :class:`~rigid_rot_sim.core.integrators.gyrostat.GyrostatRK4` with those
commands held. No orbit (no gravity gradient) and no external torque but the optional constant
``torque_body``.

Arrays carry the body index first: principal moments ``(N, 3)`` kg*m^2 (wheels included, as
:func:`~rigid_rot_sim.core.wheels.wheel_model` defines them), attitudes ``(N, 4)`` scalar-last,
principal -> world, rates ``(N, 3)`` rad/s (principal frame), wheel speeds and motor commands
``(N, n)`` rad/s and N*m (commands already clamped to each wheel's max_torque by the caller; the
speed saturation and friction act inside, as in the single-body kernel).
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange
from numba.extending import register_jitable

from rigid_rot_sim.core.arrays import ArrayLike
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.integrators.gyrostat import rk4_advance
from rigid_rot_sim.core.integrators.status import NON_FINITE, OK
from rigid_rot_sim.core.jit import compiled
from rigid_rot_sim.core.wheels import NO_ORBIT, WheelModel, hub_inertia

__all__ = ["advance_gyrostats", "hub_inverses"]

# Below this many body-steps a call runs serially: starting a parallel region costs up to a
# scheduler time slice when the cores are busy (as core/batch.py, whose threshold is 10x higher:
# a gyrostat RK4 step costs 65-100 ns in the SIMD layout, ~0.3 us body by body; at 8192 bodies x
# 10 steps the environment step took 0.7-1.5x the serial time in parallel on the busy 2-core machine).
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


# -- RK4 laid out for SIMD ------------------------------------------------------------------
#
# The loop above runs rk4_advance body by body: each step's stages wait on each other, and a
# gyrostat RK4 step costs ~0.3 us there (latency-bound, the scratch arrays of each call on the
# heap). Below, the bodies are taken in chunks held as structure of arrays (one row per state
# component, the inner loops over the chunk's bodies, which LLVM vectorises: AVX2/AVX-512
# lanes) and every operation is rk4_advance's and gyrostat_rhs's own, in their order (the
# motor's speed fade and the friction as selects instead of branches); numba compiles without
# fastmath, so each body gets the bits of the single-body kernel (test/core/test_batch_gyrostat.py
# pins the two layouts and GyrostatRK4 bit for bit). Not carried: the wheel angles, which feed
# back into nothing (the per-body loop carries them, and counts them in its finiteness test).

_SOA_CHUNK = 128  # bodies per chunk: its ~100 scratch rows stay in the L2 cache


@register_jitable
def _rhs_soa(
    m: int,
    x: np.ndarray,
    dy: np.ndarray,
    moments: np.ndarray,
    wheels: tuple[np.ndarray, ...],
    hub: np.ndarray,
    external: np.ndarray,
    commands: np.ndarray,
    acc: np.ndarray,
    net: np.ndarray,
) -> None:
    """gyrostat_rhs without an orbit for the chunk's bodies: rows of ``x`` (q, omega, Omega) -> rows of ``dy``."""
    axes, spin, max_speed, ramp, coulomb, viscous, stiction = wheels
    count = spin.shape[0]
    for j in range(m):
        acc[0, j] = moments[0, j] * x[4, j]
        acc[1, j] = moments[1, j] * x[5, j]
        acc[2, j] = moments[2, j] * x[6, j]
        acc[3, j] = external[0, j] + 0.0  # + the gravity-gradient torque, 0.0 without an orbit
        acc[4, j] = external[1, j] + 0.0
        acc[5, j] = external[2, j] + 0.0
    for i in range(count):
        g1, g2, g3 = axes[i, 0], axes[i, 1], axes[i, 2]
        top, fade, c, v, s0, jw = max_speed[i], ramp[i], coulomb[i], viscous[i], stiction[i], spin[i]
        for j in range(m):
            speed = x[7 + i, j]
            command = commands[i, j]
            # applied_motor_torque and friction_torque, every value computed and then selected (exclusive
            # conditions, so the same result as their branches): LLVM vectorises selects, not branches
            margin = (top - abs(speed)) / fade
            faded = command * margin
            faded = 0.0 if margin <= 0.0 else faded
            faded = command if margin >= 1.0 else faded
            u = command if command * speed <= 0.0 else faded
            sign = speed / s0
            sign = -1.0 if speed < -s0 else sign
            sign = 1.0 if speed > s0 else sign
            torque = u - (c * sign + v * speed)
            net[i, j] = torque
            h = jw * speed
            acc[0, j] += h * g1
            acc[1, j] += h * g2
            acc[2, j] += h * g3
            acc[3, j] -= torque * g1
            acc[4, j] -= torque * g2
            acc[5, j] -= torque * g3
    for j in range(m):
        qx, qy, qz, qw = x[0, j], x[1, j], x[2, j], x[3, j]
        w1, w2, w3 = x[4, j], x[5, j], x[6, j]
        h1, h2, h3 = acc[0, j], acc[1, j], acc[2, j]
        r1 = acc[3, j] - (w2 * h3 - w3 * h2)
        r2 = acc[4, j] - (w3 * h1 - w1 * h3)
        r3 = acc[5, j] - (w1 * h2 - w2 * h1)
        a1 = hub[0, j] * r1 + hub[1, j] * r2 + hub[2, j] * r3
        a2 = hub[3, j] * r1 + hub[4, j] * r2 + hub[5, j] * r3
        a3 = hub[6, j] * r1 + hub[7, j] * r2 + hub[8, j] * r3
        dy[0, j] = 0.5 * (qw * w1 + qx * 0.0 + qy * w3 - qz * w2)  # quaternion.multiply(q, (omega, 0))
        dy[1, j] = 0.5 * (qw * w2 - qx * w3 + qy * 0.0 + qz * w1)
        dy[2, j] = 0.5 * (qw * w3 + qx * w2 - qy * w1 + qz * 0.0)
        dy[3, j] = 0.5 * (qw * 0.0 - qx * w1 - qy * w2 - qz * w3)
        dy[4, j], dy[5, j], dy[6, j] = a1, a2, a3
        acc[0, j], acc[1, j], acc[2, j] = a1, a2, a3
    for i in range(count):
        g1, g2, g3, jw = axes[i, 0], axes[i, 1], axes[i, 2], spin[i]
        for j in range(m):
            dy[7 + i, j] = net[i, j] / jw - (g1 * acc[0, j] + g2 * acc[1, j] + g3 * acc[2, j])


@register_jitable
def _rk4_soa_chunk(
    start: int,
    stop: int,
    dt: float,
    n_steps: int,
    y: np.ndarray,
    moments: np.ndarray,
    wheels: tuple[np.ndarray, ...],
    hub_inverse: np.ndarray,
    external: np.ndarray,
    commands: np.ndarray,
    done: np.ndarray,
    status: np.ndarray,
) -> None:
    m = stop - start
    count = commands.shape[1]
    rows = 7 + count
    x = np.empty((rows, m))
    stage = np.empty((rows, m))
    k = np.empty((4, rows, m))
    inertia = np.empty((3, m))
    hub = np.empty((9, m))
    torque = np.empty((3, m))
    command = np.empty((count, m))
    acc = np.empty((6, m))
    net = np.empty((count, m))
    alive = np.ones(m, dtype=np.bool_)
    keep = np.empty(m, dtype=np.bool_)
    for j in range(m):
        b = start + j
        for r in range(rows):
            x[r, j] = y[b, r]
        for c in range(3):
            inertia[c, j] = moments[b, c]
            torque[c, j] = external[b, c]
            for d in range(3):
                hub[3 * c + d, j] = hub_inverse[b, c, d]
        for i in range(count):
            command[i, j] = commands[b, i]
        done[b] = n_steps
        status[b] = OK
    h = dt
    hh = 0.5 * h
    h6 = h / 6.0
    for step in range(n_steps):
        _rhs_soa(m, x, k[0], inertia, wheels, hub, torque, command, acc, net)
        for r in range(rows):
            for j in range(m):
                stage[r, j] = x[r, j] + hh * k[0, r, j]
        _rhs_soa(m, stage, k[1], inertia, wheels, hub, torque, command, acc, net)
        for r in range(rows):
            for j in range(m):
                stage[r, j] = x[r, j] + hh * k[1, r, j]
        _rhs_soa(m, stage, k[2], inertia, wheels, hub, torque, command, acc, net)
        for r in range(rows):
            for j in range(m):
                stage[r, j] = x[r, j] + h * k[2, r, j]
        _rhs_soa(m, stage, k[3], inertia, wheels, hub, torque, command, acc, net)
        for r in range(rows):
            for j in range(m):
                stage[r, j] = x[r, j] + h6 * (k[0, r, j] + 2.0 * (k[1, r, j] + k[2, r, j]) + k[3, r, j])
        for j in range(m):  # normalise q; a body whose step is not finite keeps its last state
            nx, ny, nz, nw = stage[0, j], stage[1, j], stage[2, j], stage[3, j]
            norm = math.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
            stage[0, j], stage[1, j], stage[2, j], stage[3, j] = nx / norm, ny / norm, nz / norm, nw / norm
            keep[j] = (norm - norm == 0.0) & (norm > 0.0)
        for r in range(rows):
            for j in range(m):
                keep[j] = keep[j] & (stage[r, j] - stage[r, j] == 0.0)
        for j in range(m):
            was_alive = alive[j]
            now = was_alive & keep[j]
            keep[j] = now
            done[start + j] = step if was_alive != now else done[start + j]
            status[start + j] = NON_FINITE if was_alive != now else status[start + j]
            alive[j] = now
        for r in range(rows):
            for j in range(m):
                x[r, j] = stage[r, j] if keep[j] else x[r, j]
    for j in range(m):
        for r in range(rows):
            y[start + j, r] = x[r, j]


# error_model="numpy": a division is the IEEE one without numba's zero-divisor test (a branch that
# stops LLVM from vectorising); the divisors are the wheels' ramps, stiction speeds and spin
# inertias (> 0, checked by wheel_model) and a quaternion norm, whose zero is reported.
@compiled(parallel=True, error_model="numpy")
def _rk4_soa_parallel(
    dt: float,
    n_steps: int,
    y: np.ndarray,
    moments: np.ndarray,
    wheels: tuple[np.ndarray, ...],
    hub_inverse: np.ndarray,
    external: np.ndarray,
    commands: np.ndarray,
    done: np.ndarray,
    status: np.ndarray,
) -> None:
    n = y.shape[0]
    for c in prange((n + _SOA_CHUNK - 1) // _SOA_CHUNK):
        start = c * _SOA_CHUNK
        stop = min(n, start + _SOA_CHUNK)
        _rk4_soa_chunk(start, stop, dt, n_steps, y, moments, wheels, hub_inverse, external, commands, done, status)


@compiled(error_model="numpy")
def _rk4_soa_serial(
    dt: float,
    n_steps: int,
    y: np.ndarray,
    moments: np.ndarray,
    wheels: tuple[np.ndarray, ...],
    hub_inverse: np.ndarray,
    external: np.ndarray,
    commands: np.ndarray,
    done: np.ndarray,
    status: np.ndarray,
) -> None:
    n = y.shape[0]
    for start in range(0, n, _SOA_CHUNK):
        stop = min(n, start + _SOA_CHUNK)
        _rk4_soa_chunk(start, stop, dt, n_steps, y, moments, wheels, hub_inverse, external, commands, done, status)


def hub_inverses(principal_moments: ArrayLike, wheels: WheelModel) -> np.ndarray:
    """``inv(I - sum J g g^T)`` (N, 3, 3), 1/(kg*m^2), for each row of ``principal_moments`` (N, 3).

    Each matrix is inverted as :class:`~rigid_rot_sim.core.integrators.gyrostat.GyrostatIntegrator`
    inverts its own (the same bits); compute it once per inertia and pass it to :func:`advance_gyrostats`.
    """
    moments = np.asarray(principal_moments, dtype=float).reshape(-1, 3)
    if moments.shape[0] == 0:
        return np.zeros((0, 3, 3))
    # one stacked call: numpy's inv runs LAPACK's gesv matrix by matrix, the bits of one call each
    return np.ascontiguousarray(np.linalg.inv(np.array([hub_inertia(row, wheels) for row in moments])))


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
    layout: str = "soa",
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
    layout : {'soa', 'per_body'}
        'soa' (default): chunks of bodies laid out for SIMD; 'per_body': the single-body kernel
        body by body. The same bits either way.

    Raises
    ------
    ValueError
        Shapes that do not match, non-finite values, dt <= 0 or n_steps < 0.
    NonFiniteStateError
        A step produced a non-finite state (names the first body).
    """
    if layout not in ("soa", "per_body"):
        raise ValueError(f"layout must be 'soa' or 'per_body', got {layout!r}")
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
    parallel = n > 1 and n * n_steps >= _PARALLEL_BODY_STEPS
    if layout == "soa":
        run_soa = _rk4_soa_parallel if parallel else _rk4_soa_serial
        run_soa(float(dt), int(n_steps), y, moments, wheels.compiled(), inverse, external, commands, done, status)
    else:
        run = _advance_parallel if parallel else _advance_serial
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
