"""Euler's equations, invariants, frames and the principal-axes set-up of RigidBody.

The sign conventions are checked against the law they come from, dL_world/dt = N_world,
not against a transcription of the formulas.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core import dynamics, validation
from rigid_rot_sim.core.dynamics import RigidBody

RNG = np.random.default_rng(20261122)
MOMENTS = np.array([1.0, 2.0, 3.0])


def random_state():
    q = Rotation.random(random_state=RNG).as_quat()
    return q, RNG.normal(size=3), RNG.normal(size=3)


@pytest.mark.parametrize("seed", range(5))
def test_euler_rhs_is_dL_world_dt_equals_torque(seed):
    """d/dt (R I omega) = R N, with dR/dt from quaternion_derivative, by central differences."""
    q, omega, torque = random_state()
    alpha = dynamics.euler_rhs(MOMENTS, omega, torque)
    qdot = dynamics.quaternion_derivative(q, omega)
    h = 1e-6

    def L_world(s):
        qs = q + s * qdot
        return dynamics.angular_momentum_world(MOMENTS, qs / np.linalg.norm(qs), omega + s * alpha)

    dL = (L_world(h) - L_world(-h)) / (2 * h)
    assert np.allclose(dL, dynamics.body_to_world(q, torque), atol=1e-8)


def test_euler_rhs_component_form():
    i1, i2, i3 = MOMENTS
    w = np.array([0.3, -1.2, 0.7])
    n = np.array([0.1, 0.2, -0.4])
    expected = [
        ((i2 - i3) * w[1] * w[2] + n[0]) / i1,
        ((i3 - i1) * w[2] * w[0] + n[1]) / i2,
        ((i1 - i2) * w[0] * w[1] + n[2]) / i3,
    ]
    assert np.allclose(dynamics.euler_rhs(MOMENTS, w, n), expected, rtol=1e-15)
    assert np.allclose(dynamics.euler_rhs(MOMENTS, w), np.array(expected) - n / MOMENTS, rtol=1e-15)


def test_euler_rhs_vectorised():
    omega = RNG.normal(size=(4, 5, 3))
    got = dynamics.euler_rhs(MOMENTS, omega)
    assert got.shape == (4, 5, 3)
    assert np.allclose(got[2, 3], dynamics.euler_rhs(MOMENTS, omega[2, 3]))


def test_quaternion_derivative_matches_body_rate_rotation():
    """q(t) = q0 (x) exp(omega t) for constant body omega: dq/dt at t = 0 by differences."""
    q0, omega, _ = random_state()
    h = 1e-6
    qp = (Rotation.from_quat(q0) * Rotation.from_rotvec(omega * h)).as_quat(canonical=False)
    qm = (Rotation.from_quat(q0) * Rotation.from_rotvec(-omega * h)).as_quat(canonical=False)
    qp *= np.sign(qp @ q0)
    qm *= np.sign(qm @ q0)
    assert np.allclose(dynamics.quaternion_derivative(q0, omega), (qp - qm) / (2 * h), atol=1e-9)


def test_energy_and_momentum():
    q, omega, _ = random_state()
    L = dynamics.angular_momentum_body(MOMENTS, omega)
    assert np.allclose(L, MOMENTS * omega)
    assert np.isclose(dynamics.kinetic_energy(MOMENTS, omega), 0.5 * omega @ (MOMENTS * omega))
    assert np.allclose(dynamics.angular_momentum_world(MOMENTS, q, omega), Rotation.from_quat(q).apply(L))
    many = RNG.normal(size=(7, 3))
    assert dynamics.kinetic_energy(MOMENTS, many).shape == (7,)


def test_body_world_round_trip():
    q = Rotation.random(6, random_state=RNG).as_quat()
    v = RNG.normal(size=(6, 3))
    w = dynamics.body_to_world(q, v)
    assert np.allclose(w, Rotation.from_quat(q).apply(v))
    assert np.allclose(dynamics.world_to_body(q, w), v)
    assert dynamics.body_to_world(q[0], v[0]).shape == (3,)


def test_rigid_body_from_principal_moments():
    body = RigidBody.from_inertia([3.0, 1.0, 2.5])
    assert body.is_principal
    assert np.array_equal(body.principal_moments, [3.0, 1.0, 2.5])
    assert np.array_equal(body.inertia_tensor, np.diag([3.0, 1.0, 2.5]))


def test_rigid_body_diagonal_tensor_keeps_axes():
    body = RigidBody.from_inertia(np.diag([3.0, 1.0, 2.5]))
    assert body.is_principal
    assert np.array_equal(body.principal_moments, [3.0, 1.0, 2.5])


def test_rigid_body_full_tensor_is_rotated_to_principal_axes():
    r = Rotation.from_rotvec([0.3, -0.7, 1.1])
    moments = np.array([2.0, 3.0, 4.5])
    tensor = r.as_matrix() @ np.diag(moments) @ r.as_matrix().T
    body = RigidBody.from_inertia(tensor)
    assert not body.is_principal
    assert np.allclose(np.sort(body.principal_moments), moments)
    axes = Rotation.from_quat(body.body_from_principal).as_matrix()
    assert np.isclose(np.linalg.det(axes), 1.0)
    assert np.allclose(axes @ np.diag(body.principal_moments) @ axes.T, tensor, atol=1e-12)
    # vectors and attitudes round-trip, and L, T agree in both frames
    omega_body = np.array([0.4, -0.1, 0.9])
    omega_p = body.vector_to_principal(omega_body)
    assert np.allclose(body.vector_from_principal(omega_p), omega_body)
    assert np.isclose(dynamics.kinetic_energy(body.principal_moments, omega_p), 0.5 * omega_body @ tensor @ omega_body)
    q_body = Rotation.from_rotvec([1.0, 0.2, -0.3]).as_quat()
    q_p = body.attitude_to_principal(q_body)
    assert np.allclose(
        dynamics.angular_momentum_world(body.principal_moments, q_p, omega_p),
        Rotation.from_quat(q_body).apply(tensor @ omega_body),
    )
    back = body.attitude_from_principal(q_p)
    assert np.allclose(back * np.sign(back @ q_body), q_body)


@pytest.mark.parametrize(
    "inertia, match",
    [
        ([1.0, -2.0, 3.0], r"inertia\[1\] must be > 0"),
        ([1.0, 0.0, 3.0], r"inertia\[1\] must be > 0"),
        ([1.0, np.nan, 3.0], r"inertia\[1\] must be finite"),
        ([1.0, 1.0, 3.0], "triangle inequality"),
        ([5.0, 1.0, 1.0], "triangle inequality"),
        ([[1.0, 0.5, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.5]], "symmetric"),
        ([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 3.0]], "triangle inequality"),
        ([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 2.0]], "must be > 0"),
        ([[1.0, 0.0], [0.0, 1.0]], "3 principal moments or a 3x3 tensor"),
        ([1.0, np.inf, 1.0], "finite"),
    ],
)
def test_rigid_body_rejects_unphysical_inertia(inertia, match):
    with pytest.raises(ValueError, match=match):
        RigidBody.from_inertia(inertia)


def test_triangle_inequality_holds_up_to_rounding():
    # a thin plate: I3 = I1 + I2, off by a rounding error
    validation.principal_moments("inertia", [1.0, 2.0, 3.0 * (1 + 1e-15)])
    with pytest.raises(ValueError, match="triangle"):
        validation.principal_moments("inertia", [1.0, 2.0, 3.0 * (1 + 1e-9)])


def test_validation_helpers_name_the_argument():
    assert validation.positive_scalar("dt", "0.5") == 0.5
    with pytest.raises(ValueError, match="dt must be > 0"):
        validation.positive_scalar("dt", 0.0)
    with pytest.raises(ValueError, match="dt must be finite"):
        validation.positive_scalar("dt", float("nan"))
    with pytest.raises(ValueError, match="t_end must be >= 0"):
        validation.nonnegative_scalar("t_end", -1.0)
    with pytest.raises(ValueError, match="dt must be a real number"):
        validation.positive_scalar("dt", "fast")
    with pytest.raises(ValueError, match=r"omega0\[2\] must be finite"):
        validation.finite_vector("omega0", [0.0, 1.0, np.inf])
    with pytest.raises(ValueError, match=r"omega0 must have shape \(3,\)"):
        validation.finite_vector("omega0", [0.0, 1.0])
    with pytest.raises(ValueError, match="q0 must be a non-zero quaternion"):
        validation.quaternion("q0", [0.0, 0.0, 0.0, 0.0])
    assert np.allclose(validation.quaternion("q0", [0, 0, 0, 2]), [0, 0, 0, 1])
