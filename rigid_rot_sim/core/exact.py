"""Exact torque-free motion of a rigid body (Euler-Poinsot): angular velocity and attitude.

``torque_free_solution(moments, omega0, q0, t0)`` returns a :class:`TorqueFreeSolution`
whose ``omega(t)`` (rad/s, principal body frame) and ``quaternion(t)`` (principal ->
world, scalar-last) are vectorised over t (s).

Derivation (kept here because the tests and the integrators rely on it)
-----------------------------------------------------------------------
Invariants: ``2E = sum I_i w_i^2`` and ``L^2 = sum I_i^2 w_i^2``. Relabel the principal
axes by a proper signed permutation (x' = P x, det P = +1, the middle moment stays
axis 2) so that axis 3 is the one the angular velocity circulates about: the largest
moment when ``D = L^2 - 2 E I2 > 0`` (above the separatrix), the smallest when
``D < 0`` (below). In both orderings (I1 < I2 < I3 or I1 > I2 > I3)

    w1 = A1 cn u,   w2 = sigma A2 sn u,   w3 = s3 A3 dn u,    u = lam (t - t0) + u0,

with s3 = sign w3 (never zero off the separatrix), sigma = eps s3,
eps = sign(I3 - I2), and (every term below is a sum of non-negative terms, so no
cancellation even next to the separatrix)

    A1^2 = w1^2 + I2 (I3 - I2) / (I1 (I3 - I1)) w2^2      = (2 E I3 - L^2) / (I1 (I3 - I1))
    A2^2 = I1 (I3 - I1) / (I2 (I3 - I2)) w1^2 + w2^2      = (2 E I3 - L^2) / (I2 (I3 - I2))
    A3^2 = I2 (I2 - I1) / (I3 (I3 - I1)) w2^2 + w3^2      = (L^2 - 2 E I1) / (I3 (I3 - I1))
    lam^2 = (I3 - I2)(I3 - I1) A3^2 / (I1 I2)
    m  = I1 (I2 - I1) A1^2 / (I3 (I3 - I2) A3^2),   1 - m = D / (I3 (I3 - I2) A3^2)

(substitute into I1 w1' = (I2 - I3) w2 w3 and cyclic, with sn' = cn dn, cn' = -sn dn,
dn' = -m sn cn). On the separatrix (D = 0, m = 1) sn = tanh, cn = dn = sech, and w1 may
have either sign: w1 = s1 A1 sech u with sigma = eps s1 s3.

Attitude: L_world is constant. In a world frame W_L whose z axis is along L, write the
body attitude as z-x-z Euler angles, R = Rz(phi) Rx(theta) Rz(psi). Then
``L_body = |L| (sin th sin psi, sin th cos psi, cos th)`` fixes theta and psi from
w(t), and the body rates give ``phi' = |L| (I1 w1^2 + I2 w2^2) / (L1^2 + L2^2)``.
With ``L1^2 + L2^2 = L^2 - I3^2 w3^2`` and the partial fractions in w3^2,

    phi' = |L| / I3 + |L| (I3 - I1) / (I1 I3) / (1 - n sn^2 u),
    n = -I3 (I2 - I1) / (I1 (I3 - I2))   (< 0 in both orderings),

so ``phi = |L| tau / I3 + |L| (I3 - I1) / (I1 I3 lam) [Pi(n; am u | m) - Pi(n; am u0 | m)]``
with the incomplete integral of the third kind. In Carlson form, for |am u| <= pi/2,
``Pi(n; am u | m) = u + (n/3) sn^3 R_J(cn^2, dn^2, 1, 1 - n sn^2)``; over each half
period 2K it grows by ``2 Pi(n|m) = 2K + (2n/3) R_J(0, 1 - m, 1, 1 - n)``, which is
how large arguments are reduced. On the separatrix
``Pi(n; am u | 1) = (u + a atan(a tanh u)) / (1 - n)`` with a = sqrt(-n).
psi = atan2(L1, L2) is evaluated from the normalised amplitudes so that it stays
continuous through pure spin about axis 3 (L1 = L2 = 0).

The elliptic functions come from the arithmetic-geometric mean with the complementary
parameter 1 - m passed exactly (scipy's ``ellipj`` takes m only, and rounding m near 1
would cost digits next to the separatrix); the quarter period is ``K = pi / (2 a_N)``
from the same AGM, so period reduction and evaluation agree.

D decides the case and sets 1 - m; where its two terms cancel it is evaluated exactly
from the floats given (error-free products and sums, Dekker and Shewchuk), so the case and the phase next to the
separatrix are those of the omega0 given (the label 'separatrix' allows 8 ulps, the flow
does not snap to it). Accuracy (against a long-double Taylor reference, t = 1000 s):
~3e-14 relative in omega and ~1e-13 in the attitude away from the separatrix; next to it
the problem itself is ill-conditioned and the error stays below that of a 1-ulp change
of omega0.

Special cases in closed form: a spherical body (omega constant); a symmetric body
(I_a = I_b = I_p, distinct axis d): ``q(t) = exp(tau L_world / I_p) q0 exp(tau beta e_d)``
with ``beta = (1/I_d - 1/I_p) L_d`` (the two flows commute); a stationary spin about
the middle axis (or a body at rest), labelled 'separatrix' because L^2 = 2 E I2 holds.

Implementation: the construction of a solution from a state and its evaluation at a time
are numba kernels on a parameter vector (``register_jitable``; Carlson's integrals and the
AGM in ``core/elliptic.py``), compiled into the cached entry points below and into the
``exact_split`` kernel; the same source runs interpreted only where Python calls it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba.extending import register_jitable
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core import validation
from rigid_rot_sim.core.dynamics import axes_by_moment
from rigid_rot_sim.core.elliptic import AGM_LEVELS, agm_tables, carlson_rf, carlson_rj, jacobi
from rigid_rot_sim.core.jit import compiled

CASES = ("spherical", "symmetric", "below_separatrix", "above_separatrix", "separatrix")
_SPHERICAL, _SYMMETRIC, _BELOW, _ABOVE, _SEPARATRIX = range(5)

_EPS = float(np.finfo(float).eps)
# Moments equal to within this many ulps of the largest are treated as equal.
_EQUAL_MOMENTS_ULPS = 4.0
# |L^2 - 2 E I2| within this many ulps of its two (opposite-sign) terms is the separatrix.
_SEPARATRIX_ULPS = 8.0
# Below this fraction of its terms, L^2 - 2 E I2 is evaluated exactly (float subtraction
# would lose more than 7 bits of it).
_EXACT_SEPARATRIX_DISTANCE = 1e-2

# The flow's parameter vector: the kind, then the fields of each kind.
_KIND = 0
_RIGID, _SYMMETRIC_FLOW, _ELLIPTIC = 0.0, 1.0, 2.0
# rigid rotation: omega (body), q0, omega_world
_R_OMEGA, _R_Q0, _R_OMEGA_WORLD = 1, 4, 8
# symmetric: moments, axis, rate_world, beta, l_body, q0
_S_MOMENTS, _S_AXIS, _S_RATE, _S_BETA, _S_L, _S_Q0 = 1, 4, 5, 8, 9, 12
# elliptic (relabelled frame): order, axis signs, moments, amplitudes, signs, psi scale,
# lam, u0, m1 (1 - m), n, |L|, K, 2 (Pi(n|m) - K), j0, g0, q_wl, q_perm, AGM levels
(_E_ORDER, _E_AXIS_SIGNS, _E_MOMENTS, _E_AMPLITUDE, _E_SIGNS, _E_PSI_SCALE, _E_LAM, _E_U0, _E_M1, _E_N,
 _E_LNORM, _E_K, _E_EXCESS, _E_J0, _E_G0, _E_QWL, _E_QPERM, _E_LEVELS) = (
    1, 4, 7, 10, 13, 16, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 31, 35)
PARAMS_SIZE = 36


def _relabelling_table() -> np.ndarray:
    """Row ``3 order[0] + order[1]``: axis signs (3) and the quaternion (4) of the proper signed
    permutation x'_k = sign_k x[order[k]] (body -> relabelled body; det = +1 by flipping axis 2)."""
    table = np.zeros((9, 7))
    for order in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
        perm = np.zeros((3, 3))
        for k, i in enumerate(order):
            perm[k, i] = 1.0
        signs = (1.0, -1.0 if np.linalg.det(perm) < 0.0 else 1.0, 1.0)
        perm[1] *= signs[1]  # keep the relabelled frame right-handed
        table[3 * order[0] + order[1]] = (*signs, *Rotation.from_matrix(perm).as_quat())
    return table


_RELABELLING = _relabelling_table()


@register_jitable
def _sign(x):
    return 1.0 if x >= 0.0 else -1.0


# -- L^2 - 2 E I2, exactly where its terms cancel -----------------------------------------


@register_jitable
def _two_product(a, b):
    """a b = p + e exactly (Dekker's splitting; no FMA needed)."""
    p = a * b
    split = 134217729.0  # 2^27 + 1
    t = split * a
    ah = t - (t - a)
    al = a - ah
    t = split * b
    bh = t - (t - b)
    bl = b - bh
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


@register_jitable
def _exact_term(i, d1, d2, w, terms, start):
    """Write 16 floats summing exactly to ``i (d1 - d2) w^2`` into terms[start:start + 16]."""
    s = d1 - d2
    bv = s - d1
    e = (d1 - (s - bv)) + (-d2 - bv)  # two_sum(d1, -d2)
    parts = np.empty(16)
    parts[0], parts[1] = s, e
    n = 2
    for factor in (i, w, w):
        for k in range(n - 1, -1, -1):
            p, err = _two_product(parts[k], factor)
            parts[2 * k], parts[2 * k + 1] = p, err
        n *= 2
    for k in range(16):
        terms[start + k] = parts[k]


@register_jitable
def _exact_sum(values):
    """The sum of the floats, rounded from the exact value (Shewchuk's partials, as fsum);
    exactly 0.0 when the exact sum is 0."""
    partials = np.zeros(values.size + 1)
    n = 0
    for x in values:
        i = 0
        for k in range(n):
            y = partials[k]
            if abs(x) < abs(y):
                x, y = y, x
            hi = x + y
            lo = y - (hi - x)
            if lo != 0.0:
                partials[i] = lo
                i += 1
            x = hi
        partials[i] = x
        n = i + 1
    total = 0.0
    for k in range(n - 1, -1, -1):
        total += partials[k]
    return total


@register_jitable
def _separatrix_distance(moments, omega, i_min, i_mid, i_max):
    """``L^2 - 2 E I2`` from its two terms of opposite sign (exact where they cancel)."""
    d_above = moments[i_max] * (moments[i_max] - moments[i_mid]) * omega[i_max] ** 2
    d_below = moments[i_min] * (moments[i_mid] - moments[i_min]) * omega[i_min] ** 2
    scale = d_above + d_below
    if abs(d_above - d_below) > _EXACT_SEPARATRIX_DISTANCE * scale:
        return d_above - d_below
    # The terms cancel: evaluate exactly (a rounded D would decide the case wrongly at the
    # separatrix and cost digits in the phase and precession next to it).
    terms = np.empty(32)
    _exact_term(moments[i_max], moments[i_max], moments[i_mid], omega[i_max], terms, 0)
    _exact_term(moments[i_min], moments[i_mid], moments[i_min], omega[i_min], terms, 16)
    for k in range(16, 32):
        terms[k] = -terms[k]
    return _exact_sum(terms)


# -- construction -------------------------------------------------------------------------


@register_jitable
def _phase(params, agm_a, agm_c, u):
    """sn, cn, dn at u and the two parts of Pi(n; am u | m) beyond u: (j, g)."""
    n = params[_E_N]
    if params[_E_M1] == 0.0:  # separatrix
        sn = math.tanh(u)
        e = math.exp(-abs(u))
        cn = 2.0 * e / (1.0 + e * e)
        a = math.sqrt(-n)
        return sn, cn, cn, 0.0, a * math.atan(a * sn)
    k = params[_E_K]
    j = math.floor((u + k) / (2.0 * k))
    r = u - 2.0 * k * j
    sn, cn, dn = jacobi(r, agm_a, agm_c, int(params[_E_LEVELS]), params[_E_M1])
    s2 = sn * sn
    g = (n / 3.0) * sn * s2 * carlson_rj(cn * cn, dn * dn, 1.0, 1.0 - n * s2)
    # sn and cn change sign over each half period 2K (dn does not)
    parity = 1.0 - 2.0 * (j % 2.0)
    return parity * sn, parity * cn, dn, j, g


@register_jitable
def _elliptic_state(params, agm_a, agm_c, tau):
    """(q, omega) of the elliptic flow at tau (s) after its anchor."""
    i1, i2, i3 = params[_E_MOMENTS], params[_E_MOMENTS + 1], params[_E_MOMENTS + 2]
    lam = params[_E_LAM]
    n = params[_E_N]
    l_norm = params[_E_LNORM]
    u = lam * tau + params[_E_U0]
    sn, cn, dn, j, g = _phase(params, agm_a, agm_c, u)
    j0, g0 = params[_E_J0], params[_E_G0]
    coeff = l_norm * (i3 - i1) / (i1 * i3 * lam)
    if params[_E_M1] == 0.0:
        phi = l_norm * tau / i3 + coeff * (lam * tau + (g - g0)) / (1.0 - n)
    else:
        phi = l_norm * tau / i1 + coeff * ((j - j0) * params[_E_EXCESS] + (g - g0))
    w0 = params[_E_SIGNS] * params[_E_AMPLITUDE] * cn
    w1 = params[_E_SIGNS + 1] * params[_E_AMPLITUDE + 1] * sn
    w2 = params[_E_SIGNS + 2] * params[_E_AMPLITUDE + 2] * dn
    theta = math.atan2(math.hypot(i1 * w0, i2 * w1), i3 * w2)
    psi = math.atan2(params[_E_PSI_SCALE] * cn, params[_E_PSI_SCALE + 1] * sn)
    q_wl = (params[_E_QWL], params[_E_QWL + 1], params[_E_QWL + 2], params[_E_QWL + 3])
    q_perm = (params[_E_QPERM], params[_E_QPERM + 1], params[_E_QPERM + 2], params[_E_QPERM + 3])
    # a product of unit quaternions: normalised against the rounding of the products
    q = quat.normalize(quat.multiply(quat.multiply(q_wl, quat.from_zxz(phi, theta, psi)), q_perm))
    omega = np.zeros(3)
    omega[int(params[_E_ORDER])] = params[_E_AXIS_SIGNS] * w0
    omega[int(params[_E_ORDER + 1])] = params[_E_AXIS_SIGNS + 1] * w1
    omega[int(params[_E_ORDER + 2])] = params[_E_AXIS_SIGNS + 2] * w2
    return q, (omega[0], omega[1], omega[2])


@register_jitable
def flow_state(params, agm_a, agm_c, tau):
    """``(q, omega)`` as tuples, tau (s) after the anchor of the flow ``params``."""
    kind = params[_KIND]
    if kind == _RIGID:
        wx, wy, wz = params[_R_OMEGA_WORLD], params[_R_OMEGA_WORLD + 1], params[_R_OMEGA_WORLD + 2]
        q0 = (params[_R_Q0], params[_R_Q0 + 1], params[_R_Q0 + 2], params[_R_Q0 + 3])
        q = quat.normalize(quat.multiply(quat.exp_rotation_vector((tau * wx, tau * wy, tau * wz)), q0))
        return q, (params[_R_OMEGA], params[_R_OMEGA + 1], params[_R_OMEGA + 2])
    if kind == _SYMMETRIC_FLOW:
        axis = int(params[_S_AXIS])
        angle = tau * params[_S_BETA]
        spin = quat.exp_rotation_vector((angle if axis == 0 else 0.0, angle if axis == 1 else 0.0,
                                         angle if axis == 2 else 0.0))
        rate = (tau * params[_S_RATE], tau * params[_S_RATE + 1], tau * params[_S_RATE + 2])
        q0 = (params[_S_Q0], params[_S_Q0 + 1], params[_S_Q0 + 2], params[_S_Q0 + 3])
        q = quat.normalize(quat.multiply(quat.multiply(quat.exp_rotation_vector(rate), q0), spin))
        l_now = quat.rotate_inverse(spin, (params[_S_L], params[_S_L + 1], params[_S_L + 2]))
        return q, (l_now[0] / params[_S_MOMENTS], l_now[1] / params[_S_MOMENTS + 1], l_now[2] / params[_S_MOMENTS + 2])
    return _elliptic_state(params, agm_a, agm_c, tau)


@register_jitable
def _elliptic_params(moments, omega, q0, order, d, params, agm_a, agm_c):
    """Fill params / the AGM tables for the triaxial body; ``d`` = L^2 - 2 E I2 (0: separatrix)."""
    row = 3 * order[0] + order[1]
    axis_signs = (_RELABELLING[row, 0], _RELABELLING[row, 1], _RELABELLING[row, 2])
    q_perm = (_RELABELLING[row, 3], _RELABELLING[row, 4], _RELABELLING[row, 5], _RELABELLING[row, 6])
    i1, i2, i3 = moments[order[0]], moments[order[1]], moments[order[2]]
    w1 = axis_signs[0] * omega[order[0]]
    w2 = axis_signs[1] * omega[order[1]]
    w3 = axis_signs[2] * omega[order[2]]
    eps = _sign(i3 - i2)
    d31, d32, d21 = i3 - i1, i3 - i2, i2 - i1
    a1 = math.sqrt(w1 * w1 + i2 * d32 / (i1 * d31) * w2 * w2)
    a2 = math.sqrt(i1 * d31 / (i2 * d32) * w1 * w1 + w2 * w2)
    a3 = math.sqrt(i2 * d21 / (i3 * d31) * w2 * w2 + w3 * w3)
    big = i3 * d32 * a3 * a3
    separatrix = d == 0.0
    m1 = d / big
    m = i1 * d21 * a1 * a1 / big
    lam = math.sqrt(d32 * d31 * a3 * a3 / (i1 * i2))
    n = -i3 * d21 / (i1 * d32)
    s3 = _sign(w3)
    s1 = _sign(w1) if separatrix else 1.0
    sigma = eps * s1 * s3
    alpha1 = 1.0 / math.sqrt(i1 * abs(d31))
    alpha2 = 1.0 / math.sqrt(i2 * abs(d32))
    # phase u0 from sn u0 = sigma w2 / A2, cn u0 = s1 w1 / A1 (normalised against rounding)
    if a1 > 0.0:
        sn0, cn0 = sigma * w2 / a2, s1 * w1 / a1
    else:
        sn0, cn0 = 0.0, 1.0
    norm = math.hypot(sn0, cn0)
    sn0, cn0 = sn0 / norm, cn0 / norm
    params[_KIND] = _ELLIPTIC
    if separatrix:
        agm_a[0], agm_c[0] = 1.0, 1.0
        levels = 0
        k = math.inf
        excess = 0.0
        u0 = math.asinh(sn0 / cn0)
        m1 = 0.0
    else:
        levels = agm_tables(m, m1, agm_a, agm_c)
        k = math.pi / (2.0 * agm_a[levels])
        excess = (2.0 * n / 3.0) * carlson_rj(0.0, m1, 1.0, 1.0 - n)
        f = sn0 * carlson_rf(cn0 * cn0, cn0 * cn0 + m1 * sn0 * sn0, 1.0)
        u0 = f if cn0 >= 0.0 else math.copysign(2.0 * k, sn0) - f
    for idx in range(3):
        params[_E_ORDER + idx] = order[idx]
        params[_E_AXIS_SIGNS + idx] = axis_signs[idx]
    params[_E_MOMENTS], params[_E_MOMENTS + 1], params[_E_MOMENTS + 2] = i1, i2, i3
    params[_E_AMPLITUDE], params[_E_AMPLITUDE + 1], params[_E_AMPLITUDE + 2] = a1, a2, a3
    params[_E_SIGNS], params[_E_SIGNS + 1], params[_E_SIGNS + 2] = s1, sigma, s3
    params[_E_PSI_SCALE], params[_E_PSI_SCALE + 1] = s1 * i1 * alpha1, sigma * i2 * alpha2
    params[_E_LAM], params[_E_U0], params[_E_M1], params[_E_N] = lam, u0, m1, n
    params[_E_LNORM] = math.sqrt((i1 * w1) ** 2 + (i2 * w2) ** 2 + (i3 * w3) ** 2)
    params[_E_K], params[_E_EXCESS], params[_E_LEVELS] = k, excess, levels
    _, _, _, j0, g0 = _phase(params, agm_a, agm_c, u0)
    params[_E_J0], params[_E_G0] = j0, g0
    # q_world<-body = q_WL (x) q_zxz(t) (x) q_perm; q_WL from q(t0) = q0, with q_zxz(t0)
    # evaluated by the flow itself so that the two agree to rounding
    for idx in range(4):
        params[_E_QWL + idx] = 1.0 if idx == 3 else 0.0
        params[_E_QPERM + idx] = 1.0 if idx == 3 else 0.0
    q_zxz0 = _elliptic_state(params, agm_a, agm_c, 0.0)[0]
    q_wl = quat.multiply(quat.multiply(q0, quat.conjugate(q_perm)), quat.conjugate(q_zxz0))
    for idx in range(4):
        params[_E_QWL + idx] = q_wl[idx]
        params[_E_QPERM + idx] = q_perm[idx]


@register_jitable
def flow_params(moments, omega, q0, params, agm_a, agm_c):
    """Build the flow from (moments, omega, q0) (tuples) into params / the AGM tables;
    returns the case (an index of CASES)."""
    i_min, i_mid, i_max = axes_by_moment(moments[0], moments[1], moments[2])
    tol = _EQUAL_MOMENTS_ULPS * _EPS * moments[i_max]
    low_equal = moments[i_mid] - moments[i_min] <= tol
    high_equal = moments[i_max] - moments[i_mid] <= tol
    if low_equal and high_equal:
        _rigid_params(omega, q0, params)
        return _SPHERICAL
    if low_equal or high_equal:
        axis = i_max if low_equal else i_min
        i_perp = moments[(axis + 1) % 3]
        l_body = (moments[0] * omega[0], moments[1] * omega[1], moments[2] * omega[2])
        rate = quat.rotate(q0, l_body)
        params[_KIND] = _SYMMETRIC_FLOW
        for idx in range(3):
            params[_S_MOMENTS + idx] = moments[idx]
            params[_S_RATE + idx] = rate[idx] / i_perp  # rad/s
            params[_S_L + idx] = l_body[idx]
        params[_S_AXIS] = axis
        params[_S_BETA] = (1.0 / moments[axis] - 1.0 / i_perp) * l_body[axis]  # rad/s
        for idx in range(4):
            params[_S_Q0 + idx] = q0[idx]
        return _SYMMETRIC
    d = _separatrix_distance(moments, omega, i_min, i_mid, i_max)
    # The label allows for rounding in the caller's omega0; the flow itself is the exact
    # solution for the omega0 given (the separatrix closed form only when d is exactly 0).
    scale = (moments[i_max] * (moments[i_max] - moments[i_mid]) * omega[i_max] ** 2
             + moments[i_min] * (moments[i_mid] - moments[i_min]) * omega[i_min] ** 2)
    if abs(d) <= _SEPARATRIX_ULPS * _EPS * scale:
        case = _SEPARATRIX
    else:
        case = _ABOVE if d > 0.0 else _BELOW
    if omega[i_min] == 0.0 and omega[i_max] == 0.0:
        # at rest, or a stationary spin about the middle axis
        _rigid_params(omega, q0, params)
    elif d < 0.0:
        _elliptic_params(moments, omega, q0, (i_max, i_mid, i_min), d, params, agm_a, agm_c)
    else:
        _elliptic_params(moments, omega, q0, (i_min, i_mid, i_max), d, params, agm_a, agm_c)
    return case


@register_jitable
def _rigid_params(omega, q0, params):
    """omega constant in the body; q(t) = exp(tau omega_world) q0."""
    params[_KIND] = _RIGID
    omega_world = quat.rotate(q0, omega)
    for idx in range(3):
        params[_R_OMEGA + idx] = omega[idx]
        params[_R_OMEGA_WORLD + idx] = omega_world[idx]
    for idx in range(4):
        params[_R_Q0 + idx] = q0[idx]


@register_jitable
def free_flow(moments, q, omega, tau):
    """Exact free flow over tau (s) from (q, omega) (tuples): ``(q(tau), omega(tau))``."""
    params = np.zeros(PARAMS_SIZE)
    agm_a = np.zeros(AGM_LEVELS)
    agm_c = np.zeros(AGM_LEVELS)
    flow_params(moments, omega, q, params, agm_a, agm_c)
    return flow_state(params, agm_a, agm_c, tau)


@compiled
def _build(moments, omega, q0, params, agm_a, agm_c):
    return flow_params(moments, omega, q0, params, agm_a, agm_c)


@compiled
def evaluate_flow(params, agm_a, agm_c, taus, out):
    """out[k] = (q, omega) at taus[k] (s after the anchor), for every k."""
    for k in range(taus.size):
        q, w = flow_state(params, agm_a, agm_c, taus[k])
        for i in range(4):
            out[k, i] = q[i]
        for i in range(3):
            out[k, 4 + i] = w[i]


@compiled
def _free_flow_compiled(moments, q, omega, tau):
    return free_flow(moments, q, omega, tau)


class _Flow:
    """A built flow: its parameter vector and AGM tables, evaluated by the compiled kernels."""

    def __init__(self, moments: np.ndarray, omega0: np.ndarray, q0: np.ndarray) -> None:
        self.params = np.zeros(PARAMS_SIZE)
        self.agm_a = np.zeros(AGM_LEVELS)
        self.agm_c = np.zeros(AGM_LEVELS)
        self.case = CASES[_build(_floats3(moments), _floats3(omega0), _floats4(q0), self.params, self.agm_a, self.agm_c)]

    def evaluate(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        out = np.empty((tau.size, 7))
        evaluate_flow(self.params, self.agm_a, self.agm_c, np.ascontiguousarray(tau, dtype=float), out)
        return out[:, :4], out[:, 4:]

    def evaluate_scalar(self, tau: float) -> tuple[tuple, tuple]:
        q, omega = self.evaluate(np.array([float(tau)]))
        return tuple(q[0].tolist()), tuple(omega[0].tolist())


def _floats3(v: Any) -> tuple[float, float, float]:
    a, b, c = np.asarray(v, dtype=float).reshape(3).tolist()
    return a, b, c


def _floats4(v: Any) -> tuple[float, float, float, float]:
    a, b, c, d = np.asarray(v, dtype=float).reshape(4).tolist()
    return a, b, c, d


@dataclass(frozen=True, eq=False)
class TorqueFreeSolution:
    """Exact motion of a torque-free rigid body from (q0, omega0) at t0.

    Attributes
    ----------
    moments : ndarray (3,)
        Principal moments (I1, I2, I3), kg*m^2, in the caller's order.
    omega0 : ndarray (3,)
        Initial angular velocity, rad/s, principal body frame.
    q0 : ndarray (4,)
        Initial attitude, principal -> world, scalar-last, unit.
    t0 : float
        Initial time, s.
    case : str
        One of ``CASES``: 'spherical', 'symmetric', or for a triaxial body
        'above_separatrix' (L^2 > 2 E I2, circulation about the largest-moment axis),
        'below_separatrix' (about the smallest) or 'separatrix' (L^2 = 2 E I2 to within
        8 ulps of its terms). The motion computed is the exact one for the omega0 given
        either way: a state a few ulps off the separatrix leaves the saddle after a while.
    """

    moments: np.ndarray
    omega0: np.ndarray
    q0: np.ndarray
    t0: float
    case: str
    _flow: Any = field(repr=False, compare=False)

    def state(self, t: Any) -> tuple[np.ndarray, np.ndarray]:
        """``(quaternion(t), omega(t))`` evaluated together (shapes (..., 4) and (..., 3))."""
        if isinstance(t, (float, int)) and not isinstance(t, bool):
            if not math.isfinite(t):
                raise ValueError(f"t must be finite, got {t}")
            q, w = self._flow.evaluate(np.array([float(t) - self.t0]))
            return q[0], w[0]
        tau = np.asarray(t, dtype=float) - self.t0
        if not np.all(np.isfinite(tau)):
            raise ValueError(f"t must be finite, got {t}")
        q, w = self._flow.evaluate(tau.reshape(-1))
        return q.reshape(tau.shape + (4,)), w.reshape(tau.shape + (3,))

    def state_floats(self, t: float) -> tuple[tuple, tuple]:
        """``(q, omega)`` at one time t (s) as float tuples, unchecked: the exact integrator's step."""
        return self._flow.evaluate_scalar(t - self.t0)

    def omega(self, t: Any) -> np.ndarray:
        """Angular velocity at time(s) t (s), rad/s, principal body frame; shape t.shape + (3,)."""
        return self.state(t)[1]

    def quaternion(self, t: Any) -> np.ndarray:
        """Attitude at time(s) t (s), principal -> world, scalar-last; shape t.shape + (4,)."""
        return self.state(t)[0]

    @property
    def angular_momentum_world(self) -> np.ndarray:
        """The conserved L_world, kg*m^2/s."""
        return Rotation.from_quat(self.q0).apply(self.moments * self.omega0)

    @property
    def energy(self) -> float:
        """The conserved kinetic energy T = 1/2 omega . I omega, J."""
        return 0.5 * float(np.dot(self.moments * self.omega0, self.omega0))


def torque_free_solution(moments: Any, omega0: Any, q0: Any = (0.0, 0.0, 0.0, 1.0), t0: float = 0.0) -> TorqueFreeSolution:
    """Exact torque-free motion of a rigid body.

    Parameters
    ----------
    moments : array_like (3,)
        Principal moments (I1, I2, I3), kg*m^2, any order.
    omega0 : array_like (3,)
        Angular velocity at t0, rad/s, principal body frame.
    q0 : array_like (4,)
        Attitude at t0, principal -> world, scalar-last (normalised on entry).
    t0 : float
        Initial time, s.

    Returns
    -------
    TorqueFreeSolution
        With ``omega(t)``, ``quaternion(t)``, ``state(t)`` vectorised over t and ``case``.

    Examples
    --------
    >>> sol = torque_free_solution((1.0, 2.0, 3.0), (1.0, 0.1, 0.5))
    >>> sol.case
    'below_separatrix'
    >>> bool(np.allclose(sol.omega(0.0), (1.0, 0.1, 0.5), rtol=0, atol=1e-15))
    True
    """
    moments = validation.principal_moments("moments", moments)
    omega0 = validation.finite_vector("omega0", omega0)
    q0 = validation.quaternion("q0", q0)
    t0 = validation.finite_scalar("t0", t0)
    return solution_from_state(moments, omega0, q0, t0)


def torque_free_flow(moments: np.ndarray, q: Any, omega: Any, tau: float) -> tuple[tuple, tuple]:
    """Exact free flow over tau (s) from (q, omega): ``(q(tau), omega(tau))`` as float tuples.

    The same as ``torque_free_solution(moments, omega, q).state(tau)`` without the input
    checks, for callers that already checked the state (``q`` a unit quaternion).
    """
    return _free_flow_compiled(_floats3(moments), _floats4(q), _floats3(omega), float(tau))


def solution_from_state(moments: np.ndarray, omega0: np.ndarray, q0: np.ndarray, t0: float) -> TorqueFreeSolution:
    """:func:`torque_free_solution` without the input checks, for callers holding a checked state.

    ``moments`` (3,) kg*m^2, ``omega0`` (3,) rad/s in the principal frame, ``q0`` (4,) a unit
    quaternion principal -> world, ``t0`` s.
    """
    flow = _Flow(moments, omega0, q0)
    return TorqueFreeSolution(moments, omega0.copy(), q0, t0, flow.case, flow)
