"""Tests for rigid_rot_sim.core.heavy_top: invariants, turning points, exact references."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.heavy_top import (
    HeavyTop,
    heavy_top_reference,
    separatrix_solution,
    separatrix_state,
)
from rigid_rot_sim.core.integrators import METHODS
from rigid_rot_sim.core.quaternion import quaternion_to_zxz

TOP = HeavyTop(mass=0.5, gravity=9.81, com_distance=0.04, com_moments=(4e-4, 4e-4, 6e-4))
# a tilted, spinning top with some nutation: theta0 = 0.5 rad, theta'0 = 0.3 rad/s
STATE = TOP.state_from_euler(0.5, 0.2, 0.1, 0.3, 5.0, 100.0)


def wrapped(a):
    return np.angle(np.exp(1j * np.asarray(a)))


def test_pivot_moments_by_parallel_axis_theorem():
    m, arm = 0.5, 0.04
    np.testing.assert_allclose(TOP.pivot_moments, [4e-4 + m * arm * arm, 4e-4 + m * arm * arm, 6e-4], rtol=1e-15)
    torque = TOP.torque
    np.testing.assert_array_equal(torque.lever_arm, [0.0, 0.0, arm])
    assert torque.weight == m * 9.81


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(mass=0.0), "mass"),
        (dict(gravity=-9.81), "gravity"),
        (dict(com_distance=math.nan), "com_distance"),
        (dict(com_moments=(4e-4, 5e-4, 6e-4)), r"com_moments\[0\] and com_moments\[1\]"),
        (dict(com_moments=(4e-4, 4e-4, -6e-4)), r"com_moments\[2\]"),
    ],
)
def test_bad_parameters(kwargs, message):
    params = dict(mass=0.5, gravity=9.81, com_distance=0.04, com_moments=(4e-4, 4e-4, 6e-4))
    params.update(kwargs)
    with pytest.raises(ValueError, match=message):
        HeavyTop(**params)


def test_euler_angles_round_trip_and_rates():
    q, omega = TOP.state_from_euler(0.7, -1.2, 2.5, 0.3, 5.0, 100.0)
    phi, theta, psi = quaternion_to_zxz(q)
    np.testing.assert_allclose([phi, theta, psi], [-1.2, 0.7, 2.5], rtol=0, atol=1e-15 * 8)
    # omega from the rates: the body z rate is psi' + phi' cos(theta); p_psi = I3 omega3
    assert omega[2] == pytest.approx(100.0 + 5.0 * math.cos(0.7), rel=1e-15)
    # the same rotation as scipy's intrinsic z-x-z
    assert (Rotation.from_quat(q).inv() * Rotation.from_euler("ZXZ", [-1.2, 0.7, 2.5])).magnitude() < 1e-15 * 8


# (method, options, dt, E rel. tolerance, p_phi rel. tolerance) for 1 s of motion
CONSERVATION = [
    ("rk4", {}, 1e-3, 1e-8, 1e-6),
    ("lie_rk4", {}, 1e-3, 1e-8, 1e-6),
    ("dop853", dict(rtol=1e-12, atol=1e-12), 1e-2, 1e-12, 1e-11),
    ("exact_split", dict(order=4), 5e-3, 1e-7, 1e-13),
]


@pytest.mark.parametrize("method, options, dt, e_tol, p_tol", CONSERVATION)
def test_invariants_conserved(method, options, dt, e_tol, p_tol):
    assert method in METHODS
    q0, omega0 = STATE
    energy, p_phi, p_psi = TOP.invariants(q0, omega0)
    traj = TOP.simulate(q0, omega0, t_end=1.0, dt=dt, method=method, **options)
    assert traj.t[-1] == 1.0
    assert np.max(np.abs(traj.energy / energy - 1.0)) < e_tol
    assert np.max(np.abs(traj.p_phi / p_phi - 1.0)) < p_tol
    # gravity has no torque about the symmetry axis: omega3 is untouched by every method
    assert np.max(np.abs(traj.p_psi / p_psi - 1.0)) < 1e-14


def test_exact_split_keeps_both_momenta_to_rounding():
    """Kicks by gravity (horizontal torque, world) and the exact free flow each keep p_phi and p_psi."""
    q0, omega0 = STATE
    _, p_phi, p_psi = TOP.invariants(q0, omega0)
    traj = TOP.simulate(q0, omega0, t_end=0.5, dt=1e-2, method="exact_split", order=2)
    assert np.max(np.abs(traj.p_phi / p_phi - 1.0)) < 1e-14
    assert np.max(np.abs(traj.p_psi / p_psi - 1.0)) < 1e-14


def test_theta_between_turning_points_and_matches_quadrature_reference():
    q0, omega0 = STATE
    ref = heavy_top_reference(TOP, q0, omega0)
    u1, u2 = ref.turning_points
    assert -1.0 <= u1 < math.cos(0.5) < u2 <= 1.0 < ref.u3
    traj = TOP.simulate(q0, omega0, t_end=1.0, dt=2e-3, method="dop853", rtol=1e-12, atol=1e-12)
    theta_min, theta_max = ref.theta_range
    assert np.all(traj.theta >= theta_min - 1e-10) and np.all(traj.theta <= theta_max + 1e-10)
    # both turning points are reached (about 7 nutation periods in 1 s)
    assert traj.theta.min() < theta_min + 1e-4 and traj.theta.max() > theta_max - 1e-4
    t = traj.t[::50]
    theta, phi, psi = ref.euler_angles(t)
    assert np.max(np.abs(traj.theta[::50] - theta)) < 1e-10
    assert np.max(np.abs(wrapped(traj.phi[::50] - phi))) < 1e-9
    assert np.max(np.abs(wrapped(traj.psi[::50] - psi))) < 1e-9


def test_separatrix_state_satisfies_the_double_root_conditions():
    q0, omega0 = separatrix_state(TOP)
    energy, p_phi, p_psi = TOP.invariants(q0, omega0)
    i1, _, i3 = TOP.pivot_moments
    mgl = TOP.mass * TOP.gravity * TOP.com_distance
    assert p_phi == pytest.approx(p_psi, rel=1e-14)
    assert energy - p_psi**2 / (2.0 * i3) == pytest.approx(mgl, rel=1e-14)
    phi, theta, psi = quaternion_to_zxz(q0)
    assert theta == pytest.approx(math.pi / 3, rel=1e-15)


def test_separatrix_closed_form_solves_the_energy_equation():
    """u = 1/(1 + sech(gamma t)) satisfies u'^2 = f(u) with f from the invariants."""
    i1, _, i3 = TOP.pivot_moments
    energy, p_phi, p_psi = TOP.invariants(*separatrix_state(TOP))
    b = 2.0 * TOP.mass * TOP.gravity * TOP.com_distance / i1
    a = (2.0 * energy - p_psi**2 / i3) / i1
    t = np.linspace(0.01, 0.5, 7)
    h = 1e-6
    u = np.cos(separatrix_solution(TOP, t)[0])
    u_dot = (np.cos(separatrix_solution(TOP, t + h)[0]) - np.cos(separatrix_solution(TOP, t - h)[0])) / (2 * h)
    f = (1 - u * u) * (a - b * u) - (p_phi - p_psi * u) ** 2 / i1**2
    np.testing.assert_allclose(u_dot**2, f, rtol=1e-7)


def test_separatrix_closed_form_matched_by_integration():
    q0, omega0 = separatrix_state(TOP)
    traj = TOP.simulate(q0, omega0, t_end=0.5, dt=1e-2, method="dop853", rtol=1e-13, atol=1e-13)
    theta, phi, psi = separatrix_solution(TOP, traj.t)
    assert traj.theta[-1] < 0.1  # the axis is rising to the vertical
    assert np.all(np.diff(traj.theta) < 0.0)
    assert np.max(np.abs(traj.theta - theta)) < 1e-11
    assert np.max(np.abs(wrapped(traj.phi - phi))) < 1e-10
    assert np.max(np.abs(wrapped(traj.psi - psi))) < 1e-10
    # 1/cos(theta) = 1 + 1/cosh(gamma t), gamma = sqrt(m g l / I1)
    gamma = math.sqrt(TOP.mass * TOP.gravity * TOP.com_distance / TOP.pivot_moments[0])
    np.testing.assert_allclose(1.0 / np.cos(traj.theta), 1.0 + 1.0 / np.cosh(gamma * traj.t), rtol=1e-11)


@pytest.mark.parametrize("method", ["rk4", "exact_split"])
def test_upright_top_has_finite_euler_angles(method):
    """theta -> 0: a sleeping top and a top passing close to the vertical report finite angles."""
    q0, omega0 = TOP.state_from_euler(0.0, 0.3, 0.0, 0.0, 0.0, 200.0)
    traj = TOP.simulate(q0, omega0, t_end=0.2, dt=1e-3, method=method)
    for angles in (traj.theta, traj.phi, traj.psi):
        assert np.all(np.isfinite(angles))
    assert np.max(traj.theta) < 1e-12
    # phi + psi is the only defined angle at theta = 0: it turns at omega3
    np.testing.assert_allclose(wrapped(traj.phi + traj.psi - 0.3 - 200.0 * traj.t), 0.0, atol=1e-8)
    q1, omega1 = TOP.state_from_euler(1e-9, 0.0, 0.0, 0.5, 0.0, 200.0)
    traj = TOP.simulate(q1, omega1, t_end=0.05, dt=1e-3, method=method)
    assert np.all(np.isfinite(traj.phi)) and np.all(np.isfinite(traj.psi)) and np.all(np.isfinite(traj.theta))
    energy, p_phi, _ = TOP.invariants(q1, omega1)
    assert np.max(np.abs(traj.energy / energy - 1.0)) < 1e-8


def test_reference_rejects_a_state_without_nutation():
    q0, omega0 = TOP.state_from_euler(0.0, 0.0, 0.0, 0.0, 0.0, 200.0)  # sleeping: u1 = u2 = 1
    with pytest.raises(ValueError, match="heavy_top_reference"):
        heavy_top_reference(TOP, q0, omega0)
