"""The Stable-Baselines3 adapter against SB3 2.x's VecEnv contract, without SB3 (it needs torch).

The reference is the contract as SB3's own ``DummyVecEnv`` implements it over single environments
(stable_baselines3/common/vec_env/dummy_vec_env.py, 2.9): ``done = terminated or truncated``,
``info["TimeLimit.truncated"] = truncated and not terminated``, a done slot's last observation in
``info["terminal_observation"]`` and the slot reset in the same step (its reset info in
``reset_infos``), rewards float32, slot i seeded ``seed + i`` at the next reset.
"""

from __future__ import annotations

import importlib.util

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import data_equivalence
from gymnasium.vector import AutoresetMode

import rigid_rot_sim.envs  # noqa: F401  (registers the ids)
from rigid_rot_sim.envs.sb3 import NativeVecEnv, sb3_vec_env, unbatch_infos
from rigid_rot_sim.envs.vector import WheelAttitudeControlVectorEnv

IDS = ["RigidRot/AttitudeControl-v0", "RigidRot/WheelAttitudeControl-v0"]
SHORT = {"max_episode_steps": 12, "angle_tolerance": 1.5, "rate_tolerance": 0.2, "hold_periods": 3}
#: SB3 2.x VecEnv's interface (base_vec_env.py): its abstract methods and the base methods SB3 calls.
SB3_VEC_ENV_API = (
    "reset step_async step_wait close get_attr set_attr env_method env_is_wrapped step seed set_options "
    "has_attr get_images render unwrapped getattr_depth_check num_envs observation_space action_space "
    "reset_infos render_mode metadata"
).split()


class DummyReference:
    """SB3's DummyVecEnv rules, written out over the single environments (what the adapter must equal)."""

    def __init__(self, env_id, n, **kwargs):
        self.envs = [gym.make(env_id, **kwargs) for _ in range(n)]
        self.reset_infos = [{} for _ in range(n)]

    def reset(self, seeds):
        rows = []
        for i, env in enumerate(self.envs):
            obs, self.reset_infos[i] = env.reset(seed=seeds[i])
            rows.append(obs)
        return np.array(rows)

    def step(self, actions):
        rows, rewards, dones, infos = [], [], [], []
        for i, env in enumerate(self.envs):
            obs, reward, terminated, truncated, info = env.step(actions[i])
            info = dict(info, **{"TimeLimit.truncated": truncated and not terminated})
            if terminated or truncated:
                info["terminal_observation"] = obs
                obs, self.reset_infos[i] = env.reset()
            rows.append(obs)
            rewards.append(reward)
            dones.append(terminated or truncated)
            infos.append(info)
        return np.array(rows), np.array(rewards, dtype=np.float32), np.array(dones), infos


@pytest.mark.parametrize("env_id", IDS)
def test_the_adapter_steps_as_sb3s_dummy_vec_env_over_the_single_envs_bit_for_bit(env_id):
    n = 4
    venv = NativeVecEnv(
        gym.make_vec(
            env_id, num_envs=n, vectorization_mode="vector_entry_point", autoreset_mode=AutoresetMode.SAME_STEP, **SHORT
        )
    )
    reference = DummyReference(env_id, n, **SHORT)
    assert venv.seed(100) == [100, 101, 102, 103]
    obs = venv.reset()
    assert obs.tobytes() == reference.reset([100, 101, 102, 103]).tobytes()
    assert data_equivalence(venv.reset_infos, reference.reset_infos, exact=True)
    assert venv.observation_space == reference.envs[0].observation_space
    assert venv.action_space == reference.envs[0].action_space
    actions = np.random.default_rng(3).uniform(-1, 1, (40, n, 3)).astype(np.float32)
    done_steps = 0
    for a in actions:
        ours, theirs = venv.step(a), reference.step(a)
        assert ours[0].tobytes() == theirs[0].tobytes()
        assert ours[1].dtype == np.float32 and ours[1].tobytes() == theirs[1].tobytes()
        assert ours[2].dtype == np.bool_ and ours[2].tolist() == theirs[2].tolist()
        assert data_equivalence(ours[3], theirs[3], exact=True)
        assert data_equivalence(venv.reset_infos, reference.reset_infos, exact=True)
        done_steps += int(ours[2].any())
    assert done_steps >= 3  # terminal observations and resets compared
    assert venv.reset().shape == (n, *venv.observation_space.shape)  # unseeded: each slot continues its generator


def test_the_adapter_has_sb3s_vec_env_interface_and_refuses_what_it_cannot_do():
    venv = NativeVecEnv(WheelAttitudeControlVectorEnv(num_envs=3, autoreset_mode=AutoresetMode.SAME_STEP))
    assert all(hasattr(venv, name) for name in SB3_VEC_ENV_API)
    assert venv.unwrapped is venv and venv.render_mode is None
    assert venv.get_attr("num_envs") == [3, 3, 3] and venv.get_attr("task", 1) == [venv.envs.task]
    assert venv.has_attr("task") and not venv.has_attr("no_such_thing")
    assert venv.env_is_wrapped(gym.Wrapper) == [False] * 3
    assert venv.getattr_depth_check("reset", already_found=True) is not None
    with pytest.raises(AttributeError, match="per-slot"):
        venv.env_method("reset", indices=[0])
    with pytest.raises(ValueError, match="all of them"):
        venv.set_attr("render_mode", None, indices=[0])
    venv.set_options({"reset_mask": np.ones(3, dtype=bool)})
    with pytest.raises(ValueError, match="no reset options"):
        venv.reset()
    with pytest.raises(ValueError, match="SAME_STEP"):
        NativeVecEnv(WheelAttitudeControlVectorEnv(num_envs=2))  # NEXT_STEP: SB3 would learn from reset steps


def test_unbatch_infos_inverts_gymnasiums_masked_batching():
    infos = {"a": np.array([1.0, 0.0, 3.0]), "_a": np.array([True, False, True]), "d": {}, "_d": np.ones(3, bool)}
    assert unbatch_infos(infos, 3) == [{"a": 1.0, "d": {}}, {"d": {}}, {"a": 3.0, "d": {}}]


def test_sb3_vec_env_is_an_sb3_vec_env_or_says_what_is_missing():
    if importlib.util.find_spec("stable_baselines3") is None or importlib.util.find_spec("torch") is None:
        with pytest.raises(ImportError, match="pip install stable-baselines3"):
            sb3_vec_env(IDS[0], num_envs=2)
        return
    from stable_baselines3.common.vec_env import VecEnv  # pragma: no cover  (where SB3 and torch are installed)

    venv = sb3_vec_env(IDS[0], num_envs=2)  # pragma: no cover
    assert isinstance(venv, VecEnv) and venv.reset().shape == (2, 10)  # pragma: no cover
