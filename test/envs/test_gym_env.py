"""The single environments through Gymnasium's own interface: its checker, seeding, bounds, limits."""

from __future__ import annotations

import contextlib
import hashlib
import io
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import rigid_rot_sim.envs
from rigid_rot_sim.envs import DEFAULT_SENSORS

IDS = ["RigidRot/AttitudeControl-v0", "RigidRot/WheelAttitudeControl-v0"]


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("sensors", [None, True])
def test_gymnasium_check_env_passes_without_a_warning(env_id, sensors):
    env = gym.make(env_id, sensors=sensors)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # Gymnasium's checker reports through warnings.warn
        check_env(env.unwrapped)
    env.close()


def test_the_module_prefixed_id_imports_the_package_and_no_ros():
    code = (
        "import gymnasium, sys; env = gymnasium.make('rigid_rot_sim.envs:RigidRot/AttitudeControl-v0'); "
        "env.reset(seed=0); env.step(env.action_space.sample()); "
        "print(type(env.unwrapped).__name__, env.spec.max_episode_steps, "
        "[m for m in sys.modules if m.startswith(('rclpy', 'rigid_rot_msgs'))])"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert result.stdout.split() == ["AttitudeControlEnv", "300", "[]"]


# The same seed and actions in another process: a script that prints a digest of every observation
# and reward of both environments, with and without sensors (one line each).
_RUN = """
import hashlib
import gymnasium as gym
import numpy as np
import rigid_rot_sim.envs
for env_id in ("RigidRot/AttitudeControl-v0", "RigidRot/WheelAttitudeControl-v0"):
    for sensors in (False, True):
        env = gym.make(env_id, sensors=sensors)
        digest = hashlib.sha256()
        actions = np.random.default_rng(7).uniform(-1, 1, (60, 3)).astype(np.float32)
        obs, info = env.reset(seed=2024)
        digest.update(obs.tobytes())
        digest.update(info["principal_moments"].tobytes())
        for action in actions:
            obs, reward, terminated, truncated, _ = env.step(action)
            digest.update(obs.tobytes())
            digest.update(np.float64(reward).tobytes())
            if terminated or truncated:
                obs, info = env.reset()
                digest.update(obs.tobytes())
        print(env_id, sensors, digest.hexdigest())
"""


def test_same_seed_and_actions_give_the_same_bytes_across_processes():
    def run() -> list[str]:
        result = subprocess.run([sys.executable, "-c", _RUN], capture_output=True, text=True, timeout=300, check=True)
        return result.stdout.splitlines()

    first, second = run(), run()
    assert len(first) == 4 and all(len(line.split()[-1]) == 64 for line in first)
    assert first == second
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(_RUN, {})  # and in this process
    assert out.getvalue().splitlines() == first
    assert len({line.split()[-1] for line in first}) == 4  # the sensors and the wheels do change the bytes


def test_the_seed_fixes_the_episode_and_another_seed_changes_it():
    env = gym.make(IDS[0])
    first, info1 = env.reset(seed=5)
    again, info2 = env.reset(seed=5)
    other, info3 = env.reset(seed=6)
    assert first.tobytes() == again.tobytes()
    assert info1["principal_moments"].tobytes() == info2["principal_moments"].tobytes()
    assert first.tobytes() != other.tobytes()
    assert not np.array_equal(info1["principal_moments"], info3["principal_moments"])
    np.testing.assert_array_equal(info1["inertia"], np.diag(info1["principal_moments"]))
    # the dispersion stays within its range
    nominal = np.array([0.8, 1.0, 1.2])
    assert np.all(np.abs(info1["principal_moments"] / nominal - 1.0) <= 0.1)


def test_sensors_change_the_reading_not_the_physics():
    truth = gym.make(IDS[0])
    sensed = gym.make(IDS[0], sensors=True)
    obs_t, info_t = truth.reset(seed=3)
    obs_s, info_s = sensed.reset(seed=3)
    np.testing.assert_array_equal(info_t["principal_moments"], info_s["principal_moments"])
    assert not np.array_equal(obs_t[:7], obs_s[:7])
    # a star tracker of ~1e-4 rad and a gyro with a 1e-4 rad/s turn-on bias: close to the truth
    assert np.max(np.abs(obs_t[:4] - obs_s[:4])) < 1e-3
    assert np.max(np.abs(obs_t[4:7] - obs_s[4:7])) < 2e-3
    for _ in range(5):
        action = np.array([0.3, -0.2, 0.1], dtype=np.float32)
        obs_t, r_t, *_ = truth.step(action)
        obs_s, r_s, *_ = sensed.step(action)
        assert r_t == r_s  # the reward is the true state's


def test_truncated_at_max_episode_steps_by_make_and_by_the_env_itself():
    env = gym.make(IDS[0], max_episode_steps=4)  # TimeLimit
    env.reset(seed=0)
    flags = [env.step(np.zeros(3, dtype=np.float32))[3] for _ in range(4)]
    assert flags == [False, False, False, True]
    raw = rigid_rot_sim.envs.attitude.AttitudeControlEnv(max_episode_steps=3)  # no wrapper: the env's own limit
    raw.reset(seed=0)
    flags = [raw.step(np.zeros(3, dtype=np.float32))[3] for _ in range(3)]
    assert flags == [False, False, True]


def test_terminated_once_held_within_tolerance():
    env = rigid_rot_sim.envs.attitude.AttitudeControlEnv(angle_tolerance=4.0, rate_tolerance=10.0, hold_periods=3)
    env.reset(seed=1)
    flags = [env.step(np.zeros(3, dtype=np.float32))[2] for _ in range(3)]
    assert flags == [False, False, True]


def test_a_pd_controller_slews_and_settles():
    env = rigid_rot_sim.envs.attitude.AttitudeControlEnv()
    obs, _ = env.reset(seed=11)
    for _ in range(300):
        action = np.clip(-(1.0 * obs[7:10] + 2.5 * obs[4:7]) / 0.2, -1, 1).astype(np.float32)
        obs, reward, terminated, truncated, _ = env.step(action)
        assert reward <= 0.0
        if terminated:
            break
    assert terminated and not truncated
    assert np.linalg.norm(obs[7:10]) < 0.01 and np.linalg.norm(obs[4:7]) < 0.005


def test_bad_input_is_refused_with_a_clear_error():
    env = rigid_rot_sim.envs.attitude.AttitudeControlEnv()
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(3))
    env.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0.0, 0.0]))
    with pytest.raises(ValueError, match="dt"):
        rigid_rot_sim.envs.attitude.AttitudeControlEnv(control_period=0.1, dt=0.03)
    with pytest.raises(ValueError, match="triangle"):
        rigid_rot_sim.envs.attitude.AttitudeControlEnv(principal_moments=(1.0, 1.0, 1.9), inertia_dispersion=0.1)
    with pytest.raises(ValueError, match="saturation"):
        rigid_rot_sim.envs.attitude.AttitudeControlEnv(
            sensors=rigid_rot_sim.envs.ObservationSensors(
                rigid_rot_sim.core.sensors.GyroModel(), DEFAULT_SENSORS.star_tracker
            )
        )


def test_full_torque_for_a_whole_episode_stays_inside_the_bounds():
    for cls in (rigid_rot_sim.envs.attitude.AttitudeControlEnv, rigid_rot_sim.envs.attitude.WheelAttitudeControlEnv):
        env = cls(max_initial_rate=0.05)
        obs, _ = env.reset(seed=0)
        truncated = False
        while not truncated:
            obs, _, terminated, truncated, _ = env.step(np.ones(3, dtype=np.float32))
            assert obs in env.observation_space
            assert not terminated


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("sensors", [False, True])
@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    seed=st.integers(0, 2**64 - 1),
    actions=st.lists(
        st.lists(st.floats(-10.0, 10.0, allow_nan=False, width=32), min_size=3, max_size=3), min_size=1, max_size=30
    ),
)
def test_every_observation_is_in_the_observation_space(env_id, sensors, seed, actions):
    env = gym.make(env_id, sensors=sensors).unwrapped
    obs, info = env.reset(seed=seed)
    assert obs in env.observation_space
    for action in actions:
        action = np.asarray(action, dtype=np.float32)
        obs, reward, terminated, truncated, _ = env.step(np.clip(action, -1, 1))
        assert obs in env.observation_space
        assert np.isfinite(reward)
        if terminated or truncated:
            obs, _ = env.reset()
            assert obs in env.observation_space
    # out-of-range actions are clipped, as the space's bounds: the same step as the clipped one
    env.reset(seed=seed)
    a = env.step(np.asarray(actions[0], dtype=np.float32))[0]
    env.reset(seed=seed)
    b = env.step(np.clip(np.asarray(actions[0], dtype=np.float32), -1, 1))[0]
    assert hashlib.sha256(a.tobytes()).digest() == hashlib.sha256(b.tobytes()).digest()
