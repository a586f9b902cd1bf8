"""Environment steps per second of the native vector environments beside Gymnasium's SyncVectorEnv.

    .venv/bin/python benchmarks/gym_vector_env.py [--sizes 1 64 1024 8192] [--seconds 2.0] [--wheels]

For each N: ``gymnasium.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")`` and, in
the same run, ``vectorization_mode="sync"`` (SyncVectorEnv over N single environments, the
baseline), both with the registered settings (control period 0.1 s, RK4 with dt 0.01 s: 10 RK4
steps per environment step) and autoreset on, stepped with random actions in [-1, 1] drawn
beforehand. A figure is N * steps / wall-clock seconds, the best of three runs of about
``--seconds / 3`` each. SyncVectorEnv is timed at N <= 1024 (at 8192 it takes minutes; its rate is
flat in N, so the ratio uses its figure at the largest N it ran). The load average is printed:
on a shared machine compare the ratios of one run. Printed, never asserted.
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
SYNC_MAX_N = 1024


def steps_per_second(envs: gym.vector.VectorEnv, seconds: float) -> float:
    """Environment steps per second (N per vector step) of ``envs``, best of three."""
    n = envs.num_envs
    rng = np.random.default_rng(0)
    envs.reset(seed=0)
    start = time.perf_counter()
    envs.step(rng.uniform(-1, 1, (n, 3)).astype(np.float32))
    one = time.perf_counter() - start
    steps = max(2, int(seconds / 3.0 / max(one, 1e-6)))
    actions = rng.uniform(-1, 1, (steps, n, 3)).astype(np.float32)
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        for a in actions:
            envs.step(a)
        best = min(best, time.perf_counter() - start)
    return n * steps / best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 64, 1024, 8192])
    parser.add_argument("--seconds", type=float, default=2.0, help="rough wall-clock budget per point")
    parser.add_argument("--wheels", action="store_true", help="RigidRot/WheelAttitudeControl-v0 instead")
    args = parser.parse_args()
    env_id = "RigidRot/WheelAttitudeControl-v0" if args.wheels else "RigidRot/AttitudeControl-v0"
    print(
        f"# {env_id}: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, numpy {np.__version__}, "
        f"numba {numba.__version__} ({numba.get_num_threads()} threads), gymnasium {gym.__version__}, "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    print(f"{'N':>6} {'native (steps/s)':>18} {'SyncVectorEnv (steps/s)':>24} {'speed-up':>9}")
    sync_rate = None
    for n in args.sizes:
        native = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point")
        rate = steps_per_second(native, args.seconds)
        native.close()
        if n <= SYNC_MAX_N:
            sync = gym.make_vec(env_id, num_envs=n, vectorization_mode="sync")
            sync_rate = steps_per_second(sync, args.seconds)
            sync.close()
            sync_text = f"{sync_rate:24.3g}"
        else:
            sync_text = f"{'(as at N=' + str(SYNC_MAX_N) + ')':>24}"
        ratio = f"{rate / sync_rate:8.0f}x" if sync_rate else f"{'-':>9}"
        print(f"{n:6d} {rate:18.3g} {sync_text} {ratio}", flush=True)
    print(
        f"# target at N = 8192: >= {TARGET:.0e} steps/s and >= 100x SyncVectorEnv; "
        f"load average now {os.getloadavg()[0]:.2f}"
    )


if __name__ == "__main__":
    main()
