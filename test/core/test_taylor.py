"""Tests of the high-order Taylor method (rigid_rot_sim/core/integrators/taylor.py).

References are independent of the method under test: closed forms, conservation laws,
and scipy's DOP853 on a right-hand side assembled from core/dynamics.py and the torque
models' own ``__call__``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rigid_rot_sim.core import dynamics
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.integrators.taylor import Taylor, derivative_map, order_for_tolerance, taylor_coefficients
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque, PolynomialTorque

MOMENTS = np.array([1.0, 2.0, 3.0])
OMEGA0 = np.array([1.0, 0.1, 0.5])
Q0 = np.array([0.1, -0.2, 0.3, 0.9]) / np.linalg.norm([0.1, -0.2, 0.3, 0.9])


def reference_rhs(moments, torque):
    """d(omega, q)/dt from core/dynamics.py and the torque callable, for solve_ivp."""

    def rhs(t, y):
        omega, q = y[:3], y[3:]
        n = np.zeros(3) if torque is None else torque(t, q / np.linalg.norm(q), omega)
        return np.concatenate([dynamics.euler_rhs(moments, omega, n), dynamics.quaternion_derivative(q, omega)])

    return rhs


def reference_solution(moments, omega0, q0, torque, t_end):
    sol = solve_ivp(
        reference_rhs(moments, torque),
        (0.0, t_end),
        np.concatenate([omega0, q0]),
        method="DOP853",
        rtol=1e-13,
        atol=1e-14,
    )
    assert sol.success
    omega, q = sol.y[:3, -1], sol.y[3:, -1]
    return omega, q / np.linalg.norm(q)


def run(moments, dt, n_steps, torque=None, omega0=OMEGA0, q0=Q0, **options):
    integrator = Taylor(moments, dt, torque, omega0=omega0, q0=q0, **options)
    for _ in range(n_steps):
        integrator.step()
    return integrator


def quaternion_distance(p, q):
    """Smallest |p -/+ q| (q and -q are the same rotation)."""
    return min(np.linalg.norm(p - q), np.linalg.norm(p + q))


# -- the recurrence -----------------------------------------------------------------------


@pytest.mark.parametrize(
    "torque",
    [
        None,
        ConstantTorque([0.1, -0.05, 0.02]),
        PolynomialTorque([[0.1, -0.05, 0.02], [0.3, 0.0, -0.1], [0.0, 0.02, 0.01]]),
        GravityTorque(lever_arm=[0.05, -0.02, 0.3], weight=9.81 * 2.0),
    ],
    ids=["free", "constant", "polynomial", "gravity"],
)
def test_first_coefficients_are_the_equations_of_motion(torque):
    """X1 = f(x0) and 2 X2 = f'(x0) f(x0) against core/dynamics and the torque's own call."""
    moments = np.array([1.3, 2.1, 2.9])
    integrator = Taylor(moments, 0.1, torque, t0=0.7)
    rng = np.random.default_rng(1)
    for _ in range(5):
        omega = rng.normal(size=3)
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        x0 = np.concatenate([omega, q])
        c, b = derivative_map(moments, torque if isinstance(torque, GravityTorque) else None)
        scaled = integrator._forcing(0.7)  # b(0.7 + s) coefficients, pre-divided by k + 1
        forcing = scaled * np.arange(1, len(scaled) + 1)[:, None]
        coeffs = taylor_coefficients(x0, 3, c, forcing if len(forcing) else None)
        rhs = reference_rhs(moments, torque)
        np.testing.assert_allclose(coeffs[1], rhs(0.7, x0), rtol=1e-13, atol=1e-14)
        # second coefficient: half the time derivative of f along the flow (central difference)
        eps = 1e-5
        f_plus = rhs(0.7 + eps, x0 + eps * rhs(0.7, x0))
        f_minus = rhs(0.7 - eps, x0 - eps * rhs(0.7, x0))
        np.testing.assert_allclose(2.0 * coeffs[2], (f_plus - f_minus) / (2 * eps), rtol=1e-7, atol=1e-8)


def test_in_place_recurrence_matches_reference_form():
    torque = GravityTorque(lever_arm=[0.0, 0.0, 0.4], weight=5.0)
    integrator = Taylor(MOMENTS, 1.0, torque, tol=1e-12)
    x0 = np.concatenate([OMEGA0, Q0])
    c, _ = derivative_map(MOMENTS, torque)
    forcing = integrator._forcing(0.0)
    h, _, x = integrator._substep(0.0, x0, 0.3, 0.3)
    coeffs = taylor_coefficients(x0, integrator.series_order, c, forcing)
    expected = np.polynomial.polynomial.polyval(h, coeffs)
    expected[3:] /= np.linalg.norm(expected[3:])
    np.testing.assert_allclose(x, expected, rtol=0, atol=1e-15)


@pytest.mark.parametrize(
    "torque",
    [None, ConstantTorque([0.1, -0.05, 0.02]), PolynomialTorque([[0.1, -0.05, 0.02], [0.3, 0.0, -0.1]])],
    ids=["free", "constant", "polynomial"],
)
def test_written_out_recurrence_matches_reference_form(torque):
    """Without gravity the recurrence is written out (rigid_body_series): the same series as the
    reference contraction of derivative_map's C, to rounding."""
    integrator = Taylor(MOMENTS, 1.0, torque, tol=1e-12)
    assert integrator._pairs.shape[0] == 0  # the written-out path, not the tables
    x0 = np.concatenate([OMEGA0, Q0])
    c, _ = derivative_map(MOMENTS, None)
    scaled = integrator._forcing(0.4)
    forcing = scaled * np.arange(1, len(scaled) + 1)[:, None]
    h, _, x = integrator._substep(0.4, x0, 0.3, 0.3)
    coeffs = taylor_coefficients(x0, integrator.series_order, c, forcing if len(forcing) else None)
    np.testing.assert_allclose(integrator._coeffs, coeffs, rtol=1e-13, atol=1e-15)
    expected = np.polynomial.polynomial.polyval(h, coeffs)
    expected[3:] /= np.linalg.norm(expected[3:])
    np.testing.assert_allclose(x, expected, rtol=0, atol=1e-15)


def test_recurrence_tables_are_shared_and_read_only():
    first = Taylor(MOMENTS, 1.0, GravityTorque(lever_arm=[0.0, 0.0, 0.4], weight=5.0))
    second = Taylor(MOMENTS.tolist(), 1.0, GravityTorque(lever_arm=[0.0, 0.0, 0.4], weight=5.0))
    assert first._terms is second._terms and first._pairs.shape[0] > 0
    with pytest.raises(ValueError):
        first._term_values[0] = 1.0
    other = Taylor(MOMENTS, 1.0, GravityTorque(lever_arm=[0.0, 0.0, 0.5], weight=5.0))
    assert not np.array_equal(other._term_values, first._term_values)


def test_order_from_tolerance():
    assert order_for_tolerance(1e-2) == 10
    assert order_for_tolerance(1e-10) == math.ceil(10 * math.log(10))
    assert order_for_tolerance(1e-300) == 30
    assert Taylor(MOMENTS, 1.0, tol=1e-12).series_order == 28
    assert Taylor(MOMENTS, 1.0, tol=1e-12, order=12).series_order == 12


# -- accuracy -----------------------------------------------------------------------------


@pytest.mark.parametrize("order", [3, 4, 6])
def test_observed_order_of_truncated_series(order):
    """Fixed order, fixed step (tol=None): global error ~ h^order."""
    t_end = 4.0
    omega_ref, _ = reference_solution(MOMENTS, OMEGA0, Q0, None, t_end)
    steps = [0.2, 0.1, 0.05]
    errors = []
    for dt in steps:
        integrator = run(MOMENTS, dt, round(t_end / dt), tol=None, order=order)
        errors.append(np.max(np.abs(integrator.omega - omega_ref)))
    slopes = np.diff(np.log(errors)) / np.diff(np.log(steps))
    assert np.all(np.abs(slopes - order) < 0.3), (errors, slopes)


def test_error_falls_with_tolerance_and_tracks_it():
    """P2 (constant body torque, 20 s) in one API step: the error follows tol."""
    torque = ConstantTorque([0.1, -0.05, 0.02])
    omega_ref, q_ref = reference_solution(MOMENTS, OMEGA0, Q0, torque, 20.0)
    errors = []
    for tol in (1e-6, 1e-9, 1e-12):
        integrator = run(MOMENTS, 20.0, 1, torque, tol=tol)
        assert integrator.t == 20.0
        assert integrator.n_substeps > 5  # large but several internal steps
        error = np.max(np.abs(integrator.omega - omega_ref))
        assert error < 100.0 * tol + 1e-12, (tol, error)
        assert quaternion_distance(integrator.q, q_ref) < 100.0 * tol + 1e-12
        errors.append(error)
    assert errors[0] > errors[1] > errors[2]


def test_polynomial_torque_on_spherical_body_integrates_exactly():
    """Spherical body: I omega' = N(t), so omega = omega0 + (integral of N) / I, over many steps."""
    inertia = 2.5
    coeffs = np.array([[0.3, -0.1, 0.2], [0.05, 0.2, -0.4], [-0.01, 0.0, 0.03]])
    integrator = run([inertia] * 3, 0.25, 12, PolynomialTorque(coeffs), tol=1e-12)
    t = integrator.t
    integral = sum(coeffs[k] * t ** (k + 1) / (k + 1) for k in range(3))
    np.testing.assert_allclose(integrator.omega, OMEGA0 + integral / inertia, rtol=1e-14, atol=1e-14)


def test_constant_torque_on_spherical_body_is_exact():
    inertia = 0.7
    torque = np.array([0.3, -0.2, 0.05])
    integrator = Taylor([inertia] * 3, 0.5, ConstantTorque(torque), omega0=OMEGA0, q0=Q0, tol=1e-10)
    for n in range(1, 9):
        integrator.step()
        t = 0.5 * n
        assert integrator.t == t
        np.testing.assert_allclose(integrator.omega, OMEGA0 + torque * t / inertia, rtol=1e-15, atol=2e-15)


def test_torque_replaced_between_steps_takes_effect():
    inertia = 2.0
    integrator = Taylor([inertia] * 3, 1.0, ConstantTorque([1.0, 0.0, 0.0]), omega0=np.zeros(3))
    integrator.step()
    integrator.torque = ConstantTorque([0.0, 2.0, 0.0])
    integrator.step()
    integrator.torque = None
    integrator.step()
    np.testing.assert_allclose(integrator.omega, [0.5, 1.0, 0.0], atol=1e-15)


def test_spherical_body_rotates_about_fixed_omega():
    """Torque-free sphere: omega constant and q(t) = q0 (x) exp(omega t) (body-frame rate)."""
    omega0 = np.array([0.7, -1.1, 0.4])
    integrator = run([2.0] * 3, 1.7, 3, None, omega0=omega0, tol=1e-13)
    t = integrator.t
    expected = np.array(quat.multiply(Q0, quat.exp_rotation_vector(omega0 * t)))
    np.testing.assert_array_equal(integrator.omega, omega0)
    assert quaternion_distance(integrator.q, expected) < 1e-13


def test_body_at_rest_stays_at_rest():
    integrator = run(MOMENTS, 0.5, 4, None, omega0=np.zeros(3), tol=1e-12)
    assert integrator.t == 2.0
    np.testing.assert_array_equal(integrator.omega, np.zeros(3))
    np.testing.assert_allclose(integrator.q, Q0, rtol=0, atol=1e-16)


def test_switching_between_gravity_and_free_rebuilds_the_recurrence():
    gravity = GravityTorque(lever_arm=[0.0, 0.1, 0.3], weight=4.0)
    switching = Taylor(MOMENTS, 1.0, gravity, omega0=OMEGA0, q0=Q0, tol=1e-13)
    switching.step()
    switching.torque = None
    switching.step()
    switching.torque = gravity
    switching.step()
    state = (0.0, Q0, OMEGA0)
    for torque in (gravity, None, gravity):  # fresh integrators, one segment each
        fresh = Taylor(MOMENTS, 1.0, torque, t0=state[0], q0=state[1], omega0=state[2], tol=1e-13)
        fresh.step()
        state = (fresh.t, fresh.q, fresh.omega)
    assert switching.t == state[0] == 3.0
    np.testing.assert_allclose(switching.omega, state[2], rtol=0, atol=1e-12)
    assert quaternion_distance(switching.q, state[1]) < 1e-12


def test_torque_free_invariants_over_one_long_step():
    """T and |L| conserved to ~tol over 100 s (P1), and the attitude matches DOP853."""
    integrator = run(MOMENTS, 100.0, 1, None, tol=1e-12)
    e0 = dynamics.kinetic_energy(MOMENTS, OMEGA0)
    l0 = dynamics.angular_momentum_world(MOMENTS, Q0, OMEGA0)
    assert abs(dynamics.kinetic_energy(MOMENTS, integrator.omega) / e0 - 1.0) < 1e-11
    l1 = dynamics.angular_momentum_world(MOMENTS, integrator.q, integrator.omega)
    assert np.linalg.norm(l1 - l0) / np.linalg.norm(l0) < 1e-11  # L_world, not just |L|
    assert abs(np.linalg.norm(integrator.q) - 1.0) < 1e-15


def test_basilisk_case_conserves_energy_and_momentum_at_1ms():
    """I = diag(500, 200, 300), omega0 = (0.5, -0.4, 0.7), 1 ms steps for 10 s."""
    moments = np.array([500.0, 200.0, 300.0])
    omega0 = np.array([0.5, -0.4, 0.7])
    integrator = run(moments, 1e-3, 10_000, None, omega0=omega0, tol=1e-13)
    assert integrator.t == pytest.approx(10.0, abs=1e-12)
    e0 = dynamics.kinetic_energy(moments, omega0)
    l0 = np.linalg.norm(moments * omega0)
    assert abs(dynamics.kinetic_energy(moments, integrator.omega) / e0 - 1.0) < 1e-12
    assert abs(np.linalg.norm(moments * integrator.omega) / l0 - 1.0) < 1e-12
    # dense output: the internal steps do not follow the 1 ms API steps
    assert integrator.n_substeps < 100


def test_dense_output_matches_reference_at_every_api_step():
    """P2 with 0.1 s API steps: each output is the series evaluated inside a large internal step."""
    torque = ConstantTorque([0.1, -0.05, 0.02])
    integrator = Taylor(MOMENTS, 0.1, torque, omega0=OMEGA0, q0=Q0, tol=1e-12)
    sol = solve_ivp(
        reference_rhs(MOMENTS, torque),
        (0.0, 5.0),
        np.concatenate([OMEGA0, Q0]),
        method="DOP853",
        rtol=1e-13,
        atol=1e-14,
        dense_output=True,
    )
    worst_omega = worst_q = 0.0
    for n in range(1, 51):
        integrator.step()
        assert integrator.t == pytest.approx(0.1 * n, rel=1e-15)
        y = sol.sol(integrator.t)
        worst_omega = max(worst_omega, np.max(np.abs(integrator.omega - y[:3])))
        worst_q = max(worst_q, quaternion_distance(integrator.q, y[3:] / np.linalg.norm(y[3:])))
        assert abs(np.linalg.norm(integrator.q) - 1.0) < 1e-15
    assert worst_omega < 1e-11 and worst_q < 1e-11
    assert integrator.n_substeps < 20  # far fewer internal steps than API steps


def test_torque_commands_at_the_step_rate_land_on_each_step():
    """A new ConstantTorque every step (a controller): exact on a spherical body, short steps."""
    inertia = 1.5
    integrator = Taylor([inertia] * 3, 0.01, None, omega0=OMEGA0, q0=Q0, tol=1e-12)
    expected = OMEGA0.copy()
    rng = np.random.default_rng(3)
    for _ in range(200):
        command = rng.normal(size=3)
        integrator.torque = ConstantTorque(command)
        integrator.step()
        expected = expected + command * 0.01 / inertia
    np.testing.assert_allclose(integrator.omega, expected, rtol=0, atol=1e-13)
    assert 200 <= integrator.n_substeps <= 210  # one (rarely two) internal steps per command


def test_heavy_top_matches_dop853_and_conserves_energy():
    """Gravity torque expanded in the recurrence against DOP853 on GravityTorque's own call."""
    moments = np.array([0.8, 0.8, 0.3])  # about the pivot
    gravity = GravityTorque(lever_arm=[0.0, 0.0, 0.25], weight=1.5 * 9.81)
    omega0 = np.array([0.4, -0.3, 20.0])
    q0 = np.array([np.sin(0.5), 0.0, 0.0, np.cos(0.5)])  # tilted 1 rad about x
    t_end = 5.0
    integrator = run(moments, t_end, 1, gravity, omega0=omega0, q0=q0, tol=1e-12)
    omega_ref, q_ref = reference_solution(moments, omega0, q0, gravity, t_end)
    assert np.max(np.abs(integrator.omega - omega_ref)) < 1e-9
    assert quaternion_distance(integrator.q, q_ref) < 1e-10

    def energy(q, omega):
        up_body = dynamics.world_to_body(q, [0.0, 0.0, 1.0])
        return dynamics.kinetic_energy(moments, omega) + gravity.weight * gravity.lever_arm @ up_body

    assert abs(energy(integrator.q, integrator.omega) - energy(q0, omega0)) < 1e-10 * abs(energy(q0, omega0))


# -- torque refusal, validation, blow-up -----------------------------------------------------


def test_arbitrary_callable_torque_is_refused_with_alternatives():
    with pytest.raises(ValueError, match="dop853") as info:
        Taylor(MOMENTS, 0.1, lambda t, q, w: np.array([0.0, 0.0, 0.1]))
    message = str(info.value)
    for name in ("ConstantTorque", "PolynomialTorque", "GravityTorque", "rk4"):
        assert name in message


def test_callable_swapped_in_between_steps_is_refused():
    integrator = Taylor(MOMENTS, 0.1, None, omega0=OMEGA0)
    integrator.step()
    integrator.torque = lambda t, q, w: np.zeros(3)
    with pytest.raises(ValueError, match="unsupported torque"):
        integrator.step()


@pytest.mark.parametrize(
    "options, match",
    [
        ({"tol": 0.0}, "tol"),
        ({"tol": float("nan")}, "tol"),
        ({"order": 1}, "order"),
        ({"order": 2.5}, "order"),
        ({"tol": None}, "order"),
        ({"max_step": 0.0}, "max_step"),
        ({"rtol": 1e-9}, "rtol"),
    ],
)
def test_bad_options_are_value_errors_naming_them(options, match):
    with pytest.raises(ValueError, match=match):
        Taylor(MOMENTS, 0.1, **options)


@pytest.mark.filterwarnings(
    "ignore:overflow encountered:RuntimeWarning", "ignore:invalid value encountered:RuntimeWarning"
)
def test_blow_up_raises_instead_of_returning_nan():
    integrator = Taylor(MOMENTS, 1.0, None, omega0=[1e200, 1e200, 1e200])
    with pytest.raises(NonFiniteStateError, match="step 1"):
        integrator.step()
    huge = Taylor([1.0] * 3, 1.0, PolynomialTorque([[0.0, 0.0, 0.0]] + [[1e300, 1e300, 1e300]] * 4))
    with pytest.raises(NonFiniteStateError):
        for _ in range(5):
            huge.step()


def test_max_step_bounds_the_internal_step():
    integrator = run(MOMENTS, 10.0, 1, None, tol=1e-8, max_step=0.5)
    assert integrator.n_substeps >= 20
    free = run(MOMENTS, 10.0, 1, None, tol=1e-8)
    np.testing.assert_allclose(integrator.omega, free.omega, atol=1e-7)


def test_fast_spin_stays_finite_and_accurate():
    """omega*dt = 50 rad per API step: the internal steps adapt, the state stays finite."""
    moments = np.array([1.0, 2.0, 3.0])
    omega0 = np.array([100.0, 1.0, 5.0])
    integrator = run(moments, 0.5, 4, None, omega0=omega0, tol=1e-12)
    omega_ref, q_ref = reference_solution(moments, omega0, Q0, None, 2.0)
    assert np.all(np.isfinite(integrator.omega)) and np.all(np.isfinite(integrator.q))
    assert np.max(np.abs(integrator.omega - omega_ref)) < 1e-11 * 100.0  # omega: relative to |omega|
    assert quaternion_distance(integrator.q, q_ref) < 1e-10  # attitude: absolute, not loosened by the spin


# -- registry and simulate ------------------------------------------------------------------


def test_registered_and_driven_by_simulate_in_one_api_step():
    from rigid_rot_sim.core.integrators import METHODS
    from rigid_rot_sim.core.simulate import simulate

    assert METHODS["taylor"] is Taylor
    torque = (0.1, -0.05, 0.02)
    traj = simulate(MOMENTS, OMEGA0, t_end=20.0, dt=20.0, method="taylor", q0=Q0, torque=torque, tol=1e-12)
    assert traj.t.tolist() == [0.0, 20.0]
    omega_ref, q_ref = reference_solution(MOMENTS, OMEGA0, Q0, ConstantTorque(torque), 20.0)
    assert np.max(np.abs(traj.omega[-1] - omega_ref)) < 1e-10
    assert quaternion_distance(traj.q[-1], q_ref) < 1e-10


def test_simulate_with_a_full_inertia_tensor_matches_dop853():
    """A non-diagonal tensor: simulate rotates the body and the torque into principal axes."""
    from rigid_rot_sim.core.simulate import simulate

    tensor = np.array([[2.0, 0.3, -0.1], [0.3, 1.5, 0.2], [-0.1, 0.2, 3.0]])
    torque = (0.05, 0.02, -0.04)
    kwargs = dict(t_end=6.0, dt=1.5, q0=Q0, torque=torque)
    taylor = simulate(tensor, OMEGA0, method="taylor", tol=1e-13, **kwargs)
    dop = simulate(tensor, OMEGA0, method="dop853", rtol=1e-13, atol=1e-13, **kwargs)
    np.testing.assert_allclose(taylor.t, dop.t, rtol=0, atol=0)
    assert np.max(np.abs(taylor.omega - dop.omega)) < 1e-10
    assert max(quaternion_distance(a, b) for a, b in zip(taylor.q, dop.q, strict=True)) < 1e-10


def test_class_order_is_the_default_series_order():
    assert Taylor.orders[0] == Taylor(MOMENTS, 1.0).series_order == order_for_tolerance(1e-12)
    assert Taylor.fixed_step is False


def test_internal_steps_do_not_depend_on_the_api_step():
    """Dense output: 200 steps of 0.1 s and one step of 20 s share their internal steps."""
    torque = ConstantTorque([0.1, -0.05, 0.02])
    fine = run(MOMENTS, 0.1, 200, torque, tol=1e-10)
    coarse = run(MOMENTS, 20.0, 1, torque, tol=1e-10)
    assert fine.n_substeps == coarse.n_substeps
    assert np.max(np.abs(fine.omega - coarse.omega)) < 1e-13
    assert quaternion_distance(fine.q, coarse.q) < 1e-13


def test_set_state_restarts_from_the_new_state():
    integrator = run(MOMENTS, 0.5, 3, ConstantTorque([0.1, 0.0, 0.0]), tol=1e-12)
    integrator.set_state(10.0, Q0, OMEGA0)
    integrator.step()
    fresh = Taylor(MOMENTS, 0.5, ConstantTorque([0.1, 0.0, 0.0]), t0=10.0, q0=Q0, omega0=OMEGA0, tol=1e-12)
    fresh.step()
    assert integrator.t == fresh.t == 10.5
    np.testing.assert_array_equal(integrator.omega, fresh.omega)
    np.testing.assert_array_equal(integrator.q, fresh.q)


# -- PolynomialTorque (core/torque.py) --------------------------------------------------------


def test_polynomial_torque_evaluates_its_polynomial_and_validates():
    coeffs = [[1.0, 0.0, -1.0], [0.5, 2.0, 0.0], [0.0, 0.0, 3.0]]
    torque = PolynomialTorque(coeffs)
    t = 1.5
    expected = np.array(coeffs[0]) + np.array(coeffs[1]) * t + np.array(coeffs[2]) * t**2
    np.testing.assert_allclose(torque(t, Q0, OMEGA0), expected, rtol=1e-15)
    np.testing.assert_array_equal(PolynomialTorque([0.1, 0.2, 0.3])(7.0, Q0, OMEGA0), [0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="shape"):
        PolynomialTorque(np.zeros((2, 2)))
    with pytest.raises(ValueError, match=r"coefficients\[1, 2\]"):
        PolynomialTorque([[0.0, 0.0, 0.0], [0.0, 0.0, float("inf")]])
