"""Tests for rigid_rot_sim.core.frames: the one home of the principal <-> body frame conversion."""

import numpy as np
import pytest

from rigid_rot_sim.core import frames
from rigid_rot_sim.core.dynamics import RigidBody

RNG = np.random.default_rng(28)
TENSOR = np.array([[2.0, 0.3, -0.1], [0.3, 3.0, 0.2], [-0.1, 0.2, 4.0]])


def random_quaternions(n):
    q = RNG.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def test_the_float_formulas_agree_with_the_bodys_trajectory_methods():
    body = RigidBody.from_inertia(TENSOR)
    assert not body.is_principal
    bp = tuple(body.body_from_principal.tolist())
    pb = frames.principal_from_body(bp)
    for q_p, v in zip(random_quaternions(20), RNG.normal(size=(20, 3)), strict=True):
        q_b = frames.attitude_from_principal(tuple(q_p), pb)
        np.testing.assert_allclose(
            np.sign(q_b[3]) * np.array(q_b),
            np.sign(body.attitude_from_principal(q_p)[3]) * body.attitude_from_principal(q_p),
            atol=1e-15,
        )
        np.testing.assert_allclose(
            frames.vector_from_principal(bp, tuple(v)), body.vector_from_principal(v), atol=1e-15
        )
        np.testing.assert_allclose(frames.vector_to_principal(pb, tuple(v)), body.vector_to_principal(v), atol=1e-15)
        # there and back
        np.testing.assert_allclose(frames.attitude_to_principal(q_b, bp), q_p, atol=1e-15)
        np.testing.assert_allclose(
            frames.vector_to_principal(pb, frames.vector_from_principal(bp, tuple(v))), v, atol=1e-15
        )


def test_columns_give_each_row_the_bits_of_a_per_body_call():
    """The sweep calls these on columns (one body per row); the engine on floats: the same bits."""
    q, pb, v = random_quaternions(50), random_quaternions(50), RNG.normal(size=(50, 3))
    attitudes = np.stack(frames.attitude_from_principal(q.T, pb.T), axis=-1)
    vectors = np.stack(frames.vector_to_principal(pb.T, v.T), axis=-1)
    for i in range(50):
        assert tuple(attitudes[i]) == frames.attitude_from_principal(tuple(q[i]), tuple(pb[i]))
        assert tuple(vectors[i]) == frames.vector_to_principal(tuple(pb[i]), tuple(v[i]))


@pytest.mark.parametrize(
    "module",
    [
        "rigid_rot_sim/run/observables.py",
        "rigid_rot_sim/run/stepper.py",
        "rigid_rot_sim/core/simulate.py",
        "rigid_rot_sim/sweep/chunks.py",
    ],
)
def test_the_users_ask_the_one_home(module):
    """No user re-spells the conversion with the raw quaternion helpers (the review found six copies)."""
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / module).read_text(encoding="utf-8")
    assert "frames." in text
    for spelled in ("quat.multiply(q_principal", "quat.rotate(body_from_principal", "quat.rotate(principal_from_body"):
        assert spelled not in text
