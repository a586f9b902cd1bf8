"""Advance N independent rigid bodies at once, in parallel over the CPU cores.

Arrays carry the body index first: principal moments ``(N, 3)`` kg*m^2 (or ``(3,)``
shared by all bodies), attitudes ``(N, 4)`` scalar-last quaternions rotating
principal -> world, angular velocities ``(N, 3)`` rad/s and torques ``(N, 3)`` N*m
(or ``(3,)``), both in the principal body frame. Each body's torque is constant in its
body frame over the run (a body-fixed thruster).

Methods (:data:`BATCH_METHODS`): ``'rk4'``, ``'implicit_midpoint'``, ``'splitting'``
(order 2) and ``'exact_split'`` (order 2: the exact free flow with torque kicks), and for
torque-free bodies ``'exact'`` (:data:`FREE_BODY_METHODS`: one evaluation of the exact flow
at ``n_steps * dt``; a torque is refused) run the single-body kernels of
:mod:`rigid_rot_sim.core.integrators` with the same names, body by body, in one compiled loop spread over the cores (numba ``prange``); so a body advanced
here has the same bits as the same body advanced alone by ``get_method(name)`` with a
:class:`~rigid_rot_sim.core.torque.ConstantTorque`, and there is no second copy of any
formula. The compiled loop is cached like the single-body one (``make setup`` builds it).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import prange
from numba.extending import register_jitable

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.exact import free_flow
from rigid_rot_sim.core.integrators import kernels
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.integrators.status import NEWTON_FAILED, NON_FINITE, OK
from rigid_rot_sim.core.jit import compiled
from rigid_rot_sim.core.torque import TORQUE_NONE, TORQUE_TIME

#: Methods for bodies under (per-body) torques.
BATCH_METHODS = ("rk4", "implicit_midpoint", "splitting", "exact_split")
#: Methods for torque-free bodies only (a torque is refused, as by the single-body method).
FREE_BODY_METHODS = ("exact",)

_EXACT = -1  # the exact flow, evaluated once at n_steps * dt (torque-free bodies)
_KERNELS = {
    "rk4": kernels.RK4,
    "implicit_midpoint": kernels.IMPLICIT_MIDPOINT,
    "splitting": kernels.SPLITTING2,
    "exact": _EXACT,
    "exact_split": kernels.EXACT_SPLIT2,
}
_FAILURES = {NON_FINITE: "non-finite state", NEWTON_FAILED: "Newton's method did not converge"}


def _as_batch(name: str, value: Any, n: int | None, width: int) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.ndim == 1:
        if array.shape != (width,):
            raise ValueError(f"{name} must have shape ({width},) or (N, {width}), got {array.shape}")
        array = np.broadcast_to(array, (n if n is not None else 1, width))
    elif array.ndim != 2 or array.shape[1] != width or (n is not None and array.shape[0] != n):
        expected = f"({n}, {width})" if n is not None else f"(N, {width})"
        raise ValueError(f"{name} must have shape ({width},) or {expected}, got {array.shape}")
    bad = ~np.isfinite(array)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"{name}{list(index)} must be finite, got {array[index]}")
    return array


@register_jitable
def _advance_body(b, method, moments, q, omega, torque, dt, n_steps, normalize_q, failed_step, failure):
    """Advance body b in place; if it fails it keeps its last good state and records the
    (1-based) failing step and the status."""
    row = torque[b : b + 1]
    kind = TORQUE_TIME if (row[0, 0] != 0.0 or row[0, 1] != 0.0 or row[0, 2] != 0.0) else TORQUE_NONE
    body_torque = (kind, row, np.zeros(4))
    body_moments = (moments[b, 0], moments[b, 1], moments[b, 2])
    # normalised as Integrator.set_state does it, so that the bits match a single body's
    # (not when continuing: a single body carries its q from one step to the next as it is)
    qx, qy, qz, qw = q[b, 0], q[b, 1], q[b, 2], q[b, 3]
    if normalize_q:
        qx, qy, qz, qw = quat.normalize((qx, qy, qz, qw))
    state = (qx, qy, qz, qw, omega[b, 0], omega[b, 1], omega[b, 2])
    if method == _EXACT:
        # as ExactFlow.advance(n_steps): one evaluation of the flow at n_steps * dt
        done, status = n_steps, OK
        if n_steps > 0:
            q_end, w_end = free_flow(body_moments, (qx, qy, qz, qw), (state[4], state[5], state[6]), n_steps * dt)
            finite = True
            for x in q_end + w_end:
                finite = finite and math.isfinite(x)
            if finite:
                state = (q_end[0], q_end[1], q_end[2], q_end[3], w_end[0], w_end[1], w_end[2])
            else:
                done, status = n_steps - 1, NON_FINITE
    else:
        state, done, status, bad = kernels.advance_steps(
            method, 0.0, 0, dt, n_steps, state, body_moments, body_torque, 0, np.empty((0, 7))
        )
    for i in range(4):
        q[b, i] = state[i]
    for i in range(3):
        omega[b, i] = state[4 + i]
    if status != OK:
        failed_step[b] = done + 1
        failure[b] = status


@compiled(parallel=True)
def _advance_bodies_parallel(method, moments, q, omega, torque, dt, n_steps, normalize_q, failed_step, failure):
    for b in prange(q.shape[0]):
        _advance_body(b, method, moments, q, omega, torque, dt, n_steps, normalize_q, failed_step, failure)


# Serial for small jobs: starting the parallel region costs up to a scheduler time slice
# (milliseconds) when the cores are busy with other work.
@compiled
def _advance_bodies_serial(method, moments, q, omega, torque, dt, n_steps, normalize_q, failed_step, failure):
    for b in range(q.shape[0]):
        _advance_body(b, method, moments, q, omega, torque, dt, n_steps, normalize_q, failed_step, failure)


_PARALLEL_BODY_STEPS = 200_000


def advance_batch(
    method: str,
    principal_moments: Any,
    q: Any,
    omega: Any,
    dt: float,
    n_steps: int,
    torque_body: Any = None,
    *,
    normalize_q: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Advance N bodies by ``n_steps`` steps of ``dt`` (s); returns new ``(q, omega)``.

    Parameters
    ----------
    method : {'rk4', 'implicit_midpoint', 'splitting', 'exact', 'exact_split'}
    principal_moments : array_like, (3,) or (N, 3)
        kg*m^2, each row > 0.
    q : array_like, (N, 4)
        Unit quaternions (x, y, z, w), principal -> world; normalised on entry unless
        ``normalize_q`` is False.
    omega : array_like, (N, 3)
        rad/s, principal body frame.
    dt : float
        s, > 0.
    n_steps : int
        >= 0.
    torque_body : array_like, (3,) or (N, 3), optional
        N*m, principal body frame, constant over the run (one per body or shared).
    normalize_q : bool, optional
        False to continue from states this function returned, as a single body's
        integrator continues from its own: q is taken as it is (normalising it again would
        round it differently), so a run cut into calls (torque changes) has the bits of one
        integrator stepping through it.

    Raises
    ------
    ValueError
        Bad input, naming the argument and the index.
    NonFiniteStateError
        A step produced a non-finite state (names the step and the first body).
    """
    if method not in _KERNELS:
        raise ValueError(f"method must be one of {list(BATCH_METHODS + FREE_BODY_METHODS)}, got {method!r}")
    omega = np.array(_as_batch("omega", omega, None, 3), dtype=float, order="C")
    n = omega.shape[0]
    q = np.array(_as_batch("q", q, n, 4), dtype=float, order="C")
    # writable C-contiguous copies: the one type the compiled loop was built for
    moments = np.array(_as_batch("principal_moments", principal_moments, n, 3), dtype=float, order="C")
    nonpositive = moments <= 0.0
    if nonpositive.any():
        index = tuple(int(i) for i in np.argwhere(nonpositive)[0])
        raise ValueError(f"principal_moments{list(index)} must be > 0, got {moments[index]}")
    norms = np.sqrt(np.einsum("ij,ij->i", q, q))
    if np.any(norms == 0.0):
        raise ValueError(f"q[{int(np.argmin(norms))}] must be a non-zero quaternion")
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be finite and > 0, got {dt}")
    if int(n_steps) != n_steps or n_steps < 0:
        raise ValueError(f"n_steps must be a non-negative integer, got {n_steps}")
    if torque_body is None:
        torque = np.zeros((n, 3))
    else:
        torque = np.array(_as_batch("torque_body", torque_body, n, 3), dtype=float, order="C")
    if method == "exact" and np.any(torque):
        raise ValueError("exact: torque_body must be None or zero (the exact flow is torque-free); use exact_split")
    failed_step = np.zeros(n, dtype=np.int64)
    failure = np.zeros(n, dtype=np.int64)
    parallel = n > 1 and n * int(n_steps) >= _PARALLEL_BODY_STEPS
    run = _advance_bodies_parallel if parallel else _advance_bodies_serial
    run(_KERNELS[method], moments, q, omega, torque, float(dt), int(n_steps), bool(normalize_q), failed_step, failure)
    if failed_step.any():
        # report the earliest failure (the bodies ran independently, in parallel)
        bad = int(np.argmin(np.where(failed_step > 0, failed_step, np.iinfo(np.int64).max)))
        step = int(failed_step[bad])
        raise NonFiniteStateError(
            f"{method}: {_FAILURES.get(int(failure[bad]), 'failure')} at step {step}, t = {step * dt:.9g} s (body {bad})"
        )
    return q, omega
