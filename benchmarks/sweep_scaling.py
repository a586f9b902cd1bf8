"""Sweep throughput on Dask: body-steps per second with 1 and 2 workers, task overhead, memory.

    .venv/bin/python benchmarks/sweep_scaling.py [--samples 131072] [--duration 5] [--chunk auto]
    .venv/bin/python benchmarks/sweep_scaling.py --scheduler tcp://HOST:8786   # an existing cluster

The workload is a dispersed torque-free sweep (free_tumble, rk4, dt = 0.01 s, inertia,
misalignment and rate dispersions), the same rows each time. Measured, in one run:

* the raw batch kernel (``core.batch.advance_batch``, rk4, the same N and steps, one
  thread), called once per chunk over the whole workload like the sweep, so that both rates
  are totals of the same work: the rate a sweep worker is measured against (target: >= 80 %
  of it); its fastest single call is printed beside it;
* in this process without Dask (run_local, numba on one thread as in a worker's task): the
  baseline rate, and its share of the raw kernel's;
* the raw kernel's workload in 2 processes at once (spawned, one thread each): the share of
  the one-process rate each keeps, the scaling the machine itself allows at that moment (a
  virtual machine's second core may be shared), against which the 2-worker efficiency reads;
* on a local cluster of 1 worker, then 2 (single-thread processes; each cluster started for
  its measurement and closed after it, as a user's sweep does): body-steps per second,
  the efficiency ``rate(2) / (2 rate(1))``, the ratio to the baseline, and the share of the
  workers' wall time spent running tasks (Dask's task stream; the rest is scheduling, moving
  results and waiting for a core);
* task overhead: the round trip of 200 no-op tasks on the 2-worker cluster (per task), and
  the share of a sweep task's time that is not simulation;
* memory per worker: resident set size after the sweep (psutil, on each worker).

The measurements run in ``--repeats`` rounds (3), each round the raw kernel, this process and
each cluster one after the other (each the fastest of ``--best-of`` runs, 2), so that a slower
spell of a shared or virtual machine touches a whole round; each round's ratios are printed,
and the fastest round's rates. Then, on paper, what a 1e9-run sweep of the shipped slew
(6000 steps per run) needs at the measured per-worker rate. Printed, never asserted. With ``--scheduler`` the 1/2-worker
steps are replaced by one measurement on that cluster.
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import platform
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from rigid_rot_sim.cluster import one_numba_thread, open_client
from rigid_rot_sim.core.batch import advance_batch
from rigid_rot_sim.sweep.chunks import choose_chunk_size
from rigid_rot_sim.sweep.runner import run_local, run_sweep
from rigid_rot_sim.sweep.spec import parse_sweep_text

SPEC = """
name: scaling
scene: free_tumble
seed: 1
samples: {samples}
duration: {duration}
grid: {{method: [rk4], dt: [0.01]}}
dispersions:
  principal_moments: {{relative: 0.02}}
  axis_misalignment: {{sigma: 1.0e-3}}
  initial_omega: {{sigma: 1.0e-3}}
checkpoints: 20
"""

SLEW_STEPS = 6000  # config/sweeps/slew_dispersion.yaml: 60 s at dt = 0.01 s


def _noop(x: int) -> int:
    return x


def _rss() -> int:
    import psutil

    return psutil.Process().memory_info().rss


def measure(client, spec, chunk: int) -> tuple[float, float, float]:
    """(wall seconds, body-steps per second, share of the workers' wall time spent in the tasks) on ``client``."""
    from distributed import get_task_stream

    with get_task_stream(client) as stream:
        start = time.perf_counter()
        run_sweep(spec, client=client, chunk_size=chunk, progress=False)
        seconds = time.perf_counter() - start
    workers = len(client.scheduler_info(n_workers=-1)["workers"])
    computing = sum(
        s["stop"] - s["start"] for task in stream.data for s in task["startstops"] if s["action"] == "compute"
    )
    return seconds, spec.n_runs * (spec.duration / spec.dts[0]) / seconds, computing / (workers * seconds)


def raw_kernel_rate(n: int, steps: int, calls: int, repeats: int) -> tuple[float, float]:
    """Body-steps per second of advance_batch alone (rk4, one thread, N = ``n``, no torque).

    Returns (the whole workload: ``calls`` calls one after the other, as the sweep's chunks run,
    fastest of ``repeats``; the fastest single call).
    """
    rng = np.random.default_rng(0)
    moments = np.array([1.0, 2.0, 3.0]) * (1.0 + 0.02 * rng.standard_normal((n, 3)))
    q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    omega = np.array([0.3, 1.0, 0.2]) + 1e-3 * rng.standard_normal((n, 3))
    with one_numba_thread():
        advance_batch("rk4", moments, q, omega, 0.01, steps, np.zeros((n, 3)))  # compiled (the same kernel) and warm
        best_run = best_call = np.inf
        for _ in range(repeats):
            run_start = time.perf_counter()
            for _ in range(calls):
                start = time.perf_counter()
                advance_batch("rk4", moments, q, omega, 0.01, steps, np.zeros((n, 3)))
                best_call = min(best_call, time.perf_counter() - start)
            best_run = min(best_run, time.perf_counter() - run_start)
    return n * steps * calls / best_run, n * steps / best_call


def _raw_kernel_rate_at(start_at: float, n: int, steps: int, calls: int) -> float:
    """raw_kernel_rate's workload rate, started at the wall-clock time ``start_at`` (in a pool process)."""
    time.sleep(max(0.0, start_at - time.time()))
    return raw_kernel_rate(n, steps, calls, 1)[0]


def two_processes_rate(pool, n: int, steps: int, calls: int) -> float:
    """The raw kernel's workload in 2 processes at once: their mean rate (what 2 single-thread workers
    could each reach on this machine now, with nothing else running)."""
    start_at = time.time() + 0.3
    rates = list(pool.map(_raw_kernel_rate_at, [start_at] * 2, [n] * 2, [steps] * 2, [calls] * 2))
    return sum(rates) / len(rates)


def task_overhead(client, n: int = 200) -> float:
    """Seconds per no-op task, submitted together and gathered (scheduler + comms + worker)."""
    client.gather(client.map(_noop, range(20), pure=False))  # warm up
    start = time.perf_counter()
    client.gather(client.map(_noop, range(n), pure=False))
    return (time.perf_counter() - start) / n


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--samples",
        type=int,
        default=131072,
        help="runs (131072: a sweep of ~1.6 s on one worker; a sweep through Dask has ~30 ms of "
        "fixed latency here, which a much shorter one measures as much as its rate)",
    )
    parser.add_argument("--duration", type=float, default=5.0, help="s of sim time per run (dt = 0.01 s)")
    parser.add_argument(
        "--chunk",
        default="auto",
        help="bodies per task: 'auto' (default), what choose_chunk_size picks for this workload on "
        "1 worker, as a sweep does; or a number (4096 is what it picks for the slew, whose runs "
        "are 12x longer: on this workload's short runs it measures Dask's per-task cost)",
    )
    parser.add_argument("--scheduler", help="measure on this existing cluster instead of local ones")
    parser.add_argument("--repeats", type=int, default=3, help="rounds (each printed)")
    parser.add_argument(
        "--best-of",
        type=int,
        default=2,
        help="runs of each measurement in a round, the fastest kept (a slow spell of the machine "
        "then has to last a whole measurement to move a ratio)",
    )
    args = parser.parse_args()
    spec = parse_sweep_text(SPEC.format(samples=args.samples, duration=args.duration), "scaling.yaml")
    args.chunk = choose_chunk_size(spec, 1)[0] if args.chunk == "auto" else int(args.chunk)
    steps = spec.duration / spec.dts[0]
    body_steps = spec.n_runs * steps
    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
        f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}"
    )
    print(
        f"workload: {spec.n_runs} runs x {steps:.0f} rk4 steps = {body_steps:.3g} body-steps, "
        f"{args.chunk} bodies per task ({-(-spec.n_runs // args.chunk)} tasks)"
    )

    n_chunk = min(args.chunk, spec.n_runs)
    calls = -(-spec.n_runs // n_chunk)
    run_local(parse_sweep_text(SPEC.format(samples=4, duration=0.1), "warm.yaml"), chunk_size=4)
    clusters = [(None, 1), (None, 2)] if args.scheduler is None else [(args.scheduler, None)]
    # rounds: the raw kernel, this process and each cluster one after the other, so that a
    # slower or faster spell of the (shared, virtual) machine touches all of a round alike.
    # Each cluster lives only for its own measurement, as a user's does: an idle cluster's
    # heartbeats and monitors would take CPU from the one being measured.
    rounds = []
    raw_call = 0.0
    overhead = 0.0
    memory: dict[str, int] = {}
    # the hardware's own scaling, measured in each round: the raw kernel in 2 processes at once
    pool = ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn"))
    two_processes_rate(pool, 64, 10, 1)  # both processes started, imports and kernels loaded
    pair_shares = []
    for k in range(args.repeats):
        raw, round_call = raw_kernel_rate(n_chunk, round(steps), calls, args.best_of)
        raw_call = max(raw_call, round_call)
        pair = max(two_processes_rate(pool, n_chunk, round(steps), calls) for _ in range(args.best_of))
        pair_shares.append(pair / raw)
        baseline = 0.0
        for _ in range(args.best_of):
            start = time.perf_counter()
            with one_numba_thread():  # as a worker's task runs, and as the raw kernel is measured
                run_local(spec, chunk_size=args.chunk)
            baseline = max(baseline, body_steps / (time.perf_counter() - start))
        measured = {}
        for scheduler, workers in clusters:
            with open_client(scheduler, workers) as client:
                n = len(client.scheduler_info(n_workers=-1)["workers"])
                # once untimed: imports and compiled kernels loaded on every worker, and its memory
                # allocator at the workload's sizes (a long sweep's first task pays this once)
                run_sweep(spec, client=client, chunk_size=args.chunk, progress=False)
                measured[n] = max((measure(client, spec, args.chunk) for _ in range(args.best_of)), key=lambda m: m[1])
                if k == args.repeats - 1 and n == max(w or n for _, w in clusters):
                    overhead = task_overhead(client)
                    memory = client.run(_rss)
        rounds.append((raw, baseline, measured))
        print(
            f"round {k + 1}: raw kernel {raw:.3g} (in 2 processes at once {pair / raw:.0%} each), "
            f"this process {baseline:.3g} ({baseline / raw:.0%}), "
            + ", ".join(
                f"{n} worker(s) {rate:.3g} ({rate / n / raw:.0%} per worker, tasks {busy:.0%} of the time)"
                for n, (_, rate, busy) in measured.items()
            )
            + " body-steps/s"
        )
    pool.shutdown()
    raw = max(r for r, _, _ in rounds)
    baseline = max(b for _, b, _ in rounds)
    print(
        f"raw batch kernel, rk4, N = {n_chunk}, {steps:.0f} steps, 1 thread, {calls} calls (the workload): "
        f"{raw:.3g} body-steps/s (fastest round; fastest single call {raw_call:.3g}); "
        f"in 2 processes at once each ran at "
        f"{', '.join(f'{p:.0%}' for p in pair_shares)} of it per round: the most 2 workers could scale"
    )
    print(
        f"in this process, no Dask:  {baseline:.3g} body-steps/s (fastest round; {baseline / raw:.0%} of the raw "
        f"kernel; per round {', '.join(f'{b / r:.0%}' for r, b, _ in rounds)})"
    )
    rates = {}
    for n in rounds[0][2]:
        rate = max(m[n][1] for _, _, m in rounds)
        rates[n] = rate
        per_round = ", ".join(f"{m[n][1] / n / r:.0%}" for r, _, m in rounds)
        print(
            f"{n} worker(s): {rate:.3g} body-steps/s (fastest round; {rate / baseline:.2f}x the baseline, "
            f"{rate / n / raw:.0%} of the raw kernel per worker; per round {per_round}"
            + (
                f"; efficiency {rate / (n * rates[1]):.0%}, per round "
                + ", ".join(f"{m[n][1] / (n * m[1][1]):.0%}" for _, _, m in rounds)
                if n > 1 and 1 in rates
                else ""
            )
            + ")"
        )
    compute = args.chunk * steps / baseline
    print(
        f"task overhead: {overhead * 1e3:.1f} ms per no-op task round trip; a {args.chunk}-body task "
        f"computes {compute:.2f} s, so overhead is {overhead / compute:.2%} of it"
    )
    print("memory per worker (RSS after the sweep): " + ", ".join(f"{m / 2**20:.0f} MiB" for m in memory.values()))
    print(f"load average at the end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    # one worker on a core of its own is the per-worker rate a cluster scales out
    per_worker = rates.get(1, max(rates.values()) / max(rates))
    runs = 1e9
    worker_hours = runs * SLEW_STEPS / per_worker / 3600.0
    print(
        f"on paper: 1e9 slew runs = {runs * SLEW_STEPS:.1e} body-steps; at {per_worker:.3g} body-steps/s per worker "
        f"that is {worker_hours:.3g} worker-hours, e.g. {worker_hours / 1000:.3g} h on 1000 workers "
        f"or {worker_hours / 24 / 100:.3g} days on 100"
    )


if __name__ == "__main__":
    main()
