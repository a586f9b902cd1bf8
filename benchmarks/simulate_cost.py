"""What a user calling ``simulate`` in a loop pays: its fixed cost, and a torque-driven run to 1e-10 (issue 21).

1. Fixed cost: one ``simulate`` call of a single step (t_end = dt = 0.01 s) for a free body and a
   constant-torque body, I = diag(1, 2, 3) kg*m^2, omega0 = (1, 0.1, 0.5) rad/s, q0 = identity,
   per method (taylor, rk4, exact); next to it, the same one-step problem through scipy's
   ``solve_ivp`` (RK45), measured in the same run.
2. Torque-driven: the same body under the constant body torque (0.1, -0.05, 0.02) N*m for
   T = 25 s, through ``simulate(..., dt=T, method="taylor", tol=...)`` (everything a user pays),
   against scipy's ``solve_ivp`` (DOP853, RK45) on the right-hand side a user would write
   (benchmarks/taylor_vs_scipy.py's), swept over tolerances; the reference is DOP853 at
   rtol = atol = 1e-14, checked against Radau at 1e-13. The figure is the fastest run of each side
   whose omega error at T is <= 1e-10 rad/s, and their ratio.

Every time is the best of several interleaved repeats (a burst of load on a shared machine hits
both sides alike); the load average is printed with the figures.

Usage:
    python benchmarks/simulate_cost.py [--repeats N]
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import time
from collections.abc import Callable

import numpy as np
from scipy.integrate import solve_ivp
from taylor_vs_scipy import scipy_rhs  # this directory is on sys.path when run as a script

from rigid_rot_sim.core.simulate import simulate

MOMENTS = (1.0, 2.0, 3.0)
OMEGA0 = (1.0, 0.1, 0.5)
Q0 = (0.0, 0.0, 0.0, 1.0)
TORQUE = (0.1, -0.05, 0.02)
T_END = 25.0
TARGET = 1e-10


def load() -> str:
    return " ".join(f"{v:.2f}" for v in os.getloadavg())


def best_time(fn: Callable[[], object], calls: int) -> float:
    """Seconds per call, the best of one batch of ``calls`` calls."""
    start = time.perf_counter()
    for _ in range(calls):
        fn()
    return (time.perf_counter() - start) / calls


def interleaved(cases: dict[str, Callable[[], object]], repeats: int, calls: int) -> dict[str, float]:
    """Best seconds per call of every case, the cases taking turns ``repeats`` times."""
    for fn in cases.values():
        fn()  # compile / warm caches
    best = {name: math.inf for name in cases}
    for _ in range(repeats):
        for name, fn in cases.items():
            best[name] = min(best[name], best_time(fn, calls))
    return best


def fixed_cost(repeats: int) -> None:
    print("\n== 1. fixed cost of one simulate() call of one step (t_end = dt = 0.01 s)")
    cases: dict[str, Callable[[], object]] = {}
    for method in ("taylor", "rk4", "exact"):
        for label, torque in (("free", None), ("constant torque", TORQUE)):
            if method == "exact" and torque is not None:
                continue  # the exact flow is torque-free
            cases[f"simulate {method:6s} {label}"] = lambda m=method, n=torque: simulate(
                MOMENTS, OMEGA0, 0.01, 0.01, m, torque=n
            )
    for label, torque in (("free", (0.0, 0.0, 0.0)), ("constant torque", TORQUE)):
        rhs = scipy_rhs(torque)
        cases[f"scipy solve_ivp RK45 {label}"] = lambda rhs=rhs: solve_ivp(
            rhs, (0.0, 0.01), list(OMEGA0 + Q0), first_step=0.01, rtol=1e-3
        )
    # many short batches: on a shared machine the best of them is the nearest to the uncontended cost
    best = interleaved(cases, 10 * repeats, calls=20)
    for name, seconds in best.items():
        print(f"   {name:34s} {seconds * 1e6:8.1f} us/call")
    print(f"   load average: {load()}")


def torque_driven(repeats: int) -> None:
    print(f"\n== 2. torque-driven run, T = {T_END:g} s, constant body torque {TORQUE} N*m, omega error <= {TARGET:.0e}")
    rhs = scipy_rhs(TORQUE)
    y0 = list(OMEGA0 + Q0)

    def scipy_run(method: str, rtol: float) -> np.ndarray:
        sol = solve_ivp(rhs, (0.0, T_END), y0, method=method, rtol=rtol, atol=rtol)
        return sol.y[:3, -1]

    reference = scipy_run("DOP853", 1e-14)
    second = scipy_run("Radau", 1e-13)
    print(f"   reference DOP853 rtol=atol=1e-14; Radau rtol=1e-13 differs by {np.max(np.abs(reference - second)):.1e}")
    cases: dict[str, Callable[[], np.ndarray]] = {}
    for tol in (1e-9, 1e-10, 1e-11, 1e-12, 1e-13):
        cases[f"simulate taylor tol={tol:.0e}"] = lambda tol=tol: simulate(
            MOMENTS, OMEGA0, T_END, T_END, "taylor", torque=TORQUE, tol=tol
        ).omega[-1]
    for rtol in (1e-9, 1e-10, 3e-11, 1e-11, 3e-12, 1e-12):
        cases[f"scipy DOP853 rtol={rtol:.0e}"] = lambda rtol=rtol: scipy_run("DOP853", rtol)
    for rtol in (1e-9, 1e-10, 3e-11, 1e-11):
        cases[f"scipy RK45 rtol={rtol:.0e}"] = lambda rtol=rtol: scipy_run("RK45", rtol)
    errors = {name: float(np.max(np.abs(fn() - reference))) for name, fn in cases.items()}
    best = interleaved(cases, repeats, calls=1)
    fastest: dict[str, tuple[float, str]] = {}
    for name, seconds in best.items():
        ok = errors[name] <= TARGET
        print(f"   {name:30s} {seconds * 1e3:9.3f} ms  omega error {errors[name]:.2e}{'' if ok else '  (misses)'}")
        side = "taylor" if name.startswith("simulate") else "scipy"
        if ok and seconds < fastest.get(side, (math.inf, ""))[0]:
            fastest[side] = (seconds, name)
    if len(fastest) == 2:
        (ours, our_name), (theirs, their_name) = fastest["taylor"], fastest["scipy"]
        print(
            f"   fastest to {TARGET:.0e}: {our_name} {ours * 1e3:.3f} ms, {their_name} {theirs * 1e3:.3f} ms: "
            f"ratio {theirs / ours:.1f}x"
        )
    else:
        print(f"   target not reached by: {sorted({'taylor', 'scipy'} - set(fastest))}")
    print(f"   load average: {load()}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=7, help="interleaved repeats per case (best is kept)")
    args = parser.parse_args()
    import scipy

    print(
        f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"{os.cpu_count()} cpus, load average {load()}"
    )
    fixed_cost(args.repeats)
    torque_driven(args.repeats)


if __name__ == "__main__":
    main()
