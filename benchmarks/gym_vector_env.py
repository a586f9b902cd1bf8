"""Environment steps per second of the native vector environments beside Gymnasium's SyncVectorEnv.

    .venv/bin/python benchmarks/gym_vector_env.py [--sizes 1 64 1024 8192] [--seconds 2.0]
        [--ids rigid wheels] [--episode-steps K]

For each id (both by default: ``RigidRot/AttitudeControl-v0`` and ``RigidRot/WheelAttitudeControl-v0``)
and each N: ``gymnasium.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")`` and, in
the same run, ``vectorization_mode="sync"`` (SyncVectorEnv over N single environments, the
baseline), both with the registered settings (control period 0.1 s, RK4 with dt 0.01 s: 10 RK4
steps per environment step; ``--episode-steps`` shortens the episodes so that autoresets fall in
the timed steps) and autoreset on, stepped with random actions in [-1, 1] drawn
beforehand. A figure is N * steps / wall-clock seconds, the best of three runs of about
``--seconds / 3`` each, the two kinds' runs interleaved so that both see the same load. The load
averages (1, 5 and 15 minutes, as ``uptime`` prints them) are printed before and after: on a shared
machine compare the ratios of one run. Printed, never asserted.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import gymnasium as gym
import numba
import numpy as np

import rigid_rot_sim.envs  # noqa: F401  (registers the ids)

#: The issue's target at N = 8192: environment steps per second, on two cores.
TARGET = 1e6
#: The ids, by the short names of ``--ids``.
IDS = {"rigid": "RigidRot/AttitudeControl-v0", "wheels": "RigidRot/WheelAttitudeControl-v0"}


def load() -> str:
    """The load averages over 1, 5 and 15 minutes, as ``uptime`` prints them."""
    return ", ".join(f"{value:.2f}" for value in os.getloadavg())


class Timer:
    """Environment steps per second of one vector environment: calibrated once, then timed in rounds."""

    def __init__(self, envs: gym.vector.VectorEnv, seconds: float) -> None:
        self.envs = envs
        n = envs.num_envs
        rng = np.random.default_rng(0)
        envs.reset(seed=0)
        start = time.perf_counter()
        envs.step(rng.uniform(-1, 1, (n, 3)).astype(np.float32))
        one = time.perf_counter() - start
        steps = max(2, int(seconds / 3.0 / max(one, 1e-6)))
        self.actions = rng.uniform(-1, 1, (steps, n, 3)).astype(np.float32)
        self.best = float("inf")

    def round(self) -> None:
        start = time.perf_counter()
        for a in self.actions:
            self.envs.step(a)
        self.best = min(self.best, time.perf_counter() - start)

    @property
    def rate(self) -> float:
        return self.envs.num_envs * len(self.actions) / self.best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 64, 1024, 8192])
    parser.add_argument("--seconds", type=float, default=2.0, help="rough wall-clock budget per point and kind")
    parser.add_argument("--ids", nargs="+", choices=sorted(IDS), default=["rigid", "wheels"], help="the envs timed")
    parser.add_argument(
        "--episode-steps", type=int, default=None, help="max_episode_steps (shorter: autoresets in the timed steps)"
    )
    args = parser.parse_args()
    options = {} if args.episode_steps is None else {"max_episode_steps": args.episode_steps}
    print(
        f"# {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, numpy {np.__version__}, "
        f"numba {numba.__version__} ({numba.get_num_threads()} threads), gymnasium {gym.__version__}, "
        f"max_episode_steps {args.episode_steps or 'as registered'}; load average {load()}"
    )
    print(f"{'id':<34} {'N':>6} {'native (steps/s)':>18} {'SyncVectorEnv (steps/s)':>24} {'speed-up':>9}")
    for name in args.ids:
        env_id = IDS[name]
        for n in args.sizes:
            native = Timer(
                gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **options), args.seconds
            )
            sync = Timer(gym.make_vec(env_id, num_envs=n, vectorization_mode="sync", **options), args.seconds)
            for _ in range(3):  # interleaved: both see the same load
                native.round()
                sync.round()
            native.envs.close()
            sync.envs.close()
            print(
                f"{env_id:<34} {n:6d} {native.rate:18.3g} {sync.rate:24.3g} {native.rate / sync.rate:8.0f}x",
                flush=True,
            )
    print(f"# target at N = 8192: >= {TARGET:.0e} steps/s and >= 100x SyncVectorEnv; load average now {load()}")


if __name__ == "__main__":
    main()
