"""Carlson's symmetric elliptic integrals and Jacobi's elliptic functions, for compiled kernels.

``register_jitable`` functions on floats: plain Python when called from Python, compiled
into the exact-flow kernels by numba (no fastmath). The integrals use Carlson's duplication
theorem ("Numerical computation of real or complex elliptic integrals", Numer. Algorithms
10, 1995) with the truncation errors of Numerical Recipes (3rd ed., section 6.12), which
bring the series remainder below double rounding; the tests compare them with scipy's
``elliprf``/``elliprj`` to a few ulps. The Jacobi functions come from the descending
arithmetic-geometric mean with the complementary parameter passed exactly
(Abramowitz & Stegun 16.4), see ``core/exact.py``.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any

import numpy as np
from numba import types
from numba.extending import intrinsic, overload, register_jitable

from rigid_rot_sim.core.arrays import FloatArray

_EPS = 2.220446049250313e-16
#: A double-double (hi, lo) as a tuple.
DoubleDouble = tuple[float, float]
#: Most AGM levels kept (the AGM converges quadratically: 40 is never reached for m < 1).
AGM_LEVELS = 40
#: Size of the AGM tables: ``a`` holds a_i at i and b_i at AGM_LEVELS + i (the descent needs b_i, see
#: :func:`jacobi_amplitude_dd`); ``c`` holds c_i.
AGM_SIZE = 2 * AGM_LEVELS
#: pi and 2 pi as double-doubles (hi + lo, |lo| <= ulp(hi) / 2).
PI_DD = (3.141592653589793, 1.2246467991473532e-16)
TWO_PI_DD = (6.283185307179586, 2.4492935982947064e-16)
FOUR_PI_DD = (12.566370614359172, 4.898587196589413e-16)
#: 1/3 as a double-double.
THIRD_DD = (0.3333333333333333, 1.850371707708594e-17)


# -- error-free transformations and double-double arithmetic -------------------------------
# A double-double (hi, lo) stands for the unevaluated sum hi + lo with |lo| <= ulp(hi) / 2:
# about 106 bits. Used where a phase or an angle grows with time (rate * t over many
# periods) and for the constants it is made of; numba without fastmath keeps IEEE order, so
# the compensations below are not reassociated away. Dekker (1971), Knuth TAOCP 4.2.2.


@register_jitable
def two_sum(a: float, b: float) -> tuple[float, float]:
    """a + b = s + e exactly (Knuth; any magnitudes)."""
    s = a + b
    bv = s - a
    return s, (a - (s - bv)) + (b - bv)


@register_jitable
def fast_two_sum(a: float, b: float) -> tuple[float, float]:
    """a + b = s + e exactly, for |a| >= |b| (or a = 0)."""
    s = a + b
    return s, b - (s - a)


def two_product(a: float, b: float) -> tuple[float, float]:
    """a b = p + e exactly: p = fl(a b) and e its rounding error.

    Interpreted, Dekker's splitting (Python 3.11 has no ``math.fma``); compiled, one fused
    multiply-add, ``e = fma(a, b, -p)`` (:func:`_two_product_fma`). Both give the exact e, so
    the same bits (barring overflow past 2^996 or products below 2^-969, where Dekker's split
    is inexact); the FMA costs 2 operations instead of 17.
    """
    p = a * b
    split = 134217729.0  # 2^27 + 1
    t = split * a
    ah = t - (t - a)
    al = a - ah
    t = split * b
    bh = t - (t - b)
    bl = b - bh
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def _fma_intrinsic(typingctx: Any, a: Any, b: Any, c: Any) -> Any:
    """fma(a, b, c) = a b + c rounded once (IEEE 754 fusedMultiplyAdd, LLVM's llvm.fma.f64): one
    instruction where the CPU has FMA, else libm's fma; exact either way, so the same bits."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        return builder.fma(*args)

    return sig, codegen


#: ``_fma(a, b, c)`` in compiled code only (numba passes the typing context itself).
_fma: Any = intrinsic(_fma_intrinsic)


@overload(two_product)
def _two_product_fma(a, b):  # type: ignore[no-untyped-def]  # numba matches the signature, annotations included
    """The compiled two_product: the FMA gives the exact rounding error of a b."""

    def impl(a, b):  # type: ignore[no-untyped-def]
        x = float(a)
        y = float(b)
        p = x * y
        return p, _fma(x, y, -p)

    return impl


@register_jitable
def dd_add(ah: float, al: float, bh: float, bl: float) -> tuple[float, float]:
    """(ah + al) + (bh + bl) as a double-double."""
    s, e = two_sum(ah, bh)
    t, f = two_sum(al, bl)
    s, e = fast_two_sum(s, e + t)
    return fast_two_sum(s, e + f)


@register_jitable
def dd_add_same_sign(ah: float, al: float, bh: float, bl: float) -> tuple[float, float]:
    """(ah + al) + (bh + bl) as a double-double where the two have the same sign (no cancellation, so
    the low parts may be added first: a few units of 1e-32 relative, cheaper than :func:`dd_add`)."""
    s, e = two_sum(ah, bh)
    return fast_two_sum(s, e + (al + bl))


@register_jitable
def dd_add_d(ah: float, al: float, b: float) -> tuple[float, float]:
    """(ah + al) + b (a double) as a double-double."""
    s, e = two_sum(ah, b)
    return fast_two_sum(s, e + al)


@register_jitable
def dd_mul(ah: float, al: float, bh: float, bl: float) -> tuple[float, float]:
    """(ah + al) (bh + bl) as a double-double."""
    p, e = two_product(ah, bh)
    return fast_two_sum(p, e + (ah * bl + al * bh))


@register_jitable
def dd_div(ah: float, al: float, bh: float, bl: float) -> tuple[float, float]:
    """(ah + al) / (bh + bl) as a double-double."""
    q1 = ah / bh
    ph, pl = dd_mul(q1, 0.0, bh, bl)
    rh, rl = dd_add(ah, al, -ph, -pl)
    q2 = rh / bh
    ph, pl = dd_mul(q2, 0.0, bh, bl)
    rh, rl = dd_add(rh, rl, -ph, -pl)
    q1, q2 = fast_two_sum(q1, q2)
    return dd_add(q1, q2, rh / bh, 0.0)


@register_jitable
def dd_sqrt(ah: float, al: float) -> tuple[float, float]:
    """sqrt(ah + al) as a double-double (ah + al >= 0)."""
    if ah <= 0.0:
        return 0.0, 0.0
    s = math.sqrt(ah)
    p, e = two_product(s, s)
    return fast_two_sum(s, ((ah - p) - e + al) / (2.0 * s))


@register_jitable
def dd_rsqrt(ah: float, al: float) -> tuple[float, float]:
    """1 / sqrt(ah + al) as a double-double (ah + al > 0): one Newton step from the double
    y = 1 / sqrt(ah), y (1 - r / 2) with r = (ah + al) y^2 - 1 from error-free products."""
    y = 1.0 / math.sqrt(ah)
    p, pe = two_product(y, y)
    t, te = two_product(ah, p)
    r = ((t - 1.0) + te) + (ah * pe + al * p)  # t - 1 is exact: t is within ulps of 1
    return fast_two_sum(y, -0.5 * y * r)


@register_jitable
def dd_sin_cos(h: float, lo: float) -> tuple[float, float]:
    """sin and cos of the angle h + lo (rad), |lo| <= ulp(h): first order in lo is exact to rounding."""
    s, c = math.sin(h), math.cos(h)
    return s + c * lo, c - s * lo


def _sin_cos_table(steps: int = 27, bits: int = 200) -> FloatArray:
    """Rows (sin hi, sin lo, cos hi, cos lo) of k / 32, k = 0..steps - 1, each correctly rounded to a
    double-double: the Taylor series in exact integer fixed point (bits fraction bits)."""
    one = 1 << bits
    rows = []
    for k in range(steps):
        x = k << (bits - 5)
        sums = []
        for term in (x, one):  # sin, cos
            total, order = term, 1 if term == x else 0
            while term:
                term = -((term * x >> bits) * x >> bits) // ((order + 1) * (order + 2))
                total += term
                order += 2
            exact = Fraction(total, one)
            hi = float(exact)
            sums += [hi, float(exact - Fraction(hi))]
        rows.append(sums)
    return np.array(rows)


#: sin and cos of k / 32 (k = 0..26, up to pi / 4 + 1 / 64) as double-doubles, for :func:`dd_sin_cos_dd`.
_SIN_COS_TABLE = _sin_cos_table()
#: pi / 2 as a double-double.
HALF_PI_DD = (0.5 * PI_DD[0], 0.5 * PI_DD[1])


@register_jitable
def dd_sin_cos_dd(h: float, lo: float) -> tuple[float, float, float, float]:
    """sin and cos of the angle h + lo (rad, |h| <= ~1e9) as double-doubles (sin_h, sin_l, cos_h, cos_l).

    The angle is reduced by pi / 2 in double-double to |b| <= pi / 4, then to r = |b| - k / 32 (|r| <= 1 / 64,
    exact), and ``sin(k / 32 + r)`` is formed from the double-double table of k / 32 and the Taylor series
    of r (to r^8: 1e-21); within ~3e-20 of the exact values for |h| <= 2 pi (r^2 is rounded)."""
    quadrant = float(math.floor(h * (1.0 / HALF_PI_DD[0]) + 0.5))
    ph, pl = two_product(quadrant, HALF_PI_DD[0])
    bh, bl = two_sum(h, -ph)
    bh, bl = fast_two_sum(bh, (bl + lo) - (pl + quadrant * HALF_PI_DD[1]))
    negative = bh < 0.0
    if negative:
        bh, bl = -bh, -bl
    k = min(int(bh * 32.0 + 0.5), _SIN_COS_TABLE.shape[0] - 1)
    rh, rl = fast_two_sum(bh - k / 32.0, bl)  # bh - k / 32 is exact (Sterbenz)
    r2 = rh * rh
    sin_r = fast_two_sum(rh, rl + rh * r2 * (-1.0 / 6.0 + r2 * (1.0 / 120.0 - r2 / 5040.0)))
    cos_m1 = r2 * (-0.5 + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0 + r2 / 40320.0)))
    row = _SIN_COS_TABLE[k]
    t = dd_mul(row[2], row[3], *sin_r)
    sh, sl = dd_add(row[0], row[1], *t)
    sh, sl = fast_two_sum(sh, sl + row[0] * cos_m1)
    t = dd_mul(row[0], row[1], *sin_r)
    ch, cl = dd_add(row[2], row[3], -t[0], -t[1])
    ch, cl = fast_two_sum(ch, cl + row[2] * cos_m1)
    if negative:
        sh, sl = -sh, -sl
    turn = int(quadrant) & 3  # quadrant mod 4, negative quadrants included
    if turn == 1:
        return ch, cl, -sh, -sl
    if turn == 2:
        return -sh, -sl, -ch, -cl
    if turn == 3:
        return -ch, -cl, sh, sl
    return sh, sl, ch, cl


@register_jitable
def dd_reduce(h: float, lo: float, period_h: float, period_l: float) -> tuple[float, float]:
    """(h + lo) - k period, k the nearest integer to (h + lo) / period: a double-double in
    [-period / 2, period / 2] (period > 0 a double-double)."""
    k = math.floor(h * (1.0 / period_h) + 0.5)  # k may be off by one at a tie: either is a reduction
    ph, pl = two_product(k, period_h)
    s, e = two_sum(h, -ph)
    return fast_two_sum(s, ((e + lo) - pl) - k * period_l)


@register_jitable
def dd_complete_integrals(m1h: float, m1l: float, nh: float, nl: float) -> tuple[float, float, float, float]:
    """Double-double K(m) and Pi(n|m) - K(m) for 1 - m = m1h + m1l in (0, 1] and n = nh + nl < 1
    (:func:`dd_complete_integrals_kp` with k' = sqrt(1 - m))."""
    kp = dd_sqrt(m1h, m1l)
    root = dd_sqrt(*kp)
    return dd_complete_integrals_kp(kp[0], kp[1], root[0], root[1], nh, nl)


@register_jitable
def dd_complete_integrals_kp(
    kh: float, kl: float, rh: float, rl: float, nh: float, nl: float
) -> tuple[float, float, float, float]:
    """Double-double K(m) and Pi(n|m) - K(m) from k' = sqrt(1 - m) = kh + kl in (0, 1] and its square root
    rh + rl (both passed, so that k' may be as small as the caller can scale it: next to the middle axis
    1 - m underflows while k' and sqrt(k') do not), and n = nh + nl < 1.

    DLMF 19.8.6 (the AGM of 1 and k' with its companion sequence p_j):
    ``Pi(n|m) = pi / (4 M) (2 + n / (1 - n) sum_j Q_j)``, so ``Pi - K = pi / (4 M) n / (1 - n)
    sum_j Q_j`` without a cancellation; every step is +, *, / or sqrt in double-double. The first
    geometric mean sqrt(1 k') is the root passed.
    """
    ah, al = 1.0, 0.0
    gh, gl = kh, kl
    first = True
    p2h, p2l = dd_add(1.0, 0.0, -nh, -nl)  # p_0^2 = 1 - n
    ph, pl = dd_sqrt(p2h, p2l)
    qh, ql = 1.0, 0.0
    sh, sl = 1.0, 0.0  # sum of Q_j
    for _ in range(AGM_LEVELS):
        agh, agl = dd_mul(ah, al, gh, gl)
        num_h, num_l = dd_add(p2h, p2l, agh, agl)
        den_h, den_l = dd_add(p2h, p2l, -agh, -agl)
        eh, el = dd_div(den_h, den_l, num_h, num_l)  # epsilon_j
        ph, pl = dd_div(num_h, num_l, 2.0 * ph, 2.0 * pl)  # p_{j+1}
        p2h, p2l = dd_mul(ph, pl, ph, pl)
        qh, ql = dd_mul(qh, ql, 0.5 * eh, 0.5 * el)
        sh, sl = dd_add(sh, sl, qh, ql)
        gap = abs((ah - gh) + (al - gl))
        sum_h, sum_l = dd_add(ah, al, gh, gl)
        if first:
            gh, gl = rh, rl
            first = False
        else:
            gh, gl = dd_sqrt(*dd_mul(ah, al, gh, gl))
        ah, al = 0.5 * sum_h, 0.5 * sum_l
        # quadratic convergence: once a - g <= 1e-17 a, the new a is within ~1e-35 of M
        # (and Q_j falls as fast); a tighter test on a - g would wait on rounding
        if gap <= 1e-17 * ah and abs(qh) <= 1e-33 * abs(sh):
            break
    kh, kl = dd_div(PI_DD[0], PI_DD[1], 2.0 * ah, 2.0 * al)
    rh, rl = dd_div(nh, nl, *dd_add(1.0, 0.0, -nh, -nl))
    xh, xl = dd_mul(*dd_mul(kh, kl, 0.5 * rh, 0.5 * rl), sh, sl)
    return kh, kl, xh, xl


@register_jitable
def carlson_rf(x: float, y: float, z: float) -> float:
    """R_F(x, y, z) for x, y, z >= 0, at most one of them zero (NaN for a non-finite argument)."""
    if not math.isfinite(x + y + z):
        return math.nan  # the duplication below would never converge
    xt, yt, zt = x, y, z
    while True:
        sx, sy, sz = math.sqrt(xt), math.sqrt(yt), math.sqrt(zt)
        lam = sx * (sy + sz) + sy * sz
        xt, yt, zt = 0.25 * (xt + lam), 0.25 * (yt + lam), 0.25 * (zt + lam)
        ave = (xt + yt + zt) / 3.0
        dx, dy, dz = (ave - xt) / ave, (ave - yt) / ave, (ave - zt) / ave
        if max(abs(dx), abs(dy), abs(dz)) <= 0.0025:
            break
    e2 = dx * dy - dz * dz
    e3 = dx * dy * dz
    return (1.0 + (e2 / 24.0 - 0.1 - 3.0 / 44.0 * e3) * e2 + e3 / 14.0) / math.sqrt(ave)


#: binom(2k, k) / (4^k (2k + 1)), k = 1..16: for 0 <= x <= y, R_C(x, y) = asin(sqrt(s)) / sqrt(s y) with
#: s = 1 - x / y (DLMF 19.2.18), and asin(z) / z = sum_k binom(2k, k) / (4^k (2k + 1)) z^(2k); at s <= 0.1
#: the terms beyond k = 16 are below 1e-19 (relative). The same series holds for x > y (s < 0).
_RC_SERIES = np.array([math.comb(2 * k, k) / (4**k * (2 * k + 1)) for k in range(1, 17)])
_RC_SERIES_S = 0.1
#: |s| below which carlson_rc sums the series directly.
_RC_SHORT_S = 0.01


@register_jitable
def carlson_rc(x: float, y: float) -> float:
    """R_C(x, y) for x >= 0, y > 0 (NaN for a non-finite argument)."""
    if not math.isfinite(x + y):
        return math.nan  # the duplication below would never converge
    s = (y - x) / y  # y - x is exact where |s| <= 1/2 (Sterbenz)
    if abs(s) <= _RC_SHORT_S:
        # near x = y (every R_C in carlson_rj after its first steps): the series of
        # :data:`_RC_SERIES` to s^8 (the rest below 2e-18 relative) instead of a duplication
        c = _RC_SERIES
        s2 = s * s
        poly = ((c[0] + c[1] * s) + s2 * (c[2] + c[3] * s)) + (s2 * s2) * ((c[4] + c[5] * s) + s2 * (c[6] + c[7] * s))
        return float((1.0 + s * poly) / math.sqrt(y))
    xt, yt = x, y
    while True:
        lam = 2.0 * math.sqrt(xt) * math.sqrt(yt) + yt
        xt, yt = 0.25 * (xt + lam), 0.25 * (yt + lam)
        ave = (xt + yt + yt) / 3.0
        s = (yt - ave) / ave
        if abs(s) <= 0.0012:
            break
    return (1.0 + s * s * (0.3 + s * (1.0 / 7.0 + s * (0.375 + s * 9.0 / 22.0)))) / math.sqrt(ave)


@register_jitable
def carlson_rj(x: float, y: float, z: float, p: float) -> float:
    """R_J(x, y, z, p) for x, y, z >= 0 (at most one zero) and p > 0 (NaN for a non-finite argument)."""
    if not math.isfinite(x + y + z + p):
        return math.nan  # the duplication below would never converge
    c1, c2, c3, c4 = 3.0 / 14.0, 1.0 / 3.0, 3.0 / 22.0, 3.0 / 26.0
    c5, c6, c7, c8 = 0.75 * c3, 1.5 * c4, 0.5 * c2, c3 + c3
    total = 0.0
    fac = 1.0
    xt, yt, zt, pt = x, y, z, p
    while True:
        sx, sy, sz = math.sqrt(xt), math.sqrt(yt), math.sqrt(zt)
        lam = sx * (sy + sz) + sy * sz
        alpha = pt * (sx + sy + sz) + sx * sy * sz
        alpha *= alpha
        beta = pt * (pt + lam) * (pt + lam)
        total += fac * carlson_rc(alpha, beta)
        fac *= 0.25
        xt, yt, zt, pt = 0.25 * (xt + lam), 0.25 * (yt + lam), 0.25 * (zt + lam), 0.25 * (pt + lam)
        ave = 0.2 * (xt + yt + zt + pt + pt)
        inv = 1.0 / ave
        dx, dy, dz, dp = (ave - xt) * inv, (ave - yt) * inv, (ave - zt) * inv, (ave - pt) * inv
        if max(abs(dx), abs(dy), abs(dz), abs(dp)) <= 0.0015:
            break
    ea = dx * (dy + dz) + dy * dz
    eb = dx * dy * dz
    ec = dp * dp
    ed = ea - 3.0 * ec
    ee = eb + 2.0 * dp * (ea - ec)
    series = 1.0 + ed * (-c1 + c5 * ed - c6 * ee) + eb * (c7 + dp * (-c8 + dp * c4)) + dp * ea * (c2 - dp * c3)
    series -= c2 * dp * ec
    return 3.0 * total + fac * series / (ave * math.sqrt(ave))


@register_jitable
def _estrin16(c: FloatArray, x: float) -> float:
    """sum_k c[k] x^k for k < 16 by Estrin's scheme (short dependency chains)."""
    x2 = x * x
    x4 = x2 * x2
    x8 = x4 * x4
    a = (c[0] + c[1] * x) + x2 * (c[2] + c[3] * x)
    b = (c[4] + c[5] * x) + x2 * (c[6] + c[7] * x)
    d = (c[8] + c[9] * x) + x2 * (c[10] + c[11] * x)
    e = (c[12] + c[13] * x) + x2 * (c[14] + c[15] * x)
    return float((a + x4 * b) + x8 * (d + x4 * e))


@register_jitable
def carlson_rc_dd(xh: float, xl: float, yh: float, yl: float) -> tuple[float, float]:
    """R_C(x, y) as a double-double for 0 <= x <= y (double-doubles): duplication steps in double-double
    (R_C(x, y) = R_C((x + l) / 4, (y + l) / 4), l = 2 sqrt(x y) + y, which divide y - x by 4 and keep it
    exact) until s = 1 - x / y <= 0.1, then the series in s in double (it is 1 + O(s))."""
    dh, dl = dd_add(yh, yl, -xh, -xl)
    while dh > _RC_SERIES_S * yh:
        root = dd_sqrt(*dd_mul(xh, xl, yh, yl))
        lam = dd_add_same_sign(2.0 * root[0], 2.0 * root[1], yh, yl)
        yh, yl = dd_add_same_sign(yh, yl, *lam)
        yh, yl, dh, dl = 0.25 * yh, 0.25 * yl, 0.25 * dh, 0.25 * dl
        xh, xl = dd_add(yh, yl, -dh, -dl)
    ratio = dh / yh
    series = _estrin16(_RC_SERIES, ratio) * ratio
    rh, rl = dd_rsqrt(yh, yl)
    return fast_two_sum(rh, rl + rh * series)


@register_jitable
def _rj_step_dd(
    x: DoubleDouble,
    y: DoubleDouble,
    z: DoubleDouble,
    p: DoubleDouble,
    sx: DoubleDouble,
    sy: DoubleDouble,
    sz: DoubleDouble,
) -> tuple[DoubleDouble, DoubleDouble, DoubleDouble, DoubleDouble, DoubleDouble]:
    """One duplication step of R_J in double-double, for p >= x, y, z (double-doubles, with the square
    roots sx, sy, sz of x, y, z): ``R_J(x, y, z, p) = 3 R_C(alpha, beta) + R_J(x', y', z', p') / 4`` with
    x' = (x + lam) / 4 and so on (Carlson 1995); returns R_C(alpha, beta) and (x', y', z', p')."""
    lam = dd_add_same_sign(*dd_mul(*sx, *dd_add_same_sign(*sy, *sz)), *dd_mul(*sy, *sz))
    total = dd_add_same_sign(*dd_add_same_sign(*sx, *sy), *sz)
    root = dd_add_same_sign(*dd_mul(*p, *total), *dd_mul(*dd_mul(*sx, *sy), *sz))
    shifted = dd_add_same_sign(*p, *lam)
    rc = carlson_rc_dd(*dd_mul(*root, *root), *dd_mul(*p, *dd_mul(*shifted, *shifted)))  # alpha <= beta
    x = dd_add_same_sign(*x, *lam)
    y = dd_add_same_sign(*y, *lam)
    z = dd_add_same_sign(*z, *lam)
    return (
        rc,
        (0.25 * x[0], 0.25 * x[1]),
        (0.25 * y[0], 0.25 * y[1]),
        (0.25 * z[0], 0.25 * z[1]),
        (0.25 * shifted[0], 0.25 * shifted[1]),
    )


#: third_kind_excess_dd takes up to three more duplication steps in double-double while x < _SPREAD_X_P p.
_SPREAD_X_P = 0.5


@register_jitable
def third_kind_excess_dd(
    sn: tuple[float, float], cn: tuple[float, float], dn: tuple[float, float], nh: float, nl: float
) -> tuple[float, float]:
    """``Pi(n; phi | m) - F(phi | m) = (n / 3) sn^3 R_J(cn^2, dn^2, 1, 1 - n sn^2)`` as a double-double, for
    sn, cn, dn of the amplitude phi (|phi| <= pi / 2; double-doubles) and n = nh + nl < 1.

    R_J's first duplication step carries most of it (3 R_C(alpha, beta)) and is formed in double-double
    (:func:`_rj_step_dd`, :func:`carlson_rc_dd`) from the roots |cn|, dn, 1 at hand; where x stays small
    against p (cn near 0), the remainder R_J(x', y', z', p') / 4 is still a large share with its arguments
    far apart, and up to three more steps follow. Only the last remainder (1/4 to 1/256 of R_J at the
    duplicated arguments) comes in double (:func:`carlson_rj`): within ~0.35 ulp of the largest value."""
    s2 = dd_mul(*sn, *sn)
    ns2 = dd_mul(nh, nl, *s2)
    p = dd_add(1.0, 0.0, -ns2[0], -ns2[1])  # 1 - n sn^2 >= 1 >= cn^2, dn^2
    c = (abs(cn[0]), math.copysign(1.0, cn[0]) * cn[1])
    one = (1.0, 0.0)
    rc, x, y, z, p = _rj_step_dd(dd_mul(*c, *c), dd_mul(*dn, *dn), one, p, c, dn, one)
    rj = dd_mul(3.0, 0.0, *rc)  # 3 rc_hi is not exact
    weight = 0.25
    while x[0] < _SPREAD_X_P * p[0] and weight > 0.01:
        # a small x (cn^2 near 0) leaves the remainder R_J(x, y, z, p) a large share of the whole, and
        # its arguments far apart, where carlson_rj is least accurate: one more step in double-double
        rc, x, y, z, p = _rj_step_dd(x, y, z, p, dd_sqrt(*x), dd_sqrt(*y), dd_sqrt(*z))
        rj = dd_add_same_sign(*rj, *dd_mul(3.0 * weight, 0.0, *rc))
        weight *= 0.25
    rj = dd_add_d(*rj, weight * carlson_rj(x[0], y[0], z[0], p[0]))
    prefactor = dd_mul(*dd_mul(nh, nl, *THIRD_DD), *dd_mul(*s2, *sn))
    return dd_mul(*prefactor, *rj)


@register_jitable
def agm_tables(m: float, m1: float, a: FloatArray, c: FloatArray) -> int:
    """Fill the tables with the descending AGM of (1, sqrt(1 - m)) (:func:`agm_tables_kp`); returns L.
    ``m1`` = 1 - m is passed exactly."""
    kp = math.sqrt(m1)
    return agm_tables_kp(m, kp, math.sqrt(kp), a, c)


@register_jitable
def agm_tables_kp(m: float, kp: float, root_kp: float, a: FloatArray, c: FloatArray) -> int:
    """Fill a[0..L] (a_i), a[AGM_LEVELS..AGM_LEVELS + L] (b_i) and c[0..L] with the descending AGM of
    (1, k'), k' = sqrt(1 - m), given with its square root (the first geometric mean, passed so that the
    caller can form it from a scaled k' next to the middle axis); returns L.

    ``c_{i+1} = c_i^2 / (4 a_{i+1})`` avoids the subtraction (a_i - b_i) / 2; the b_i are kept for the
    descent (a_i^2 - b_i^2 = c_i^2, see :func:`jacobi_amplitude_dd`).
    """
    a[0] = 1.0
    c[0] = math.sqrt(m)
    b = kp
    a[AGM_LEVELS] = b
    levels = 0
    while abs(c[levels]) > _EPS * a[levels] and levels + 1 < AGM_LEVELS:
        a_next = 0.5 * (a[levels] + b)
        c[levels + 1] = c[levels] * c[levels] / (4.0 * a_next)
        b = root_kp if levels == 0 else math.sqrt(a[levels] * b)
        a[levels + 1] = a_next
        a[AGM_LEVELS + levels + 1] = b
        levels += 1
    return levels


#: Up to this c_i / a_i the descent takes asin directly (cheaper; the atan2 form is for m near 1).
_DESCENT_ASIN = 0.875


@register_jitable
def _descent_term(c_i: float, a_i: float, b_i: float, ph: float, pl: float) -> float:
    """asin(c_i sin(phi) / a_i) for phi = ph + pl, the term of one step of the descent (A&S 16.4). Where
    c_i / a_i is near 1 (m near 1: the separatrix, the middle axis) as the angle
    atan2(c_i sin phi, sqrt(a_i^2 cos^2 phi + b_i^2 sin^2 phi)): with a_i^2 - c_i^2 = b_i^2 the cosine has
    no cancellation, where asin of an argument near 1 would lose half the digits (sin and cos of phi then
    take pl to first order, :func:`dd_sin_cos`)."""
    if c_i <= _DESCENT_ASIN * a_i:  # asin's argument at most 7/8: its derivative below 2.1, no digits lost
        return math.asin(c_i * math.sin(ph) / a_i)
    sin_phi, cos_phi = dd_sin_cos(ph, pl)
    x, y = a_i * cos_phi, b_i * sin_phi  # both below 1 in size: no overflow in the squares
    return math.atan2(c_i * sin_phi, math.sqrt(x * x + y * y))


@register_jitable
def jacobi(r: float, a: FloatArray, c: FloatArray, levels: int, m1: float) -> tuple[float, float, float]:
    """sn, cn, dn of r (|r| <= K) from the AGM tables (Abramowitz & Stegun 16.4)."""
    phi = (2.0**levels * a[levels]) * r
    for i in range(levels, 0, -1):
        phi = 0.5 * (phi + _descent_term(c[i], a[i], a[AGM_LEVELS + i], phi, 0.0))
    sn = math.sin(phi)
    cn = math.cos(phi)
    return sn, cn, math.sqrt(cn * cn + m1 * sn * sn)


@register_jitable
def jacobi_amplitude_dd(
    rh: float, rl: float, a: FloatArray, c: FloatArray, levels: int, top_h: float, top_l: float
) -> tuple[float, float]:
    """The amplitude am(r) of r = rh + rl (|r| <= K) as a double-double, from the AGM tables:
    phi_N = 2^N a_N r from a_N = top_h + top_l (a double-double of the AGM limit), and each
    descent phi_{i-1} = (phi_i + asin(c_i sin(phi_i) / a_i)) / 2 (A&S 16.4) adds a bounded term
    to it, so the amplitude keeps the digits of r instead of a few ulps of it. The term is formed as an
    atan2 from sin and cos of phi_i (:func:`_descent_term`), which stays accurate where the asin
    argument nears 1 (m near 1): the term is within a few ulps of 1 (absolute), halved i times on the way
    down."""
    scale = 2.0**levels
    ph, pl = dd_mul(top_h, top_l, rh, rl)
    ph, pl = scale * ph, scale * pl
    for i in range(levels, 0, -1):
        ph, pl = dd_add_d(ph, pl, _descent_term(c[i], a[i], a[AGM_LEVELS + i], ph, pl))
        ph, pl = 0.5 * ph, 0.5 * pl
    return ph, pl


@register_jitable
def jacobi_dd(
    rh: float, rl: float, a: FloatArray, c: FloatArray, levels: int, m1h: float, m1l: float, top_h: float, top_l: float
) -> tuple[tuple[float, float], tuple[float, float], tuple[float, float]]:
    """sn, cn, dn of r = rh + rl (|r| <= K) as double-doubles, from :func:`jacobi_amplitude_dd` and
    :func:`dd_sin_cos_dd` (1 - m = m1h + m1l, dn = sqrt(cn^2 + (1 - m) sn^2))."""
    sh, sl, ch, cl = dd_sin_cos_dd(*jacobi_amplitude_dd(rh, rl, a, c, levels, top_h, top_l))
    dn2 = dd_add(*dd_mul(ch, cl, ch, cl), *dd_mul(m1h, m1l, *dd_mul(sh, sl, sh, sl)))
    return (sh, sl), (ch, cl), dd_sqrt(*dn2)


def agm_buffers() -> tuple[FloatArray, FloatArray]:
    """Zeroed (a, c) arrays for :func:`agm_tables`."""
    return np.zeros(AGM_SIZE), np.zeros(AGM_SIZE)
