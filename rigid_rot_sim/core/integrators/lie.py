"""``lie_rk4``: the fourth-order commutator-free Lie group method (Crouch-Grossman class).

Celledoni, Marthinsen and Owren, "Commutator-free Lie group methods", Future Generation
Computer Systems 19 (2003): the classical RK4 tableau where every stage attitude is
reached by exponentials of body-frame increments ``K_i = h omega_i`` composed on the
right (``Rdot = R [omega]x``), and the step by two exponentials:

    Q2 = q_n (x) exp(K1/2),   Q3 = q_n (x) exp(K2/2),   Q4 = Q2 (x) exp(K3 - K1/2)
    q_{n+1} = q_n (x) exp((3K1 + 2K2 + 2K3 - K4)/12) (x) exp((-K1 + 2K2 + 2K3 + 3K4)/12)

The angular velocity takes the plain RK4 stages (its space is a vector space, where the
exponential is a translation). No commutators, no dexp^-1 series: the attitude is a
product of exact rotations by construction.
"""

from __future__ import annotations

from numba.extending import register_jitable

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.dynamics import euler_rhs_components
from rigid_rot_sim.core.integrators.fixed_step import FixedStepIntegrator
from rigid_rot_sim.core.integrators.status import OK, State, StepResult
from rigid_rot_sim.core.quaternion import Floats
from rigid_rot_sim.core.torque import TorqueData, attitude_dependent, has_torque, torque_at


@register_jitable
def cf4_step(t: float, state: State, h: float, moments: Floats, torque: TorqueData) -> StepResult:
    """One step of the commutator-free order-4 method on (q, omega)."""
    qx, qy, qz, qw, w1, w2, w3 = state
    i1, i2, i3 = moments
    qn = (qx, qy, qz, qw)
    hh = 0.5 * h
    th = t + hh
    forced = has_torque(torque)
    need_q = forced and attitude_dependent(torque)

    n1 = n2 = n3 = 0.0
    q2 = qn
    if forced:
        n1, n2, n3 = torque_at(torque, t, qn, (w1, w2, w3))
    a1, b1, c1 = euler_rhs_components(i1, i2, i3, w1, w2, w3, n1, n2, n3)

    x1, x2, x3 = w1 + hh * a1, w2 + hh * b1, w3 + hh * c1
    if forced:
        if need_q:
            q2 = quat.multiply(qn, quat.exp_rotation_vector((hh * w1, hh * w2, hh * w3)))
        n1, n2, n3 = torque_at(torque, th, q2, (x1, x2, x3))
    a2, b2, c2 = euler_rhs_components(i1, i2, i3, x1, x2, x3, n1, n2, n3)
    K2 = (x1, x2, x3)  # divided by h

    x1, x2, x3 = w1 + hh * a2, w2 + hh * b2, w3 + hh * c2
    if forced:
        q3 = quat.multiply(qn, quat.exp_rotation_vector((hh * K2[0], hh * K2[1], hh * K2[2]))) if need_q else qn
        n1, n2, n3 = torque_at(torque, th, q3, (x1, x2, x3))
    a3, b3, c3 = euler_rhs_components(i1, i2, i3, x1, x2, x3, n1, n2, n3)
    K3 = (x1, x2, x3)

    x1, x2, x3 = w1 + h * a3, w2 + h * b3, w3 + h * c3
    if forced:
        if need_q:
            v = (h * (K3[0] - 0.5 * w1), h * (K3[1] - 0.5 * w2), h * (K3[2] - 0.5 * w3))
            q4 = quat.multiply(q2, quat.exp_rotation_vector(v))
        else:
            q4 = qn
        n1, n2, n3 = torque_at(torque, t + h, q4, (x1, x2, x3))
    a4, b4, c4 = euler_rhs_components(i1, i2, i3, x1, x2, x3, n1, n2, n3)
    K4 = (x1, x2, x3)

    h12 = h / 12.0
    # body-frame increments compose on the right: q_n (x) exp(first) (x) exp(second)
    first = (
        h12 * (3.0 * w1 + 2.0 * (K2[0] + K3[0]) - K4[0]),
        h12 * (3.0 * w2 + 2.0 * (K2[1] + K3[1]) - K4[1]),
        h12 * (3.0 * w3 + 2.0 * (K2[2] + K3[2]) - K4[2]),
    )
    second = (
        h12 * (-w1 + 2.0 * (K2[0] + K3[0]) + 3.0 * K4[0]),
        h12 * (-w2 + 2.0 * (K2[1] + K3[1]) + 3.0 * K4[1]),
        h12 * (-w3 + 2.0 * (K2[2] + K3[2]) + 3.0 * K4[2]),
    )
    q = quat.multiply(quat.multiply(qn, quat.exp_rotation_vector(first)), quat.exp_rotation_vector(second))
    h6 = h / 6.0
    q = quat.normalize(q)
    return (
        q[0],
        q[1],
        q[2],
        q[3],
        w1 + h6 * (a1 + 2.0 * (a2 + a3) + a4),
        w2 + h6 * (b1 + 2.0 * (b2 + b3) + b4),
        w3 + h6 * (c1 + 2.0 * (c2 + c3) + c4),
    ), OK


class LieRK4(FixedStepIntegrator):
    """Commutator-free Lie group method of order 4 (Celledoni-Marthinsen-Owren CF4)."""

    name = "lie_rk4"
    orders = (4,)
    stability = "explicit"
    kernel_name = "lie_rk4"
