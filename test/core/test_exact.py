"""Tests for rigid_rot_sim.core.exact: the exact torque-free solution in every case.

References are independent of the code under test: scipy's DOP853 on Euler's equations
and the quaternion kinematics written out here, the textbook symmetric-top solution, and
the invariants T, |L| and L_world.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.exact import CASES, torque_free_solution


def _rhs(moments):
    i1, i2, i3 = moments

    def rhs(t, y):
        w1, w2, w3, x, y_, z, w = y
        return [
            (i2 - i3) * w2 * w3 / i1,
            (i3 - i1) * w3 * w1 / i2,
            (i1 - i2) * w1 * w2 / i3,
            # dq/dt = 1/2 q (x) (omega, 0), scalar-last
            0.5 * (w * w1 + y_ * w3 - z * w2),
            0.5 * (w * w2 + z * w1 - x * w3),
            0.5 * (w * w3 + x * w2 - y_ * w1),
            -0.5 * (x * w1 + y_ * w2 + z * w3),
        ]

    return rhs


def reference(moments, omega0, q0, t, tol=1e-13):
    """DOP853 reference state (q, omega) at the times t."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    sol = solve_ivp(
        _rhs(moments), (0.0, t[-1]), np.concatenate([omega0, q0]), method="DOP853", rtol=tol, atol=tol, t_eval=t
    )
    assert sol.success
    y = sol.y.T
    q = y[:, 3:] / np.linalg.norm(y[:, 3:], axis=1, keepdims=True)
    return q, y[:, :3]


def rotation_distance(q1, q2):
    """Angle (rad) of the rotation between two attitudes (sign of q irrelevant)."""
    return (Rotation.from_quat(q1).inv() * Rotation.from_quat(q2)).magnitude()


Q0 = Rotation.from_rotvec([0.3, -0.7, 1.1]).as_quat()

CASE_BODIES = [
    ("below_separatrix", (1.0, 2.0, 3.0), (1.0, 0.1, 0.5)),
    ("above_separatrix", (1.0, 2.0, 3.0), (0.1, 0.2, 1.0)),
    ("above_separatrix", (3.0, 1.0, 2.0), (1.0, 0.1, 0.2)),  # moments not in ascending order
    ("below_separatrix", (2.0, 3.0, 1.5), (0.4, -0.3, 1.2)),
    ("separatrix", (3.0, 4.0, 6.0), (1.0, 0.3, 0.5)),  # I1 (I2-I1) w1^2 = I3 (I3-I2) w3^2 exactly
    ("separatrix", (3.0, 4.0, 6.0), (-1.0, 0.3, 0.5)),
    ("symmetric", (2.0, 2.0, 3.0), (0.3, 0.4, 0.5)),
    ("symmetric", (2.0, 3.0, 3.0), (0.3, 0.4, 0.5)),
    ("spherical", (2.0, 2.0, 2.0), (0.3, 0.4, 0.5)),
]


@pytest.mark.parametrize("case, moments, omega0", CASE_BODIES)
def test_case_label_and_initial_state(case, moments, omega0):
    sol = torque_free_solution(moments, omega0, Q0, t0=5.0)
    assert sol.case == case and sol.case in CASES
    q, w = sol.state(5.0)
    np.testing.assert_allclose(w, omega0, rtol=0, atol=1e-15 * 4)
    assert rotation_distance(q, Q0) < 1e-15 * 8


@pytest.mark.parametrize("case, moments, omega0", CASE_BODIES)
def test_matches_dop853_over_20_s(case, moments, omega0):
    t = np.linspace(0.0, 20.0, 9)
    sol = torque_free_solution(moments, omega0, Q0)
    q_ref, w_ref = reference(np.array(moments), np.array(omega0), Q0, t)
    scale = np.linalg.norm(omega0)
    assert np.max(np.abs(sol.omega(t) - w_ref)) < 1e-11 * scale
    assert np.max(rotation_distance(sol.quaternion(t), q_ref)) < 1e-11


@pytest.mark.parametrize(
    "moments, omega0",
    [((1.0, 2.0, 3.0), (1.0, 0.1, 0.5)), ((3.0, 2.0, 1.0), (0.1, 0.2, 1.0)), ((2.0, 2.0, 3.0), (0.3, 0.4, 0.5))],
)
def test_matches_dop853_at_1000_s(moments, omega0):
    sol = torque_free_solution(moments, omega0, Q0)
    q_ref, w_ref = reference(np.array(moments), np.array(omega0), Q0, [1000.0], tol=1e-12)
    # DOP853 at rtol = atol = 1e-12 is itself only good to ~1e-8 after 1000 s
    assert np.max(np.abs(sol.omega(1000.0) - w_ref[0])) < 5e-8 * np.linalg.norm(omega0)
    assert rotation_distance(sol.quaternion(1000.0), q_ref[0]) < 5e-8


@pytest.mark.parametrize("case, moments, omega0", CASE_BODIES)
def test_invariants_along_1000_s(case, moments, omega0):
    moments = np.array(moments)
    sol = torque_free_solution(moments, omega0, Q0)
    t = np.linspace(0.0, 1000.0, 4001)
    q, w = sol.state(t)
    energy = 0.5 * np.sum(moments * w * w, axis=1)
    l_world = Rotation.from_quat(q).apply(moments * w)
    l0 = sol.angular_momentum_world
    assert np.max(np.abs(energy / sol.energy - 1.0)) < 1e-13
    assert np.max(np.abs(np.linalg.norm(l_world, axis=1) / np.linalg.norm(l0) - 1.0)) < 1e-13
    assert np.max(np.linalg.norm(l_world - l0, axis=1)) < 1e-12 * np.linalg.norm(l0)


def test_symmetric_textbook_solution():
    """I1 = I2: (w1, w2) turns at (I3 - I1) w3 / I1 about e3; the body axis e3 cones about L."""
    i1, i3 = 2.0, 3.0
    w0 = np.array([0.3, 0.4, 0.5])
    sol = torque_free_solution((i1, i1, i3), w0, Q0)
    t = np.linspace(0.0, 1000.0, 101)
    rate = (i3 - i1) * w0[2] / i1
    c, s = np.cos(rate * t), np.sin(rate * t)
    w_exact = np.stack([c * w0[0] - s * w0[1], s * w0[0] + c * w0[1], np.full_like(t, w0[2])], axis=1)
    np.testing.assert_allclose(sol.omega(t), w_exact, rtol=0, atol=1e-13)
    # the symmetry axis precesses about L_world at |L| / I1 with a fixed cone angle
    l_world = sol.angular_momentum_world
    axis_world = Rotation.from_quat(sol.quaternion(t)).apply([0.0, 0.0, 1.0])
    l_hat = l_world / np.linalg.norm(l_world)
    axis0 = axis_world[0]
    expected = Rotation.from_rotvec(np.outer(t * np.linalg.norm(l_world) / i1, l_hat)).apply(axis0)
    np.testing.assert_allclose(axis_world, expected, rtol=0, atol=1e-12)


def test_nearly_symmetric_elliptic_path_tends_to_closed_form():
    """The elliptic-function path at m ~ 1e-10 agrees with the symmetric closed form."""
    w0 = (0.3, 0.4, 0.5)
    t = np.linspace(0.0, 50.0, 11)
    near = torque_free_solution((2.0, 2.0 * (1 + 1e-10), 3.0), w0, Q0)
    exact = torque_free_solution((2.0, 2.0, 3.0), w0, Q0)
    assert near.case == "above_separatrix" and exact.case == "symmetric"
    assert np.max(np.abs(near.omega(t) - exact.omega(t))) < 1e-8
    assert np.max(rotation_distance(near.quaternion(t), exact.quaternion(t))) < 1e-8


def test_separatrix_tends_to_middle_axis_spin():
    moments = np.array([3.0, 4.0, 6.0])
    sol = torque_free_solution(moments, (1.0, 0.3, 0.5), Q0)
    w = sol.omega(200.0)
    l_norm = np.linalg.norm(moments * np.array([1.0, 0.3, 0.5]))
    assert abs(w[0]) < 1e-30 and abs(w[2]) < 1e-30
    assert abs(abs(w[1]) - l_norm / moments[1]) < 1e-14


@pytest.mark.parametrize("omega0", [(0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 0.0)])
def test_stationary_spins(omega0):
    sol = torque_free_solution((1.0, 2.0, 3.0), omega0, Q0)
    t = np.array([0.0, 7.0, 1000.0])
    np.testing.assert_allclose(sol.omega(t), np.broadcast_to(omega0, (3, 3)), rtol=0, atol=1e-15)
    expected = Rotation.from_rotvec(np.outer(t, Rotation.from_quat(Q0).apply(omega0))) * Rotation.from_quat(Q0)
    assert np.max(rotation_distance(sol.quaternion(t), expected.as_quat())) < 1e-12


def test_group_property_near_separatrix():
    """Restarting from the state at t1 gives the same state at t1 + t2 (m = 1 - 1e-12)."""
    moments = np.array([3.0, 4.0, 6.0])
    w0 = np.array([1.0, 0.3, 0.5 * (1 + 1e-12)])
    sol = torque_free_solution(moments, w0, Q0)
    assert sol.case == "above_separatrix"
    q1, w1 = sol.state(37.0)
    restart = torque_free_solution(moments, w1, q1, t0=37.0)
    t = np.array([40.0, 55.0, 80.0])
    assert np.max(np.abs(restart.omega(t) - sol.omega(t))) < 1e-9
    assert np.max(rotation_distance(restart.quaternion(t), sol.quaternion(t))) < 1e-9


def test_vectorised_shapes():
    sol = torque_free_solution((1.0, 2.0, 3.0), (1.0, 0.1, 0.5))
    t = np.arange(6.0).reshape(2, 3)
    assert sol.omega(t).shape == (2, 3, 3) and sol.quaternion(t).shape == (2, 3, 4)
    assert sol.omega(1.0).shape == (3,) and sol.quaternion(1.0).shape == (4,)
    np.testing.assert_array_equal(sol.omega(t)[1, 2], sol.omega(5.0))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(moments=(1.0, -2.0, 3.0), omega0=(1.0, 0.0, 0.0)), r"moments\[1\]"),
        (dict(moments=(1.0, 1.0, 3.0), omega0=(1.0, 0.0, 0.0)), "triangle"),
        (dict(moments=(1.0, 2.0, 3.0), omega0=(1.0, np.nan, 0.0)), r"omega0\[1\]"),
        (dict(moments=(1.0, 2.0, 3.0), omega0=(1.0, 0.0, 0.0), q0=(0.0, 0.0, 0.0, 0.0)), "q0"),
        (dict(moments=(1.0, 2.0, 3.0), omega0=(1.0, 0.0, 0.0), t0=np.inf), "t0"),
    ],
)
def test_bad_input(kwargs, message):
    with pytest.raises(ValueError, match=message):
        torque_free_solution(**kwargs)


def test_non_finite_time_is_rejected():
    sol = torque_free_solution((1.0, 2.0, 3.0), (1.0, 0.1, 0.5))
    with pytest.raises(ValueError, match="t must be finite"):
        sol.omega([0.0, np.nan])


@pytest.mark.parametrize("ulps", [-3, -1, 1, 3, 1000])
def test_within_ulps_of_the_separatrix(ulps):
    """A few ulps off the separatrix: labelled 'separatrix' within 8 ulps, else by the sign of
    L^2 - 2 E I2; the solution stays finite and correct (ill-conditioned there: short horizon)."""
    w3 = 0.5
    for _ in range(abs(ulps)):
        w3 = np.nextafter(w3, np.inf if ulps > 0 else -np.inf)
    omega0 = np.array([1.0, 0.3, w3])
    sol = torque_free_solution((3.0, 4.0, 6.0), omega0, Q0)
    # L^2 - 2 E I2 = 6 * 2 * w3^2 - 3 * 1 * 1^2 = 12 w3^2 - 3 has the sign of ulps
    assert sol.case == ("separatrix" if abs(ulps) <= 3 else "above_separatrix")
    t = np.linspace(0.0, 10.0, 6)
    q_ref, w_ref = reference(np.array([3.0, 4.0, 6.0]), omega0, Q0, t)
    q, w = sol.state(t)
    assert np.all(np.isfinite(q)) and np.all(np.isfinite(w))
    assert np.max(np.abs(w - w_ref)) < 1e-11
    assert np.max(rotation_distance(q, q_ref)) < 1e-11


def test_scalar_and_array_evaluation_agree():
    for moments, omega0 in [
        ((1.0, 2.0, 3.0), (1.0, 0.1, 0.5)),
        ((3.0, 4.0, 6.0), (1.0, 0.3, 0.5)),
        ((2.0, 2.0, 3.0), (0.3, 0.4, 0.5)),
        ((2.0, 2.0, 2.0), (0.3, 0.4, 0.5)),
    ]:
        sol = torque_free_solution(moments, omega0, Q0)
        q_arr, w_arr = sol.state(np.array([123.25]))
        q, w = sol.state(123.25)
        np.testing.assert_allclose(w, w_arr[0], rtol=0, atol=1e-14)
        assert rotation_distance(q, q_arr[0]) < 1e-14
