"""The exact flow against a 40-digit mpmath reference, in ulps of the correctly rounded value.

The reference (test/core/mp_reference.py) is the textbook solution evaluated with mpmath's
Jacobi functions and elliptic integrals, checked here against Euler's equations and the
attitude kinematics. The cases follow Principia's Euler-solver tests: rotation about each
principal axis, close to the third axis, a near-sphere, the general case, each over >= 100 rad.

Metric: for a component x with reference value r, the error |x - r| in units of
ulp(r) where 4 ulp(r) >= 1e-16 (|r| >= 1/8 of the scale), else in units of 2.5e-17 * scale
(near a zero crossing the bound is 1e-16 absolute); scale is 1 for q and |omega| for omega.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

mpmath = pytest.importorskip("mpmath")  # pinned in the Makefile's TEST_PINS

from rigid_rot_sim.core.exact import torque_free_solution  # noqa: E402
from mp_reference import Reference, ode_residual  # noqa: E402

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
BOUND = 4.0
SAMPLES = 24


def _scaled_errors(values, reference, scale):
    """Errors in the units of the module docstring (against the mpf reference itself)."""
    out = []
    for x, r in zip(values, reference):
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
        sign = 1.0 if sum(float(a) * b for a, b in zip(q_ref, q_ours[k])) >= 0.0 else -1.0
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
    assert max(abs(float(a) - b) for a, b in zip(w, omega0)) == 0.0
    assert max(abs(float(a) - b) for a, b in zip(q, Q0)) < 1e-30


@pytest.mark.parametrize("name", sorted(CASES))
def test_within_a_few_ulps_over_100_rad(name):
    errors = max_errors(name)
    assert errors["q"] <= BOUND and errors["omega"] <= BOUND, errors


if __name__ == "__main__":  # the figures of the report: python test/core/test_exact_ulps.py
    for case in CASES:
        e = max_errors(case, samples=100)
        print(f"{case:16s} q {e['q']:8.2f}  omega {e['omega']:8.2f}")
