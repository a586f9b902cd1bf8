"""A PD attitude controller on RigidRot/AttitudeControl-v0, and a cross-entropy search over its gains.

    .venv/bin/python tools/gym_pd_search.py [--episodes 1024] [--iterations 6] [--population 16] [--train 128]

The worked example of docs/gym.md. The policy is the quaternion-feedback PD law

    torque = clip(-(kp e + kd omega), -max_torque, max_torque)      (N*m, body axes)

on the observation's error rotation vector ``e`` (rad) and rate ``omega`` (rad/s); the action is
``torque / max_torque``. :func:`evaluate` runs one episode per seed in the native vector environment
(one slot per episode, each slot its own gains) and reports the success rate (terminated: held
within tolerance), the mean settle time (s, from the reset to the start of the hold, over the
successes) and the mean return. :func:`cross_entropy_search` searches log(kp), log(kd) with a
Gaussian: each iteration evaluates ``population`` candidates on the same ``train`` seeds in one
batch, refits the Gaussian to the best quarter and keeps the best candidate seen (the baseline is
the first). The baseline and the result are then compared on ``episodes`` other seeds. numpy only.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

import rigid_rot_sim.envs  # noqa: F401  (registers the ids)

ENV_ID = "RigidRot/AttitudeControl-v0"
#: Textbook gains for the nominal body (I ~ 1 kg*m^2): natural frequency 0.5 rad/s, damping 0.7.
BASELINE_GAINS = (0.25, 0.7)
TRAIN_SEED = 1
TEST_SEED = 2


@dataclass(frozen=True)
class Score:
    """Per-gain results over its episodes: success rate, mean settle time (s; nan without a success), mean return."""

    success_rate: np.ndarray
    settle_time: np.ndarray
    mean_return: np.ndarray


def evaluate(gains: np.ndarray, seeds: list[int]) -> Score:
    """Run every (kp, kd) row of ``gains`` (G, 2) on every seed: G * len(seeds) episodes in one vector env."""
    gains = np.asarray(gains, dtype=float).reshape(-1, 2)
    g, e = len(gains), len(seeds)
    envs = gym.make_vec(ENV_ID, num_envs=g * e, vectorization_mode="vector_entry_point")
    task = envs.unwrapped.task
    kp = np.repeat(gains[:, 0], e)[:, None]
    kd = np.repeat(gains[:, 1], e)[:, None]
    obs, _ = envs.reset(seed=seeds * g)
    returns = np.zeros(g * e)
    ended = np.zeros(g * e, dtype=bool)
    success = np.zeros(g * e, dtype=bool)
    settle = np.full(g * e, np.nan)
    for k in range(1, task.max_episode_steps + 1):
        torque = -(kp * obs[:, 7:10] + kd * obs[:, 4:7])
        action = np.clip(torque / task.max_torque, -1.0, 1.0).astype(np.float32)
        obs, reward, terminated, truncated, _ = envs.step(action)
        live = ~ended
        returns[live] += reward[live]
        done_now = live & terminated
        success |= done_now
        settle[done_now] = (k - task.hold_periods) * task.control_period
        ended |= terminated | truncated
        if ended.all():
            break
    envs.close()
    with np.errstate(invalid="ignore"):  # a gain without a success has no settle time
        settle_mean = np.array(
            [np.nanmean(row) if np.any(np.isfinite(row)) else np.nan for row in settle.reshape(g, e)]
        )
    return Score(success.reshape(g, e).mean(axis=1), settle_mean, returns.reshape(g, e).mean(axis=1))


def cross_entropy_search(
    seeds: list[int], iterations: int, population: int, rng: np.random.Generator, start: tuple[float, float]
) -> tuple[np.ndarray, float, list[float]]:
    """The best gains found (2,), their mean return on ``seeds``, and the best return after each iteration."""
    mean = np.log(np.asarray(start, dtype=float))
    sigma = np.full(2, 1.0)
    best_gains, best_return = np.asarray(start, dtype=float), -np.inf
    history = []
    elite = max(2, population // 4)
    for _ in range(iterations):
        candidates = np.exp(mean + sigma * rng.normal(size=(population, 2)))
        candidates[0] = best_gains  # the incumbent (the baseline at first) is scored on the same seeds
        score = evaluate(candidates, seeds)
        order = np.argsort(score.mean_return)[::-1]
        if score.mean_return[order[0]] > best_return:
            best_gains, best_return = candidates[order[0]].copy(), float(score.mean_return[order[0]])
        top = np.log(candidates[order[:elite]])
        mean = top.mean(axis=0)
        sigma = np.maximum(top.std(axis=0), 0.05)
        history.append(best_return)
    return best_gains, best_return, history


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=1024, help="test episodes (seeded) for the comparison")
    parser.add_argument("--iterations", type=int, default=6)
    parser.add_argument("--population", type=int, default=16)
    parser.add_argument("--train", type=int, default=128, help="training episodes per candidate")
    args = parser.parse_args()
    test_seeds = [int(s) for s in np.random.SeedSequence(TEST_SEED).generate_state(args.episodes, np.uint64)]
    train_seeds = [int(s) for s in np.random.SeedSequence(TRAIN_SEED).generate_state(args.train, np.uint64)]

    start = time.perf_counter()
    baseline = evaluate(np.array([BASELINE_GAINS]), test_seeds)
    baseline_s = time.perf_counter() - start
    start = time.perf_counter()
    gains, train_return, history = cross_entropy_search(
        train_seeds, args.iterations, args.population, np.random.default_rng(0), BASELINE_GAINS
    )
    search_s = time.perf_counter() - start
    start = time.perf_counter()
    found = evaluate(gains[None, :], test_seeds)
    found_s = time.perf_counter() - start

    print(f"{args.episodes} test episodes of {ENV_ID} (seeds from SeedSequence({TEST_SEED}))")
    print(f"{'policy':<28} {'success':>8} {'settle (s)':>11} {'return':>9} {'wall (s)':>9}")
    for name, score, seconds in (
        (f"PD kp={BASELINE_GAINS[0]:.3g} kd={BASELINE_GAINS[1]:.3g}", baseline, baseline_s),
        (f"CEM kp={gains[0]:.3g} kd={gains[1]:.3g}", found, found_s),
    ):
        print(
            f"{name:<28} {score.success_rate[0]:8.1%} {score.settle_time[0]:11.2f} "
            f"{score.mean_return[0]:9.2f} {seconds:9.2f}"
        )
    print(
        f"cross-entropy search: {args.iterations} iterations x {args.population} candidates x {args.train} "
        f"episodes in {search_s:.1f} s; best training return per iteration: {', '.join(f'{h:.2f}' for h in history)}"
    )


if __name__ == "__main__":
    main()
