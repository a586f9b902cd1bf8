"""Explicit fixed-step methods: ``euler`` (baseline) and ``rk4`` (classical RK4).

Both advance the attitude by the exponential map, never ``q += dt * dq/dt``, so the
quaternion stays a unit quaternion (a rotation) whatever the step.

``rk4`` is the classical RK4 tableau applied in exponential coordinates: with
``q(t_n + s) = q_n (x) exp(u(s))`` the rotation vector obeys ``du/ds = dexp^-1_{-u}(omega)
= omega + 1/2 u x omega + 1/12 u x (u x omega) + O(|u|^4)``, and (u, omega) is a state in
a vector space where RK4 applies unchanged (Munthe-Kaas 1998, "RKMK"). Truncating the
series after the second term keeps order 4 because its next term vanishes (B3 = 0) and
the one after is O(dt^4).
"""

from __future__ import annotations

from numba.extending import register_jitable

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.dynamics import euler_rhs_components
from rigid_rot_sim.core.integrators.fixed_step import FixedStepIntegrator
from rigid_rot_sim.core.integrators.status import OK, State, StepResult
from rigid_rot_sim.core.quaternion import Floats, Vector
from rigid_rot_sim.core.torque import TorqueData, attitude_dependent, has_torque, torque_at


@register_jitable
def euler_step(t: float, state: State, h: float, moments: Floats, torque: TorqueData) -> StepResult:
    """Explicit Euler on omega; attitude ``q (x) exp(h omega_n)``. Order 1."""
    qx, qy, qz, qw, w1, w2, w3 = state
    i1, i2, i3 = moments
    n1 = n2 = n3 = 0.0
    if has_torque(torque):
        n1, n2, n3 = torque_at(torque, t, (qx, qy, qz, qw), (w1, w2, w3))
    a1, a2, a3 = euler_rhs_components(i1, i2, i3, w1, w2, w3, n1, n2, n3)
    q = quat.normalize(quat.multiply((qx, qy, qz, qw), quat.exp_rotation_vector((h * w1, h * w2, h * w3))))
    return (q[0], q[1], q[2], q[3], w1 + h * a1, w2 + h * a2, w3 + h * a3), OK


@register_jitable
def _dexpinv(u1: float, u2: float, u3: float, w1: float, w2: float, w3: float) -> Vector:
    """``omega + 1/2 u x omega + 1/12 u x (u x omega)``: du/ds for q = q_n (x) exp(u)."""
    c1 = u2 * w3 - u3 * w2
    c2 = u3 * w1 - u1 * w3
    c3 = u1 * w2 - u2 * w1
    return (
        w1 + 0.5 * c1 + (u2 * c3 - u3 * c2) / 12.0,
        w2 + 0.5 * c2 + (u3 * c1 - u1 * c3) / 12.0,
        w3 + 0.5 * c3 + (u1 * c2 - u2 * c1) / 12.0,
    )


@register_jitable
def rk4_step(t: float, state: State, h: float, moments: Floats, torque: TorqueData) -> StepResult:
    """Classical RK4 in exponential coordinates of the attitude (RKMK4). Order 4."""
    qx, qy, qz, qw, w1, w2, w3 = state
    i1, i2, i3 = moments
    qn = (qx, qy, qz, qw)
    hh = 0.5 * h
    th = t + hh
    forced = has_torque(torque)
    attitude_torque = attitude_dependent(torque)

    # stage 1: u = 0, du/ds = omega
    n1 = n2 = n3 = 0.0
    if forced:
        n1, n2, n3 = torque_at(torque, t, qn, (w1, w2, w3))
    a1, b1, c1 = euler_rhs_components(i1, i2, i3, w1, w2, w3, n1, n2, n3)
    U1 = (w1, w2, w3)

    # stage 2
    x1, x2, x3 = w1 + hh * a1, w2 + hh * b1, w3 + hh * c1
    u = (hh * w1, hh * w2, hh * w3)
    if forced:
        q = quat.multiply(qn, quat.exp_rotation_vector(u)) if attitude_torque else qn
        n1, n2, n3 = torque_at(torque, th, q, (x1, x2, x3))
    a2, b2, c2 = euler_rhs_components(i1, i2, i3, x1, x2, x3, n1, n2, n3)
    U2 = _dexpinv(u[0], u[1], u[2], x1, x2, x3)

    # stage 3
    x1, x2, x3 = w1 + hh * a2, w2 + hh * b2, w3 + hh * c2
    u = (hh * U2[0], hh * U2[1], hh * U2[2])
    if forced:
        q = quat.multiply(qn, quat.exp_rotation_vector(u)) if attitude_torque else qn
        n1, n2, n3 = torque_at(torque, th, q, (x1, x2, x3))
    a3, b3, c3 = euler_rhs_components(i1, i2, i3, x1, x2, x3, n1, n2, n3)
    U3 = _dexpinv(u[0], u[1], u[2], x1, x2, x3)

    # stage 4
    x1, x2, x3 = w1 + h * a3, w2 + h * b3, w3 + h * c3
    u = (h * U3[0], h * U3[1], h * U3[2])
    if forced:
        q = quat.multiply(qn, quat.exp_rotation_vector(u)) if attitude_torque else qn
        n1, n2, n3 = torque_at(torque, t + h, q, (x1, x2, x3))
    a4, b4, c4 = euler_rhs_components(i1, i2, i3, x1, x2, x3, n1, n2, n3)
    U4 = _dexpinv(u[0], u[1], u[2], x1, x2, x3)

    h6 = h / 6.0
    u = (
        h6 * (U1[0] + 2.0 * (U2[0] + U3[0]) + U4[0]),
        h6 * (U1[1] + 2.0 * (U2[1] + U3[1]) + U4[1]),
        h6 * (U1[2] + 2.0 * (U2[2] + U3[2]) + U4[2]),
    )
    q = quat.normalize(quat.multiply(qn, quat.exp_rotation_vector(u)))
    return (
        q[0],
        q[1],
        q[2],
        q[3],
        w1 + h6 * (a1 + 2.0 * (a2 + a3) + a4),
        w2 + h6 * (b1 + 2.0 * (b2 + b3) + b4),
        w3 + h6 * (c1 + 2.0 * (c2 + c3) + c4),
    ), OK


class Euler(FixedStepIntegrator):
    """Explicit Euler (order 1): the baseline still in common use; not for production runs."""

    name = "euler"
    orders = (1,)
    stability = "explicit"
    kernel_name = "euler"


class RK4(FixedStepIntegrator):
    """Classical fourth-order Runge-Kutta with the attitude in exponential coordinates."""

    name = "rk4"
    orders = (4,)
    stability = "explicit"
    kernel_name = "rk4"
