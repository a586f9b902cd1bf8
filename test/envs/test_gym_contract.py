"""The native vector environments against Gymnasium 1.x's vector contract, with Gymnasium's own classes as
the reference: reset_mask, the three autoreset modes, RecordEpisodeStatistics, and spaces on every path."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import data_equivalence
from gymnasium.vector import AutoresetMode
from gymnasium.wrappers.vector import RecordEpisodeStatistics

import rigid_rot_sim.envs  # registers the ids
from rigid_rot_sim.envs.attitude import TASK_ARGUMENTS, AttitudeControlEnv
from rigid_rot_sim.envs.vector import AttitudeControlVectorEnv

IDS = ["RigidRot/AttitudeControl-v0", "RigidRot/WheelAttitudeControl-v0"]
#: Short episodes that end both ways: loose tolerances terminate some, the horizon truncates others.
SHORT = {"max_episode_steps": 12, "angle_tolerance": 1.5, "rate_tolerance": 0.2, "hold_periods": 3}
SEEDS = [21, 22, 23, 24, 25]


def _pair(env_id, mode, **kwargs):
    native = gym.make_vec(
        env_id, num_envs=len(SEEDS), vectorization_mode="vector_entry_point", autoreset_mode=mode, **kwargs
    )
    sync = gym.make_vec(
        env_id, num_envs=len(SEEDS), vectorization_mode="sync", vector_kwargs={"autoreset_mode": mode}, **kwargs
    )
    return native, sync


def _same(a, b):
    assert data_equivalence(a, b, exact=True)
    assert a[0].tobytes() == b[0].tobytes()  # the observations to the bit (== does not see -0.0 and 0.0 apart)


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_each_autoreset_mode_equals_sync_vector_env_over_the_single_env_slot_by_slot(env_id, mode):
    """Observations, rewards, flags and infos (final_obs included) to the bit, through autoresets."""
    native, sync = _pair(env_id, mode, **SHORT)
    assert native.metadata["autoreset_mode"] is mode is sync.metadata["autoreset_mode"]
    _same(native.reset(seed=SEEDS), sync.reset(seed=SEEDS))
    actions = np.random.default_rng(7).uniform(-1, 1, (40, len(SEEDS), 3)).astype(np.float32)
    ends = 0
    for a in actions:
        result = native.step(a)
        _same(result, sync.step(a))
        ends += int(np.sum(result[2] | result[3]))
    assert ends >= 5  # the comparison went through autoresets (SAME_STEP: final_obs compared too)


@pytest.mark.parametrize("env_id", IDS)
def test_disabled_autoreset_with_reset_mask_equals_sync_vector_env(env_id):
    native, sync = _pair(env_id, AutoresetMode.DISABLED, **SHORT)
    _same(native.reset(seed=SEEDS), sync.reset(seed=SEEDS))
    actions = np.random.default_rng(8).uniform(-1, 1, (40, len(SEEDS), 3)).astype(np.float32)
    resets = 0
    for a in actions:
        result = native.step(a)
        _same(result, sync.step(a))
        ended = result[2] | result[3]
        if ended.any():
            with pytest.raises(RuntimeError, match="DISABLED"):
                native.step(a)  # an ended slot is not stepped on
            _same(native.reset(options={"reset_mask": ended.copy()}), sync.reset(options={"reset_mask": ended.copy()}))
            resets += 1
    assert resets >= 3


@pytest.mark.parametrize("env_id", IDS)
def test_reset_mask_resets_only_those_slots_as_sync_vector_env_does(env_id):
    """The other slots keep their state, step count and generator: the same bits as SyncVectorEnv's slots."""
    native, sync = _pair(env_id, AutoresetMode.NEXT_STEP, **SHORT)
    _same(native.reset(seed=SEEDS), sync.reset(seed=SEEDS))
    rng = np.random.default_rng(9)
    for k in range(30):
        a = rng.uniform(-1, 1, (len(SEEDS), 3)).astype(np.float32)
        before = native.step(a)
        _same(before, sync.step(a))
        if k % 4 == 3:
            mask = rng.random(len(SEEDS)) < 0.5
            mask[k % len(SEEDS)] = True
            seeds = [100 + k if (m and k % 8 == 3) else None for m in mask]  # some reseeded, some continued
            options = {"reset_mask": mask}
            after = native.reset(seed=seeds, options=options)
            assert options["reset_mask"] is mask  # the caller's options are left alone
            _same(after, sync.reset(seed=seeds, options={"reset_mask": mask.copy()}))
            assert after[0][~mask].tobytes() == before[0][~mask].tobytes()
            assert not after[1]["_principal_moments"][~mask].any()


def test_reset_mask_is_checked_as_gymnasium_checks_it():
    envs = AttitudeControlVectorEnv(num_envs=3)
    with pytest.raises(RuntimeError, match="every slot"):
        envs.reset(options={"reset_mask": np.array([True, False, False])})
    envs.reset(seed=0)
    with pytest.raises(TypeError, match="numpy array"):
        envs.reset(options={"reset_mask": [True, False, False]})
    with pytest.raises(ValueError, match=r"shape `\(3,\)`"):
        envs.reset(options={"reset_mask": np.array([True, False])})
    with pytest.raises(TypeError, match="dtype=np.bool_"):
        envs.reset(options={"reset_mask": np.array([1, 0, 0])})
    with pytest.raises(ValueError, match="at least one True"):
        envs.reset(options={"reset_mask": np.zeros(3, dtype=bool)})


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_record_episode_statistics_with_partial_resets_counts_no_episode_longer_than_the_limit(mode):
    """The user's report: with partial resets RecordEpisodeStatistics saw 310-step episodes, limit 300."""
    limit, n = 300, 8
    envs = RecordEpisodeStatistics(
        gym.make_vec(IDS[0], n, vectorization_mode="vector_entry_point", autoreset_mode=mode), buffer_length=1000
    )
    envs.reset(seed=1)
    rng = np.random.default_rng(2)
    lengths = []
    partial = {150: [0, 1], 420: [2, 3, 4]}  # slots restarted by hand, mid-episode, the others running on
    for k in range(1000):
        _, _, terminated, truncated, info = envs.step(rng.uniform(-1, 1, (n, 3)).astype(np.float32))
        if "episode" in info:
            lengths += info["episode"]["l"][info["_episode"]].tolist()
        if k in partial:
            mask = np.zeros(n, dtype=bool)
            mask[partial[k]] = True
            assert not (terminated | truncated)[mask].any()
            envs.reset(options={"reset_mask": mask})
    assert len(lengths) >= n
    assert max(lengths) == limit  # truncations counted at the limit, never beyond it


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("steps", [None, 50])
def test_spaces_are_the_single_envs_on_every_path_whatever_the_episode_length(env_id, steps):
    kwargs = {} if steps is None else {"max_episode_steps": steps}
    single = gym.make(env_id, **kwargs)
    reference = (single.observation_space, single.action_space)
    assert reference[0] == gym.make(env_id).observation_space  # max_episode_steps changes no bound
    for mode in ("sync", "async", "vector_entry_point"):
        envs = gym.make_vec(env_id, num_envs=2, vectorization_mode=mode, **kwargs)
        assert (envs.single_observation_space, envs.single_action_space) == reference, mode
        assert envs.observation_space == gym.vector.utils.batch_space(reference[0], 2), mode
        envs.close()
    assert AttitudeControlEnv(max_episode_steps=7).observation_space == AttitudeControlEnv().observation_space
    with pytest.raises(ValueError, match="observation_horizon"):
        AttitudeControlEnv(max_episode_steps=301)
    longer = AttitudeControlEnv(max_episode_steps=600, observation_horizon=600)  # longer episodes: bounds sized on
    assert np.all(longer.observation_space.high[4:7] > single.observation_space.high[4:7])


def test_autoreset_mode_is_a_vector_argument_and_unknown_arguments_name_the_env():
    envs = gym.make_vec(IDS[1], num_envs=2, vectorization_mode="vector_entry_point", autoreset_mode="SameStep")
    assert envs.metadata["autoreset_mode"] is AutoresetMode.SAME_STEP
    assert AttitudeControlVectorEnv.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP  # the class is untouched
    with pytest.raises(ValueError, match="AutoresetMode.SAME_STEP"):
        AttitudeControlVectorEnv(autoreset_mode="sometimes")
    for make in (
        lambda: gym.make(IDS[0], autoreset_mode=AutoresetMode.SAME_STEP),
        lambda: gym.make_vec(IDS[0], 2, vectorization_mode="sync", autoreset_mode=AutoresetMode.SAME_STEP),
    ):
        with pytest.raises(TypeError, match="AttitudeControlEnv: unexpected argument 'autoreset_mode'") as caught:
            make()
        assert "SlewTask" not in str(caught.value) and "vector_kwargs" in str(caught.value)
    with pytest.raises(TypeError, match="WheelAttitudeControlVectorEnv: unexpected argument 'max_torqe'") as caught:
        gym.make_vec(IDS[1], 2, vectorization_mode="vector_entry_point", max_torqe=1.0)
    assert all(name in str(caught.value) for name in ("num_envs", "autoreset_mode", "sensors", *TASK_ARGUMENTS))


def test_the_wheel_env_at_scale_runs_the_parallel_simd_kernel_with_the_single_envs_bits():
    """2048 slots x 10 RK4 steps a step: the parallel structure-of-arrays kernel; sampled slots == the single env."""
    n, steps = 2048, 4
    envs = gym.make_vec(IDS[1], num_envs=n, vectorization_mode="vector_entry_point")
    obs, _ = envs.reset(seed=5)
    actions = np.random.default_rng(6).uniform(-1, 1, (steps, n, 3)).astype(np.float32)
    history = np.array([obs] + [envs.step(a)[0] for a in actions])
    for slot in (0, 777, 1500, n - 1):
        single = gym.make(IDS[1]).unwrapped
        rows = [single.reset(seed=rigid_rot_sim.envs.vector.slot_seeds(5, n)[slot])[0]]
        rows += [single.step(a[slot])[0] for a in actions]
        assert np.array(rows).tobytes() == np.ascontiguousarray(history[:, slot]).tobytes(), f"slot {slot}"
