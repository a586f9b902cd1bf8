"""``field_observation=True``: the body-axis magnetic field ends the observation; off, nothing changes."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from scipy.spatial.transform import Rotation

import rigid_rot_sim.envs
from rigid_rot_sim.core import geomagnetic
from rigid_rot_sim.envs.task import FIELD_POINT, world_field

IDS = ["rigid_rot_sim.envs:RigidRot/AttitudeControl-v0", "rigid_rot_sim.envs:RigidRot/WheelAttitudeControl-v0"]
WIDTH = {IDS[0]: 10, IDS[1]: 13}


def test_the_world_field_is_igrf14s_dipole_at_the_point_in_tesla():
    assert rigid_rot_sim.envs.ENV_IDS  # the package registered the ids
    expected = geomagnetic.field_ned("dipole", *FIELD_POINT) * 1e-9
    assert np.array_equal(np.array(world_field()), expected)
    assert 2.0e-5 < np.linalg.norm(expected) < 3.0e-5  # a dipole of ~29.4 uT at the surface, (6371/6871)^3 at 500 km


@pytest.mark.parametrize("env_id", IDS)
def test_the_field_columns_are_the_world_field_in_the_body_axes_and_the_rest_is_unchanged(env_id):
    plain = gym.make(env_id)
    field = gym.make(env_id, field_observation=True)
    n = WIDTH[env_id]
    assert plain.observation_space.shape == (n,) and field.observation_space.shape == (n + 3,)
    assert field.observation_space.low[:n].tolist() == plain.observation_space.low.tolist()
    (o_plain, _), (o_field, _) = plain.reset(seed=5), field.reset(seed=5)
    rng = np.random.default_rng(0)
    b_world = np.array(world_field())
    for _ in range(20):
        assert np.array_equal(o_field[:n], o_plain)  # the same bits besides the field
        q = field.unwrapped.bodies.q[0]  # the true attitude, body -> world
        np.testing.assert_allclose(o_field[n:], Rotation.from_quat(q).inv().apply(b_world), rtol=0, atol=1e-18)
        assert np.linalg.norm(o_field[n:]) == pytest.approx(np.linalg.norm(b_world), rel=1e-14)
        assert field.observation_space.contains(o_field)
        action = rng.uniform(-1, 1, 3).astype(np.float32)
        o_plain, *_ = plain.step(action)
        o_field, *_ = field.step(action)


@pytest.mark.parametrize("env_id", IDS)
def test_spaces_and_bits_are_the_same_on_every_path_with_the_field(env_id):
    single = gym.make(env_id, field_observation=True)
    reference = (single.observation_space, single.action_space)
    for mode in ("sync", "vector_entry_point"):
        envs = gym.make_vec(env_id, num_envs=2, vectorization_mode=mode, field_observation=True)
        assert (envs.single_observation_space, envs.single_action_space) == reference, mode
        assert envs.observation_space == gym.vector.utils.batch_space(reference[0], 2), mode
        obs, _ = envs.reset(seed=[3, 4])
        first, _ = single.reset(seed=3)
        assert np.array_equal(obs[0], first), mode
        envs.close()


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("sensors", [None, True])
def test_check_env_passes_without_a_warning_with_the_field(env_id, sensors):
    env = gym.make(env_id, field_observation=True, sensors=sensors)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)


def test_field_observation_must_be_a_bool():
    with pytest.raises(ValueError, match="field_observation must be True or False"):
        gym.make(IDS[0], field_observation=1)
