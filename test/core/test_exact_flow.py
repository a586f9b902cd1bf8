"""Tests for the ``exact`` and ``exact_split`` integrators (integrators/exact_flow.py)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.exact import torque_free_solution
from rigid_rot_sim.core.integrators import METHODS, get_method
from rigid_rot_sim.core.integrators.exact_flow import ExactFlow, ExactSplit
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque

MOMENTS = np.array([1.0, 2.0, 3.0])
OMEGA0 = np.array([1.0, 0.1, 0.5])
Q0 = Rotation.from_rotvec([0.3, -0.7, 1.1]).as_quat()


def rotation_distance(q1, q2):
    return (Rotation.from_quat(q1).inv() * Rotation.from_quat(q2)).magnitude()


def test_registered():
    assert METHODS["exact"] is ExactFlow and METHODS["exact_split"] is ExactSplit
    assert get_method("exact").name == "exact" and get_method("exact_split").name == "exact_split"


def test_exact_steps_follow_the_solution_to_1000_s():
    integ = ExactFlow(MOMENTS, 0.5, q0=Q0, omega0=OMEGA0, t0=2.0)
    sol = torque_free_solution(MOMENTS, OMEGA0, Q0, t0=2.0)
    for _ in range(10):
        integ.step()
    assert integ.t == 7.0 and integ.n_steps == 10
    integ.advance(1990)
    assert integ.t == 1002.0 and integ.n_steps == 2000
    q, w = sol.state(1002.0)
    assert np.max(np.abs(integ.omega - w)) < 1e-15 * 8
    assert rotation_distance(integ.q, q) < 1e-15 * 8


def test_exact_advance_equals_repeated_steps():
    a = ExactFlow(MOMENTS, 0.1, q0=Q0, omega0=OMEGA0)
    b = ExactFlow(MOMENTS, 0.1, q0=Q0, omega0=OMEGA0)
    a.advance(25)
    for _ in range(25):
        b.step()
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.omega, b.omega)
    assert a.t == b.t


def test_exact_set_state_and_dt_change():
    integ = ExactFlow(MOMENTS, 0.1, q0=Q0, omega0=OMEGA0)
    integ.advance(10)
    integ.dt = 0.25  # simulate() may shorten a step
    integ.advance(4)
    assert abs(integ.t - 2.0) < 1e-15
    sol = torque_free_solution(MOMENTS, OMEGA0, Q0)
    assert np.max(np.abs(integ.omega - sol.omega(2.0))) < 1e-14
    integ.set_state(0.0, Q0, (0.1, 0.2, 1.0))
    integ.advance(8)
    other = torque_free_solution(MOMENTS, (0.1, 0.2, 1.0), Q0)
    assert np.max(np.abs(integ.omega - other.omega(2.0))) < 1e-14
    assert rotation_distance(integ.q, other.quaternion(2.0)) < 1e-14


def test_exact_refuses_torque():
    with pytest.raises(ValueError, match="exact_split"):
        ExactFlow(MOMENTS, 0.1, ConstantTorque(np.array([0.0, 0.1, 0.0])), omega0=OMEGA0)
    with pytest.raises(ValueError, match="exact_split"):
        ExactFlow(MOMENTS, 0.1, GravityTorque(np.array([0.0, 0.0, 1.0]), 9.81), omega0=OMEGA0)
    integ = ExactFlow(MOMENTS, 0.1, ConstantTorque(np.zeros(3)), omega0=OMEGA0)
    integ.step()
    integ.torque = ConstantTorque(np.array([0.0, 0.0, 1.0]))  # replaced between steps
    with pytest.raises(ValueError, match="exact_split"):
        integ.step()


def test_exact_rejects_unknown_option():
    with pytest.raises(ValueError, match="order"):
        ExactFlow(MOMENTS, 0.1, omega0=OMEGA0, order=2)


@pytest.mark.parametrize("order", [2, 4])
def test_exact_split_without_torque_is_exact(order):
    integ = ExactSplit(MOMENTS, 0.7, q0=Q0, omega0=OMEGA0, order=order)
    integ.advance(100)
    sol = torque_free_solution(MOMENTS, OMEGA0, Q0)
    assert np.max(np.abs(integ.omega - sol.omega(70.0))) < 1e-12
    assert rotation_distance(integ.q, sol.quaternion(70.0)) < 1e-12


def test_exact_split_rejects_bad_order():
    with pytest.raises(ValueError, match="order must be one of"):
        ExactSplit(MOMENTS, 0.1, omega0=OMEGA0, order=3)


def _torqued_reference(torque_body, t_end):
    i1, i2, i3 = MOMENTS
    n1, n2, n3 = torque_body

    def rhs(t, y):
        w1, w2, w3, x, y_, z, w = y
        return [
            ((i2 - i3) * w2 * w3 + n1) / i1,
            ((i3 - i1) * w3 * w1 + n2) / i2,
            ((i1 - i2) * w1 * w2 + n3) / i3,
            0.5 * (w * w1 + y_ * w3 - z * w2),
            0.5 * (w * w2 + z * w1 - x * w3),
            0.5 * (w * w3 + x * w2 - y_ * w1),
            -0.5 * (x * w1 + y_ * w2 + z * w3),
        ]

    sol = solve_ivp(rhs, (0.0, t_end), np.concatenate([OMEGA0, Q0]), method="DOP853", rtol=1e-13, atol=1e-13)
    y = sol.y[:, -1]
    return y[3:] / np.linalg.norm(y[3:]), y[:3]


@pytest.mark.parametrize("order, steps", [(2, (0.2, 0.1, 0.05)), (4, (0.4, 0.2, 0.1))])
def test_exact_split_observed_order_under_constant_torque(order, steps):
    torque = np.array([0.1, -0.05, 0.02])
    t_end = 4.0
    q_ref, w_ref = _torqued_reference(torque, t_end)
    errors = []
    for dt in steps:
        integ = ExactSplit(MOMENTS, dt, ConstantTorque(torque), q0=Q0, omega0=OMEGA0, order=order)
        integ.advance(round(t_end / dt))
        assert abs(integ.t - t_end) < 1e-12
        errors.append(np.linalg.norm(integ.omega - w_ref) + rotation_distance(integ.q, q_ref))
    observed = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(observed - order) < 0.3), (errors, observed)
    assert errors[-1] > 1e-11  # still well above the reference's own error


def test_exact_split_spherical_body_under_constant_torque():
    """omega(t) = omega0 + N t / I exactly for a spherical body (the kicks are exact)."""
    torque = np.array([0.1, -0.05, 0.02])
    integ = ExactSplit((2.0, 2.0, 2.0), 0.3, ConstantTorque(torque), omega0=OMEGA0, order=4)
    integ.advance(10)
    np.testing.assert_allclose(integ.omega, OMEGA0 + torque * 3.0 / 2.0, rtol=0, atol=1e-14)


def test_simulate_with_exact_matches_the_solution():
    from rigid_rot_sim.core.simulate import simulate

    traj = simulate(MOMENTS, OMEGA0, t_end=100.0, dt=0.3, method="exact", q0=Q0, save_every=7)
    sol = torque_free_solution(MOMENTS, OMEGA0, Q0)
    q, w = sol.state(traj.t)
    # the two time grids (k * 0.3 and j * 2.1) differ by rounding
    assert np.max(np.abs(traj.omega - w)) < 1e-13
    assert np.max(rotation_distance(traj.q, q)) < 1e-13
    assert traj.t[-1] == 100.0
