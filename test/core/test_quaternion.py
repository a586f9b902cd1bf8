"""Quaternion helpers against scipy's Rotation (scalar-last, body -> world) and identities."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core import quaternion as quat

finite = st.floats(-10.0, 10.0, allow_nan=False)
vectors = st.tuples(finite, finite, finite)
quaternions = st.tuples(finite, finite, finite, finite).filter(lambda q: math.fsum(x * x for x in q) > 1e-6)


def unit(q):
    return np.asarray(q) / np.linalg.norm(q)


def same_rotation(p, q, atol=1e-12):
    """Equal as rotations (q and -q are the same rotation)."""
    p, q = np.asarray(p), np.asarray(q)
    return np.allclose(p, q, atol=atol) or np.allclose(p, -q, atol=atol)


@settings(max_examples=200, deadline=None)
@given(quaternions, quaternions)
def test_multiply_is_scipy_composition(p, q):
    p, q = unit(p), unit(q)
    expected = (Rotation.from_quat(p) * Rotation.from_quat(q)).as_quat()
    assert same_rotation(quat.multiply(p, q), expected)


def test_multiply_is_the_hamilton_product():
    i, j, k, one = (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)
    assert quat.multiply(i, j) == k
    assert quat.multiply(j, k) == i
    assert quat.multiply(k, i) == j
    assert quat.multiply(i, i) == (0, 0, 0, -1)
    assert quat.multiply(one, (1.0, 2.0, 3.0, 4.0)) == (1.0, 2.0, 3.0, 4.0)


@settings(max_examples=100, deadline=None)
@given(quaternions)
def test_conjugate_is_inverse(q):
    q = unit(q)
    assert np.allclose(quat.multiply(q, quat.conjugate(q)), quat.IDENTITY, atol=1e-15)
    assert same_rotation(quat.conjugate(q), Rotation.from_quat(q).inv().as_quat())


@settings(max_examples=200, deadline=None)
@given(vectors)
def test_exp_rotation_vector_is_scipy_from_rotvec(v):
    expected = Rotation.from_rotvec(v).as_quat()
    got = quat.exp_rotation_vector(v)
    assert same_rotation(got, expected, atol=1e-14)
    assert math.isclose(math.fsum(x * x for x in got), 1.0, rel_tol=0, abs_tol=1e-15)


@pytest.mark.parametrize("angle", [0.0, 1e-300, 1e-12, 1e-9, 1e-8, 1.0001e-8, 1e-6, 1e-3])
def test_exp_rotation_vector_small_angles(angle):
    v = angle * np.array([0.6, -0.8, 0.0])
    got = np.array(quat.exp_rotation_vector(v))
    expected = np.array([*(math.sin(angle / 2) * np.array([0.6, -0.8, 0.0])), math.cos(angle / 2)])
    assert np.allclose(got, expected, rtol=1e-15, atol=1e-300)
    assert np.all(np.isfinite(got))


@settings(max_examples=100, deadline=None)
@given(vectors)
def test_cayley_is_the_matrix_cayley_transform(v):
    v = np.asarray(v)
    hat = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    eye = np.eye(3)
    expected = np.linalg.solve(eye - hat / 2, eye + hat / 2)
    got = Rotation.from_quat(quat.cayley(v)).as_matrix()
    assert np.allclose(got, expected, atol=1e-12 * max(1.0, np.linalg.norm(v)))


@settings(max_examples=200, deadline=None)
@given(quaternions, vectors)
def test_rotate_is_body_to_world(q, v):
    q = unit(q)
    r = Rotation.from_quat(q)
    assert np.allclose(quat.rotate(q, v), r.apply(v), atol=1e-12)
    assert np.allclose(quat.rotate_inverse(q, v), r.apply(v, inverse=True), atol=1e-12)
    assert np.allclose(quat.rotate_inverse(q, quat.rotate(q, v)), v, atol=1e-12)


def test_rotate_convention_quarter_turn_about_z():
    q = (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))  # +90 deg about z, body -> world
    assert np.allclose(quat.rotate(q, (1.0, 0.0, 0.0)), (0.0, 1.0, 0.0), atol=1e-15)


@settings(max_examples=50, deadline=None)
@given(quaternions)
def test_normalize(q):
    n = quat.normalize(q)
    assert math.isclose(math.fsum(x * x for x in n), 1.0, abs_tol=1e-15)
    assert np.allclose(np.asarray(n) * np.linalg.norm(q), q, rtol=1e-14, atol=1e-14)


def test_zxz_quaternion_matches_scipy():
    angles = np.array([[0.3, 1.1, -0.7], [2.5, 0.0, 1.0], [-3.0, 3.0, 0.2]])
    q = quat.zxz_to_quaternion(angles[:, 0], angles[:, 1], angles[:, 2])
    distance = (Rotation.from_quat(q).inv() * Rotation.from_euler("ZXZ", angles)).magnitude()
    assert np.max(distance) < 1e-15 * 8


def _bits(rotation):
    return rotation.as_quat(canonical=False).view(np.uint64)


def test_compose_rotations_gives_scipys_bits():
    """Arrays (unit, far from unit, from rotation vectors), one against many, single ones, inverses."""
    rng = np.random.default_rng(5)
    n = 20_000
    a = Rotation.from_quat(rng.normal(size=(n, 4)) * rng.choice([1.0, 1e-3, 1e5], size=(n, 1)))
    b = Rotation.from_quat(rng.normal(size=(n, 4)))
    v = Rotation.from_rotvec(rng.normal(size=(n, 3)) * rng.choice([1e-9, 1e-3, 3.0], size=(n, 1)))
    for p, q in ((a, b), (a, v), (v, a), (a[:1], v), (v, a[0]), (a.inv(), b), (a[3], v[7])):
        ours, theirs = quat.compose_rotations(p, q), p * q
        assert ours.single == theirs.single and np.array_equal(_bits(ours), _bits(theirs))
    assert np.array_equal(quat.compose_rotations(a.inv(), b).magnitude(), (a.inv() * b).magnitude())
