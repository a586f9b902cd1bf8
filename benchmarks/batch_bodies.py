"""Body-steps per second of rigid_rot_sim.core.batch, per method, for N = 1 to 1e6 bodies.

    .venv/bin/python benchmarks/batch_bodies.py [--max-n 1000000] [--seconds 1.0]

Each figure is the best of three timed runs, each run advancing N random bodies
(I in [1, 3] kg*m^2, |omega| ~ 1 rad/s, a constant body torque per body) by as many steps
of 1 ms as fill about ``--seconds / 3`` of wall-clock time. Then, for rk4 at the largest N,
the same compiled loop on one thread (``numba.set_num_threads(1)``) in the same run: the
parallel speed-up over the cores; and rk4's structure-of-arrays loop (the default layout)
against the per-body loop it replaced (``layout="per_body"``), on all threads and on one,
interleaved in the same run (issue 21). For reference, the numpy-vectorised batch core this
replaced did about 2e6 body-steps/s for rk4 on this machine (issue 11). Printed, never
asserted: on a shared machine compare ratios of one run.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numba
import numpy as np

from rigid_rot_sim.core.batch import BATCH_METHODS, advance_batch

#: rk4 body-steps/s of the numpy batch core before the compiled kernels (issue 11).
OLD_NUMPY_RK4 = 2e6


def body_steps_per_second(method: str, n: int, seconds: float, rng: np.random.Generator, layout: str = "soa") -> float:
    moments = np.sort(rng.uniform(1.0, 3.0, size=(n, 3)), axis=1)
    q = rng.normal(size=(n, 4))
    omega = rng.normal(size=(n, 3))
    torque = 0.01 * rng.normal(size=(n, 3))
    # calibrate the number of steps on one step
    start = time.perf_counter()
    advance_batch(method, moments, q, omega, 1e-3, 1, torque, layout=layout)
    one = time.perf_counter() - start
    steps = max(1, int(seconds / 3.0 / max(one, 1e-7)))
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        advance_batch(method, moments, q, omega, 1e-3, steps, torque, layout=layout)
        best = min(best, time.perf_counter() - start)
    return n * steps / best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-n", type=int, default=1_000_000)
    parser.add_argument("--seconds", type=float, default=1.0, help="rough wall-clock budget per point")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    sizes = [n for n in (1, 10, 100, 1_000, 10_000, 100_000, 1_000_000) if n <= args.max_n]
    print(
        f"# {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, numpy {np.__version__}, "
        f"numba {numba.__version__} ({numba.get_num_threads()} threads), load average {os.getloadavg()[0]:.2f}"
    )
    print(f"{'N':>9} " + " ".join(f"{m + ' [body-steps/s]':>32}" for m in BATCH_METHODS))
    rk4 = 0.0
    for n in sizes:
        rates = [body_steps_per_second(m, n, args.seconds, rng) for m in BATCH_METHODS]
        rk4 = rates[BATCH_METHODS.index("rk4")]
        print(f"{n:>9} " + " ".join(f"{r:>32.3e}" for r in rates), flush=True)
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    one = body_steps_per_second("rk4", sizes[-1], args.seconds, rng)
    numba.set_num_threads(threads)
    print(
        f"rk4, N = {sizes[-1]}: {rk4:.3e} body-steps/s on {threads} threads, {one:.3e} on 1 thread "
        f"({rk4 / one:.2f}x); {rk4 / OLD_NUMPY_RK4:.1f}x the numpy batch core's {OLD_NUMPY_RK4:.0e}"
    )
    # issue 21: the structure-of-arrays rk4 against the per-body loop it replaced, same run, same bodies
    n = sizes[-1]
    rates = {}
    for label, count in ((f"{threads} threads", threads), ("1 thread", 1)):
        numba.set_num_threads(count)
        for layout in ("per_body", "soa", "per_body", "soa"):  # interleaved: load bursts hit both alike
            rate = body_steps_per_second("rk4", n, args.seconds, rng, layout)
            rates[label, layout] = max(rates.get((label, layout), 0.0), rate)
    numba.set_num_threads(threads)
    for label in (f"{threads} threads", "1 thread"):
        old, new = rates[label, "per_body"], rates[label, "soa"]
        print(
            f"rk4 with attitude, N = {n}, {label}: per-body loop {old:.3e}, SIMD layout {new:.3e} body-steps/s "
            f"({new / old:.2f}x)"
        )
    print(f"load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}")


if __name__ == "__main__":
    main()
