"""Work and precision of the gyrostat methods against scipy on P5 (a body with a free reaction wheel).

    .venv/bin/python benchmarks/gyrostat_vs_scipy.py

P5 (rigid_rot_sim.analysis.problems): I = (1, 2, 3) kg*m^2, one 0.05 kg*m^2 wheel about (1, 1, 1)
at 40 rad/s, 20 s. Each line: best of three wall-clock times (ms) and the final omega error against
the certified reference. The baseline, measured in the same run, is what a careful scipy user
writes: solve_ivp (RK45, DOP853) on the same right-hand side (the core's formula, interpreted).
Printed, never asserted: on a shared machine compare ratios of one run.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable

import numpy as np
from scipy.integrate import solve_ivp

from rigid_rot_sim.analysis.metrics import omega_error
from rigid_rot_sim.analysis.problems import P5, scipy_rhs


def best_ms(run: Callable[[], np.ndarray], repeats: int = 3) -> tuple[float, np.ndarray]:
    best, omega = float("inf"), np.zeros(3)
    for _ in range(repeats):
        start = time.perf_counter()
        omega = run()
        best = min(best, time.perf_counter() - start)
    return best * 1e3, omega


def scipy_run(method: str, tol: float) -> Callable[[], np.ndarray]:
    def run() -> np.ndarray:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            sol = solve_ivp(
                scipy_rhs(P5), (0.0, P5.t_end), P5.initial_vector(), method=method, rtol=tol, atol=tol * 1e-2
            )
        return sol.y[4:7, -1]

    return run


def main() -> None:
    reference = P5.reference()
    P5.final_state("gyrostat_rk4", 0.1)  # load the compiled kernels before timing
    P5.final_state("dopri5", P5.t_end, rtol=1e-6)
    lines: list[tuple[str, Callable[[], np.ndarray]]] = []
    for dt in (1e-2, 1e-3):
        lines.append((f"gyrostat_rk4 dt={dt:g}", lambda dt=dt: P5.final_state("gyrostat_rk4", dt)[1]))
    for tol in (1e-8, 1e-10, 1e-12):
        lines.append(
            (f"dopri5 rtol={tol:g}", lambda tol=tol: P5.final_state("dopri5", P5.t_end, rtol=tol, atol=tol * 1e-2)[1])
        )
        lines.append((f"scipy RK45 rtol={tol:g}", scipy_run("RK45", tol)))
        lines.append((f"scipy DOP853 rtol={tol:g}", scipy_run("DOP853", tol)))
    print(f"{'line':28s} {'ms':>9s} {'omega error':>12s}")
    for label, run in lines:
        ms, omega = best_ms(run)
        print(f"{label:28s} {ms:9.2f} {omega_error(reference.omega, omega):12.2e}")


if __name__ == "__main__":
    main()
