"""``splitting``: symplectic splitting of the free rigid body into exact rotations.

After Dullweber, Leimkuhler and McLachlan, J. Chem. Phys. 107 (1997): the kinetic energy
(L in the principal frame) is a sum of terms whose flows are exact rotations. Written
with the Casimir |L|^2 separated out (k: the axis of the median moment, i and j the others),

    H = |L|^2 / (2 I_k) + L_i^2 / 2 (1/I_i - 1/I_k) + L_j^2 / 2 (1/I_j - 1/I_k),

* the Casimir term C leaves L_body fixed and turns the body about L:
  ``q <- q (x) exp(tau L / I_k)``;
* the term X_i keeps L_i and turns L_body about e_i by ``-phi`` and the body by
  ``q <- q (x) exp(phi e_i)``, with ``phi = (1/I_i - 1/I_k) L_i tau``.

The free step is the symmetric (Strang) product ``X_i(h/2) X_j(h/2) C(h) X_j(h/2) X_i(h/2)``
(order 2). A term with I_i = I_k vanishes, so the step is the exact flow for symmetric
and spherical bodies, and the splitting error of a near-symmetric body is proportional
to its asymmetry. Orders 4 and 6 are symmetric compositions of the step (option ``order``):
Yoshida's triple jump (Phys. Lett. A 150, 1990) for 4, Yoshida's seven-stage solution A for 6.

Every sub-flow is an exact rotation, so |L| (and L_world) change only by round-off and
the attitude stays a rotation; T is not conserved by each sub-flow, so it is kept only to
O(h^order) (a bounded oscillation, no drift: the method is symplectic).

Torque enters as kicks around each free step: ``omega += h/2 N(t) / I`` (explicit)
before, free flow, and after it the adjoint kick ``omega' = omega + h/2 N(t+h, q, omega') / I``
(solved by fixed-point iteration, exact in one evaluation for torques that do not depend
on omega). The kick pair is then a symmetric method, so the compositions keep their order.
"""

from __future__ import annotations

import math
from typing import Any

from numba.extending import register_jitable

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.dynamics import axes_by_moment
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.integrators.fixed_step import FixedStepIntegrator
from rigid_rot_sim.core.integrators.status import KICK_FAILED, OK
from rigid_rot_sim.core.torque import has_torque, torque_at

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
#: (qx, qy, qz, qw, w1, w2, w3): the state of a step.
State7 = tuple[float, float, float, float, float, float, float]
Vector = tuple[float, float, float]


@register_jitable
def _x_flow(
    term: int,
    half: float,
    qx: float,
    qy: float,
    qz: float,
    qw: float,
    w1: float,
    w2: float,
    w3: float,
    i1: float,
    i2: float,
    i3: float,
) -> State7:
    """X_term: the body turns by phi = 2 half about the axis ``term``, L_body by -phi."""
    s, c = math.sin(half), math.cos(half)
    sn, cs = 2.0 * s * c, 1.0 - 2.0 * s * s  # sin, cos of phi
    if term == 0:
        w2, w3 = cs * w2 + sn * (i3 / i2) * w3, cs * w3 - sn * (i2 / i3) * w2
        qx, qy, qz, qw = qw * s + qx * c, qy * c + qz * s, qz * c - qy * s, qw * c - qx * s
    elif term == 1:
        w3, w1 = cs * w3 + sn * (i1 / i3) * w1, cs * w1 - sn * (i3 / i1) * w3
        qx, qy, qz, qw = qx * c - qz * s, qw * s + qy * c, qz * c + qx * s, qw * c - qy * s
    else:
        w1, w2 = cs * w1 + sn * (i2 / i1) * w2, cs * w2 - sn * (i1 / i2) * w1
        qx, qy, qz, qw = qx * c + qy * s, qy * c - qx * s, qw * s + qz * c, qw * c - qz * s
    return qx, qy, qz, qw, w1, w2, w3


@register_jitable
def _free_strang(
    qx: float,
    qy: float,
    qz: float,
    qw: float,
    w1: float,
    w2: float,
    w3: float,
    h: float,
    i1: float,
    i2: float,
    i3: float,
) -> State7:
    """``X_i(h/2) X_j(h/2) C(h) X_j(h/2) X_i(h/2)`` on (q, omega) in the principal frame.

    The X terms are those about the axes other than the median one k (in axis order,
    then reversed), skipping a term whose moment equals I_k (it vanishes); X_a turns by
    ``phi = (1 - I_a / I_k) tau omega_a``; the Casimir C by ``tau (I / I_k) omega``.
    """
    if not math.isfinite(w1 + w2 + w3):
        nan = math.nan
        return nan, nan, nan, nan, nan, nan, nan
    k = axes_by_moment(i1, i2, i3)[1]
    ik = i1 if k == 0 else i2 if k == 1 else i3
    c1, c2, c3 = i1 / ik, i2 / ik, i3 / ik
    qx, qy, qz, qw, w1, w2, w3 = _x_terms((0, 1, 2), k, ik, h, qx, qy, qz, qw, w1, w2, w3, i1, i2, i3)
    qx, qy, qz, qw = quat.multiply((qx, qy, qz, qw), quat.exp_rotation_vector((h * c1 * w1, h * c2 * w2, h * c3 * w3)))
    return _x_terms((2, 1, 0), k, ik, h, qx, qy, qz, qw, w1, w2, w3, i1, i2, i3)


@register_jitable
def _x_terms(
    axes: tuple[int, int, int],
    k: int,
    ik: float,
    h: float,
    qx: float,
    qy: float,
    qz: float,
    qw: float,
    w1: float,
    w2: float,
    w3: float,
    i1: float,
    i2: float,
    i3: float,
) -> State7:
    """The X terms over h/2 in the order ``axes``, skipping the median axis k and any axis
    whose moment equals I_k."""
    for a in axes:
        ia = i1 if a == 0 else i2 if a == 1 else i3
        if a != k and ia != ik:
            rate = 1.0 - ia / ik
            half = 0.5 * 0.5 * h * rate * (w1 if a == 0 else w2 if a == 1 else w3)
            qx, qy, qz, qw, w1, w2, w3 = _x_flow(a, half, qx, qy, qz, qw, w1, w2, w3, i1, i2, i3)
    return qx, qy, qz, qw, w1, w2, w3


@register_jitable
def splitting_step(
    t: float, state: State7, h: float, moments: Vector, torque: Any, coefficients: tuple[float, ...]
) -> tuple[State7, int]:
    """One step of the symmetric composition ``coefficients`` of the kicked Strang step."""
    qx, qy, qz, qw, w1, w2, w3 = state
    i1, i2, i3 = moments
    if not has_torque(torque):
        for gamma in coefficients:
            qx, qy, qz, qw, w1, w2, w3 = _free_strang(qx, qy, qz, qw, w1, w2, w3, gamma * h, i1, i2, i3)
    else:
        n1, n2, n3 = torque_at(torque, t, (qx, qy, qz, qw), (w1, w2, w3))
        for gamma in coefficients:
            tau = gamma * h
            hk = 0.5 * tau
            w1, w2, w3 = kick(w1, w2, w3, hk, n1, n2, n3, i1, i2, i3)
            qx, qy, qz, qw, w1, w2, w3 = _free_strang(qx, qy, qz, qw, w1, w2, w3, tau, i1, i2, i3)
            t += tau
            # the torque at the kicked state is also the next explicit kick's torque
            w1, w2, w3, n1, n2, n3, converged = adjoint_kick(torque, t, (qx, qy, qz, qw), w1, w2, w3, hk, i1, i2, i3)
            if not converged:
                return state, KICK_FAILED
    inv = 1.0 / math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    return (qx * inv, qy * inv, qz * inv, qw * inv, w1, w2, w3), OK


@register_jitable
def kick(
    w1: float, w2: float, w3: float, hk: float, n1: float, n2: float, n3: float, i1: float, i2: float, i3: float
) -> Vector:
    """The explicit kick ``omega + hk N / I``."""
    return w1 + hk * n1 / i1, w2 + hk * n2 / i2, w3 + hk * n3 / i3


@register_jitable
def adjoint_kick(
    torque: Any,
    t: float,
    q: tuple[float, float, float, float],
    w1: float,
    w2: float,
    w3: float,
    hk: float,
    i1: float,
    i2: float,
    i3: float,
) -> tuple[float, float, float, float, float, float, bool]:
    """Solve ``x = w + hk N(t, q, x) / I`` by fixed-point iteration; return x, N(t, q, x), converged."""
    x1, x2, x3 = w1, w2, w3
    n1, n2, n3 = torque_at(torque, t, q, (x1, x2, x3))
    for _ in range(_KICK_ITERATIONS):
        y1, y2, y3 = kick(w1, w2, w3, hk, n1, n2, n3, i1, i2, i3)
        change = max(abs(y1 - x1), abs(y2 - x2), abs(y3 - x3))
        x1, x2, x3 = y1, y2, y3
        n1, n2, n3 = torque_at(torque, t, q, (x1, x2, x3))
        # a non-finite torque is returned as is, for the step's non-finite check to report
        if change <= 4e-16 * max(abs(y1), abs(y2), abs(y3)) or not math.isfinite(y1 + y2 + y3):
            return x1, x2, x3, n1, n2, n3, True
    return x1, x2, x3, n1, n2, n3, False


#: What a failed torque kick is reported as (splitting and exact_split).
KICK_ERROR = "the torque kick did not converge (torque too stiff in omega for this step; use implicit_midpoint)"


class Splitting(FixedStepIntegrator):
    """Exact-rotation splitting of the free body (DLM 1997), order 2, 4 or 6, with torque kicks.

    Options
    -------
    order : {2, 4, 6}
        Order of the symmetric composition (default 2).
    """

    name = "splitting"
    orders = tuple(COMPOSITIONS)
    stability = "unconditional"
    error_types = {KICK_FAILED: (NonFiniteStateError, KICK_ERROR)}

    def __init__(self, *args: Any, order: int = 2, **kwargs: Any) -> None:
        if order not in self.orders:
            raise ValueError(f"splitting: order must be one of {sorted(self.orders)}, got {order!r}")
        self._order = order
        self.kernel_name = f"splitting{order}"
        super().__init__(*args, **kwargs)
