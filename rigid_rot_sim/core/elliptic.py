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

import numpy as np
from numba.extending import register_jitable

from rigid_rot_sim.core.validation import FloatArray

_EPS = 2.220446049250313e-16
#: Most AGM levels kept (the AGM converges quadratically: 40 is never reached for m < 1).
AGM_LEVELS = 40


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


@register_jitable
def carlson_rc(x: float, y: float) -> float:
    """R_C(x, y) for x >= 0, y > 0 (NaN for a non-finite argument)."""
    if not math.isfinite(x + y):
        return math.nan  # the duplication below would never converge
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
        dx, dy, dz, dp = (ave - xt) / ave, (ave - yt) / ave, (ave - zt) / ave, (ave - pt) / ave
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
def agm_tables(m: float, m1: float, a: FloatArray, c: FloatArray) -> int:
    """Fill a[0..L], c[0..L] with the descending AGM of (1, sqrt(1 - m)); returns L.

    ``m1`` = 1 - m is passed exactly; ``c_{i+1} = c_i^2 / (4 a_{i+1})`` avoids the
    subtraction (a_i - b_i) / 2.
    """
    a[0] = 1.0
    c[0] = math.sqrt(m)
    b = math.sqrt(m1)
    levels = 0
    while abs(c[levels]) > _EPS * a[levels] and levels + 1 < AGM_LEVELS:
        a_next = 0.5 * (a[levels] + b)
        c[levels + 1] = c[levels] * c[levels] / (4.0 * a_next)
        b = math.sqrt(a[levels] * b)
        a[levels + 1] = a_next
        levels += 1
    return levels


@register_jitable
def jacobi(r: float, a: FloatArray, c: FloatArray, levels: int, m1: float) -> tuple[float, float, float]:
    """sn, cn, dn of r (|r| <= K) from the AGM tables (Abramowitz & Stegun 16.4)."""
    phi = (2.0**levels * a[levels]) * r
    for i in range(levels, 0, -1):
        phi = 0.5 * (phi + math.asin(c[i] * math.sin(phi) / a[i]))
    sn = math.sin(phi)
    cn = math.cos(phi)
    return sn, cn, math.sqrt(cn * cn + m1 * sn * sn)


def agm_buffers() -> tuple[FloatArray, FloatArray]:
    """Zeroed (a, c) arrays for :func:`agm_tables`."""
    return np.zeros(AGM_LEVELS), np.zeros(AGM_LEVELS)
