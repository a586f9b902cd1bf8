"""Advance N independent rigid bodies at once, vectorised over N with numpy.

Arrays carry the body index first: principal moments ``(N, 3)`` kg*m^2 (or ``(3,)``
shared by all bodies), attitudes ``(N, 4)`` scalar-last quaternions rotating
principal -> world, angular velocities ``(N, 3)`` rad/s and torques ``(N, 3)`` N*m
(or ``(3,)``), both in the principal body frame. The torque is held constant over
each step (a body-fixed thruster, or a command sampled once per step).

Methods (the single-body integrators of :mod:`rigid_rot_sim.core.integrators` with
the same names advance one body; these advance many in fused array operations, so
the per-step Python overhead is paid once for all N bodies):

* ``'rk4'``: classical RK4 for omega, with the attitude carried along the same
  stages as a rotation vector ``theta`` in ``q_n (x) exp(theta)`` (Runge-Kutta
  Munthe-Kaas): the quaternion stays unit by construction, order 4; the same
  scheme as the single-body ``rk4`` (:mod:`rigid_rot_sim.core.integrators.explicit`).
* ``'implicit_midpoint'``: the midpoint rule for ``L_body' = L x omega + N``
  solved by Newton's method, and the attitude advanced by the Cayley rotation
  that the midpoint rule applies to L, so that for a free body T, |L| and L_world
  are conserved to round-off, at any step (A-stable, order 2).

Why duplicate the single-body formulas here: those run on Python floats for one body;
these are the same equations written over arrays of bodies.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from rigid_rot_sim.core.integrators.base import NonFiniteStateError

BATCH_METHODS = ("rk4", "implicit_midpoint")

_NEWTON_MAX_ITER = 60


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


def _quat_multiply(p: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Hamilton product of (N, 4) scalar-last quaternions."""
    px, py, pz, pw = p[:, 0], p[:, 1], p[:, 2], p[:, 3]
    rx, ry, rz, rw = r[:, 0], r[:, 1], r[:, 2], r[:, 3]
    return np.stack(
        (
            pw * rx + px * rw + py * rz - pz * ry,
            pw * ry - px * rz + py * rw + pz * rx,
            pw * rz + px * ry - py * rx + pz * rw,
            pw * rw - px * rx - py * ry - pz * rz,
        ),
        axis=1,
    )


def _quat_exp(theta: np.ndarray) -> np.ndarray:
    """Unit quaternions (N, 4) of rotation vectors theta (N, 3), rad."""
    angle = np.sqrt(np.einsum("ij,ij->i", theta, theta))
    half = 0.5 * angle
    # sin(a/2)/a without the 0/0 at a = 0 (series below 1e-4: error < 1e-18)
    small = angle < 1e-4
    safe = np.where(small, 1.0, angle)
    scale = np.where(small, 0.5 - angle * angle / 48.0, np.sin(half) / safe)
    return np.concatenate((theta * scale[:, None], np.cos(half)[:, None]), axis=1)


def _euler_rhs(moments: np.ndarray, omega: np.ndarray, accel: np.ndarray | None) -> np.ndarray:
    """omega' = I^-1 ((I omega) x omega + N); accel = N / I precomputed."""
    i1, i2, i3 = moments[:, 0], moments[:, 1], moments[:, 2]
    w1, w2, w3 = omega[:, 0], omega[:, 1], omega[:, 2]
    out = np.stack(((i2 - i3) / i1 * w2 * w3, (i3 - i1) / i2 * w3 * w1, (i1 - i2) / i3 * w1 * w2), axis=1)
    if accel is not None:
        out += accel
    return out


def _dexpinv(theta: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """theta' = omega + 1/2 theta x omega + 1/12 theta x (theta x omega) for q = q_n (x) exp(theta).

    The series truncated as in the single-body rk4 (its next term vanishes and the one
    after is O(dt^4)), so both give the same numbers to round-off.
    """
    cross = np.cross(theta, omega)
    return omega + 0.5 * cross + np.cross(theta, cross) / 12.0


def _rk4_step(moments, q, omega, dt, accel):
    k1w = _euler_rhs(moments, omega, accel)
    k1t = omega
    w2 = omega + 0.5 * dt * k1w
    t2 = 0.5 * dt * k1t
    k2w = _euler_rhs(moments, w2, accel)
    k2t = _dexpinv(t2, w2)
    w3 = omega + 0.5 * dt * k2w
    t3 = 0.5 * dt * k2t
    k3w = _euler_rhs(moments, w3, accel)
    k3t = _dexpinv(t3, w3)
    w4 = omega + dt * k3w
    t4 = dt * k3t
    k4w = _euler_rhs(moments, w4, accel)
    k4t = _dexpinv(t4, w4)
    sixth = dt / 6.0
    omega_new = omega + sixth * (k1w + 2.0 * k2w + 2.0 * k3w + k4w)
    theta = sixth * (k1t + 2.0 * k2t + 2.0 * k3t + k4t)
    q_new = _quat_multiply(q, _quat_exp(theta))
    # exp(theta) is unit to round-off; renormalising stops round-off from accumulating
    q_new /= np.sqrt(np.einsum("ij,ij->i", q_new, q_new))[:, None]
    return q_new, omega_new


def _newton_midpoint(coeffs, omega, accel, a, guess, max_iter):
    """Newton for g(m) = m - omega - a (f(m) + accel) = 0; returns (m, converged mask).

    A body stops iterating once it has converged, so its result does not depend on the
    other bodies of the batch (how a sweep chunks its runs changes no bit of any run).
    """
    c1, c2, c3 = coeffs
    rhs0 = omega if accel is None else omega + a * accel
    m = guess.copy()
    converged = np.zeros(m.shape[0], dtype=bool)
    tiny = np.finfo(float).tiny
    for _ in range(max_iter):
        m1, m2, m3 = m[:, 0], m[:, 1], m[:, 2]
        g = m - rhs0 - a * np.stack((c1 * m2 * m3, c2 * m3 * m1, c3 * m1 * m2), axis=1)
        # Jacobian of g: identity minus a times that of f (whose diagonal is zero)
        j12, j13 = -a * c1 * m3, -a * c1 * m2
        j21, j23 = -a * c2 * m3, -a * c2 * m1
        j31, j32 = -a * c3 * m2, -a * c3 * m1
        # Cramer's rule on [[1, j12, j13], [j21, 1, j23], [j31, j32, 1]]
        a11, a22, a33 = 1.0 - j23 * j32, 1.0 - j13 * j31, 1.0 - j12 * j21
        a12, a13 = j13 * j32 - j12, j12 * j23 - j13
        a21, a23 = j23 * j31 - j21, j13 * j21 - j23
        a31, a32 = j21 * j32 - j31, j12 * j31 - j32
        det = a11 + j12 * a21 + j13 * a31
        g1, g2, g3 = g[:, 0], g[:, 1], g[:, 2]
        with np.errstate(all="ignore"):
            delta = np.stack(
                (
                    (a11 * g1 + a12 * g2 + a13 * g3) / det,
                    (a21 * g1 + a22 * g2 + a23 * g3) / det,
                    (a31 * g1 + a32 * g2 + a33 * g3) / det,
                ),
                axis=1,
            )
        delta[converged] = 0.0
        m = m - delta
        size = np.maximum(np.abs(m).max(axis=1), tiny)
        converged |= np.abs(delta).max(axis=1) <= 4.0 * np.finfo(float).eps * size
        if converged.all():
            break
    return m, converged


def _solve_midpoint(coeffs, omega, accel, a):
    """The midpoint m = (omega_n + omega_n+1) / 2, by Newton from omega_n.

    At rotations per step beyond about 2 rad Newton from omega_n can wander off the
    solution branch that starts at m = omega_n for dt = 0; the bodies where it fails are
    re-solved by continuation in the step (a = k a / K, each solve started from the last),
    with K doubled until every stage converges.
    """
    m, ok = _newton_midpoint(coeffs, omega, accel, a, omega, 12)
    stages = 4
    while not ok.all():
        if stages > 4096:
            raise FloatingPointError(
                f"implicit_midpoint: Newton did not converge at dt = {2 * a:g} s "
                f"(body {int(np.argmin(ok))}, {stages // 2} continuation stages)"
            )
        bad = ~ok
        sub_coeffs = tuple(c[bad] for c in coeffs)
        sub_omega = omega[bad]
        sub_accel = None if accel is None else accel[bad]
        sub_m = sub_omega
        sub_ok = np.ones(sub_omega.shape[0], dtype=bool)
        for k in range(1, stages + 1):
            sub_m, stage_ok = _newton_midpoint(sub_coeffs, sub_omega, sub_accel, a * k / stages, sub_m, _NEWTON_MAX_ITER)
            sub_ok &= stage_ok
        m[bad] = sub_m
        ok[bad] = sub_ok
        stages *= 2
    return m


def _midpoint_step(moments, q, omega, dt, accel):
    """Implicit midpoint for omega, and the Cayley rotation it implies for the attitude."""
    a = 0.5 * dt
    i1, i2, i3 = moments[:, 0], moments[:, 1], moments[:, 2]
    coeffs = ((i2 - i3) / i1, (i3 - i1) / i2, (i1 - i2) / i3)
    m = _solve_midpoint(coeffs, omega, accel, a)
    omega_new = 2.0 * m - omega
    # Cayley rotation by 2 atan(|m| dt / 2) about m: the rotation the midpoint rule applies to L
    half = np.concatenate((a * m, np.ones((m.shape[0], 1))), axis=1)
    half /= np.sqrt(np.einsum("ij,ij->i", half, half))[:, None]
    q_new = _quat_multiply(q, half)
    q_new /= np.sqrt(np.einsum("ij,ij->i", q_new, q_new))[:, None]
    return q_new, omega_new


_STEPS = {"rk4": _rk4_step, "implicit_midpoint": _midpoint_step}


def advance_batch(
    method: str,
    principal_moments: Any,
    q: Any,
    omega: Any,
    dt: float,
    n_steps: int,
    torque_body: Any = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Advance N bodies by ``n_steps`` steps of ``dt`` (s); returns new ``(q, omega)``.

    Parameters
    ----------
    method : {'rk4', 'implicit_midpoint'}
    principal_moments : array_like, (3,) or (N, 3)
        kg*m^2, each row > 0.
    q : array_like, (N, 4)
        Unit quaternions (x, y, z, w), principal -> world; normalised on entry.
    omega : array_like, (N, 3)
        rad/s, principal body frame.
    dt : float
        s, > 0.
    n_steps : int
        >= 0.
    torque_body : array_like, (3,) or (N, 3), optional
        N*m, principal body frame, constant over the run.

    Raises
    ------
    ValueError
        Bad input, naming the argument and the index.
    NonFiniteStateError
        A step produced a non-finite state (names the step and the first body).
    """
    if method not in _STEPS:
        raise ValueError(f"method must be one of {list(BATCH_METHODS)}, got {method!r}")
    omega = _as_batch("omega", omega, None, 3).copy()
    n = omega.shape[0]
    q = _as_batch("q", q, n, 4).copy()
    moments = _as_batch("principal_moments", principal_moments, n, 3)
    nonpositive = moments <= 0.0
    if nonpositive.any():
        index = tuple(int(i) for i in np.argwhere(nonpositive)[0])
        raise ValueError(f"principal_moments{list(index)} must be > 0, got {moments[index]}")
    norms = np.sqrt(np.einsum("ij,ij->i", q, q))
    if np.any(norms == 0.0):
        raise ValueError(f"q[{int(np.argmin(norms))}] must be a non-zero quaternion")
    q /= norms[:, None]
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be finite and > 0, got {dt}")
    if int(n_steps) != n_steps or n_steps < 0:
        raise ValueError(f"n_steps must be a non-negative integer, got {n_steps}")
    accel = None
    if torque_body is not None:
        accel = _as_batch("torque_body", torque_body, n, 3) / moments
    step = _STEPS[method]
    for k in range(int(n_steps)):
        # overflow is caught below and reported with its step, not as a numpy warning
        with np.errstate(over="ignore", invalid="ignore"):
            q, omega = step(moments, q, omega, float(dt), accel)
        if not (np.isfinite(omega).all() and np.isfinite(q).all()):
            bad = int(np.argwhere(~(np.isfinite(omega).all(axis=1) & np.isfinite(q).all(axis=1)))[0, 0])
            raise NonFiniteStateError(
                f"{method}: non-finite state at step {k + 1}, t = {(k + 1) * dt:.9g} s (body {bad})"
            )
    return q, omega
