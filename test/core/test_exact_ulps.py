"""The exact flow against a 40-digit mpmath reference, in ulps of the correctly rounded value.

The reference (test/core/mp_reference.py) is the textbook solution evaluated with mpmath's
Jacobi functions and elliptic integrals, checked here against Euler's equations and the
attitude kinematics. The cases follow Principia's Euler-solver tests: rotation about each
principal axis, close to the third axis, a near-sphere, the general case, each over >= 100 rad.

Metric: for a component x with reference value r, the error |x - r| in units of
ulp(r) where 4 ulp(r) >= 1e-16 (|r| >= 1/8 of the scale), else in units of 2.5e-17 * scale
(near a zero crossing 4 units are 1e-16 absolute); scale is 1 for q and |omega| for omega.

Issue 21 asks for 4 units on every component, and that is the bound held here. Measured (101 times
per case, the __main__ below, and at 2 x 100 random times; 25 times in the tests): omega <= 2.0 on
every case; q <= 0.5 on the spins about a principal axis (a uniform rotation, the product
q0 (x) exp(tau omega) compensated with the factor a double-double, issue 29; 3.4 before) and 0.6 to
2.6 on the triaxial cases (general_scaled the largest), where the flow before the double-double phase
was at up to 570 (omega) and 1222 (q), and before the
double-double precession and half angles at up to 13.2 (q). What is left is the rounding of the
remainder of R_J in double (1/4 to 1/256 of it, see third_kind_excess_dd) and of the final components.
"""

from __future__ import annotations

import math
import sys

import mpmath  # pinned in the Makefile's TEST_PINS
import numpy as np
import pytest
from mp_reference import Reference, ode_residual  # test/core, on sys.path under pytest

from rigid_rot_sim.core.exact import torque_free_solution

Q0 = (0.5, -0.5, 0.5, 0.5)  # exactly unit, not the identity
# name: (moments, omega0, t_end); |omega| t_end >= 100 rad
CASES = {
    "about_axis_1": ((1.0, 2.0, 3.0), (1.25, 0.0, 0.0), 100.0),
    "about_axis_2": ((1.0, 2.0, 3.0), (0.0, 1.25, 0.0), 100.0),
    "about_axis_3": ((1.0, 2.0, 3.0), (0.0, 0.0, 1.25), 100.0),
    "near_axis_3": ((1.0, 2.0, 3.0), (1e-3, -2e-3, 1.25), 100.0),
    "near_axis_1": ((3.0, 5.0, 7.0), (1.0, 1e-4, 3e-4), 100.0),
    "near_sphere": ((1.0, 1.0 + 1e-3, 1.0 + 2.5e-3), (0.6, 0.7, 0.8), 100.0),
    "general_above": ((1.0, 2.0, 3.0), (0.3, 0.5, 1.0), 100.0),
    "general_below": ((3.0, 2.0, 1.0), (1.0, 0.1, 0.5), 100.0),
    "general_scaled": ((0.7, 0.9, 1.3), (0.9, -0.8, 0.4), 100.0),
}
BOUND_OMEGA = 4.0  # the target
BOUND_Q_PRINCIPAL = 1.0  # on the spins about a principal axis (0.49 reached: the factor rounded once, issue 29)
BOUND_Q = 4.0  # the target, on the triaxial cases (2.6 reached)
PRINCIPAL = ("about_axis_1", "about_axis_2", "about_axis_3")
SAMPLES = 24


def _scaled_errors(values, reference, scale):
    """Errors in the units of the module docstring (against the mpf reference itself)."""
    out = []
    for x, r in zip(values, reference, strict=True):
        error = float(abs(mpmath.mpf(float(x)) - r))
        rounded = float(r)
        unit = math.ulp(rounded) if abs(rounded) >= 0.125 * scale else 2.5e-17 * scale
        out.append(error / unit)
    return out


def max_errors(name: str, samples: int = SAMPLES) -> dict[str, float]:
    """Largest scaled error of q and of omega over the case's times."""
    moments, omega0, t_end = CASES[name]
    ref = Reference(moments, omega0, Q0)
    sol = torque_free_solution(moments, omega0, Q0)
    times = np.linspace(0.0, t_end, samples + 1)
    q_ours, w_ours = sol.state(times)
    scale = float(np.linalg.norm(omega0))
    worst_q = worst_w = 0.0
    for k, t in enumerate(times):
        q_ref, w_ref = ref.state(float(t))
        sign = 1.0 if sum(float(a) * b for a, b in zip(q_ref, q_ours[k], strict=True)) >= 0.0 else -1.0
        worst_q = max(worst_q, *_scaled_errors(sign * q_ours[k], q_ref, 1.0))
        worst_w = max(worst_w, *_scaled_errors(w_ours[k], w_ref, scale))
    return {"q": worst_q, "omega": worst_w}


@pytest.mark.parametrize("name", ["near_axis_3", "general_above", "general_below", "near_sphere"])
def test_reference_satisfies_the_equations_of_motion(name):
    moments, omega0, t_end = CASES[name]
    ref = Reference(moments, omega0, Q0)
    for t in (0.7, 0.61 * t_end):
        assert ode_residual(ref, t) < 1e-19
    q, w = ref.state(0.0)
    assert max(abs(float(a) - b) for a, b in zip(w, omega0, strict=True)) == 0.0
    assert min(max(abs(sign * a - b) for a, b in zip(q, Q0, strict=True)) for sign in (1, -1)) < 1e-30  # q ~ -q


@pytest.mark.parametrize("name", sorted(CASES))
def test_within_a_few_ulps_over_100_rad(name):
    errors = max_errors(name)
    bound_q = BOUND_Q_PRINCIPAL if name in PRINCIPAL else BOUND_Q
    assert errors["q"] <= bound_q and errors["omega"] <= BOUND_OMEGA, errors


@pytest.mark.parametrize("m, n", [(0.3, -0.5), (0.9, -3.0), (1e-6, -0.2), (0.999999, -1.5), (0.5, -40.0)])
def test_double_double_complete_integrals(m, n):
    """K(m) and Pi(n|m) - K(m) (DLMF 19.8.6 in double-double) to ~1e-31 relative."""
    from rigid_rot_sim.core.elliptic import dd_complete_integrals

    k_h, k_l, x_h, x_l = dd_complete_integrals(1.0 - m, 0.0, n, 0.0)
    with mpmath.workdps(40):
        m_exact = 1 - mpmath.mpf(1.0 - m)
        k = mpmath.ellipk(m_exact)
        excess = mpmath.ellippi(n, m_exact) - k
        assert abs((k_h + mpmath.mpf(k_l) - k) / k) < 1e-31
        assert abs((x_h + mpmath.mpf(x_l) - excess) / excess) < 1e-31


def _dd_value(pair):
    return mpmath.mpf(pair[0]) + mpmath.mpf(pair[1])


def test_double_double_sin_cos():
    """dd_sin_cos_dd to ~3e-20 over four turns (both signs, low parts included)."""
    from rigid_rot_sim.core.elliptic import dd_sin_cos_dd

    rng = np.random.default_rng(7)
    with mpmath.workdps(40):
        for h in rng.uniform(-4.0 * math.pi, 4.0 * math.pi, 400):
            lo = float(h) * 1e-17 * float(rng.uniform(-1.0, 1.0))
            s_h, s_l, c_h, c_l = dd_sin_cos_dd(float(h), lo)
            angle = mpmath.mpf(float(h)) + lo
            assert abs(_dd_value((s_h, s_l)) - mpmath.sin(angle)) < 1e-19
            assert abs(_dd_value((c_h, c_l)) - mpmath.cos(angle)) < 1e-19


def test_double_double_rc_and_third_kind_excess():
    """carlson_rc_dd to ~1e-17 relative, and Pi(n; phi|m) - F(phi|m) from sn, cn, dn within half an ulp of
    its largest value (0.25-0.35 reached; carlson_rj in double on the whole is at 2-3 ulps)."""
    from rigid_rot_sim.core.elliptic import carlson_rc_dd, third_kind_excess_dd

    rng = np.random.default_rng(8)
    with mpmath.workdps(40):
        for _ in range(200):
            y = float(rng.uniform(0.1, 50.0))
            x = y * float(rng.uniform(0.0, 1.0)) ** 3
            assert abs(_dd_value(carlson_rc_dd(x, 0.0, y, 0.0)) / mpmath.elliprc(x, y) - 1) < 1e-17
        for m, n in ((0.1, -3.0), (0.52, -0.67), (0.84, -1.08), (1e-6, -3.0), (0.5, -40.0)):
            errors, values = [], []
            for phi in np.linspace(-1.5707, 1.5707, 61):
                p = mpmath.mpf(float(phi))
                sn, cn = mpmath.sin(p), mpmath.cos(p)
                dn = mpmath.sqrt(1 - m * sn * sn)
                as_dd = [(float(v), float(v - float(v))) for v in (sn, cn, dn)]
                exact = mpmath.ellippi(n, p, m) - mpmath.ellipf(p, m)
                errors.append(abs(_dd_value(third_kind_excess_dd(*as_dd, n, 0.0)) - exact))
                values.append(abs(exact))
            assert max(errors) <= 0.5 * math.ulp(float(max(values))), (m, n)


if __name__ == "__main__":  # the figures of the report: PYTHONPATH=. python test/core/test_exact_ulps.py
    for case in CASES:
        e = max_errors(case, samples=int(sys.argv[1]) if len(sys.argv) > 1 else 100)
        print(f"{case:16s} q {e['q']:8.2f}  omega {e['omega']:8.2f}")
