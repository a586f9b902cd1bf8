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
:mod:`rigid_rot_sim.core.integrators` with the same names, body by body, in one compiled
loop spread over the cores (numba ``prange``); so a body advanced here has the same bits as
the same body advanced alone by ``get_method(name)`` with a
:class:`~rigid_rot_sim.core.torque.ConstantTorque`. The compiled loop is cached like the
single-body one (``make setup`` builds it). The one second copy of a formula is deliberate:
``rk4`` (the sweeps' workhorse) runs by default in chunks of bodies laid out for SIMD
(structure of arrays, the inner loops over bodies, see ``_rk4_soa_chunk``), which re-writes
rk4_step's operations in its order, so the same bits as the per-body loop
(``layout="per_body"``; ``test/core/test_batch.py`` pins the two bit for bit).
:func:`advance_batch_recording` runs several stretches in one call and keeps the rates at the
end of each (a sweep's checkpoints), with the bits of calls cut there.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange
from numba.extending import register_jitable

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.arrays import ArrayLike, FloatArray, IntArray
from rigid_rot_sim.core.exact import free_flow
from rigid_rot_sim.core.integrators import kernels
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.integrators.status import NEWTON_FAILED, NON_FINITE, OK
from rigid_rot_sim.core.jit import serial_and_parallel
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


def _as_batch(name: str, value: ArrayLike, n: int | None, width: int) -> np.ndarray:
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
def _advance_body(
    b: int,
    method: int,
    moments: FloatArray,
    q: FloatArray,
    omega: FloatArray,
    torque: FloatArray,
    dt: float,
    n_steps: int,
    normalize_q: bool,
    failed_step: IntArray,
    failure: IntArray,
    record_steps: IntArray,
    omega_at: FloatArray,
) -> None:
    """Advance body b in place; if it fails it keeps its last good state and records the
    (1-based) failing step and the status. After each of ``record_steps`` (increasing, 1-based)
    its rates go to ``omega_at[r, b]``: the run is cut there into calls as separate
    advance_batch calls would cut it, so that it has their bits."""
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
    n_records = record_steps.shape[0]
    no_saves = np.empty((0, 7))
    begun = 0
    for r in range(n_records + 1):
        end = record_steps[r] if r < n_records else n_steps
        span = end - begun
        if method == _EXACT:
            # as ExactFlow.advance(span): one evaluation of the flow at span * dt
            done, status = span, OK
            if span > 0:
                q_end, w_end = free_flow(  # exact.py's kernels are untyped
                    body_moments, (state[0], state[1], state[2], state[3]), (state[4], state[5], state[6]), span * dt
                )
                finite = True
                for x in q_end + w_end:
                    finite = finite and math.isfinite(x)
                if finite:
                    state = (q_end[0], q_end[1], q_end[2], q_end[3], w_end[0], w_end[1], w_end[2])
                else:
                    done, status = span - 1, NON_FINITE
        else:
            state, done, status, bad = kernels.advance_steps(
                method, 0.0, 0, dt, span, state, body_moments, body_torque, 0, no_saves
            )
        if status != OK:
            failed_step[b] = begun + done + 1
            failure[b] = status
            break
        if r < n_records:
            for i in range(3):
                omega_at[r, b, i] = state[4 + i]
        begun = end
    for i in range(4):
        q[b, i] = state[i]
    for i in range(3):
        omega[b, i] = state[4 + i]


def _advance_bodies(
    method: int,
    moments: FloatArray,
    q: FloatArray,
    omega: FloatArray,
    torque: FloatArray,
    dt: float,
    n_steps: int,
    normalize_q: bool,
    failed_step: IntArray,
    failure: IntArray,
    record_steps: IntArray,
    omega_at: FloatArray,
) -> None:
    for b in prange(q.shape[0]):
        _advance_body(
            b, method, moments, q, omega, torque, dt, n_steps, normalize_q, failed_step, failure, record_steps, omega_at
        )


# Serial for small jobs: starting the parallel region costs up to a scheduler time slice
# (milliseconds) when the cores are busy with other work.
_advance_bodies_serial, _advance_bodies_parallel = serial_and_parallel(_advance_bodies)

_PARALLEL_BODY_STEPS = 200_000

# -- rk4 laid out for SIMD ------------------------------------------------------------------
#
# The loops above advance one body through all its steps: a step's stages depend on each
# other, so the core waits on every division and square root (latency-bound, ~200 ns per
# body-step). Below, the bodies are taken in chunks held as structure of arrays (one row per
# component) and each step runs as three loops over the chunk's bodies: the stages up to the
# rotation vector (branch-free arithmetic that LLVM vectorises: AVX2/AVX-512 lanes), the
# exponential map's sine and cosine (libm, one body at a time: a vectorised sine would round
# differently), and the product, normalisation and finiteness test (vectorised, with selects
# instead of branches). Every operation is rk4_step's own, in its order (explicit.py: Euler's
# equations, _dexpinv, quaternion.exp_rotation_vector, multiply, normalize), and numba
# compiles without fastmath, so each body gets the bits of the single-body kernel;
# test/core/test_batch.py checks it against RK4 body by body.

_SOA_CHUNK = 512  # bodies per chunk: its scratch rows stay in the L1/L2 cache


@register_jitable
def _rk4_soa_chunk(
    start: int,
    stop: int,
    moments: FloatArray,
    q: FloatArray,
    omega: FloatArray,
    torque: FloatArray,
    dt: float,
    n_steps: int,
    normalize_q: bool,
    failed_step: IntArray,
    failure: IntArray,
    record_steps: IntArray,
    omega_at: FloatArray,
) -> None:
    m = stop - start
    # state and per-body constants, one row per component
    x = np.empty((7, m))  # qx, qy, qz, qw, w1, w2, w3
    k = np.empty((6, m))  # I1, I2, I3, N1, N2, N3
    r = np.empty((7, m))  # rotation vector u, its angle, new omega
    sc = np.empty((2, m))  # sin(|u|/2)/|u|, cos(|u|/2)
    alive = np.ones(m, dtype=np.bool_)
    for j in range(m):
        b = start + j
        qx, qy, qz, qw = q[b, 0], q[b, 1], q[b, 2], q[b, 3]
        if normalize_q:  # as _advance_body: continuing from our own output takes q as it is
            qx, qy, qz, qw = quat.normalize((qx, qy, qz, qw))
        x[0, j], x[1, j], x[2, j], x[3, j] = qx, qy, qz, qw
        for i in range(3):
            x[4 + i, j] = omega[b, i]
            k[i, j] = moments[b, i]
        forced = torque[b, 0] != 0.0 or torque[b, 1] != 0.0 or torque[b, 2] != 0.0
        for i in range(3):  # as torque_at: the row when any component is non-zero, else 0.0
            k[3 + i, j] = torque[b, i] if forced else 0.0
    h = dt
    hh = 0.5 * h
    h6 = h / 6.0
    record = 0
    for step in range(n_steps):
        for j in range(m):
            i1, i2, i3, n1, n2, n3 = k[0, j], k[1, j], k[2, j], k[3, j], k[4, j], k[5, j]
            w1, w2, w3 = x[4, j], x[5, j], x[6, j]
            # stage 1
            a1 = ((i2 - i3) * w2 * w3 + n1) / i1
            b1 = ((i3 - i1) * w3 * w1 + n2) / i2
            c1 = ((i1 - i2) * w1 * w2 + n3) / i3
            # stage 2
            x1, x2, x3 = w1 + hh * a1, w2 + hh * b1, w3 + hh * c1
            u1, u2, u3 = hh * w1, hh * w2, hh * w3
            a2 = ((i2 - i3) * x2 * x3 + n1) / i1
            b2 = ((i3 - i1) * x3 * x1 + n2) / i2
            c2 = ((i1 - i2) * x1 * x2 + n3) / i3
            d1, d2, d3 = u2 * x3 - u3 * x2, u3 * x1 - u1 * x3, u1 * x2 - u2 * x1
            v21 = x1 + 0.5 * d1 + (u2 * d3 - u3 * d2) / 12.0
            v22 = x2 + 0.5 * d2 + (u3 * d1 - u1 * d3) / 12.0
            v23 = x3 + 0.5 * d3 + (u1 * d2 - u2 * d1) / 12.0
            # stage 3
            x1, x2, x3 = w1 + hh * a2, w2 + hh * b2, w3 + hh * c2
            u1, u2, u3 = hh * v21, hh * v22, hh * v23
            a3 = ((i2 - i3) * x2 * x3 + n1) / i1
            b3 = ((i3 - i1) * x3 * x1 + n2) / i2
            c3 = ((i1 - i2) * x1 * x2 + n3) / i3
            d1, d2, d3 = u2 * x3 - u3 * x2, u3 * x1 - u1 * x3, u1 * x2 - u2 * x1
            v31 = x1 + 0.5 * d1 + (u2 * d3 - u3 * d2) / 12.0
            v32 = x2 + 0.5 * d2 + (u3 * d1 - u1 * d3) / 12.0
            v33 = x3 + 0.5 * d3 + (u1 * d2 - u2 * d1) / 12.0
            # stage 4
            x1, x2, x3 = w1 + h * a3, w2 + h * b3, w3 + h * c3
            u1, u2, u3 = h * v31, h * v32, h * v33
            a4 = ((i2 - i3) * x2 * x3 + n1) / i1
            b4 = ((i3 - i1) * x3 * x1 + n2) / i2
            c4 = ((i1 - i2) * x1 * x2 + n3) / i3
            d1, d2, d3 = u2 * x3 - u3 * x2, u3 * x1 - u1 * x3, u1 * x2 - u2 * x1
            v41 = x1 + 0.5 * d1 + (u2 * d3 - u3 * d2) / 12.0
            v42 = x2 + 0.5 * d2 + (u3 * d1 - u1 * d3) / 12.0
            v43 = x3 + 0.5 * d3 + (u1 * d2 - u2 * d1) / 12.0
            v1 = h6 * (w1 + 2.0 * (v21 + v31) + v41)
            v2 = h6 * (w2 + 2.0 * (v22 + v32) + v42)
            v3 = h6 * (w3 + 2.0 * (v23 + v33) + v43)
            r[0, j], r[1, j], r[2, j] = v1, v2, v3
            r[3, j] = math.sqrt(v1 * v1 + v2 * v2 + v3 * v3)
            r[4, j] = w1 + h6 * (a1 + 2.0 * (a2 + a3) + a4)
            r[5, j] = w2 + h6 * (b1 + 2.0 * (b2 + b3) + b4)
            r[6, j] = w3 + h6 * (c1 + 2.0 * (c2 + c3) + c4)
        for j in range(m):  # exp_rotation_vector's scalar part
            angle = r[3, j]
            if not angle < math.inf:
                sc[0, j], sc[1, j] = math.nan, math.nan
            elif angle < quat.SMALL_ANGLE:
                sc[0, j], sc[1, j] = 0.5 - angle * angle / 48.0, 1.0 - angle * angle / 8.0
            else:
                half = 0.5 * angle
                sc[0, j], sc[1, j] = math.sin(half) / angle, math.cos(half)
        for j in range(m):
            s, c = sc[0, j], sc[1, j]
            ex, ey, ez, ew = s * r[0, j], s * r[1, j], s * r[2, j], c
            px, py, pz, pw = x[0, j], x[1, j], x[2, j], x[3, j]
            nx = pw * ex + px * ew + py * ez - pz * ey
            ny = pw * ey - px * ez + py * ew + pz * ex
            nz = pw * ez + px * ey - py * ex + pz * ew
            nw = pw * ew - px * ex - py * ey - pz * ez
            inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
            nx, ny, nz, nw = nx * inv, ny * inv, nz * inv, nw * inv
            w1, w2, w3 = r[4, j], r[5, j], r[6, j]
            finite = (
                (nx - nx == 0.0)
                & (ny - ny == 0.0)
                & (nz - nz == 0.0)
                & (nw - nw == 0.0)
                & (w1 - w1 == 0.0)
                & (w2 - w2 == 0.0)
                & (w3 - w3 == 0.0)
            )
            was_alive = alive[j]
            keep = was_alive & finite
            x[0, j] = nx if keep else px
            x[1, j] = ny if keep else py
            x[2, j] = nz if keep else pz
            x[3, j] = nw if keep else pw
            x[4, j] = w1 if keep else x[4, j]
            x[5, j] = w2 if keep else x[5, j]
            x[6, j] = w3 if keep else x[6, j]
            failed_step[start + j] = step + 1 if was_alive != keep else failed_step[start + j]  # failed now
            alive[j] = keep
        if record < record_steps.shape[0] and step + 1 == record_steps[record]:
            for j in range(m):
                for i in range(3):
                    omega_at[record, start + j, i] = x[4 + i, j]
            record += 1
    for j in range(m):
        b = start + j
        for i in range(4):
            q[b, i] = x[i, j]
        for i in range(3):
            omega[b, i] = x[4 + i, j]
        if not alive[j]:
            failure[b] = NON_FINITE


# error_model="numpy": a division is the IEEE one without numba's zero-divisor test (a branch that
# stops LLVM from vectorising); the divisors here are moments (> 0, checked), constants and a
# quaternion norm, whose zero gives a non-finite state, reported as such.
def _rk4_soa(
    moments: FloatArray,
    q: FloatArray,
    omega: FloatArray,
    torque: FloatArray,
    dt: float,
    n_steps: int,
    normalize_q: bool,
    failed_step: IntArray,
    failure: IntArray,
    record_steps: IntArray,
    omega_at: FloatArray,
) -> None:
    n = q.shape[0]
    for c in prange((n + _SOA_CHUNK - 1) // _SOA_CHUNK):
        start = c * _SOA_CHUNK
        _rk4_soa_chunk(
            start,
            min(n, start + _SOA_CHUNK),
            moments,
            q,
            omega,
            torque,
            dt,
            n_steps,
            normalize_q,
            failed_step,
            failure,
            record_steps,
            omega_at,
        )


_rk4_soa_serial, _rk4_soa_parallel = serial_and_parallel(_rk4_soa, error_model="numpy")


def advance_batch(
    method: str,
    principal_moments: ArrayLike,
    q: ArrayLike,
    omega: ArrayLike,
    dt: float,
    n_steps: int,
    torque_body: ArrayLike | None = None,
    *,
    normalize_q: bool = True,
    layout: str = "soa",
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
    layout : {'soa', 'per_body'}
        How rk4 runs: 'soa' (default) in chunks of bodies laid out for SIMD, 'per_body' one
        body after another (the loop the other methods use). The same bits either way.

    Raises
    ------
    ValueError
        Bad input, naming the argument and the index.
    NonFiniteStateError
        A step produced a non-finite state (names the step and the first body).
    """
    if int(n_steps) != n_steps or n_steps < 0:
        raise ValueError(f"n_steps must be a non-negative integer, got {n_steps}")
    q_end, omega_end, _ = _advance(
        method,
        principal_moments,
        q,
        omega,
        dt,
        int(n_steps),
        torque_body,
        normalize_q,
        layout,
        np.empty(0, dtype=np.int64),
    )
    return q_end, omega_end


def advance_batch_recording(
    method: str,
    principal_moments: ArrayLike,
    q: ArrayLike,
    omega: ArrayLike,
    dt: float,
    record_steps: ArrayLike,
    torque_body: ArrayLike | None = None,
    *,
    normalize_q: bool = True,
    layout: str = "soa",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`advance_batch` over ``record_steps[-1]`` steps, keeping the rates after each of ``record_steps``.

    Returns ``(q, omega, omega_at)``: the final states, as advance_batch gives them, and
    ``omega_at`` (K, N, 3) rad/s, principal body frame, the rates after ``record_steps[k]``
    steps. Every value has the bits of advance_batch calls cut at those steps (the first
    with ``normalize_q``, the others continuing with ``normalize_q=False``), in one call:
    a sweep's checkpoints without a return to Python at each (~5 % of a short run's time).

    record_steps : array_like of int, (K,)
        Increasing, >= 1.

    Raises
    ------
    ValueError, NonFiniteStateError
        As advance_batch. After a failure the records are not defined: run the calls cut
        there to see which came before it.
    """
    steps = np.asarray(record_steps)
    if steps.ndim != 1 or steps.size == 0 or not np.issubdtype(steps.dtype, np.integer):
        raise ValueError(f"record_steps must be a non-empty 1-D array of integers, got {record_steps!r}")
    if steps[0] < 1 or np.any(np.diff(steps) <= 0):
        raise ValueError(f"record_steps must be increasing and >= 1, got {steps.tolist()}")
    steps = np.ascontiguousarray(steps, dtype=np.int64)
    return _advance(method, principal_moments, q, omega, dt, int(steps[-1]), torque_body, normalize_q, layout, steps)


def _advance(
    method: str,
    principal_moments: ArrayLike,
    q: ArrayLike,
    omega: ArrayLike,
    dt: float,
    n_steps: int,
    torque_body: ArrayLike | None,
    normalize_q: bool,
    layout: str,
    record_steps: IntArray,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The checks and the compiled loop of advance_batch and advance_batch_recording."""
    if layout not in ("soa", "per_body"):
        raise ValueError(f"layout must be 'soa' or 'per_body', got {layout!r}")
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
    # rows whose squared norm is (or underflows to) zero; a product with ones is the cheapest
    # row sum numpy has for 4 columns (einsum or sum(axis=1) cost a sweep's segment call 2-5x more)
    zero = (q * q) @ np.ones(4) == 0.0
    if zero.any():
        raise ValueError(f"q[{int(np.argmax(zero))}] must be a non-zero quaternion")
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be finite and > 0, got {dt}")
    if torque_body is None:
        torque = np.zeros((n, 3))
    else:
        torque = np.array(_as_batch("torque_body", torque_body, n, 3), dtype=float, order="C")
    if method == "exact" and np.any(torque):
        raise ValueError("exact: torque_body must be None or zero (the exact flow is torque-free); use exact_split")
    failed_step = np.zeros(n, dtype=np.int64)
    failure = np.zeros(n, dtype=np.int64)
    omega_at = np.empty((record_steps.shape[0], n, 3))
    parallel = n > 1 and n * n_steps >= _PARALLEL_BODY_STEPS
    if method == "rk4" and layout == "soa":
        run_soa = _rk4_soa_parallel if parallel else _rk4_soa_serial
        run_soa(
            moments,
            q,
            omega,
            torque,
            float(dt),
            n_steps,
            bool(normalize_q),
            failed_step,
            failure,
            record_steps,
            omega_at,
        )
    else:
        run = _advance_bodies_parallel if parallel else _advance_bodies_serial
        run(
            _KERNELS[method],
            moments,
            q,
            omega,
            torque,
            float(dt),
            n_steps,
            bool(normalize_q),
            failed_step,
            failure,
            record_steps,
            omega_at,
        )
    if failed_step.any():
        # report the earliest failure (the bodies ran independently, in parallel)
        bad = int(np.argmin(np.where(failed_step > 0, failed_step, np.iinfo(np.int64).max)))
        step = int(failed_step[bad])
        raise NonFiniteStateError(
            f"{method}: {_FAILURES.get(int(failure[bad]), 'failure')} at step {step}, "
            f"t = {step * dt:.9g} s (body {bad})"
        )
    return q, omega, omega_at
