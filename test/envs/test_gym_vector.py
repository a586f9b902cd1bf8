"""The native vector environments: Gymnasium's conventions; slot i == the single env seeded s_i, bit for bit."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import data_equivalence
from gymnasium.vector import AutoresetMode

import rigid_rot_sim.envs  # noqa: F401  (registers the ids)
from rigid_rot_sim.envs.attitude import AttitudeControlEnv, WheelAttitudeControlEnv
from rigid_rot_sim.envs.vector import AttitudeControlVectorEnv, WheelAttitudeControlVectorEnv, slot_seeds

IDS = ["RigidRot/AttitudeControl-v0", "RigidRot/WheelAttitudeControl-v0"]
SINGLE = {IDS[0]: AttitudeControlEnv, IDS[1]: WheelAttitudeControlEnv}
#: Short episodes that end both ways: loose tolerances terminate some, the horizon truncates others.
SHORT = {"max_episode_steps": 12, "angle_tolerance": 1.5, "rate_tolerance": 0.2, "hold_periods": 3}


@pytest.mark.parametrize(
    ("env_id", "cls"), list(zip(IDS, [AttitudeControlVectorEnv, WheelAttitudeControlVectorEnv], strict=True))
)
def test_make_vec_builds_the_native_vector_env_with_its_autoreset_mode(env_id, cls):
    envs = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point")
    assert type(envs) is cls
    assert envs.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    assert envs.num_envs == 3
    assert envs.single_observation_space == gym.make(env_id).observation_space
    assert envs.observation_space.shape == (3, *envs.single_observation_space.shape)
    assert envs.action_space.shape == (3, 3)
    assert envs.spec is not None and envs.spec.id == env_id
    obs, info = envs.reset(seed=0)
    assert obs in envs.observation_space
    assert info["principal_moments"].shape == (3, 3) and info["_principal_moments"].all()
    actions = envs.action_space.sample()
    obs, reward, terminated, truncated, info = envs.step(actions)
    assert obs in envs.observation_space
    assert reward.shape == (3,) and reward.dtype == np.float64
    assert terminated.dtype == np.bool_ and truncated.dtype == np.bool_
    envs.close()


def _run(envs, actions):
    """Every step's (obs, reward, terminated, truncated, info) under ``actions`` (steps, N, 3)."""
    return [envs.step(a) for a in actions]


@pytest.mark.parametrize("env_id", IDS)
def test_the_native_vector_env_matches_sync_vector_env_over_the_single_env_exactly(env_id):
    """Gymnasium's SyncVectorEnv defines NEXT_STEP autoreset: ours gives the same results, infos included."""
    n, steps = 5, 40
    seeds = [11, 12, 13, 14, 15]
    actions = np.random.default_rng(1).uniform(-1, 1, (steps, n, 3)).astype(np.float32)
    native = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **SHORT)
    sync = gym.make_vec(env_id, num_envs=n, vectorization_mode="sync", **SHORT)
    assert sync.metadata["autoreset_mode"] == native.metadata["autoreset_mode"]
    first_native, first_sync = native.reset(seed=seeds), sync.reset(seed=seeds)
    assert data_equivalence(first_native, first_sync, exact=True)
    ended = np.zeros(n, dtype=bool)
    restarted = np.zeros(n, dtype=bool)
    for a in actions:
        result_native, result_sync = native.step(a), sync.step(a)
        assert data_equivalence(result_native, result_sync, exact=True)
        assert result_native[0].tobytes() == result_sync[0].tobytes()
        restarted |= ended & ~result_native[2] & ~result_native[3]
        ended = result_native[2] | result_native[3]
    assert restarted.sum() >= 2  # the check covered autoresets


def _single_slot(env_id, seed, actions, **kwargs):
    """The single env reset with ``seed`` and driven by ``actions``, resetting itself as NEXT_STEP does."""
    env = SINGLE[env_id](**kwargs)  # the class itself: its own max_episode_steps, no wrapper
    obs, _ = env.reset(seed=seed)
    rows = [obs]
    done = False
    for a in actions:
        if done:
            obs, _ = env.reset()
            done = False
        else:
            obs, _, terminated, truncated, _ = env.step(a)
            done = terminated or truncated
        rows.append(obs)
    return np.array(rows)


@pytest.mark.parametrize("env_id", IDS)
def test_slot_i_is_the_single_env_seeded_s_i_bit_for_bit_over_episodes_with_resets(env_id):
    n, steps = 6, 45
    seeds = [int(s) for s in np.random.default_rng(3).integers(0, 2**63, n)]
    actions = np.random.default_rng(4).uniform(-1.2, 1.2, (steps, n, 3)).astype(np.float32)
    envs = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **SHORT)
    obs, _ = envs.reset(seed=seeds)
    history = [obs] + [envs.step(a)[0] for a in actions]
    history = np.array(history)  # (steps + 1, n, m)
    for i, seed in enumerate(seeds):
        alone = _single_slot(env_id, seed, actions[:, i], **SHORT)
        assert alone.tobytes() == np.ascontiguousarray(history[:, i]).tobytes(), f"slot {i}"


def test_one_seed_spawns_the_slots_seeds_by_the_documented_rule():
    seeds = slot_seeds(42, 4)
    assert seeds == [int(np.random.SeedSequence(42, spawn_key=(i,)).generate_state(1, np.uint64)[0]) for i in range(4)]
    assert slot_seeds(42, 2) == seeds[:2]  # a slot's seed does not depend on the number of slots
    assert len(set(seeds)) == 4
    envs = AttitudeControlVectorEnv(num_envs=4)
    obs, _ = envs.reset(seed=42)
    for i, seed in enumerate(seeds):
        single, _ = gym.make(IDS[0]).reset(seed=seed)
        assert single.tobytes() == obs[i].tobytes()


def test_sensors_in_the_vector_env_give_each_slot_the_single_envs_readings():
    n = 3
    actions = np.random.default_rng(5).uniform(-1, 1, (8, n, 3)).astype(np.float32)
    envs = AttitudeControlVectorEnv(num_envs=n, sensors=True)
    obs, _ = envs.reset(seed=[1, 2, 3])
    history = np.array([obs] + [envs.step(a)[0] for a in actions])
    for i, seed in enumerate([1, 2, 3]):
        alone = _single_slot(IDS[0], seed, actions[:, i], sensors=True)
        assert alone.tobytes() == np.ascontiguousarray(history[:, i]).tobytes()


def test_make_vec_passes_max_episode_steps_and_the_vector_env_truncates_there():
    envs = gym.make_vec(IDS[0], num_envs=2, vectorization_mode="vector_entry_point", max_episode_steps=3)
    envs.reset(seed=0)
    flags = [envs.step(np.zeros((2, 3)))[3].tolist() for _ in range(4)]
    assert flags == [[False, False], [False, False], [True, True], [False, False]]  # then the autoreset step


def test_bad_use_is_refused():
    envs = AttitudeControlVectorEnv(num_envs=2)
    with pytest.raises(RuntimeError, match="reset"):
        envs.step(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="2 slots"):
        envs.reset(seed=[1, 2, 3])
    with pytest.raises(ValueError, match="num_envs"):
        AttitudeControlVectorEnv(num_envs=0)
    envs.reset(seed=None)  # from entropy
    with pytest.raises(ValueError, match=r"\(2, 3\)"):
        envs.step(np.zeros(3))
    with pytest.raises(ValueError, match="finite"):
        envs.step(np.array([[0.0, 0.0, np.inf], [0.0, 0.0, 0.0]]))


def test_next_step_autoreset_as_gymnasium_defines_it():
    """An episode that ends at step k: step k + 1 ignores the action, resets the slot, reward 0, flags false."""
    loose = {"angle_tolerance": 4.0, "rate_tolerance": 10.0, "hold_periods": 2}  # every episode ends at step 2
    envs = AttitudeControlVectorEnv(num_envs=2, **loose)
    single = AttitudeControlEnv(**loose)
    obs, _ = envs.reset(seed=[5, 6])
    single.reset(seed=5)
    first = envs.step(np.zeros((2, 3)))
    assert first[2].tolist() == [False, False]
    obs, reward, terminated, truncated, info = envs.step(np.zeros((2, 3)))
    assert terminated.tolist() == [True, True] and not truncated.any() and np.all(reward <= 0.0)
    assert info == {}
    obs, reward, terminated, truncated, info = envs.step(np.full((2, 3), 1.0))  # the action is ignored
    assert reward.tolist() == [0.0, 0.0] and not terminated.any() and not truncated.any()
    assert info["_principal_moments"].tolist() == [True, True]  # the resets' infos, masked
    single.step(np.zeros(3))
    single.step(np.zeros(3))
    restarted, single_info = single.reset()  # the next episode of the same generator
    assert restarted.tobytes() == obs[0].tobytes()
    assert single_info["principal_moments"].tobytes() == info["principal_moments"][0].tobytes()
    assert envs.step(np.zeros((2, 3)))[2].tolist() == [False, False]  # a fresh episode: step 1 of 2
