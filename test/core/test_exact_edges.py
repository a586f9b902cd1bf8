"""The exact flows at the edges of the state space (issue 29): next to every principal axis down to
subnormal and zero transverse components, next to the separatrix on both sides, symmetric and
near-spherical bodies, extreme scales.

References: the 40-digit mpmath solutions of test/core/mp_reference.py (triaxial and symmetric, both
checked against Euler's equations), the limiting motion (a spin about the axis by |omega| t) and the
linearised motion next to an axis (the transverse components scale with the perturbation), and the
invariants. Units of the ulp bounds as in test_exact_ulps.py (4 units: 4 ulps of the value, or 1e-16
of the scale next to a zero crossing).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mp_reference import Reference, SymmetricReference, ode_residual  # test/core, on sys.path under pytest
from scipy.spatial.transform import Rotation
from test_exact_ulps import _scaled_errors

from rigid_rot_sim.core.exact import torque_free_flow, torque_free_solution
from rigid_rot_sim.core.integrators.exact_flow import ExactFlow, ExactSplit
from rigid_rot_sim.core.integrators.explicit import RK4

Q0 = (0.5, -0.5, 0.5, 0.5)
MOMENTS = (1.0, 2.0, 3.0)
PERTURBATIONS = (1e-3, 1e-6, 1e-9, 1e-12, 1e-16, 1e-30, 1e-100, 1e-160, 1e-200, 1e-300, 1e-307, 5e-324, 0.0)
BOUND = 4.0


def _ulps(sol_q, sol_w, ref_q, ref_w, scale_w):
    sign = 1.0 if sum(float(a) * b for a, b in zip(ref_q, sol_q, strict=True)) >= 0.0 else -1.0
    return max(_scaled_errors(sign * np.asarray(sol_q), ref_q, 1.0)), max(_scaled_errors(sol_w, ref_w, scale_w))


def _one_ulp_references(moments, omega0):
    """References from omega0 with one component moved by one ulp (each component, both ways)."""
    out = []
    for k in range(3):
        for direction in (-math.inf, math.inf):
            moved = list(omega0)
            moved[k] = math.nextafter(moved[k], direction)
            out.append(Reference(moments, moved, Q0))
    return out


def _bound(t, ref_q, ref_w, others, scale):
    """4 units, or twice what a 1-ulp change of omega0 moves the exact solution by at t: next to the
    separatrix the problem itself is ill-conditioned, and the AGM's absolute rounding in the amplitude
    (a few 1e-16, over up to ~8 levels) is held to that (measured: up to 1.5x there)."""
    moved = 0.0
    for other in others:
        q, w = other.state(t)
        moved = max(moved, *_ulps([float(x) for x in q], [float(x) for x in w], ref_q, ref_w, scale))
    return max(BOUND, 2.0 * moved)


def _spin(omega, t, q0=Q0):
    """The limiting motion: a rotation by |omega| t about omega (body frame) after q0."""
    return (Rotation.from_quat(q0) * Rotation.from_rotvec(np.asarray(omega, dtype=float) * t)).as_quat()


def _distance(q1, q2):
    return float((Rotation.from_quat(q1).inv() * Rotation.from_quat(q2)).magnitude())


def _near_axis(axis, eps):
    omega = [0.7 * eps, -1.3 * eps, 0.9 * eps]
    omega[axis] = 1.25
    return tuple(omega)


# -- next to each principal axis ----------------------------------------------------------------


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("eps", PERTURBATIONS)
def test_near_every_axis_tends_to_the_spin(axis, eps):
    """Finite, the right invariants, and within the perturbation's own size of the pure spin (at t = 4 s,
    the middle axis's departure e^(lam t) included)."""
    omega0 = _near_axis(axis, eps)
    sol = torque_free_solution(MOMENTS, omega0, Q0)
    t = np.linspace(-4.0, 4.0, 9)
    q, w = sol.state(t)
    assert np.all(np.isfinite(q)) and np.all(np.isfinite(w))
    growth = math.exp(4.0 * 1.25 * math.sqrt(2.0)) if axis == 1 else 1.0  # lam <= |omega| sqrt(2) here
    for k, tk in enumerate(t):
        assert _distance(q[k], _spin(omega0, tk)) <= 4.0 * eps * growth * (1.0 + abs(tk)) + 1e-15
        assert abs(w[k, axis] - 1.25) <= 4.0 * (eps * growth) ** 2 + 4e-16
    energy = np.sum(np.array(MOMENTS) * w * w, axis=1)
    assert np.max(np.abs(energy / energy[4] - 1.0)) <= 1e-15


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_tiny_transverse_components_scale_with_the_perturbation(axis):
    """Below 1e-20 the motion next to an axis is linear in the perturbation: omega_transverse(t) / eps is
    the same for every eps down to the subnormals (to a few ulps), the attitude the spin's."""
    t = np.array([0.5, 3.0, -2.0])
    ratios = []
    for eps in (1e-20, 1e-60, 1e-150, 1e-250, 1e-300):
        _, w = torque_free_solution(MOMENTS, _near_axis(axis, eps), Q0).state(t)
        w = np.delete(w, axis, axis=1) / eps
        ratios.append(w)
        assert np.all(np.isfinite(w)) and np.max(np.abs(w)) > 0.1
    for w in ratios[1:]:
        np.testing.assert_allclose(w, ratios[0], rtol=1e-14, atol=0)


def test_middle_axis_departure_is_a_time_shift_down_to_the_subnormals():
    """Next to the middle axis a perturbation c times smaller departs later by ln(1 / c) / lam_u (lam_u =
    omega_2 sqrt((I3 - I2)(I2 - I1) / (I1 I3)), the saddle's rate) and is the same motion after: omega(t + shift)
    from 2^-30 eps equals omega(t) from eps, from normal k' into the subnormals (the perturbations below
    are exact in either)."""
    lam_u = 1.25 * math.sqrt((3.0 - 2.0) * (2.0 - 1.0) / (1.0 * 3.0))
    for e in (-990, -1040):
        big = torque_free_solution(MOMENTS, (0.75 * 2.0**e, 1.25, 0.875 * 2.0**e), Q0)
        small = torque_free_solution(MOMENTS, (0.75 * 2.0 ** (e - 30), 1.25, 0.875 * 2.0 ** (e - 30)), Q0)
        flip = -e * math.log(2.0) / lam_u  # about where the first departure is
        t = flip + np.linspace(-5.0, 15.0, 9)
        w_big = big.omega(t)
        w_small = small.omega(t + 30.0 * math.log(2.0) / lam_u)
        assert np.max(np.abs(w_big[:, 1])) > 0.5 and np.min(w_big[:, 1]) < 0.0  # it did flip in that window
        np.testing.assert_allclose(w_small, w_big, rtol=0, atol=1e-11)


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("eps", [1e-3, 1e-6, 1e-9, 1e-12])
def test_near_every_axis_against_mpmath(axis, eps):
    """Within 4 units of the 40-digit reference over 20 s (next to the middle axis, through its departures:
    within what a 1-ulp change of omega0 makes, where that is more)."""
    omega0 = _near_axis(axis, eps)
    ref = Reference(MOMENTS, omega0, Q0)
    others = _one_ulp_references(MOMENTS, omega0) if axis == 1 else []
    sol = torque_free_solution(MOMENTS, omega0, Q0)
    scale = float(np.linalg.norm(omega0))
    for t in (0.0, 1.5, 4.0, 9.0, 16.0, 20.0):
        q, w = sol.state(t)
        q_ref, w_ref = ref.state(t)
        err_q, err_w = _ulps(q, w, q_ref, w_ref, scale)
        bound = _bound(t, q_ref, w_ref, others, scale)
        assert err_q <= bound and err_w <= bound, (t, err_q, err_w, bound)


@pytest.mark.parametrize("eps", [1e-9, 1e-12, 1e-16])
def test_exact_split_next_to_the_middle_axis(eps):
    """exact_split (short flows, K in double) agrees with the exact flow and with rk4 (issue 29: it was
    2.6e-5 off at 1e-12, O(1) at 1e-16)."""
    omega0 = np.array(_near_axis(1, eps))
    steps, dt = 400, 0.01
    split = ExactSplit(np.array(MOMENTS), dt, q0=np.array(Q0), omega0=omega0)
    split.advance(steps)
    exact = ExactFlow(np.array(MOMENTS), dt, q0=np.array(Q0), omega0=omega0)
    exact.advance(steps)
    rk4 = RK4(np.array(MOMENTS), dt, q0=np.array(Q0), omega0=omega0)
    rk4.advance(steps)
    assert _distance(split.q, exact.q) < 1e-14 and np.max(np.abs(split.omega - exact.omega)) < 1e-14
    assert _distance(rk4.q, exact.q) < 1e-9


# -- next to the separatrix, both sides ---------------------------------------------------------


@pytest.mark.parametrize("rel", [1e-2, 1e-5, 1e-8, -1e-8, -1e-5, -1e-2])
def test_both_sides_of_the_separatrix_against_mpmath(rel):
    """I = (3, 4, 6), omega0 = (1, 0.3, 0.5 (1 + rel)): L^2 - 2 E I2 has the sign of rel; within 4 units or
    what a 1-ulp change of omega0 makes (the problem's own conditioning there)."""
    moments, omega0 = (3.0, 4.0, 6.0), (1.0, 0.3, 0.5 * (1.0 + rel))
    sol = torque_free_solution(moments, omega0, Q0)
    assert sol.case == ("above_separatrix" if rel > 0 else "below_separatrix")
    ref = Reference(moments, omega0, Q0)
    others = _one_ulp_references(moments, omega0)
    scale = float(np.linalg.norm(omega0))
    for t in (0.0, 2.5, 7.0, 19.0):
        q, w = sol.state(t)
        q_ref, w_ref = ref.state(t)
        err_q, err_w = _ulps(q, w, q_ref, w_ref, scale)
        bound = _bound(t, q_ref, w_ref, others, scale)
        assert err_q <= bound and err_w <= bound, (t, err_q, err_w, bound)


# -- symmetric bodies (Principia's Euler-solver cases) and spins about an axis ---------------------

# name: (moments, omega0, distinct axis)
SYMMETRIC = {
    "tall_skinny": ((3.0, 9.0, 9.0), (7.0 / 3.0, 0.0, 5.0 / 9.0), 0),
    "short_fat": ((3.0, 3.0, 5.5), (0.0, 5.0 / 3.0, 7.0 / 5.5), 2),  # Principia's I3 = 9 is no rigid body
    "separatrix_constant_momentum": ((2.0, 3.0, 3.0), (0.0, 4.0 / 3.0, 5.0 / 3.0), 0),
    "oblate_general": ((2.0, 2.0, 3.5), (0.3, -0.4, 0.9), 2),
    "prolate_general": ((1.5, 0.4, 1.5), (0.2, 1.1, -0.7), 1),
}


@pytest.mark.parametrize("name", sorted(SYMMETRIC))
def test_symmetric_reference_satisfies_the_equations_of_motion(name):
    moments, omega0, axis = SYMMETRIC[name]
    assert ode_residual(SymmetricReference(moments, omega0, Q0, axis), 3.7) < 1e-19


@pytest.mark.parametrize("name", sorted(SYMMETRIC))
def test_symmetric_within_ulps(name):
    """q, omega and the body momentum I omega within 4 units over 5 s (Principia's sampling, every 0.1 s)
    and at 100 s (the tall-skinny body momentum was at 161 ulps near a zero crossing)."""
    moments, omega0, axis = SYMMETRIC[name]
    ref = SymmetricReference(moments, omega0, Q0, axis)
    sol = torque_free_solution(moments, omega0, Q0)
    assert sol.case == "symmetric"
    scale = float(np.linalg.norm(omega0))
    l_scale = float(np.linalg.norm(np.array(moments) * omega0))
    import mpmath

    for t in [0.1 * k for k in range(50)] + [100.0]:
        q, w = sol.state(t)
        q_ref, w_ref = ref.state(t)
        err_q, err_w = _ulps(q, w, q_ref, w_ref, scale)
        l_ours = [mpmath.mpf(float(i)) * mpmath.mpf(float(x)) for i, x in zip(moments, w, strict=True)]
        l_ref = [mpmath.mpf(float(i)) * x for i, x in zip(moments, w_ref, strict=True)]
        err_l = max(_scaled_errors([float(x) for x in l_ours], l_ref, l_scale))
        assert err_q <= BOUND and err_w <= BOUND and err_l <= BOUND, (t, err_q, err_w, err_l)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_rotation_about_each_axis_within_an_ulp(axis):
    """A spin about a principal axis (Principia's I = (2, 3, 5), 10 s): q within 1 unit of the rotation."""
    omega0 = [0.0, 0.0, 0.0]
    omega0[axis] = (2.5, 2.0, 1.4)[axis]
    ref = Reference((2.0, 3.0, 5.0), omega0, (0.0, 0.0, 0.0, 1.0))
    sol = torque_free_solution((2.0, 3.0, 5.0), omega0, (0.0, 0.0, 0.0, 1.0))
    for t in (1.0, 10.0, 77.0):
        q, w = sol.state(t)
        err_q, err_w = _ulps(q, w, *ref.state(t), 1.0)
        assert err_q <= 1.0 and err_w == 0.0, (t, err_q)


# -- extreme scales ---------------------------------------------------------------------------------


@pytest.mark.parametrize("factor", [2.0**-600, 1e-300, 1e300, 2.0**900])
def test_omega_scale_is_a_time_scale(factor):
    """omega0 times c gives omega(t) = c omega_1(c t), q(t) = q_1(c t) (Euler's equations are homogeneous),
    bit for bit where c is a power of 2."""
    omega1 = np.array([0.3, 0.5, 1.0])
    base = torque_free_solution(MOMENTS, omega1, Q0)
    scaled = torque_free_solution(MOMENTS, omega1 * factor, Q0)
    for t in (0.5, 3.0):
        q1, w1 = base.state(t)
        q, w = scaled.state(t / factor)
        np.testing.assert_allclose(w, w1 * factor, rtol=2e-15, atol=0)
        assert _distance(q, q1) < 1e-15


@pytest.mark.parametrize("factor", [2.0**-900, 1e-200, 1e250])
def test_moments_scale_changes_nothing(factor):
    omega0 = (0.3, 0.5, 1.0)
    base = torque_free_solution(MOMENTS, omega0, Q0)
    scaled = torque_free_solution(np.array(MOMENTS) * factor, omega0, Q0)
    q1, w1 = base.state(13.0)
    q, w = scaled.state(13.0)
    np.testing.assert_allclose(w, w1, rtol=4e-16, atol=1e-300)
    assert _distance(q, q1) < 1e-15


# -- the whole state space: a hypothesis sweep --------------------------------------------------------

_SHAPES = st.sampled_from(
    [
        (1.0, 2.0, 3.0),
        (3.0, 2.0, 1.0),
        (2.0, 2.0, 3.0),
        (1.5, 3.0, 1.5),
        (2.0, 2.0, 2.0),
        (1.0, 1.0 + 1e-9, 1.0 + 3e-9),
        (1.0, 1.0 + 2e-16, 1.5),
        (0.7, 0.9, 1.3),
        (1.0, 1.0, 2.0),
    ]
)


@st.composite
def _states(draw):
    moments = draw(_SHAPES)
    axis = draw(st.integers(0, 2))
    exponents = draw(st.lists(st.integers(-1080, 2), min_size=2, max_size=2))
    signs = draw(st.lists(st.sampled_from([-1.0, 1.0]), min_size=3, max_size=3))
    mantissas = draw(st.lists(st.floats(1.0, 2.0), min_size=2, max_size=2))
    omega = [0.0, 0.0, 0.0]
    others = [k for k in range(3) if k != axis]
    for k, e, mant in zip(others, exponents, mantissas, strict=True):
        omega[k] = 0.0 if e < -1074 else math.ldexp(mant, e)
    omega[axis] = draw(st.floats(0.5, 3.0))
    omega = [s * w for s, w in zip(signs, omega, strict=True)]
    q0 = draw(st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(lambda v: sum(x * x for x in v) > 0.1))
    t = draw(st.floats(-30.0, 30.0))
    return moments, omega, q0, axis, t


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_states())
def test_hypothesis_whole_state_space(state):
    """Every axis, every body shape, transverse components from 4 down to the smallest subnormal and 0: a
    finite unit q, energy and |L| conserved to a few ulps, L_world conserved, and the pure spin in the limit."""
    moments, omega, q0, axis, t = state
    q0 = np.array(q0) / np.linalg.norm(q0)
    sol = torque_free_solution(moments, omega, q0)
    q, w = sol.state(t)
    assert np.all(np.isfinite(q)) and np.all(np.isfinite(w))
    assert abs(np.linalg.norm(q) - 1.0) < 4e-16
    i = np.array(moments)
    w0 = np.array(omega)
    assert abs(np.sum(i * w * w) / np.sum(i * w0 * w0) - 1.0) < 1e-15
    assert abs(np.linalg.norm(i * w) / np.linalg.norm(i * w0) - 1.0) < 1e-15
    l_world = Rotation.from_quat(q).apply(i * w)
    assert np.max(np.abs(l_world - sol.angular_momentum_world)) < 1e-14 * np.linalg.norm(i * w0)
    transverse = max(abs(omega[k]) for k in range(3) if k != axis)
    if transverse * math.exp(1.5 * abs(omega[axis] * t)) < 1e-25:
        assert _distance(q, _spin(omega, t, q0)) < 4e-15 * (1.0 + abs(t))
    # a short flow (exact_split's step) from the same state is as finite and keeps the invariants
    qs, ws = torque_free_flow(i, tuple(q0), tuple(omega), 0.01)
    assert np.all(np.isfinite(qs)) and np.all(np.isfinite(ws))
    assert abs(np.sum(i * np.array(ws) ** 2) / np.sum(i * w0 * w0) - 1.0) < 1e-15
