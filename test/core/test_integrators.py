"""Every registered integrator: conservation, convergence order, torque, the step API.

References are independent of the method under test: the exact elliptic-function
solution (core/exact.py), conservation laws, solutions in closed form, and a tight
scipy DOP853 run on a right-hand side built from core/dynamics.py.
"""

from __future__ import annotations

import math
import re
import typing

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core import dynamics
from rigid_rot_sim.core.exact import torque_free_solution
from rigid_rot_sim.core.integrators import METHODS, NonFiniteStateError, get_method
from rigid_rot_sim.core.integrators.base import Stability
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque

# Methods with an ``order`` option: every order is a variant of its own.
ORDER_OPTIONS = {name: cls.orders for name, cls in METHODS.items() if len(cls.orders) > 1}
OWN_METHODS = ("euler", "rk4", "dop853", "implicit_midpoint", "lie_rk4", "splitting")


def variants(names=None):
    out = []
    for name in names or METHODS:
        if name in ORDER_OPTIONS and name in METHODS:
            out += [pytest.param(name, {"order": o}, id=f"{name}-{o}") for o in ORDER_OPTIONS[name]]
        elif name in METHODS:
            out.append(pytest.param(name, {}, id=name))
    return out


def make(name, options, moments, dt, torque=None, q0=(0.0, 0.0, 0.0, 1.0), omega0=(0.0, 0.0, 0.0)):
    return get_method(name)(moments, dt, torque, q0=q0, omega0=omega0, **options)


def refuses_torque(name, options, torque):
    """True (after checking the message) when a method is torque-free only, like ``exact``."""
    try:
        make(name, options, [1.0, 1.0, 1.0], 0.1, torque)
    except ValueError as error:
        assert "torque" in str(error)
        return True
    return False


def nominal_order(name, options):
    return options.get("order", get_method(name).orders[0])


def attitude_error(q, q_ref):
    return float(np.max((Rotation.from_quat(q).inv() * Rotation.from_quat(q_ref)).magnitude()))


def state_error(integrator, q_ref, omega_ref):
    return max(float(np.max(np.abs(integrator.omega - omega_ref))), attitude_error(integrator.q, q_ref))


# --- registry -------------------------------------------------------------------------


def test_registry_names_match_classes():
    for name, cls in METHODS.items():
        assert cls.name == name
        assert get_method(name) is cls
    assert set(OWN_METHODS) <= set(METHODS)


def test_every_method_states_its_orders_and_stability_class():
    for name, cls in METHODS.items():
        assert cls.stability in typing.get_args(Stability), name
        assert cls.orders and all(isinstance(order, int) and order >= 0 for order in cls.orders), name
        assert make(name, {}, MOMENTS, 0.01).order == cls.orders[0]
        assert (cls.stability == "exact") == (cls.orders == (0,)), name
    for name, orders in ORDER_OPTIONS.items():
        for order in orders:
            assert make(name, {"order": order}, MOMENTS, 0.01).order == order
        with pytest.raises(ValueError, match="order must be one of"):
            make(name, {"order": max(orders) + 1}, MOMENTS, 0.01)
    assert ORDER_OPTIONS == {"splitting": (2, 4, 6), "exact_split": (2, 4)}


def test_unknown_method_lists_valid_names():
    with pytest.raises(ValueError, match="unknown integrator 'rk5'") as info:
        get_method("rk5")
    for name in METHODS:
        assert name in str(info.value)


@pytest.mark.parametrize("name, options", variants())
def test_unknown_option_is_rejected(name, options):
    with pytest.raises(ValueError, match="bogus"):
        make(name, {**options, "bogus": 1}, [1.0, 2.0, 3.0], 0.1)


@pytest.mark.parametrize("order", [1, 3, 8, "4"])
def test_splitting_order_option_is_validated(order):
    with pytest.raises(ValueError, match="order must be one of"):
        make("splitting", {"order": order}, [1.0, 2.0, 3.0], 0.1)


@pytest.mark.parametrize("option, value", [("rtol", 0.0), ("atol", -1.0), ("rtol", float("nan")), ("max_step", 0.0)])
def test_dop853_tolerances_are_validated(option, value):
    with pytest.raises(ValueError, match=option):
        make("dop853", {option: value}, [1.0, 2.0, 3.0], 0.1)


# --- Basilisk's conservation bar --------------------------------------------------------

BAR_MOMENTS = np.array([500.0, 200.0, 300.0])
BAR_OMEGA0 = np.array([0.5, -0.4, 0.7])


def run_bar(name, options):
    integrator = make(name, options, BAR_MOMENTS, 1e-3, omega0=BAR_OMEGA0)
    integrator.advance(10_000)
    assert integrator.t == pytest.approx(10.0, abs=1e-12)
    T0 = dynamics.kinetic_energy(BAR_MOMENTS, BAR_OMEGA0)
    L0 = np.linalg.norm(BAR_MOMENTS * BAR_OMEGA0)
    dT = abs(dynamics.kinetic_energy(BAR_MOMENTS, integrator.omega) / T0 - 1.0)
    dL = abs(np.linalg.norm(BAR_MOMENTS * integrator.omega) / L0 - 1.0)
    L_world = dynamics.angular_momentum_world(BAR_MOMENTS, integrator.q, integrator.omega)
    dL_world = np.linalg.norm(L_world - BAR_MOMENTS * BAR_OMEGA0) / L0
    return dT, dL, dL_world


def test_bar_rk4():
    dT, dL, _ = run_bar("rk4", {})
    assert dT < 1e-10 and dL < 1e-10


def test_bar_implicit_midpoint_conserves_T_L_and_L_world_to_round_off():
    dT, dL, dL_world = run_bar("implicit_midpoint", {})
    assert dT < 1e-13 and dL < 1e-13 and dL_world < 1e-13


@pytest.mark.parametrize("order", [2, 4, 6])
def test_bar_splitting_conserves_L_to_round_off(order):
    dT, dL, dL_world = run_bar("splitting", {"order": order})
    assert dL < 1e-13 and dL_world < 1e-13
    if order >= 4:
        assert dT < 1e-13


def test_splitting_order_2_energy_error_is_bounded_and_second_order():
    """Sub-flows are exact rotations that do not each conserve T: the order-2 method keeps T
    only to O(h^2), without drift (it is symplectic). This is why its T change on the bar
    (about 1e-8 at 1 ms) misses 1e-13; orders 4 and 6 meet it."""

    def max_energy_error(dt, t_end):
        integrator = make("splitting", {"order": 2}, BAR_MOMENTS, dt, omega0=BAR_OMEGA0)
        q, omega = integrator.advance_saving(round(t_end / dt / 10), 10)
        T = dynamics.kinetic_energy(BAR_MOMENTS, omega)
        T0 = dynamics.kinetic_energy(BAR_MOMENTS, BAR_OMEGA0)
        return np.abs(T / T0 - 1.0)

    coarse = max_energy_error(4e-3, 40.0)
    fine = max_energy_error(2e-3, 40.0)
    assert np.max(coarse) / np.max(fine) == pytest.approx(4.0, rel=0.1)
    # bounded: the largest error over the second half is no larger than over the first
    half = len(coarse) // 2
    assert np.max(coarse[half:]) < 1.1 * np.max(coarse[:half])
    assert np.max(coarse) < 1e-5  # about 0.15 h^2


# --- convergence order ------------------------------------------------------------------

MOMENTS = np.array([1.0, 2.0, 3.0])
OMEGA0 = np.array([1.0, 0.1, 0.5])
Q0 = Rotation.from_rotvec([0.3, -0.2, 0.5]).as_quat()
T_ORDER = 5.0
BASE_STEP = {1: 0.02, 2: 0.05, 3: 0.1, 4: 0.1, 5: 0.2, 6: 0.2}


def step_sweep(order):
    h0 = BASE_STEP.get(order, 0.2)
    return [h0, h0 / 2, h0 / 4]


def observed_orders(errors):
    return [math.log2(errors[k] / errors[k + 1]) for k in range(len(errors) - 1)]


@pytest.fixture(scope="module")
def free_reference():
    solution = torque_free_solution(MOMENTS, OMEGA0, Q0)
    return solution.quaternion(T_ORDER), solution.omega(T_ORDER)


@pytest.mark.parametrize("name, options", variants())
def test_convergence_order_free_body(name, options, free_reference):
    q_ref, omega_ref = free_reference
    cls = get_method(name)
    if not cls.fixed_step:
        # adaptive: dt only sets the output grid; the error is set by the tolerance
        integrator = make(name, options, MOMENTS, 0.5, q0=Q0, omega0=OMEGA0)
        integrator.advance(round(T_ORDER / 0.5))
        assert state_error(integrator, q_ref, omega_ref) < 1e-8
        return
    order = nominal_order(name, options)
    errors = []
    for h in step_sweep(order):
        integrator = make(name, options, MOMENTS, h, q0=Q0, omega0=OMEGA0)
        integrator.advance(round(T_ORDER / h))
        errors.append(state_error(integrator, q_ref, omega_ref))
    if max(errors) < 1e-10:
        # exact on the free body (``exact``, ``exact_split``): rounding only, whatever the step
        assert order == 0 or name == "exact_split", f"{name}: errors {errors} are rounding only"
        return
    assert min(errors) > 1e-12, f"errors {errors} reach rounding: the sweep is too fine to measure an order"
    for p in observed_orders(errors):
        assert abs(p - order) <= 0.3, f"{name} {options}: errors {errors}, observed orders {observed_orders(errors)}"


GRAVITY = GravityTorque(np.array([0.1, 0.2, -0.3]), 2.0)


def general_torque(t, q, omega):
    """Depends on time, attitude (gravity about a pivot) and omega (damping)."""
    return GRAVITY(t, q, omega) - 0.05 * np.asarray(omega) + np.array([0.1 * math.sin(t), 0.0, 0.05])


@pytest.fixture(scope="module")
def torqued_reference():
    def rhs(t, y):
        q, omega = y[:4] / np.linalg.norm(y[:4]), y[4:]
        return np.concatenate(
            [dynamics.quaternion_derivative(q, omega), dynamics.euler_rhs(MOMENTS, omega, general_torque(t, q, omega))]
        )

    sol = solve_ivp(rhs, (0.0, T_ORDER), np.concatenate([Q0, OMEGA0]), method="DOP853", rtol=1e-13, atol=1e-15)
    y = sol.y[:, -1]
    return y[:4] / np.linalg.norm(y[:4]), y[4:]


@pytest.mark.parametrize("name, options", variants())
def test_convergence_order_with_general_torque(name, options, torqued_reference):
    if refuses_torque(name, options, general_torque):
        return
    q_ref, omega_ref = torqued_reference
    cls = get_method(name)
    if not cls.fixed_step:
        integrator = make(name, options, MOMENTS, 0.5, general_torque, q0=Q0, omega0=OMEGA0)
        integrator.advance(round(T_ORDER / 0.5))
        assert state_error(integrator, q_ref, omega_ref) < 1e-8
        return
    order = nominal_order(name, options)
    errors = []
    for h in step_sweep(order):
        integrator = make(name, options, MOMENTS, h, general_torque, q0=Q0, omega0=OMEGA0)
        integrator.advance(round(T_ORDER / h))
        errors.append(state_error(integrator, q_ref, omega_ref))
    assert min(errors) > 1e-12
    for p in observed_orders(errors):
        assert abs(p - order) <= 0.3, f"{name} {options}: errors {errors}, observed orders {observed_orders(errors)}"


def test_dop853_error_follows_tolerance(free_reference):
    q_ref, omega_ref = free_reference
    errors = []
    for rtol in (1e-6, 1e-9, 1e-12):
        integrator = make("dop853", {"rtol": rtol, "atol": rtol * 1e-2}, MOMENTS, 0.01, q0=Q0, omega0=OMEGA0)
        integrator.advance(round(T_ORDER / 0.01))
        errors.append(state_error(integrator, q_ref, omega_ref))
    assert errors[0] < 1e-4 and errors[1] < 1e-7 and errors[2] < 1e-10
    assert errors[0] > errors[1] > errors[2]


# --- unit quaternion, step API ----------------------------------------------------------


@pytest.mark.parametrize("name, options", variants())
def test_quaternion_stays_unit(name, options):
    torque = None if refuses_torque(name, options, general_torque) else general_torque
    integrator = make(name, options, MOMENTS, 0.01, torque, q0=Q0, omega0=OMEGA0)
    norms = []
    for _ in range(200):
        integrator.advance(5)
        norms.append(np.linalg.norm(integrator.q))
    assert np.max(np.abs(np.array(norms) - 1.0)) < 4e-16


@pytest.mark.parametrize("name, options", variants())
def test_step_and_advance_agree(name, options):
    a = make(name, options, MOMENTS, 0.05, q0=Q0, omega0=OMEGA0)
    b = make(name, options, MOMENTS, 0.05, q0=Q0, omega0=OMEGA0)
    for _ in range(20):
        a.step()
    b.advance(20)
    assert a.n_steps == b.n_steps == 20
    assert a.t == pytest.approx(1.0, abs=1e-14) and b.t == pytest.approx(1.0, abs=1e-14)
    tol = 0.0 if get_method(name).fixed_step else 1e-9
    assert np.max(np.abs(a.omega - b.omega)) <= tol
    assert attitude_error(a.q, b.q) <= tol + 1e-15


@pytest.mark.parametrize("name, options", variants())
def test_set_state_restarts_from_the_new_state(name, options):
    a = make(name, options, MOMENTS, 0.05, q0=Q0, omega0=OMEGA0)
    a.advance(10)
    a.set_state(0.0, Q0, -OMEGA0)
    a.advance(10)
    b = make(name, options, MOMENTS, 0.05, q0=Q0, omega0=-OMEGA0)
    b.advance(10)
    assert np.allclose(a.omega, b.omega, atol=1e-12)
    assert attitude_error(a.q, b.q) < 1e-12


# --- torque -------------------------------------------------------------------------------


@pytest.mark.parametrize("name, options", variants())
def test_constant_torque_on_spherical_body_is_exact(name, options):
    """omega' = N / I exactly when I1 = I2 = I3: every consistent method is exact on it."""
    N = np.array([0.3, -0.2, 0.1])
    torque = ConstantTorque(N)
    if refuses_torque(name, options, torque):
        return
    inertia = 2.5
    omega0 = np.array([0.4, 1.0, -0.7])
    integrator = make(name, options, [inertia] * 3, 0.1, torque, q0=Q0, omega0=omega0)
    integrator.advance(30)
    assert np.allclose(integrator.omega, omega0 + N * integrator.t / inertia, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name, options", variants())
def test_torque_may_be_replaced_between_steps(name, options):
    N = np.array([0.3, -0.2, 0.1])
    if refuses_torque(name, options, ConstantTorque(N)):
        return
    omega0 = np.array([0.4, 1.0, -0.7])
    integrator = make(name, options, [2.0] * 3, 0.1, None, omega0=omega0)
    integrator.advance(10)
    integrator.torque = ConstantTorque(N)
    integrator.advance(10)
    integrator.torque = None
    integrator.advance(5)
    assert np.allclose(integrator.omega, omega0 + N * 1.0 / 2.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name, options", variants())
def test_world_frame_torque_changes_L_world_linearly(name, options):
    """A torque fixed in the world: dL_world/dt = N_world exactly, so L_world(t) = L0 + N t."""
    N_world = np.array([0.02, -0.05, 0.03])

    def torque(t, q, omega):
        return dynamics.world_to_body(q, N_world)

    if refuses_torque(name, options, torque):
        return
    integrator = make(name, options, MOMENTS, 0.01, torque, q0=Q0, omega0=OMEGA0)
    L0 = dynamics.angular_momentum_world(MOMENTS, Q0, OMEGA0)
    integrator.advance(300)
    L = dynamics.angular_momentum_world(MOMENTS, integrator.q, integrator.omega)
    tol = {1: 1e-2, 2: 1e-4}.get(nominal_order(name, options), 1e-8)
    assert np.linalg.norm(L - (L0 + N_world * integrator.t)) < tol * np.linalg.norm(L0)


# --- non-finite states --------------------------------------------------------------------


def nan_after(t_bad):
    def torque(t, q, omega):
        return np.array([np.nan, 0.0, 0.0]) if t > t_bad else np.array([0.0, 0.1, 0.0])

    return torque


@pytest.mark.parametrize("name, options", variants())
def test_non_finite_state_names_step_and_time(name, options):
    torque = nan_after(0.0525)
    if refuses_torque(name, options, torque):
        return
    integrator = make(name, options, MOMENTS, 0.01, torque, q0=Q0, omega0=OMEGA0)
    with pytest.raises(NonFiniteStateError) as info:
        integrator.advance(100)
    message = str(info.value)
    match = re.search(r"step (\d+), t = ([0-9.eE+-]+) s", message)
    assert match, message
    step, t = int(match.group(1)), float(match.group(2))
    assert step * 0.01 == pytest.approx(t) or not get_method(name).fixed_step
    # a composition's sub-steps may reach past t_{n+1} (negative and > 1 coefficients)
    assert t >= 0.0525 - 0.01
    # the state is left finite, at or before the failure
    assert np.all(np.isfinite(integrator.q)) and np.all(np.isfinite(integrator.omega))
    assert integrator.t < t


def test_rk4_non_finite_state_is_reported_at_the_failing_step():
    integrator = make("rk4", {}, MOMENTS, 0.01, nan_after(0.0525), omega0=OMEGA0)
    with pytest.raises(NonFiniteStateError, match=r"rk4: non-finite state at step 6, t = 0.06 s"):
        for _ in range(100):
            integrator.step()
    assert integrator.n_steps == 5
    assert integrator.t == pytest.approx(0.05)


@pytest.mark.parametrize("name, options", variants(OWN_METHODS))
def test_overflow_is_non_finite_state(name, options):
    integrator = make(name, options, MOMENTS, 1.0, omega0=[1e200, 1e200, 1e200])
    with pytest.raises(NonFiniteStateError, match="step"):
        integrator.advance(10)


# --- the stiff cases implicit_midpoint is for ---------------------------------------------


def test_implicit_midpoint_high_spin_large_steps_conserves_invariants():
    """h * |omega| = 20 rad per step: Newton still converges; T, |L| and L_world are kept."""
    omega0 = np.array([200.0, 0.5, 3.0])
    integrator = make("implicit_midpoint", {}, MOMENTS, 0.1, q0=Q0, omega0=omega0)
    integrator.advance(1000)
    T0 = dynamics.kinetic_energy(MOMENTS, omega0)
    L0 = dynamics.angular_momentum_world(MOMENTS, Q0, omega0)
    assert dynamics.kinetic_energy(MOMENTS, integrator.omega) == pytest.approx(T0, rel=1e-13)
    assert np.linalg.norm(MOMENTS * integrator.omega) == pytest.approx(np.linalg.norm(L0), rel=1e-13)
    L = dynamics.angular_momentum_world(MOMENTS, integrator.q, integrator.omega)
    assert np.linalg.norm(L - L0) < 1e-12 * np.linalg.norm(L0)


def test_implicit_midpoint_is_stable_on_stiff_damping():
    """N = -c omega with h c / I = 500: A-stability keeps |omega| decaying; rk4 blows up."""
    c = 5000.0

    def damping(t, q, omega):
        return -c * np.asarray(omega)

    integrator = make("implicit_midpoint", {}, MOMENTS, 0.1, damping, q0=Q0, omega0=OMEGA0)
    norms = [np.linalg.norm(OMEGA0)]
    for _ in range(50):
        integrator.step()
        norms.append(np.linalg.norm(integrator.omega))
    assert all(b < a for a, b in zip(norms, norms[1:], strict=False))
    explicit = make("rk4", {}, MOMENTS, 0.1, damping, q0=Q0, omega0=OMEGA0)
    with pytest.raises(NonFiniteStateError):
        explicit.advance(1000)


def test_float_torque_matches_the_torque_models():
    from rigid_rot_sim.core.torque import PolynomialTorque, float_torque

    rng = np.random.default_rng(7)
    models = [
        ConstantTorque(np.array([0.1, -0.2, 0.3])),
        PolynomialTorque(np.array([[0.1, -0.2, 0.3], [0.5, 0.0, -1.0], [0.01, 0.02, 0.03]])),
        GravityTorque(np.array([0.1, -0.4, 0.25]), 9.81 * 2.0),
        general_torque,
    ]
    for model in models:
        f, attitude_dependent = float_torque(model)
        for _ in range(10):
            t = float(rng.uniform(-3, 3))
            q = Rotation.random(random_state=rng).as_quat()
            w = rng.normal(size=3)
            assert np.allclose(f(t, tuple(q), tuple(w)), model(t, q, w), rtol=1e-14, atol=1e-15)
        assert attitude_dependent == (model is general_torque or isinstance(model, GravityTorque))
    assert float_torque(None) == (None, False)
    assert float_torque(ConstantTorque(np.zeros(3)))[0] is None


@pytest.mark.parametrize(
    "name, options", [("implicit_midpoint", {}), ("splitting", {"order": 2}), ("splitting", {"order": 6})]
)
def test_random_bodies_keep_their_invariants(name, options):
    """Any physical body and initial rate: |L| (and T for implicit_midpoint) to round-off."""
    rng = np.random.default_rng(11)
    for _ in range(15):
        a, b = rng.uniform(0.1, 10.0, size=2)
        moments = np.array([a, b, rng.uniform(abs(a - b), a + b)])  # triangle inequality holds
        omega0 = rng.normal(scale=3.0, size=3)
        q0 = Rotation.random(random_state=rng).as_quat()
        integrator = make(name, options, moments, 0.05, q0=q0, omega0=omega0)
        integrator.advance(200)
        L0 = dynamics.angular_momentum_world(moments, q0, omega0)
        L = dynamics.angular_momentum_world(moments, integrator.q, integrator.omega)
        assert np.linalg.norm(L - L0) < 1e-12 * np.linalg.norm(L0)
        if name == "implicit_midpoint":
            T0 = dynamics.kinetic_energy(moments, omega0)
            assert dynamics.kinetic_energy(moments, integrator.omega) == pytest.approx(T0, rel=1e-12)


@pytest.mark.parametrize("moments", [(1.0, 1.0, 1.7), (2.0, 1.2, 2.0), (0.8, 1.5, 1.5), (1.3, 1.3, 1.3)])
@pytest.mark.parametrize("order", [2, 4])
def test_splitting_is_exact_for_symmetric_bodies(moments, order):
    """With the Casimir separated at a repeated moment, one X term vanishes and the other
    commutes with C: the step is the exact flow, at any step size."""
    solution = torque_free_solution(moments, OMEGA0, Q0)
    integrator = make("splitting", {"order": order}, moments, 0.5, q0=Q0, omega0=OMEGA0)
    integrator.advance(40)
    assert np.max(np.abs(integrator.omega - solution.omega(20.0))) < 1e-12
    assert attitude_error(integrator.q, solution.quaternion(20.0)) < 1e-12
