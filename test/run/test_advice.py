"""Tests for rigid_rot_sim.run.advice: the bounds against linear theory computed independently."""

import math
import re

import numpy as np
import pytest

from rigid_rot_sim.run import advice


def euler_jacobian(moments, omega):
    """Jacobian of omega' = I^-1 ((I omega) x omega), by central differences."""
    moments = np.asarray(moments, float)

    def rhs(w):
        return np.cross(moments * w, w) / moments

    jac = np.zeros((3, 3))
    h = 1e-6
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        jac[:, k] = (rhs(omega + e) - rhs(omega - e)) / (2 * h)
    return jac


@pytest.mark.parametrize("moments", [(1.0, 2.0, 3.0), (500.0, 200.0, 300.0), (0.00017231, 0.00000658, 0.00017243)])
def test_gyroscopic_frequency_is_max_linearised_rate_about_principal_axes(moments):
    spin = 3.7
    rates = []
    for axis in range(3):
        omega = np.zeros(3)
        omega[axis] = spin
        rates.append(np.max(np.abs(np.linalg.eigvals(euler_jacobian(moments, omega)))))
    assert advice.gyroscopic_frequency(moments, spin) == pytest.approx(max(rates), rel=1e-6)
    assert advice.gyroscopic_frequency(moments, spin) <= spin * (1 + 1e-12)


def test_sphere_has_no_gyroscopic_frequency():
    assert advice.gyroscopic_frequency((2.0, 2.0, 2.0), 100.0) == 0.0
    assert advice.max_stable_dt("rk4", (2.0, 2.0, 2.0), 100.0) == math.inf


def rk4_amplification(z):
    return abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)


def test_rk4_limit_is_edge_of_stability_region_on_imaginary_axis():
    moments, spin = (1.0, 2.0, 3.0), 2.0
    nu = advice.gyroscopic_frequency(moments, spin)
    dt = advice.max_stable_dt("rk4", moments, spin)
    assert rk4_amplification(1j * nu * dt * 0.999) < 1.0
    assert rk4_amplification(1j * nu * dt * 1.001) > 1.0


def test_rk4_warns_above_limit_and_not_well_below():
    moments, spin = (1.0, 2.0, 3.0), 5.0
    limit = advice.max_stable_dt("rk4", moments, spin)
    above = advice.step_warnings("rk4", moments, spin, 1.2 * limit)
    assert any("max stable dt" in w and f"{limit:.3g}" in w for w in above)
    assert advice.step_warnings("rk4", moments, spin, 0.01 * limit) == []


def test_euler_always_warns_for_spinning_asymmetric_body_with_growth_time():
    moments, spin, dt = (1.0, 2.0, 3.0), 1.0, 1e-3
    warnings = advice.step_warnings("euler", moments, spin, dt)
    assert len(warnings) == 1 and "unstable" in warnings[0]
    nu = advice.gyroscopic_frequency(moments, spin)
    # one e-fold of amplitude: (1 + (nu dt)^2)^(n/2) = e
    n = advice.euler_growth_time(moments, spin, dt) / dt
    assert (1 + (nu * dt) ** 2) ** (n / 2) == pytest.approx(math.e, rel=1e-9)


@pytest.mark.parametrize("method", ["implicit_midpoint", "splitting", "exact_split"])
def test_structure_preserving_only_warn_on_rotation_per_step(method):
    moments = (1.0, 2.0, 3.0)
    assert advice.max_stable_dt(method, moments, 10.0) == math.inf
    assert advice.step_warnings(method, moments, 10.0, 0.1) == []
    assert any("rotation per step" in w for w in advice.step_warnings(method, moments, 10.0, 1.0))


def test_exact_and_adaptive_never_warn():
    for method in ("exact", "dop853", "taylor"):
        assert advice.step_warnings(method, (1.0, 2.0, 3.0), 1e3, 10.0) == []


def test_choose_integrator():
    moments = (1.0, 2.0, 3.0)
    assert advice.choose_integrator(moments, 1.0, 0.01, "none") == "exact"
    for kind in advice.TORQUE_KINDS:
        choice = advice.choose_integrator(moments, 50.0, 0.1, kind)
        # whatever is chosen must be stable at this spin rate and step
        assert advice.max_stable_dt(choice, moments, 50.0) >= 0.1


@pytest.mark.parametrize(
    "args, name",
    [
        (((1.0, -2.0, 3.0), 1.0, 0.1, "none"), "principal_moments[1]"),
        (((1.0, 2.0), 1.0, 0.1, "none"), "principal_moments"),
        (((1.0, 2.0, 3.0), float("nan"), 0.1, "none"), "omega_max"),
        (((1.0, 2.0, 3.0), 1.0, 0.0, "none"), "dt"),
        (((1.0, 2.0, 3.0), 1.0, 0.1, "wind"), "torque_kind"),
    ],
)
def test_bad_input_names_argument(args, name):
    with pytest.raises(ValueError, match=re.escape(name)):
        advice.choose_integrator(*args)


def test_implicit_midpoint_warns_beyond_measured_newton_limit():
    moments, spin = (1.0, 2.0, 3.0), 10.0
    nu = advice.gyroscopic_frequency(moments, spin)
    assert any("Newton" in w for w in advice.step_warnings("implicit_midpoint", moments, spin, 1.1 * 4.0 / nu))
    assert not any("Newton" in w for w in advice.step_warnings("implicit_midpoint", moments, spin, 0.9 * 4.0 / nu))
    assert advice.practical_step_limit("implicit_midpoint", moments, spin) == pytest.approx(4.0 / nu)
    assert advice.practical_step_limit("rk4", moments, spin) == advice.max_stable_dt("rk4", moments, spin)
