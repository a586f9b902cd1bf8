"""``splitting``: symplectic splitting of the free rigid body into exact rotations.

Dullweber, Leimkuhler and McLachlan, J. Chem. Phys. 107 (1997). The kinetic energy
``H = sum_i L_i^2 / (2 I_i)`` (L in the principal frame) is split into its three terms.
The flow of ``L_i^2 / (2 I_i)`` for a time tau is exact: L_i and omega_i = L_i / I_i are
constant, the body rotates about principal axis i by ``phi = omega_i tau``
(``q <- q (x) exp(phi e_i)``) and L_body rotates about e_i by ``-phi`` (L_world stays
fixed). The free step is the symmetric (Strang) product

    X1(h/2) X2(h/2) X3(h) X2(h/2) X1(h/2)       (order 2)

and orders 4 and 6 are its symmetric compositions (option ``order``): Yoshida's
triple jump (Phys. Lett. A 150, 1990) for 4, and Yoshida's seven-stage solution A for 6.

Every sub-flow is an exact rotation, so |L| (and L_world) change only by round-off and
the attitude stays a rotation; T is not a sum of invariants of the sub-flows, so it is
conserved only to O(h^order) (bounded oscillation, no drift: the method is symplectic).

Torque enters as kicks around each free step: ``omega += h/2 N(t) / I`` (explicit)
before, free flow, and after it the adjoint kick ``omega' = omega + h/2 N(t+h, q, omega') / I``
(solved by fixed-point iteration, exact in one evaluation for torques that do not depend
on omega). The kick pair is then a symmetric method, so the compositions keep their order.
"""

from __future__ import annotations

import math
from typing import Any

from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.integrators.fixed_step import FixedStepIntegrator

_CBRT2 = 2.0 ** (1.0 / 3.0)
# Yoshida 1990, Table 1, solution A (w1, w2, w3); w0 = 1 - 2 (w1 + w2 + w3)
_Y6 = (-1.17767998417887, 0.235573213359357, 0.784513610477560)
_Y6_W0 = 1.0 - 2.0 * sum(_Y6)

COMPOSITIONS: dict[int, tuple[float, ...]] = {
    2: (1.0,),
    4: (1.0 / (2.0 - _CBRT2), -_CBRT2 / (2.0 - _CBRT2), 1.0 / (2.0 - _CBRT2)),
    6: (_Y6[2], _Y6[1], _Y6[0], _Y6_W0, _Y6[0], _Y6[1], _Y6[2]),
}

_KICK_ITERATIONS = 50


def _free_strang(qx, qy, qz, qw, w1, w2, w3, h, i1, i2, i3):
    """X1(h/2) X2(h/2) X3(h) X2(h/2) X1(h/2) on (q, omega) in the principal frame."""
    hh = 0.5 * h
    r23, r32 = i2 / i3, i3 / i2
    r31, r13 = i3 / i1, i1 / i3
    r12, r21 = i1 / i2, i2 / i1
    for axis, tau in ((1, hh), (2, hh), (3, h), (2, hh), (1, hh)):
        if axis == 1:
            half = 0.5 * tau * w1
            s, c = math.sin(half), math.cos(half)
            sn, cs = 2.0 * s * c, 1.0 - 2.0 * s * s  # sin, cos of the full angle
            # L2, L3 rotate by -phi about e1
            w2, w3 = cs * w2 + sn * r32 * w3, cs * w3 - sn * r23 * w2
            qx, qy, qz, qw = qw * s + qx * c, qy * c + qz * s, qz * c - qy * s, qw * c - qx * s
        elif axis == 2:
            half = 0.5 * tau * w2
            s, c = math.sin(half), math.cos(half)
            sn, cs = 2.0 * s * c, 1.0 - 2.0 * s * s
            w3, w1 = cs * w3 + sn * r13 * w1, cs * w1 - sn * r31 * w3
            qx, qy, qz, qw = qx * c - qz * s, qw * s + qy * c, qz * c + qx * s, qw * c - qy * s
        else:
            half = 0.5 * tau * w3
            s, c = math.sin(half), math.cos(half)
            sn, cs = 2.0 * s * c, 1.0 - 2.0 * s * s
            w1, w2 = cs * w1 + sn * r21 * w2, cs * w2 - sn * r12 * w1
            qx, qy, qz, qw = qx * c + qy * s, qy * c - qx * s, qw * s + qz * c, qw * c - qz * s
    return qx, qy, qz, qw, w1, w2, w3


def _make_kernel(coefficients: tuple[float, ...]):
    def kernel(t, state, h, moments, torque, attitude_torque):
        qx, qy, qz, qw, w1, w2, w3 = state
        i1, i2, i3 = moments
        if torque is None:
            for gamma in coefficients:
                qx, qy, qz, qw, w1, w2, w3 = _free_strang(qx, qy, qz, qw, w1, w2, w3, gamma * h, i1, i2, i3)
        else:
            n1, n2, n3 = torque(t, (qx, qy, qz, qw), (w1, w2, w3))
            for gamma in coefficients:
                tau = gamma * h
                hk = 0.5 * tau
                w1 += hk * n1 / i1
                w2 += hk * n2 / i2
                w3 += hk * n3 / i3
                qx, qy, qz, qw, w1, w2, w3 = _free_strang(qx, qy, qz, qw, w1, w2, w3, tau, i1, i2, i3)
                t += tau
                # the torque at the kicked state is also the next explicit kick's torque
                w1, w2, w3, n1, n2, n3 = _adjoint_kick(torque, t, (qx, qy, qz, qw), w1, w2, w3, hk, i1, i2, i3)
        inv = 1.0 / math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        return qx * inv, qy * inv, qz * inv, qw * inv, w1, w2, w3

    return kernel


def _adjoint_kick(torque, t, q, w1, w2, w3, hk, i1, i2, i3):
    """Solve ``x = w + hk N(t, q, x) / I`` by fixed-point iteration; return x and N(t, q, x)."""
    x1, x2, x3 = w1, w2, w3
    n1, n2, n3 = torque(t, q, (x1, x2, x3))
    for _ in range(_KICK_ITERATIONS):
        y1, y2, y3 = w1 + hk * n1 / i1, w2 + hk * n2 / i2, w3 + hk * n3 / i3
        change = max(abs(y1 - x1), abs(y2 - x2), abs(y3 - x3))
        x1, x2, x3 = y1, y2, y3
        n1, n2, n3 = torque(t, q, (x1, x2, x3))
        # a non-finite torque is returned as is, for the step's non-finite check to report
        if change <= 4e-16 * max(abs(y1), abs(y2), abs(y3)) or not math.isfinite(y1 + y2 + y3):
            return x1, x2, x3, n1, n2, n3
    raise NonFiniteStateError(
        f"splitting: the torque kick at t = {t:.9g} s did not converge "
        "(torque too stiff in omega for this step; use implicit_midpoint)"
    )


_KERNELS = {order: _make_kernel(c) for order, c in COMPOSITIONS.items()}


class Splitting(FixedStepIntegrator):
    """Exact-rotation splitting of the free body (DLM 1997), order 2, 4 or 6, with torque kicks.

    Options
    -------
    order : {2, 4, 6}
        Order of the symmetric composition (default 2).
    """

    name = "splitting"
    order = 2

    def __init__(self, *args: Any, order: int = 2, **kwargs: Any) -> None:
        if order not in COMPOSITIONS:
            raise ValueError(f"splitting: order must be one of {sorted(COMPOSITIONS)}, got {order!r}")
        self.order = order  # instance attribute: the nominal order of this instance
        self.kernel = _KERNELS[order]
        super().__init__(*args, **kwargs)
