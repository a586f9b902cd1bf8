"""The slew task's arithmetic: the error rotation vector, the reward and the hold count."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.slew import attitude_error, slew_update


def test_the_error_is_the_rotation_vector_from_the_target_to_the_attitude():
    rng = np.random.default_rng(0)
    for _ in range(50):
        target = Rotation.random(random_state=rng)
        v = rng.normal(size=3)
        v *= rng.uniform(0.0, 3.1) / np.linalg.norm(v)
        q = (target * Rotation.from_rotvec(v)).as_quat()
        e, angle = attitude_error(q, target.as_quat())
        np.testing.assert_allclose(e, v, rtol=0, atol=1e-12)
        assert math.isclose(angle, np.linalg.norm(v), abs_tol=1e-12)
        # -q is the same attitude: the same error, the shorter way round
        e_neg, _ = attitude_error(-q, target.as_quat())
        np.testing.assert_array_equal(e_neg, e)


def test_no_error_at_the_target_and_pi_at_the_far_side():
    target = np.array([0.1, -0.2, 0.3, 0.9]) / np.linalg.norm([0.1, -0.2, 0.3, 0.9])
    e, angle = attitude_error(target, target)
    assert angle < 1e-15 and np.all(np.abs(e) < 1e-15)  # round-off of conj(t) (x) t
    e, angle = attitude_error(np.array([0.0, 0.0, 0.0, 1.0]), np.array([0.0, 0.0, 0.0, 1.0]))
    assert angle == 0.0 and e.tolist() == [0.0, 0.0, 0.0]  # v = 0 exactly: no division
    flipped = (Rotation.from_quat(target) * Rotation.from_rotvec([0.0, 0.0, math.pi])).as_quat()
    e, angle = attitude_error(flipped, target)
    assert math.isclose(angle, math.pi, rel_tol=1e-12)
    assert math.isclose(abs(e[2]), math.pi, rel_tol=1e-12)


def test_reward_observation_and_hold_count():
    n = 3
    identity = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    q = identity.copy()
    q[1] = Rotation.from_rotvec([0.2, 0.0, 0.0]).as_quat()
    omega = np.array([[0.0, 0.0, 0.001], [0.0, 0.3, 0.4], [0.0, 0.0, 0.0]])
    action = np.array([[0.0, 0.0, 0.0], [1.0, -1.0, 0.5], [0.0, 0.0, 0.0]])
    weights = np.array([1.0, 0.1, 0.01])
    tolerances = np.array([0.01, 0.005, 2.0])
    hold = np.array([0, 5, 1], dtype=np.int64)
    observation = np.zeros((n, 13))
    reward = np.zeros(n)
    terminated = slew_update(q, omega, q, omega, identity, action, weights, tolerances, hold, observation, reward, True)
    assert hold.tolist() == [1, 0, 2]  # within: counted; outside: back to 0
    assert terminated.tolist() == [False, False, True]
    assert math.isclose(reward[1], -(0.2 + 0.1 * 0.5 + 0.01 * 2.25), rel_tol=1e-12)
    assert reward[0] == -0.1 * 0.001 and reward[2] == 0.0
    np.testing.assert_array_equal(observation[:, :4], q)
    np.testing.assert_array_equal(observation[:, 4:7], omega)
    np.testing.assert_allclose(observation[1, 7:10], [0.2, 0.0, 0.0], atol=1e-15)
    assert not observation[:, 10:].any()  # columns past 10 are the caller's


def test_an_observed_state_changes_the_observation_not_the_reward():
    n = 1
    identity = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    seen = Rotation.from_rotvec([[0.0, 0.1, 0.0]]).as_quat()
    args = (np.array([[0.0, 0.0, 1.0]]), identity, np.zeros((n, 3)), identity, np.zeros((n, 3)), np.ones(3), np.ones(3))
    observation, reward = np.zeros((n, 10)), np.zeros(n)
    slew_update(seen, *args, np.zeros(n, dtype=np.int64), observation, reward, False)
    np.testing.assert_allclose(observation[0, 7:10], [0.0, 0.1, 0.0], atol=1e-15)
    assert observation[0, 6] == 1.0
    assert reward[0] == 0.0  # the true state is at the target, at rest
