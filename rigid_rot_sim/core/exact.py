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
theta and psi are never formed as angles: the half-angle factor ``Rx(theta) Rz(psi) = (sh c, -sh s,
ch s, ch c)`` (ch, sh = cos, sin theta/2; c, s = cos, sin psi/2, psi = atan2(L1, L2)) comes from
L_body / |L| by +, * and 1/sqrt (``cos^2(a/2) = (1 + cos a) / 2``, ``sin(a/2) = sin a / (2 cos(a/2))``,
each from the side where it does not cancel).

The elliptic functions come from the arithmetic-geometric mean with the complementary
parameter 1 - m passed exactly (scipy's ``ellipj`` takes m only, and rounding m near 1
would cost digits next to the separatrix); the quarter period is ``K = pi / (2 a_N)``
from the same AGM, so period reduction and evaluation agree.

D decides the case and sets 1 - m; where its two terms cancel it is evaluated exactly
from the floats given (error-free products and sums, Dekker and Shewchuk), so the case and the phase next to the
separatrix are those of the omega0 given (the label 'separatrix' allows 8 ulps, the flow
does not snap to it).

Where the angles grow with time the arithmetic is compensated (double-doubles, ``core/elliptic.py``): lam, u0,
K, m, n, |L|, |L| / I1, COEFF and the precession per half period 2K (``Pi(n|m) - K`` by the AGM of DLMF
19.8.6) are built to ~1e-32 from the floats given, u = lam t + u0 and its reduction by 2K, the Jacobi
amplitude, phi and its reduction by 4 pi are carried in double-double, so the phase does not lose a digit per
decade of t. sn, cn, dn come in double-double from the amplitude (``dd_sin_cos_dd``: a table of k/32 and a
short Taylor series, ~3e-20), and so does the bounded part of the precession ``g = Pi(n; am u | m) - u``
(``third_kind_excess_dd``: R_J's first duplication step, and where its remainder's arguments stay far apart
(small cn) up to three more, in double-double with R_C by ``carlson_rc_dd``; only the last remainder, 1/4 to
1/256 of R_J, in double). The attitude is composed as ``q = Q (x) z(t)``, Q = q_WL (x) q_perm a double-double
from the build and z = q_perm* (x) q_zxz (x) q_perm (a signed permutation of q_zxz, exact; q_zxz a
double-double from the half angles above and phi's half angle in double-double), the product summed without
rounding error (Dot2: Ogita, Rump and Oishi 2005) and normalised to first order before its one rounding.
Accuracy against a 40-digit mpmath reference (test/core/test_exact_ulps.py, 100 rad of rotation, units of the
correctly rounded value, 1e-16 absolute near a zero crossing): omega within ~2 ulps (u0 refined by a Newton
step on its amplitude), q within ~3.5 units on every case (the triaxial ones at 0.6-2.6, the spins about a
principal axis at 2.3-3.4). Next to the separatrix the problem itself is ill-conditioned and the error stays
below that of a 1-ulp change of omega0.

Special cases in closed form: a spherical body (omega constant); a symmetric body
(I_a = I_b = I_p, distinct axis d): ``q(t) = q0 exp(tau L0 / I_p) exp(tau beta e_d)`` (body frame; it is
exp(tau L_world / I_p) q0 exp(tau beta e_d), the two flows commute) with ``beta = (1/I_d - 1/I_p) L_d``,
L_body turning by -tau beta about e_d; a spin about a principal axis (or a body at rest): omega constant,
``q(t) = q0 (x) exp(tau omega)``; about the middle axis it is labelled 'separatrix' because L^2 = 2 E I2
holds. Both are compensated as above: the half angles, their sines and cosines and the factors are
double-doubles and the product with q0 is rounded once (within ~1 unit of the correctly rounded value).

The edges of the state space (issue 29; the rules and their bounds in docs/numerics.md): moments and a
largest |omega_k| outside [2^-_RANGE, 2^_RANGE] are rescaled by powers of 2 (Euler's equations are
homogeneous: omega times c is time over c); two components too small to be squared are scaled by a power
of 4 where they enter by ratio (next to the axis of circulation the amplitudes and psi, next to the middle
axis k' = sqrt(1 - m), which then enters the AGM and the complete integrals directly); the AGM's descent
is written with atan2 so that m near 1 costs no digits; for k' < 1/16 the Jacobi functions within K / 2 of
a turning point come from the reflection u = K - v and the precession's bounded part from its integral
from K (_reflected_phase), and for k' < 2^-24 from the expansion about m = 1 (_hyperbolic_jacobi), which
also serves k' below the normal doubles (within ~1e-308 of the middle axis): no finite state is refused.

Implementation: the construction of a solution from a state and its evaluation at a time
are numba kernels on a parameter vector (``register_jitable``; Carlson's integrals and the
AGM in ``core/elliptic.py``), compiled into the cached entry points below and into the
``exact_split`` kernel; the same source runs interpreted only where Python calls it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba.extending import register_jitable
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core import validation
from rigid_rot_sim.core.arrays import ArrayLike, FloatArray
from rigid_rot_sim.core.dynamics import axes_by_moment
from rigid_rot_sim.core.elliptic import (
    AGM_SIZE,
    FOUR_PI_DD,
    PI_DD,
    TWO_PI_DD,
    DoubleDouble,
    agm_tables_kp,
    carlson_rf,
    carlson_rj,
    dd_add,
    dd_add_d,
    dd_complete_integrals_kp,
    dd_div,
    dd_mul,
    dd_reduce,
    dd_rsqrt,
    dd_sin_cos_dd,
    dd_sqrt,
    fast_two_sum,
    jacobi_amplitude_dd,
    jacobi_dd,
    third_kind_excess_dd,
    two_product,
    two_sum,
)
from rigid_rot_sim.core.jit import compiled

#: Float sequences the kernels take (tuples in compiled code, arrays or lists where Python calls them).
Floats = Sequence[float] | FloatArray
Quat = tuple[float, float, float, float]
Vec3 = tuple[float, float, float]

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
# rigid rotation: omega (body), q0, |omega| (a double-double), the unit axis (body)
_R_OMEGA, _R_Q0, _R_RATE, _R_AXIS = 1, 4, 11, 13
# symmetric: moments, axis, rate_world, beta, l_body, q0
# symmetric: moments, axis d, |L| / I_p, beta, L_body(t0) (hi x3, lo x3), q0, L_body(t0) / |L| (hi x3, lo x3);
# the rates are double-doubles (hi, lo)
_S_MOMENTS, _S_AXIS, _S_RATE, _S_BETA, _S_L, _S_Q0, _S_LAXIS = 1, 4, 5, 7, 9, 15, 19
# elliptic (relabelled frame): order, axis signs, moments, amplitudes, signs, 1 / |L|,
# lam, u0, m1 (1 - m), n, |L|, K, COEFF = |L| (I3 - I1) / (I1 I3 lam), j0, g0, Q = q_WL (x) q_perm
# (a double-double: hi in QWL, lo in QWL_LO, see _elliptic_state),
# AGM levels; lam, u0, K, m1, n, COEFF and g0 are double-doubles (hi in the slot named, lo in *_LO); RATE = |L| / I1,
# TURN (the precession beyond RATE t per half period 2K), AGM_TOP (the AGM limit), RNORM = 1 / |L| and
# LSCALE = s_k I_k A_k (L_body = LSCALE * (cn, sn, dn); hi x3 then lo x3) too.
(
    _E_ORDER,
    _E_AXIS_SIGNS,
    _E_MOMENTS,
    _E_AMPLITUDE,
    _E_SIGNS,
    _E_RNORM,
    _E_LAM,
    _E_U0,
    _E_M1,
    _E_N,
    _E_LNORM,
    _E_K,
    _E_COEFF,
    _E_J0,
    _E_G0,
    _E_QWL,
    _E_QWL_LO,
    _E_LEVELS,
    _E_LAM_LO,
    _E_U0_LO,
    _E_K_LO,
    _E_RATE,
    _E_TURN,
    _E_AGM_TOP,
    _E_LSCALE,
    _E_N_LO,
    _E_COEFF_LO,
    _E_G0_LO,
    _E_M1_LO,
) = (1, 4, 7, 10, 13, 16, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 31, 35, 36, 37, 38, 39, 41, 43, 45, 51, 52, 53, 54)
# ASCALE: 1 / S_A, the scale of the amplitudes and LSCALE of axes 1 and 2 (see _elliptic_params)
_E_ASCALE = 55
# every kind: the time scale c (omega = c omega_true, tau_flow = tau / c; see flow_params), 1.0 mostly
_TSCALE = 56
# k' = sqrt(1 - m) (a double-double) for the reflection next to the turning points (see _phase)
_E_KP = 57
# Pi(n|m) - K (a double-double), for the precession in the reflection (see _reflected_phase)
_E_EXCESS = 59
PARAMS_SIZE = 61
# Exponent limits of the rules in flow_params and _elliptic_params (powers of 2, so every rescaling is exact):
# moments and the largest |omega_k| outside [2^-_RANGE, 2^_RANGE] are brought to [1, 2); two components below
# 2^-_TINY (then below 2^(_RANGE - _TINY) of the largest) are scaled up by a power of 4 before they are squared.
_RANGE = 100
_TINY = 300


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
def _sign(x: float) -> float:
    return 1.0 if x >= 0.0 else -1.0


# -- L^2 - 2 E I2, exactly where its terms cancel -----------------------------------------


@register_jitable
def _exact_term(i: float, d1: float, d2: float, w: float, terms: FloatArray, start: int) -> None:
    """Write 16 floats summing exactly to ``i (d1 - d2) w^2`` into terms[start:start + 16]."""
    s = d1 - d2
    bv = s - d1
    e = (d1 - (s - bv)) + (-d2 - bv)  # two_sum(d1, -d2)
    parts = np.empty(16)
    parts[0], parts[1] = s, e
    n = 2
    for factor in (i, w, w):
        for k in range(n - 1, -1, -1):
            p, err = two_product(parts[k], factor)
            parts[2 * k], parts[2 * k + 1] = p, err
        n *= 2
    for k in range(16):
        terms[start + k] = parts[k]


@register_jitable
def _exact_sum(values: FloatArray) -> float:
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
def _separatrix_distance(moments: Floats, omega: Floats, i_min: int, i_mid: int, i_max: int) -> float:
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


#: Below this k' (next to the separatrix) the Jacobi functions within K / 2 of a turning point come from
#: the reflection of :func:`_reflected_jacobi`, and u0 from the complementary amplitude (_elliptic_params).
_SMALL_KP = 0.0625


#: Below this k' the Jacobi functions within K / 2 of u = 0 (and, by the reflection, of the turning
#: points) come from their expansion about m = 1 (:func:`_hyperbolic_jacobi`), not from the AGM
_HYPERBOLIC_KP = 2.0**-24


@register_jitable
def _hyperbolic_jacobi(r: float, m1: float) -> tuple[float, float, float]:
    """sn, cn, dn at 0 <= r <= K / 2 for 1 - m = m1 small (A&S 16.15.1-3, to first order in m1):

        sn = tanh r + (m1 / 4) (sinh r cosh r - r) sech^2 r
        cn = sech r - (m1 / 4) (sinh r cosh r - r) tanh r sech r
        dn = sech r + (m1 / 4) (sinh r cosh r + r) tanh r sech r

    The neglected terms are of relative order (m1 sinh r cosh r)^2 <= (m1 e^K / 4)^2 = k'^2 (e^K ~ 4 / k'),
    below 2^-48 for k' < _HYPERBOLIC_KP; cn and dn keep their relative accuracy where they are of order k'
    (the amplitude near pi / 2 would not)."""
    t = math.tanh(r)
    ch = math.cosh(r)  # below 1e163: r <= K / 2 <= 373
    sech = 1.0 / ch
    sinh = t * ch  # (sinh r cosh r -+ r) sech r = sinh r -+ r sech r: no square of cosh (it would overflow)
    q = 0.25 * m1
    return t + q * (t - r * sech * sech), sech - q * t * (sinh - r * sech), sech + q * t * (sinh + r * sech)


@register_jitable
def _hyperbolic_excess(params: FloatArray, rh: float, rl: float, t: float) -> DoubleDouble:
    """g = Pi(n; am r | m) - r (a double-double) at 0 <= r = rh + rl <= K / 2 for k' < _HYPERBOLIC_KP,
    t = sn r (to first order): at m = 1, g = (n r + a atan(a tanh r)) / (1 - n), a = sqrt(-n) (the
    separatrix's closed form), and its first order in 1 - m, from g' = f(sn) with f(s) = n s^2 / (1 - n s^2)
    and sn's first order s1 (see _hyperbolic_jacobi), ``m1 (n / 2) (A - B)`` with (t = tanh r, J = atan(a t)
    / a, partial fractions in t^2 and one integration by parts)

        A = r / (1 - n)^2 - n J / (1 - n)^2 - (t / (2 (1 - n t^2)) + J / 2) / (1 - n)
        B = t^2 r / (2 (1 - n t^2)) - (r - J) / (2 (1 - n))

    (of size m1 K: 2^-48 K at most). The term in r is a double-double product: g is of the size of K."""
    n_h, n_l = params[_E_N], params[_E_N_LO]
    one_minus_n = dd_add(1.0, 0.0, -n_h, -n_l)
    slope = dd_div(n_h, n_l, *one_minus_n)
    a = math.sqrt(-n_h)
    tanh = math.tanh(rh)
    jay = math.atan(a * tanh) / a
    omn = one_minus_n[0]
    den = 1.0 - n_h * tanh * tanh
    big_a = rh / (omn * omn) - n_h * jay / (omn * omn) - (tanh / (2.0 * den) + 0.5 * jay) / omn
    big_b = tanh * tanh * rh / (2.0 * den) - (rh - jay) / (2.0 * omn)
    first = params[_E_M1] * 0.5 * n_h * (big_a - big_b)
    g = dd_mul(*slope, rh, rl)
    return dd_add_d(*g, a * math.atan(a * tanh) / omn + first)


@register_jitable
def _reflected_phase(
    params: FloatArray, agm_a: FloatArray, agm_c: FloatArray, rh: float, rl: float, hyperbolic: bool
) -> tuple[DoubleDouble, DoubleDouble, DoubleDouble, float, float]:
    """sn, cn, dn (double-doubles) and g = Pi(n; am r | m) - r (g_h, g_l) at r = rh + rl, K / 2 < |r| <= K,
    from v = K - |r| (A&S 16.8): ``sn(K - v) = cn v / dn v``, ``cn(K - v) = k' sn v / dn v``,
    ``dn(K - v) = k' / dn v``; g is odd in r and, with dPi(n; am u) / du = 1 / (1 - n sn^2 u) and
    sn(K - w) = cd w and
    ``1 / (1 - n cd^2) = dn^2 / (dn^2 - n cn^2) = (m / n' + (1 - m / n') / (1 - n' sn^2)) / (1 - n)``
    integrated from K (the last term is Pi(n'; am v | m) = v + (n' / 3) sn^3 R_J(...)):

        g(K - v) = (Pi(n|m) - K) - n v / (1 - n) + n (1 - m) / (3 (1 - n)^2) sn^3 v R_J(cn^2 v, dn^2 v, 1, p')

    with ``n' = (m - n) / (1 - n)`` and ``p' = 1 - n' sn^2 v = (dn^2 v - n cn^2 v) / (1 - n)``.

    Next to the separatrix cn and dn are of order k' around the turning point (the body next to the
    middle axis): from the amplitude near pi / 2 they would carry its absolute rounding, here they keep
    their relative accuracy (psi needs it), and g, which is logarithmic in them and of the size of K,
    is the sum of terms in v without a cancellation (the last one is of order 1 - m)."""
    side = _sign(rh)
    vh, vl = dd_add(params[_E_K], params[_E_K_LO], -side * rh, -side * rl)
    if hyperbolic:
        sv_h, cv_h, dv_h = _hyperbolic_jacobi(vh, params[_E_M1])
        sv, cv, dv = (sv_h, 0.0), (cv_h, 0.0), (dv_h, 0.0)
    else:
        sv, cv, dv = _jacobi_at(params, agm_a, agm_c, vh, vl)
    inv = dd_div(1.0, 0.0, *dv)
    kp = (params[_E_KP], params[_E_KP + 1])
    sn = dd_mul(*cv, *inv)
    g = _reflected_excess(params, vh, vl, sv[0], cv[0], dv[0])
    return (side * sn[0], side * sn[1]), dd_mul(*dd_mul(*kp, *sv), *inv), dd_mul(*kp, *inv), side * g[0], side * g[1]


@register_jitable
def _jacobi_at(
    params: FloatArray, agm_a: FloatArray, agm_c: FloatArray, uh: float, ul: float
) -> tuple[DoubleDouble, DoubleDouble, DoubleDouble]:
    """sn, cn, dn (double-doubles) at u = uh + ul of the flow's modulus (its AGM tables and parameters)."""
    return jacobi_dd(
        uh,
        ul,
        agm_a,
        agm_c,
        int(params[_E_LEVELS]),
        params[_E_M1],
        params[_E_M1_LO],
        params[_E_AGM_TOP],
        params[_E_AGM_TOP + 1],
    )


@register_jitable
def _reflected_excess(params: FloatArray, vh: float, vl: float, sv: float, cv: float, dv: float) -> DoubleDouble:
    """g(K - v) (a double-double; see _reflected_phase) from v = vh + vl and sn, cn, dn at v."""
    n_h, n_l = params[_E_N], params[_E_N_LO]
    one_minus_n = dd_add(1.0, 0.0, -n_h, -n_l)
    slope = dd_div(n_h, n_l, *one_minus_n)
    g = dd_add(params[_E_EXCESS], params[_E_EXCESS + 1], *dd_mul(-slope[0], -slope[1], vh, vl))
    c2, d2 = cv * cv, dv * dv
    rest = n_h * params[_E_M1] / (3.0 * one_minus_n[0] * one_minus_n[0]) * sv**3
    if rest != 0.0:
        rest *= carlson_rj(c2, d2, 1.0, (d2 - n_h * c2) / one_minus_n[0])
    return dd_add_d(*g, rest)


@register_jitable
def _phase(
    params: FloatArray, agm_a: FloatArray, agm_c: FloatArray, uh: float, ul: float
) -> tuple[DoubleDouble, DoubleDouble, DoubleDouble, float, float, float]:
    """sn, cn, dn at u = uh + ul and the two parts of Pi(n; am u | m) beyond u: (j, g_h, g_l),
    j the number of half periods 2K from 0 to u and g = g_h + g_l a bounded remainder."""
    n = params[_E_N]
    if params[_E_K] == math.inf:  # separatrix (k' of another flow may underflow to 0)
        u = uh + ul
        tanh = math.tanh(u)
        e = math.exp(-abs(u))
        sech = 2.0 * e / (1.0 + e * e)
        a = math.sqrt(-n)
        return (tanh, 0.0), (sech, 0.0), (sech, 0.0), 0.0, a * math.atan(a * tanh), 0.0
    k = params[_E_K]
    j = math.floor((uh + k) / (2.0 * k))
    # u - 2 K j in double-double: the phase is reduced without the rounding of u or of K j
    ph, pl = two_product(j, 2.0 * k)
    rh, rl = dd_add(uh, ul, -ph, -pl - j * 2.0 * params[_E_K_LO])
    parity = 1.0 - 2.0 * (j % 2.0)
    hyperbolic = params[_E_KP] < _HYPERBOLIC_KP
    if params[_E_KP] < _SMALL_KP and abs(rh) > 0.5 * k:
        sn, cn, dn, g_h, g_l = _reflected_phase(params, agm_a, agm_c, rh, rl, hyperbolic)
        return (parity * sn[0], parity * sn[1]), (parity * cn[0], parity * cn[1]), dn, j, g_h, g_l
    if hyperbolic:
        side = _sign(rh)
        sn_a, cn_a, dn_a = _hyperbolic_jacobi(abs(rh), params[_E_M1])
        g_h, g_l = _hyperbolic_excess(params, abs(rh), abs(rl), sn_a)
        return (side * parity * sn_a, 0.0), (parity * cn_a, 0.0), (dn_a, 0.0), j, side * g_h, side * g_l
    else:
        sn, cn, dn = _jacobi_at(params, agm_a, agm_c, rh, rl)
    if params[_E_KP] < _SMALL_KP and abs(rh) > 0.25 * k:
        # between ~K / 4 and K / 2 the reflected excess is the better conditioned: cn and dn here, of order
        # k'^(1/4) to k'^(1/2), carry the amplitude's absolute rounding, which the excess of
        # third_kind_excess_dd (logarithmic in them) divides by cn ~ 2 e^-r, the reflected one multiplies by
        # ~ (1 - m) e^(3 v) (its last term); measured, the split at K / 4 does best.
        # sn, cn, dn at v = K - |r| by the same reflection
        side = _sign(rh)
        vh, vl = dd_add(k, params[_E_K_LO], -side * rh, -side * rl)
        kp = params[_E_KP]
        g_h, g_l = _reflected_excess(params, vh, vl, cn[0] / dn[0], kp * abs(sn[0]) / dn[0], kp / dn[0])
        g_h, g_l = side * g_h, side * g_l
    else:
        g_h, g_l = third_kind_excess_dd(sn, cn, dn, n, params[_E_N_LO])
    # sn and cn change sign over each half period 2K (dn does not)
    return (parity * sn[0], parity * sn[1]), (parity * cn[0], parity * cn[1]), dn, j, g_h, g_l


@register_jitable
def _elliptic_state(params: FloatArray, agm_a: FloatArray, agm_c: FloatArray, tau: float) -> tuple[Quat, Vec3]:
    """(q, omega) of the elliptic flow at tau (s) after its anchor."""
    i3 = params[_E_MOMENTS + 2]
    lam = params[_E_LAM]
    n = params[_E_N]
    l_norm = params[_E_LNORM]
    # u = lam tau + u0 and the precession angle phi in double-double: both grow with tau
    uh, ul = two_product(lam, tau)
    uh, ul = dd_add(uh, ul + params[_E_LAM_LO] * tau, params[_E_U0], params[_E_U0_LO])
    sn, cn, dn, j, g_h, g_l = _phase(params, agm_a, agm_c, uh, ul)
    j0, g0 = params[_E_J0], params[_E_G0]
    coeff = params[_E_COEFF]
    if params[_E_K] == math.inf:  # separatrix
        phi_h, phi_l = l_norm * tau / i3 + coeff * (lam * tau + (g_h - g0)) / (1.0 - n), 0.0
    else:
        phi_h, phi_l = two_product(params[_E_RATE], tau)
        turn_h, turn_l = two_product(params[_E_TURN], j - j0)
        phi_h, phi_l = dd_add(phi_h, phi_l + params[_E_RATE + 1] * tau, turn_h, turn_l + params[_E_TURN + 1] * (j - j0))
        # the bounded part COEFF (g - g0) in double-double: it is up to ~2 rad
        bounded = dd_mul(coeff, params[_E_COEFF_LO], *dd_add(g_h, g_l, -g0, -params[_E_G0_LO]))
        phi_h, phi_l = dd_add(phi_h, phi_l, *bounded)
    # (amplitudes 1 and 2 kept times S_A: ASCALE is 1 but next to the axis of circulation)
    w0 = params[_E_SIGNS] * params[_E_AMPLITUDE] * cn[0] * params[_E_ASCALE]
    w1 = params[_E_SIGNS + 1] * params[_E_AMPLITUDE + 1] * sn[0] * params[_E_ASCALE]
    w2 = params[_E_SIGNS + 2] * params[_E_AMPLITUDE + 2] * dn[0]
    # L_body = (I1 w1, I2 w2, I3 w3) from I_k A_k s_k (double-doubles) and cn, sn, dn
    l_body = (
        dd_mul(params[_E_LSCALE], params[_E_LSCALE + 3], *cn),
        dd_mul(params[_E_LSCALE + 1], params[_E_LSCALE + 4], *sn),
        dd_mul(params[_E_LSCALE + 2], params[_E_LSCALE + 5], *dn),
    )
    z_hi, z_lo = _zxz_from_momentum(phi_h, phi_l, *l_body, (params[_E_RNORM], params[_E_RNORM + 1]), params[_E_ASCALE])
    order, axis_signs = params[_E_ORDER : _E_ORDER + 3], params[_E_AXIS_SIGNS : _E_AXIS_SIGNS + 3]
    q = _compensated_product(
        params[_E_QWL : _E_QWL + 4],
        params[_E_QWL_LO : _E_QWL_LO + 4],
        _in_body_frame(z_hi, order, axis_signs),
        _in_body_frame(z_lo, order, axis_signs),
    )
    omega = np.zeros(3)
    omega[int(params[_E_ORDER])] = params[_E_AXIS_SIGNS] * w0
    omega[int(params[_E_ORDER + 1])] = params[_E_AXIS_SIGNS + 1] * w1
    omega[int(params[_E_ORDER + 2])] = params[_E_AXIS_SIGNS + 2] * w2
    return q, (omega[0], omega[1], omega[2])


@register_jitable
def _in_body_frame(z: Floats, order: Floats, axis_signs: Floats) -> Quat:
    """q_perm* (x) z (x) q_perm for the relabelling x' = P x (P = q_perm's matrix): the vector part
    goes to P^T v, (P^T v)[order[k]] = axis_signs[k] v[k], a signed permutation, so exact."""
    v0 = v1 = v2 = 0.0
    for k in range(3):
        if order[k] == 0.0:
            v0 = axis_signs[k] * z[k]
        elif order[k] == 1.0:
            v1 = axis_signs[k] * z[k]
        else:
            v2 = axis_signs[k] * z[k]
    return (v0, v1, v2, z[3])


@register_jitable
def _dot2_product(p_hi: Floats, p_lo: Floats, q: Floats, q_lo: Floats) -> tuple[Quat, Quat]:
    """``(p_hi + p_lo) (x) (q + q_lo)`` as arrays (hi, lo) whose sum is the product to ~1e-32: each
    component's four terms summed by Dot2 (see _compensated_product)."""
    qx, qy, qz, qw = q
    lx, ly, lz, lw = q_lo
    x = _dot2(p_hi, p_lo, (qw, qz, -qy, qx), (lw, lz, -ly, lx))
    y = _dot2(p_hi, p_lo, (-qz, qw, qx, qy), (-lz, lw, lx, ly))
    z = _dot2(p_hi, p_lo, (qy, -qx, qw, qz), (ly, -lx, lw, lz))
    w = _dot2(p_hi, p_lo, (-qx, -qy, -qz, qw), (-lx, -ly, -lz, lw))
    return (x[0], y[0], z[0], w[0]), (x[1], y[1], z[1], w[1])


@register_jitable
def _dot2(a_hi: Floats, a_lo: Floats, b: Floats, b_lo: Floats) -> DoubleDouble:
    """``sum_j (a_hi[j] + a_lo[j]) (b[j] + b_lo[j])`` as (s, c), s + c within ~1e-32 of it (Dot2, see
    _compensated_product; the products of the low parts are below that and left out)."""
    s, c = two_product(a_hi[0], b[0])
    c += a_lo[0] * b[0] + a_hi[0] * b_lo[0]
    for j in range(1, 4):
        t, e = two_product(a_hi[j], b[j])
        s, f = two_sum(s, t)
        c += e + f + (a_lo[j] * b[j] + a_hi[j] * b_lo[j])
    return s, c


@register_jitable
def _compensated_product(p_hi: Floats, p_lo: Floats, q: Floats, q_lo: Floats) -> Quat:
    """``(p_hi + p_lo) (x) (q + q_lo)`` normalised, each component rounded once from ~1e-32 (a unit quaternion).

    The Hamilton product's 16 terms are summed without rounding error (Ogita, Rump and Oishi's
    Dot2: two_product and two_sum, errors kept in a second sum) with p_lo's terms in that
    second sum; the norm is then brought to 1 to first order, ``x (1 - (|x|^2 - 1) / 2)`` with
    |x|^2 - 1 compensated in the same way (|x| is 1 to within a few ulps: x (1 - d / 2) is
    1 / sqrt(1 + d) to 1e-31). A plain double product and normalisation would leave an ulp or
    two of each of the four terms of every component.
    """
    hi, lo = _dot2_product(p_hi, p_lo, q, q_lo)
    d, c = _dot2(hi, (2.0 * lo[0], 2.0 * lo[1], 2.0 * lo[2], 2.0 * lo[3]), hi, (0.0, 0.0, 0.0, 0.0))
    d = (d - 1.0) + c  # d ~ 1: d - 1 is exact (Sterbenz)
    return (
        hi[0] + (lo[0] - 0.5 * d * hi[0]),
        hi[1] + (lo[1] - 0.5 * d * hi[1]),
        hi[2] + (lo[2] - 0.5 * d * hi[2]),
        hi[3] + (lo[3] - 0.5 * d * hi[3]),
    )


@register_jitable
def _half_angles_dd(near_h: float, near_l: float, far_h: float, far_l: float) -> tuple[DoubleDouble, DoubleDouble]:
    """cos and sin of half the angle a in [0, pi / 2] with cos a = near and sin a = far (double-doubles):
    cos^2 = (1 + near) / 2 and sin = far / (2 cos), free of cancellation."""
    big_h, big_l = two_sum(1.0, near_h)
    big_h, big_l = fast_two_sum(big_h, big_l + near_l)
    r_h, r_l = dd_rsqrt(2.0 * big_h, 2.0 * big_l)  # 1 / (2 cos)
    return dd_mul(big_h, big_l, r_h, r_l), dd_mul(far_h, far_l, r_h, r_l)


@register_jitable
def _dot2_pair(
    a_h: float, a_l: float, b_h: float, b_l: float, c_h: float, c_l: float, d_h: float, d_l: float
) -> DoubleDouble:
    """``a b + c d`` (double-doubles) as a double-double (Dot2; the products of low parts left out)."""
    p, pe = two_product(a_h, b_h)
    q, qe = two_product(c_h, d_h)
    s, se = two_sum(p, q)
    return fast_two_sum(s, se + pe + qe + ((a_h * b_l + a_l * b_h) + (c_h * d_l + c_l * d_h)))


@register_jitable
def _zxz_from_momentum(
    phi_h: float,
    phi_l: float,
    l1: DoubleDouble,
    l2: DoubleDouble,
    l3: DoubleDouble,
    r_norm: DoubleDouble,
    across: float,
) -> tuple[Quat, Quat]:
    """The quaternion of Rz(phi) Rx(theta) Rz(psi) with ``L_body = |L| (sin th sin psi, sin th cos psi, cos th)``
    for L_body = (across l1, across l2, l3) and r_norm = 1 / |L| (double-doubles; ``across`` a power of 2, so
    that l1 and l2 may be given scaled where they would underflow) and phi = phi_h + phi_l (rad), as (hi, lo)
    tuples.

    Rx(theta) Rz(psi) is ``(sh c, -sh s, ch s, ch c)`` with ch, sh = cos, sin(theta / 2) and c, s = cos,
    sin(psi / 2): all four from L_body by +, * and 1 / sqrt in double-double (:func:`_half_angles_dd`), so
    the rounding of the angles theta and psi never enters; phi is reduced by 4 pi (the period of its
    half angle) in double-double and the half angle keeps its low part into its sine and cosine."""
    sq12 = dd_add(*dd_mul(*l1, *l1), *dd_mul(*l2, *l2))
    if sq12[0] > 0.0:
        r_across = dd_rsqrt(*sq12)
        sin_theta = dd_mul(*dd_mul(*sq12, *r_across), *r_norm)
        sin_theta = (sin_theta[0] * across, sin_theta[1] * across)
        # psi = atan2(l1, l2) in (-pi, pi]: its half angle from |l2|, |l1| and the sign of l1
        near, far = _half_angles_dd(
            *dd_mul(abs(l2[0]), math.copysign(1.0, l2[0]) * l2[1], *r_across),
            *dd_mul(abs(l1[0]), math.copysign(1.0, l1[0]) * l1[1], *r_across),
        )
    else:  # along the axis: psi is 0 by convention (sin theta = 0 anyway)
        sin_theta, near, far = (0.0, 0.0), (1.0, 0.0), (0.0, 0.0)
    c, s = (near, far) if l2[0] >= 0.0 else (far, near)
    if l1[0] < 0.0:
        s = (-s[0], -s[1])
    near, far = _half_angles_dd(*dd_mul(abs(l3[0]), math.copysign(1.0, l3[0]) * l3[1], *r_norm), *sin_theta)
    ch, sh = (near, far) if l3[0] >= 0.0 else (far, near)
    bx, by, bz, bw = dd_mul(*sh, *c), dd_mul(-sh[0], -sh[1], *s), dd_mul(*ch, *s), dd_mul(*ch, *c)
    phi_h, phi_l = dd_reduce(phi_h, phi_l, FOUR_PI_DD[0], FOUR_PI_DD[1])
    sp_h, sp_l, cp_h, cp_l = dd_sin_cos_dd(0.5 * phi_h, 0.5 * phi_l)
    # (0, 0, sin(phi / 2), cos(phi / 2)) (x) B
    x = _dot2_pair(cp_h, cp_l, *bx, -sp_h, -sp_l, *by)
    y = _dot2_pair(cp_h, cp_l, *by, sp_h, sp_l, *bx)
    z = _dot2_pair(cp_h, cp_l, *bz, sp_h, sp_l, *bw)
    w = _dot2_pair(cp_h, cp_l, *bw, -sp_h, -sp_l, *bz)
    return (x[0], y[0], z[0], w[0]), (x[1], y[1], z[1], w[1])


@register_jitable
def flow_state(params: FloatArray, agm_a: FloatArray, agm_c: FloatArray, tau: float) -> tuple[Quat, Vec3]:
    """``(q, omega)`` as tuples, tau (s) after the anchor of the flow ``params`` (its time scale undone)."""
    scale = params[_TSCALE]
    if scale == 1.0:
        return _flow_state(params, agm_a, agm_c, tau)
    q, w = _flow_state(params, agm_a, agm_c, tau / scale)
    return q, (w[0] / scale, w[1] / scale, w[2] / scale)


@register_jitable
def _flow_state(params: FloatArray, agm_a: FloatArray, agm_c: FloatArray, tau: float) -> tuple[Quat, Vec3]:
    """flow_state in the flow's own time scale."""
    kind = params[_KIND]
    if kind == _RIGID:
        q0 = (params[_R_Q0], params[_R_Q0 + 1], params[_R_Q0 + 2], params[_R_Q0 + 3])
        # the half angle tau |omega| / 2 in double-double, reduced by 2 pi before sin / cos
        half_h, half_l = two_product(0.5 * params[_R_RATE], tau)
        half_h, half_l = dd_reduce(half_h, half_l + 0.5 * params[_R_RATE + 1] * tau, TWO_PI_DD[0], TWO_PI_DD[1])
        s_h, s_l, c_h, c_l = dd_sin_cos_dd(half_h, half_l)
        x = dd_mul(s_h, s_l, params[_R_AXIS], 0.0)
        y = dd_mul(s_h, s_l, params[_R_AXIS + 1], 0.0)
        z = dd_mul(s_h, s_l, params[_R_AXIS + 2], 0.0)
        # exp(tau omega_world) q0 = q0 exp(tau omega), the factor a double-double, so the product is rounded once
        q = _compensated_product(q0, (0.0, 0.0, 0.0, 0.0), (x[0], y[0], z[0], c_h), (x[1], y[1], z[1], c_l))
        return q, (params[_R_OMEGA], params[_R_OMEGA + 1], params[_R_OMEGA + 2])
    if kind == _SYMMETRIC_FLOW:
        return _symmetric_state(params, tau)
    return _elliptic_state(params, agm_a, agm_c, tau)


@register_jitable
def _half_turn(rate_h: float, rate_l: float, tau: float) -> tuple[DoubleDouble, DoubleDouble]:
    """sin and cos (double-doubles) of half the angle (rate_h + rate_l) tau (rad/s times s), reduced by 2 pi
    in double-double."""
    h, lo = two_product(0.5 * rate_h, tau)
    h, lo = dd_reduce(h, lo + 0.5 * rate_l * tau, TWO_PI_DD[0], TWO_PI_DD[1])
    sh, sl, ch, cl = dd_sin_cos_dd(h, lo)
    return (sh, sl), (ch, cl)


@register_jitable
def _dd_sum3(a: DoubleDouble, b: DoubleDouble, c: DoubleDouble) -> DoubleDouble:
    return dd_add(*dd_add(*a, *b), *c)


@register_jitable
def _symmetric_state(params: FloatArray, tau: float) -> tuple[Quat, Vec3]:
    """(q, omega) of the symmetric body: ``q = q0 (x) exp(tau L0 / I_p) (x) exp(tau beta e_d)`` (body frame:
    exp(tau L_world / I_p) q0 = q0 exp(tau L0 / I_p)) and L_body turning by -tau beta about e_d.

    Both half angles and their sines and cosines are double-doubles, so are the two factors and their
    product; the product with q0 is then summed without rounding error and normalised (_compensated_product),
    and L_body(t) comes from the double-double cos and sin of tau beta, so each output is rounded once."""
    axis = int(params[_S_AXIS])
    s_a, c_a = _half_turn(params[_S_RATE], params[_S_RATE + 1], tau)
    s_b, c_b = _half_turn(params[_S_BETA], params[_S_BETA + 1], tau)
    av = (
        dd_mul(*s_a, params[_S_LAXIS], params[_S_LAXIS + 3]),
        dd_mul(*s_a, params[_S_LAXIS + 1], params[_S_LAXIS + 4]),
        dd_mul(*s_a, params[_S_LAXIS + 2], params[_S_LAXIS + 5]),
    )
    # A (x) B with A = (s_a u, c_a), B = (s_b e_d, c_b): vector c_a s_b e_d + c_b a + s_b (a x e_d),
    # scalar c_a c_b - s_b a_d (a x e_d: component d+1 is a_{d+2}, component d+2 is -a_{d+1}, d is 0)
    nxt, prv = (axis + 1) % 3, (axis + 2) % 3
    own = dd_mul(*c_a, *s_b)
    along = dd_add(*own, *dd_mul(*c_b, *av[axis]))
    at_nxt = dd_add(*dd_mul(*c_b, *av[nxt]), *dd_mul(*s_b, *av[prv]))
    at_prv = dd_add(*dd_mul(*c_b, *av[prv]), *dd_mul(-s_b[0], -s_b[1], *av[nxt]))
    x = along if axis == 0 else (at_nxt if nxt == 0 else at_prv)
    y = along if axis == 1 else (at_nxt if nxt == 1 else at_prv)
    z = along if axis == 2 else (at_nxt if nxt == 2 else at_prv)
    w = dd_add(*dd_mul(*c_a, *c_b), *dd_mul(-s_b[0], -s_b[1], *av[axis]))
    q0 = (params[_S_Q0], params[_S_Q0 + 1], params[_S_Q0 + 2], params[_S_Q0 + 3])
    q = _compensated_product(q0, (0.0, 0.0, 0.0, 0.0), (x[0], y[0], z[0], w[0]), (x[1], y[1], z[1], w[1]))
    # L_body(t): the components d+1, d+2 turned by -alpha, alpha = tau beta: cos = 1 - 2 s^2, sin = 2 s c
    cos_b = dd_add(1.0, 0.0, *dd_mul(-2.0 * s_b[0], -2.0 * s_b[1], *s_b))
    sin_b = dd_mul(2.0 * s_b[0], 2.0 * s_b[1], *c_b)
    l_nxt = (params[_S_L + nxt], params[_S_L + 3 + nxt])
    l_prv = (params[_S_L + prv], params[_S_L + 3 + prv])
    new_nxt = dd_add(*dd_mul(*cos_b, *l_nxt), *dd_mul(*sin_b, *l_prv))
    new_prv = dd_add(*dd_mul(*cos_b, *l_prv), *dd_mul(-sin_b[0], -sin_b[1], *l_nxt))
    w_axis = dd_div(params[_S_L + axis], params[_S_L + 3 + axis], params[_S_MOMENTS + axis], 0.0)[0]
    w_nxt = dd_div(*new_nxt, params[_S_MOMENTS + nxt], 0.0)[0]
    w_prv = dd_div(*new_prv, params[_S_MOMENTS + prv], 0.0)[0]
    w0 = w_axis if axis == 0 else (w_nxt if nxt == 0 else w_prv)
    w1 = w_axis if axis == 1 else (w_nxt if nxt == 1 else w_prv)
    w2 = w_axis if axis == 2 else (w_nxt if nxt == 2 else w_prv)
    return q, (w0, w1, w2)


@register_jitable
def _dd_ratio_sum(
    num_a: float, num_b: DoubleDouble, den_a: float, den_b: DoubleDouble, x: float, y: float
) -> DoubleDouble:
    """``(num_a num_b) / (den_a den_b) x^2 + y^2`` in double-double (num_b, den_b double-doubles)."""
    ratio = dd_div(*dd_mul(num_a, 0.0, num_b[0], num_b[1]), *dd_mul(den_a, 0.0, den_b[0], den_b[1]))
    term = dd_mul(*ratio, *two_product(x, x))
    return dd_add(*term, *two_product(y, y))


#: exact_split's short flows take K and Pi(n|m) - K in double down to this k' (below, in double-double)
_SHORT_RUN_KP = 2.0**-26
#: The Newton step on u0 where dn(u0) is at least this (it divides am0's rounding by dn)
_NEWTON_DN = 0.0625


@register_jitable
def _tiny_pair_scale(x: float, y: float) -> float:
    """A power of 4, S, with max(|x|, |y|) S in [2^-_TINY, 2^(2 - _TINY)) where max(|x|, |y|) is below
    2^-_TINY (and not 0), else 1."""
    top = max(abs(x), abs(y))
    if top == 0.0 or top >= 2.0**-_TINY:
        return 1.0
    exponent = math.frexp(top)[1]  # top in [2^(e - 1), 2^e)
    return math.ldexp(1.0, 2 * ((-_TINY - exponent) // 2 + 1))


@register_jitable
def _asinh_ratio(sn: float, cn_scaled: float, scale: float) -> float:
    """asinh(sn / cn) for cn = cn_scaled / scale (scale a power of 2), where the ratio may overflow:
    asinh(x) = ln(2 |x|) + O(1 / x^2) with sign beyond 2^27."""
    ratio = sn / cn_scaled  # the true ratio / scale
    if abs(ratio) * scale < 2.0**27:
        return math.asinh(ratio * scale)
    return math.copysign(math.log(2.0 * abs(ratio)) + math.log(scale), ratio)


@register_jitable
def _elliptic_params(
    moments: Floats,
    omega: Floats,
    q0: Floats,
    order: tuple[int, int, int],
    d: float,
    params: FloatArray,
    agm_a: FloatArray,
    agm_c: FloatArray,
    long_run: bool,
) -> None:
    """Fill params / the AGM tables for the triaxial body; ``d`` = L^2 - 2 E I2 (0: separatrix).

    The constants of the phase and of the precession (lam, u0, |L| / I1, and with ``long_run``
    K and the precession per half period) are double-doubles from the floats given: over many
    periods their rounding would otherwise grow into the phase (100 rad at 1e-16 relative is
    1e-14). Without ``long_run`` (a flow evaluated within about a radian of its anchor, as a
    step of exact_split) K and Pi(n|m) - K come in double from the AGM table and Carlson's R_J,
    which costs half as much to build and is as accurate there.
    """
    row = 3 * order[0] + order[1]
    axis_signs = (_RELABELLING[row, 0], _RELABELLING[row, 1], _RELABELLING[row, 2])
    i1, i2, i3 = moments[order[0]], moments[order[1]], moments[order[2]]
    w1 = axis_signs[0] * omega[order[0]]
    w2 = axis_signs[1] * omega[order[1]]
    w3 = axis_signs[2] * omega[order[2]]
    eps = _sign(i3 - i2)
    # Two components too small to be squared (flow_params has brought the largest to at least
    # 2^-_RANGE, so these are below 2^(_RANGE - _TINY) of it and their squares are nothing beside its):
    # (w1, w2) next to the axis of circulation (region A) or (w1, w3) next to the middle axis (region B)
    # are scaled by a power of 4, S, for what depends on them in ratio (amplitudes, phase, psi, k').
    scale_a = _tiny_pair_scale(w1, w2)
    scale_b = _tiny_pair_scale(w1, w3)
    d31, d32, d21 = two_sum(i3, -i1), two_sum(i3, -i2), two_sum(i2, -i1)
    # region A: A1, A2 (and LSCALE of axes 1, 2) are kept times S_A, undone at evaluation by ASCALE
    a1_sq = _dd_ratio_sum(i2, d32, i1, d31, w2 * scale_a, w1 * scale_a)
    a2_sq = _dd_ratio_sum(i1, d31, i2, d32, w1 * scale_a, w2 * scale_a)
    a3_sq = _dd_ratio_sum(i2, d21, i3, d31, w2, w3)
    a1_dd, a2_dd, a3_dd = dd_sqrt(*a1_sq), dd_sqrt(*a2_sq), dd_sqrt(*a3_sq)
    a1, a2, a3 = a1_dd[0], a2_dd[0], a3_dd[0]
    big = dd_mul(*dd_mul(i3, 0.0, *d32), *a3_sq)
    # region B: 1 - m = k'^2 is formed times S_B^2 (it underflows next to the middle axis), k' and
    # sqrt(k') from it by exact powers of 2
    above = dd_mul(*dd_mul(i3, 0.0, *d32), *two_product(w3 * scale_b, w3 * scale_b))
    below = dd_mul(*dd_mul(i1, 0.0, *d21), *two_product(w1 * scale_b, w1 * scale_b))
    m1s_dd = dd_div(*dd_add(*above, -below[0], -below[1]), *big)
    kps_dd = dd_sqrt(*m1s_dd)  # k' S_B
    kp_dd = (kps_dd[0] / scale_b, kps_dd[1] / scale_b)
    root_scale = math.sqrt(scale_b)  # exact: S_B is a power of 4
    root_kp = dd_sqrt(*kps_dd)
    root_kp = (root_kp[0] / root_scale, root_kp[1] / root_scale)
    m1_dd = (m1s_dd[0] / scale_b / scale_b, m1s_dd[1] / scale_b / scale_b)
    # (k' below the normal doubles, within ~1e-308 of the middle axis, is the expansion about m = 1 all the
    # way: its cn and dn near the turning points are then subnormal, needed to their absolute accuracy only,
    # and sqrt(k'), the AGM's first geometric mean, comes from k' S_B)
    m = dd_div(*dd_mul(*dd_mul(i1, 0.0, *d21), *a1_sq), *big)[0] / scale_a / scale_a
    lam_dd = dd_sqrt(*dd_div(*dd_mul(*dd_mul(*d32, *d31), *a3_sq), *two_product(i1, i2)))
    n_dd = dd_div(*dd_mul(-i3, 0.0, *d21), *dd_mul(i1, 0.0, *d32))
    l_dd = dd_sqrt(*dd_add(*dd_add(*_square_dd(i1, w1), *_square_dd(i2, w2)), *_square_dd(i3, w3)))
    coeff_dd = dd_div(*dd_mul(*l_dd, *d31), *dd_mul(*two_product(i1, i3), *lam_dd))
    separatrix = d == 0.0
    m1 = m1_dd[0]
    n = n_dd[0]
    s3 = _sign(w3)
    s1 = _sign(w1) if separatrix else 1.0
    sigma = eps * s1 * s3
    # phase u0 from sn u0 = sigma w2 / A2, cn u0 = s1 w1 / A1 (normalised against rounding); cn0 times
    # S_B (cn0_s) for the comparison with k' next to the middle axis
    if a1 > 0.0:
        sn0, cn0_s = sigma * w2 * scale_a / a2, s1 * w1 * scale_a * scale_b / a1
    else:
        sn0, cn0_s = 0.0, 1.0
    norm = math.hypot(sn0, cn0_s / scale_b)
    sn0, cn0_s = sn0 / norm, cn0_s / norm
    cn0 = cn0_s / scale_b
    params[_KIND] = _ELLIPTIC
    k_dd = (math.inf, 0.0)
    excess_dd = (0.0, 0.0)
    turn_dd = (0.0, 0.0)
    u0_dd = (0.0, 0.0)
    if separatrix:
        agm_a[0], agm_c[0] = 1.0, 1.0
        levels = 0
        u0_dd = (_asinh_ratio(sn0, cn0_s, scale_b), 0.0)
        m1 = 0.0
    else:
        levels = agm_tables_kp(m, kp_dd[0], root_kp[0], agm_a, agm_c)
        if long_run or kp_dd[0] < _SHORT_RUN_KP:
            # (R_J(0, k'^2, 1, 1 - n) in double would not converge once k'^2 underflows)
            k_h, k_l, excess_h, excess_l = dd_complete_integrals_kp(*kp_dd, *root_kp, n_dd[0], n_dd[1])
        else:
            k_h, k_l = math.pi / (2.0 * agm_a[levels]), 0.0
            excess_h, excess_l = (n / 3.0) * carlson_rj(0.0, m1, 1.0, 1.0 - n), 0.0
        k_dd = (k_h, k_l)
        excess_dd = (excess_h, excess_l)
        turn_dd = dd_mul(*coeff_dd, 2.0 * excess_h, 2.0 * excess_l)
        if kp_dd[0] >= _SMALL_KP or cn0_s * cn0_s >= kps_dd[0] * scale_b * sn0 * sn0:
            # F(am0 | m) from am0 itself (sn0, cn0), the nearer end of the quarter period
            f = sn0 * carlson_rf(cn0 * cn0, cn0 * cn0 + m1 * sn0 * sn0, 1.0)
            if cn0 >= 0.0:
                u0_dd = (f, 0.0)
            else:
                u0_dd = dd_add(math.copysign(2.0 * k_h, sn0), math.copysign(2.0 * k_l, sn0), -f, 0.0)
            newton = long_run
        else:
            # next to the separatrix (k' < _SMALL_KP) and nearer the turning point sn = +-1 than am0 = am(K / 2):
            # u0 = +-(K -+ F(psi | m)) with tan am0 tan psi = 1 / k' (A&S 17.4.13), psi from cn0 and k' sn0
            # (both small there: taken times S_B); F(am0 | m) would be the difference of K and F(psi | m)
            across = math.hypot(cn0_s, kps_dd[0] * sn0)
            sin_psi, cos_psi = abs(cn0_s) / across, kps_dd[0] * abs(sn0) / across
            v0 = sin_psi * carlson_rf(cos_psi * cos_psi, cos_psi * cos_psi + m1 * sin_psi * sin_psi, 1.0)
            u0_dd = dd_add(k_h, k_l, -_sign(cn0) * v0, 0.0)
            u0_dd = (_sign(sn0) * u0_dd[0], _sign(sn0) * u0_dd[1])
            newton = False
        if newton and a1 > 0.0:
            # one Newton step on am(u0) = am0 (d am / du = dn), am0 from
            # tan am0 = sigma w2 A1 / (w1 A2) with A1 / A2 = sqrt(I2 (I3 - I2) / (I1 (I3 - I1))); only where
            # dn(u0) >= 1/16: the step divides am0's rounding by dn
            ratio = dd_sqrt(*dd_div(*dd_mul(i2, 0.0, *d32), *dd_mul(i1, 0.0, *d31)))[0]
            am0 = math.atan2(sigma * w2 * scale_a * ratio, w1 * scale_a)
            top = dd_div(*PI_DD, 2.0 * k_h, 2.0 * k_l)
            j = math.floor((u0_dd[0] + k_h) / (2.0 * k_h))
            ph, pl = two_product(j, 2.0 * k_h)
            rh, rl = dd_add(u0_dd[0], u0_dd[1], -ph, -pl - j * 2.0 * k_l)
            am_h, am_l = jacobi_amplitude_dd(rh, rl, agm_a, agm_c, levels, top[0], top[1])
            sn_u, cn_u = math.sin(am_h), math.cos(am_h)
            dn_u = math.sqrt(cn_u * cn_u + m1 * sn_u * sn_u)
            if dn_u >= _NEWTON_DN:
                miss = ((am0 - j * PI_DD[0]) - am_h) - (am_l + j * PI_DD[1])
                u0_dd = dd_add_d(u0_dd[0], u0_dd[1], miss / dn_u)
    for idx in range(3):
        params[_E_ORDER + idx] = order[idx]
        params[_E_AXIS_SIGNS + idx] = axis_signs[idx]
    params[_E_MOMENTS], params[_E_MOMENTS + 1], params[_E_MOMENTS + 2] = i1, i2, i3
    params[_E_AMPLITUDE], params[_E_AMPLITUDE + 1], params[_E_AMPLITUDE + 2] = a1, a2, a3
    params[_E_SIGNS], params[_E_SIGNS + 1], params[_E_SIGNS + 2] = s1, sigma, s3
    for idx, (sign, moment, amplitude) in enumerate(((s1, i1, a1_dd), (sigma, i2, a2_dd), (s3, i3, a3_dd))):
        params[_E_LSCALE + idx], params[_E_LSCALE + 3 + idx] = dd_mul(sign * moment, 0.0, *amplitude)
    params[_E_ASCALE] = 1.0 / scale_a
    params[_E_KP], params[_E_KP + 1] = (0.0, 0.0) if separatrix else kp_dd
    params[_E_EXCESS], params[_E_EXCESS + 1] = excess_dd
    params[_E_LAM], params[_E_LAM_LO] = lam_dd
    params[_E_U0], params[_E_U0_LO] = u0_dd
    params[_E_M1], params[_E_M1_LO], params[_E_N], params[_E_N_LO] = m1, m1_dd[1], n, n_dd[1]
    params[_E_LNORM] = l_dd[0]
    # 1 / |L|: L_body(t) from the amplitudes and the double-double sn, cn, dn has this norm to ~1e-20
    params[_E_RNORM], params[_E_RNORM + 1] = dd_div(1.0, 0.0, *l_dd)
    params[_E_K], params[_E_K_LO] = k_dd
    params[_E_COEFF], params[_E_COEFF_LO] = coeff_dd
    params[_E_RATE], params[_E_RATE + 1] = dd_div(*l_dd, i1, 0.0)
    params[_E_TURN], params[_E_TURN + 1] = turn_dd
    params[_E_LEVELS] = levels
    # the AGM limit a_N = pi / (2 K) in double-double, for the amplitude in jacobi_dd
    params[_E_AGM_TOP], params[_E_AGM_TOP + 1] = 0.0, 0.0
    if not separatrix:
        params[_E_AGM_TOP] = agm_a[levels]
        if long_run:
            params[_E_AGM_TOP], params[_E_AGM_TOP + 1] = dd_div(*PI_DD, 2.0 * k_dd[0], 2.0 * k_dd[1])
    _, _, _, j0, g0_h, g0_l = _phase(params, agm_a, agm_c, u0_dd[0], u0_dd[1])
    params[_E_J0], params[_E_G0], params[_E_G0_LO] = j0, g0_h, g0_l
    # q_world<-body = q_WL (x) q_zxz(t) (x) q_perm; q_WL from q(t0) = q0, with q_zxz(t0) from the
    # omega0 given (phi = 0; theta and psi as _elliptic_state takes them from the flow's omega):
    # the flow's own omega(t0) agrees with it to an ulp, and evaluating the flow at t0 would
    # cost a whole evaluation more per build
    # q = q_WL (x) q_zxz (x) q_perm = Q (x) z, z = q_perm* (x) q_zxz (x) q_perm (_in_body_frame, exact)
    # and Q = q_WL (x) q_perm = q0 (x) z(t0)*, kept as a double-double; q0 and z(t0) need not be
    # unit to the last bit: the evaluation normalises the product
    for k in range(3):
        params[_E_ORDER + k] = order[k]
        params[_E_AXIS_SIGNS + k] = axis_signs[k]
    z0_hi, z0_lo = _zxz_from_momentum(
        0.0,
        0.0,
        two_product(i1, w1 * scale_a),
        two_product(i2, w2 * scale_a),
        two_product(i3, w3),
        (params[_E_RNORM], params[_E_RNORM + 1]),
        1.0 / scale_a,
    )
    order_k, signs_k = params[_E_ORDER : _E_ORDER + 3], params[_E_AXIS_SIGNS : _E_AXIS_SIGNS + 3]
    q_hi, q_lo = _dot2_product(
        q0,
        (0.0, 0.0, 0.0, 0.0),
        quat.conjugate(_in_body_frame(z0_hi, order_k, signs_k)),
        quat.conjugate(_in_body_frame(z0_lo, order_k, signs_k)),
    )
    for idx in range(4):
        params[_E_QWL + idx], params[_E_QWL_LO + idx] = fast_two_sum(q_hi[idx], q_lo[idx])


@register_jitable
def _square_dd(i: float, w: float) -> DoubleDouble:
    """(i w)^2 in double-double."""
    return dd_mul(*two_product(i, w), *two_product(i, w))


@register_jitable
def flow_params(
    moments: Floats, omega: Floats, q0: Floats, params: FloatArray, agm_a: FloatArray, agm_c: FloatArray, long_run: bool
) -> int:
    """Build the flow from (moments, omega, q0) (tuples) into params / the AGM tables;
    returns the case (an index of CASES). ``long_run``: the flow will be evaluated far from
    its anchor (see _elliptic_params); a solution object always is.

    Euler's equations are homogeneous: moments times a constant change nothing, and omega times c gives
    omega(t) = omega_c(t / c) / c, q(t) = q_c(t / c). Moments or a largest |omega_k| outside
    [2^-_RANGE, 2^_RANGE] are brought into it by a power of 2 (exact), the time scale c kept in params."""
    moments = _in_range(moments)
    scale = _range_scale(max(abs(omega[0]), abs(omega[1]), abs(omega[2])))
    omega = (omega[0] * scale, omega[1] * scale, omega[2] * scale)
    case = _flow_params(moments, omega, q0, params, agm_a, agm_c, long_run)
    params[_TSCALE] = scale
    return case


@register_jitable
def _range_scale(top: float) -> float:
    """1.0 for top (> 0) in [2^-_RANGE, 2^_RANGE] or 0, else the power of 2 that brings it to [1, 2)
    (or to at least 2^-74 from a subnormal: 2^1074 is not a double)."""
    if top == 0.0 or 2.0**-_RANGE <= top <= 2.0**_RANGE:
        return 1.0
    return math.ldexp(1.0, min(1 - math.frexp(top)[1], 1000))


@register_jitable
def _in_range(moments: Floats) -> Vec3:
    """The moments times the power of 2 of :func:`_range_scale` (the motion does not depend on it)."""
    scale = _range_scale(max(moments[0], moments[1], moments[2]))
    return (moments[0] * scale, moments[1] * scale, moments[2] * scale)


@register_jitable
def _flow_params(
    moments: Floats, omega: Floats, q0: Floats, params: FloatArray, agm_a: FloatArray, agm_c: FloatArray, long_run: bool
) -> int:
    """flow_params for moments and omega in range."""
    i_min, i_mid, i_max = axes_by_moment(moments[0], moments[1], moments[2])
    tol = _EQUAL_MOMENTS_ULPS * _EPS * moments[i_max]
    low_equal = moments[i_mid] - moments[i_min] <= tol
    high_equal = moments[i_max] - moments[i_mid] <= tol
    if low_equal and high_equal:
        _rigid_params(omega, q0, params)
        return _SPHERICAL
    if low_equal or high_equal:
        axis = i_max if low_equal else i_min
        _symmetric_params(moments, omega, q0, axis, params)
        return _SYMMETRIC
    # next to the middle axis the other two components may be too small to square: D times a power of 16
    # (the sign and the zero are what is used here)
    pair = _tiny_pair_scale(omega[i_min], omega[i_max])
    scaled = (
        omega[0] * (1.0 if i_mid == 0 else pair),
        omega[1] * (1.0 if i_mid == 1 else pair),
        omega[2] * (1.0 if i_mid == 2 else pair),
    )
    d = _separatrix_distance(moments, scaled, i_min, i_mid, i_max)
    # The label allows for rounding in the caller's omega0; the flow itself is the exact
    # solution for the omega0 given (the separatrix closed form only when d is exactly 0).
    scale = (
        moments[i_max] * (moments[i_max] - moments[i_mid]) * scaled[i_max] ** 2
        + moments[i_min] * (moments[i_mid] - moments[i_min]) * scaled[i_min] ** 2
    )
    if abs(d) <= _SEPARATRIX_ULPS * _EPS * scale:
        case = _SEPARATRIX
    else:
        case = _ABOVE if d > 0.0 else _BELOW
    if (omega[0] == 0.0) + (omega[1] == 0.0) + (omega[2] == 0.0) >= 2:
        # at rest, or a spin about a principal axis: omega is constant (the elliptic flow's
        # precession would be the difference of terms of order 1 there, so a few ulps off)
        _rigid_params(omega, q0, params)
    elif d < 0.0:
        _elliptic_params(moments, omega, q0, (i_max, i_mid, i_min), d, params, agm_a, agm_c, long_run)
    else:
        _elliptic_params(moments, omega, q0, (i_min, i_mid, i_max), d, params, agm_a, agm_c, long_run)
    return case


@register_jitable
def _symmetric_params(moments: Floats, omega: Floats, q0: Floats, axis: int, params: FloatArray) -> None:
    """The symmetric body (distinct axis ``axis``): |L| / I_p, beta = (1 / I_d - 1 / I_p) L_d =
    L_d (I_p - I_d) / (I_d I_p) and L_body(t0) / |L| as double-doubles from the floats given."""
    i_perp = moments[(axis + 1) % 3]
    i_d = moments[axis]
    l_body = (two_product(moments[0], omega[0]), two_product(moments[1], omega[1]), two_product(moments[2], omega[2]))
    sq = _dd_sum3(dd_mul(*l_body[0], *l_body[0]), dd_mul(*l_body[1], *l_body[1]), dd_mul(*l_body[2], *l_body[2]))
    norm = dd_sqrt(*sq)
    r_norm = dd_div(1.0, 0.0, *norm) if norm[0] > 0.0 else (0.0, 0.0)  # at rest: no axis
    params[_KIND] = _SYMMETRIC_FLOW
    for idx in range(3):
        params[_S_MOMENTS + idx] = moments[idx]
        params[_S_L + idx], params[_S_L + 3 + idx] = l_body[idx]
        params[_S_LAXIS + idx], params[_S_LAXIS + 3 + idx] = dd_mul(*l_body[idx], *r_norm)
    params[_S_AXIS] = axis
    params[_S_RATE], params[_S_RATE + 1] = dd_div(*norm, i_perp, 0.0)  # rad/s
    beta = dd_div(*dd_mul(*l_body[axis], *two_sum(i_perp, -i_d)), *two_product(i_d, i_perp))
    params[_S_BETA], params[_S_BETA + 1] = beta  # rad/s
    for idx in range(4):
        params[_S_Q0 + idx] = q0[idx]


@register_jitable
def _rigid_params(omega: Floats, q0: Floats, params: FloatArray) -> None:
    """omega constant in the body; q(t) = exp(tau omega_world) q0 = q0 exp(tau omega)."""
    params[_KIND] = _RIGID
    rate = dd_sqrt(
        *dd_add(
            *dd_add(*two_product(omega[0], omega[0]), *two_product(omega[1], omega[1])),
            *two_product(omega[2], omega[2]),
        )
    )
    # in the body frame, the axis of a spin about a principal axis is exactly +-e_k
    # (sqrt(w^2) = |w| in IEEE arithmetic)
    norm = math.sqrt(omega[0] ** 2 + omega[1] ** 2 + omega[2] ** 2)
    for idx in range(3):
        params[_R_OMEGA + idx] = omega[idx]
        params[_R_AXIS + idx] = omega[idx] / norm if norm > 0.0 else 0.0
    params[_R_RATE], params[_R_RATE + 1] = rate
    for idx in range(4):
        params[_R_Q0 + idx] = q0[idx]


@register_jitable
def free_flow(moments: Floats, q: Floats, omega: Floats, tau: float) -> tuple[Quat, Vec3]:
    """Exact free flow over tau (s) from (q, omega) (tuples): ``(q(tau), omega(tau))``."""
    params = np.zeros(PARAMS_SIZE)
    agm_a = np.zeros(AGM_SIZE)
    agm_c = np.zeros(AGM_SIZE)
    # beyond about a radian of rotation the phase constants are worth their double-double
    long_run = abs(tau) * math.sqrt(omega[0] ** 2 + omega[1] ** 2 + omega[2] ** 2) > 1.0
    flow_params(moments, omega, q, params, agm_a, agm_c, long_run)
    return flow_state(params, agm_a, agm_c, tau)


@compiled
def _build(moments: Floats, omega: Floats, q0: Floats, params: FloatArray, agm_a: FloatArray, agm_c: FloatArray) -> int:
    return flow_params(moments, omega, q0, params, agm_a, agm_c, True)


@compiled
def evaluate_flow(params: FloatArray, agm_a: FloatArray, agm_c: FloatArray, taus: FloatArray, out: FloatArray) -> None:
    """out[k] = (q, omega) at taus[k] (s after the anchor), for every k."""
    for k in range(taus.size):
        q, w = flow_state(params, agm_a, agm_c, taus[k])
        for i in range(4):
            out[k, i] = q[i]
        for i in range(3):
            out[k, 4 + i] = w[i]


@compiled
def _free_flow_compiled(moments: Floats, q: Floats, omega: Floats, tau: float) -> tuple[Quat, Vec3]:
    return free_flow(moments, q, omega, tau)


class _Flow:
    """A built flow: its parameter vector and AGM tables, evaluated by the compiled kernels."""

    def __init__(self, moments: np.ndarray, omega0: np.ndarray, q0: np.ndarray) -> None:
        self.params = np.zeros(PARAMS_SIZE)
        self.agm_a = np.zeros(AGM_SIZE)
        self.agm_c = np.zeros(AGM_SIZE)
        self.case = CASES[
            _build(_floats3(moments), _floats3(omega0), _floats4(q0), self.params, self.agm_a, self.agm_c)
        ]

    def evaluate(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        out = np.empty((tau.size, 7))
        evaluate_flow(self.params, self.agm_a, self.agm_c, np.ascontiguousarray(tau, dtype=float), out)
        return out[:, :4], out[:, 4:]

    def evaluate_scalar(self, tau: float) -> tuple[Quat, Vec3]:
        q, omega = self.evaluate(np.array([float(tau)]))
        return _floats4(q[0]), _floats3(omega[0])


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

    def state(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
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

    def state_floats(self, t: float) -> tuple[Quat, Vec3]:
        """``(q, omega)`` at one time t (s) as float tuples, unchecked: the exact integrator's step."""
        result: tuple[Quat, Vec3] = self._flow.evaluate_scalar(t - self.t0)
        return result

    def omega(self, t: ArrayLike) -> np.ndarray:
        """Angular velocity at time(s) t (s), rad/s, principal body frame; shape t.shape + (3,)."""
        return self.state(t)[1]

    def quaternion(self, t: ArrayLike) -> np.ndarray:
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


def torque_free_solution(
    moments: ArrayLike, omega0: ArrayLike, q0: ArrayLike = (0.0, 0.0, 0.0, 1.0), t0: float = 0.0
) -> TorqueFreeSolution:
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


def torque_free_flow(moments: np.ndarray, q: ArrayLike, omega: ArrayLike, tau: float) -> tuple[Quat, Vec3]:
    """Exact free flow over tau (s) from (q, omega): ``(q(tau), omega(tau))`` as float tuples.

    The same as ``torque_free_solution(moments, omega, q).state(tau)`` without the input
    checks, for callers that already checked the state (``q`` a unit quaternion).
    """
    result: tuple[Quat, Vec3] = _free_flow_compiled(_floats3(moments), _floats4(q), _floats3(omega), float(tau))
    return result


def solution_from_state(moments: np.ndarray, omega0: np.ndarray, q0: np.ndarray, t0: float) -> TorqueFreeSolution:
    """:func:`torque_free_solution` without the input checks, for callers holding a checked state.

    ``moments`` (3,) kg*m^2, ``omega0`` (3,) rad/s in the principal frame, ``q0`` (4,) a unit
    quaternion principal -> world, ``t0`` s.
    """
    flow = _Flow(moments, omega0, q0)
    return TorqueFreeSolution(moments, omega0.copy(), q0, t0, flow.case, flow)
