"""``implicit_midpoint``: the implicit midpoint rule, Lie-Poisson form (order 2, A-stable).

With W the midpoint angular velocity (principal frame) the step is

    W = omega_n + h/2 * alpha(t + h/2, q_mid, W)        (alpha: Euler's equations)
    omega_{n+1} = 2 W - omega_n
    q_{n+1} = q_n (x) cay(h W),    q_mid = q_n (x) sqrt(cay(h W))

Free body: the rule conserves every quadratic invariant of the momentum equation, so
T and |L| change only by round-off; and since ``L_{n+1} = cay(-h W) L_n`` is exactly
the same midpoint equation written for L, the Cayley attitude update makes L_world
constant to round-off as well (``R_{n+1} L_{n+1} = R_n cay(hW) cay(-hW) L_n``).
The attitude is always a rotation.

The implicit equation is solved by Newton's method on the 3x3 system, to round-off
(fixed-point iteration would diverge when h * |omega| is large, the stiff gyroscopic
case this method is for). For a general torque callable its Jacobian with respect to W
(through omega and the midpoint attitude) is taken once per step by forward differences.
Newton starts from an explicit Euler predictor. At many radians per step it can fail to
converge from there; the step is then re-solved by continuation in the step length
(``h k / K`` for k = 1..K, each solve started from the last, K doubled up to 4096), which
follows the branch of solutions that starts at W = omega_n for h = 0.
"""

from __future__ import annotations

import math

from numba.extending import register_jitable

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.dynamics import euler_rhs_components
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.integrators.fixed_step import FixedStepIntegrator
from rigid_rot_sim.core.integrators.status import NEWTON_FAILED, OK, State, StepResult
from rigid_rot_sim.core.quaternion import Floats, Quaternion
from rigid_rot_sim.core.torque import TorqueData, attitude_dependent, has_torque, torque_at

_EPS = 2.220446049250313e-16
_MAX_ITERATIONS = 60
_MAX_CONTINUATION_STAGES = 4096


class NewtonConvergenceError(NonFiniteStateError):
    """The implicit equation of a step could not be solved."""


@register_jitable
def _half_cayley(qn: Floats, h: float, W1: float, W2: float, W3: float) -> Quaternion:
    """Midpoint attitude ``q_n (x) sqrt(cay(h W))``: the normalised mean of q_n and q_{n+1}."""
    c = quat.cayley((h * W1, h * W2, h * W3))
    return quat.multiply(qn, quat.normalize((c[0], c[1], c[2], c[3] + 1.0)))


@register_jitable
def _newton(
    t: float,
    qn: Quaternion,
    w1: float,
    w2: float,
    w3: float,
    h: float,
    moments: Floats,
    torque: TorqueData,
    W1: float,
    W2: float,
    W3: float,
) -> tuple[float, float, float, bool]:
    """Solve ``2 (W - omega_n) = h alpha(t + h/2, q_mid, W)`` from W; returns (W1, W2, W3, converged)."""
    i1, i2, i3 = moments
    tm = t + 0.5 * h
    k1, k2, k3 = (i2 - i3) / i1, (i3 - i1) / i2, (i1 - i2) / i3
    forced = has_torque(torque)
    attitude_torque = attitude_dependent(torque)

    # d(N/I)/dW of a general torque, frozen over the iteration
    d11 = d12 = d13 = d21 = d22 = d23 = d31 = d32 = d33 = 0.0
    if forced and attitude_torque:
        b1, b2, b3 = torque_at(torque, tm, _half_cayley(qn, h, W1, W2, W3), (W1, W2, W3))
        for j in range(3):
            P1, P2, P3 = W1, W2, W3
            if j == 0:
                delta = 1.5e-8 * max(abs(P1), 1.0)
                P1 += delta
            elif j == 1:
                delta = 1.5e-8 * max(abs(P2), 1.0)
                P2 += delta
            else:
                delta = 1.5e-8 * max(abs(P3), 1.0)
                P3 += delta
            m1, m2, m3 = torque_at(torque, tm, _half_cayley(qn, h, P1, P2, P3), (P1, P2, P3))
            c1, c2, c3 = (m1 - b1) / (delta * i1), (m2 - b2) / (delta * i2), (m3 - b3) / (delta * i3)
            if j == 0:
                d11, d21, d31 = c1, c2, c3
            elif j == 1:
                d12, d22, d32 = c1, c2, c3
            else:
                d13, d23, d33 = c1, c2, c3

    n1 = n2 = n3 = 0.0
    previous = math.inf
    for _ in range(_MAX_ITERATIONS):
        if forced:
            n1, n2, n3 = torque_at(torque, tm, _half_cayley(qn, h, W1, W2, W3) if attitude_torque else qn, (W1, W2, W3))
        a1, a2, a3 = euler_rhs_components(i1, i2, i3, W1, W2, W3, n1, n2, n3)
        g1 = 2.0 * (W1 - w1) - h * a1
        g2 = 2.0 * (W2 - w2) - h * a2
        g3 = 2.0 * (W3 - w3) - h * a3
        # J = 2 Id - h d(alpha)/dW
        j11 = 2.0 - h * d11
        j12 = -h * (k1 * W3 + d12)
        j13 = -h * (k1 * W2 + d13)
        j21 = -h * (k2 * W3 + d21)
        j22 = 2.0 - h * d22
        j23 = -h * (k2 * W1 + d23)
        j31 = -h * (k3 * W2 + d31)
        j32 = -h * (k3 * W1 + d32)
        j33 = 2.0 - h * d33
        # Cramer's rule for J d = -g
        c11 = j22 * j33 - j23 * j32
        c12 = j23 * j31 - j21 * j33
        c13 = j21 * j32 - j22 * j31
        det = j11 * c11 + j12 * c12 + j13 * c13
        if det == 0.0 or not math.isfinite(det):
            return W1, W2, W3, True  # the finiteness check below decides
        inv = -1.0 / det
        e1 = inv * (g1 * c11 + g2 * (j13 * j32 - j12 * j33) + g3 * (j12 * j23 - j13 * j22))
        e2 = inv * (g1 * c12 + g2 * (j11 * j33 - j13 * j31) + g3 * (j13 * j21 - j11 * j23))
        e3 = inv * (g1 * c13 + g2 * (j12 * j31 - j11 * j32) + g3 * (j11 * j22 - j12 * j21))
        W1 += e1
        W2 += e2
        W3 += e3
        size = max(abs(e1), abs(e2), abs(e3))
        scale = max(abs(W1), abs(W2), abs(W3))
        if size <= 4.0 * _EPS * scale:
            return W1, W2, W3, True
        # converged to the round-off floor, where corrections stop shrinking
        if size <= 1e-12 * scale and size >= 0.5 * previous:
            return W1, W2, W3, True
        if not math.isfinite(size):
            return W1, W2, W3, True
        previous = size
    return W1, W2, W3, False


@register_jitable
def implicit_midpoint_step(t: float, state: State, h: float, moments: Floats, torque: TorqueData) -> StepResult:
    qx, qy, qz, qw, w1, w2, w3 = state
    i1, i2, i3 = moments
    qn = (qx, qy, qz, qw)
    hh = 0.5 * h

    # predictor: explicit Euler to the midpoint
    n1 = n2 = n3 = 0.0
    if has_torque(torque):
        n1, n2, n3 = torque_at(torque, t, qn, (w1, w2, w3))
    a1, a2, a3 = euler_rhs_components(i1, i2, i3, w1, w2, w3, n1, n2, n3)
    W1, W2, W3, converged = _newton(t, qn, w1, w2, w3, h, moments, torque, w1 + hh * a1, w2 + hh * a2, w3 + hh * a3)
    stages = 4
    while not converged:
        # continuation in the step length along the branch that starts at W = omega_n
        if stages > _MAX_CONTINUATION_STAGES:
            return state, NEWTON_FAILED
        W1, W2, W3 = w1, w2, w3
        converged = True
        for k in range(1, stages + 1):
            W1, W2, W3, ok = _newton(t, qn, w1, w2, w3, h * k / stages, moments, torque, W1, W2, W3)
            converged = converged and ok
        stages *= 2
    if not (math.isfinite(W1) and math.isfinite(W2) and math.isfinite(W3)):
        return (math.nan, math.nan, math.nan, math.nan, W1, W2, W3), OK  # reported as a non-finite state

    q = quat.normalize(quat.multiply(qn, quat.cayley((h * W1, h * W2, h * W3))))
    return (q[0], q[1], q[2], q[3], 2.0 * W1 - w1, 2.0 * W2 - w2, 2.0 * W3 - w3), OK


class ImplicitMidpoint(FixedStepIntegrator):
    """Implicit midpoint rule with the Cayley attitude update (order 2, A-stable, conservative)."""

    name = "implicit_midpoint"
    orders = (2,)
    stability = "unconditional"
    kernel_name = "implicit_midpoint"
    error_types = {NEWTON_FAILED: (NewtonConvergenceError, "Newton's method did not converge")}
