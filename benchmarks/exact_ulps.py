"""Cost per evaluation of the exact torque-free flow: this tree against a baseline commit (issue 21).

The compensated (double-double) phase and angles of core/exact.py must cost at most 1.5x the
flow before them. Both trees are timed in the same run, alternately, each in its own process
(``PYTHONPATH`` set to the tree; the baseline is checked out with ``git worktree add --detach``
under a temporary directory and removed afterwards), on the same problems:

- ``evaluate``: a flow built once, evaluated at 20000 times over 100 s
  (``TorqueFreeSolution.state`` on an array: the compiled ``evaluate_flow`` loop), ns per time;
- ``step``: ``free_flow(moments, q, omega, tau)`` from a state, compiled in a loop, tau = 0.01 s
  (what ``exact_split`` pays per step), ns per call;
- ``build+evaluate``: the same at 20000 times over 100 s (``free_flow`` far from the anchor,
  as the batch kernel's ``exact`` over a run), ns per call.

Cases: the general triaxial body I = (1, 2, 3) kg*m^2, omega0 = (0.3, 0.5, 1.0) rad/s, the
near-sphere I = (1, 1.001, 1.0025), omega0 = (0.6, 0.7, 0.8), the symmetric body I = (2, 2, 3),
omega0 = (0.3, 0.4, 0.5) and a state 1e-6 above the separatrix (I = (3, 4, 6), omega0 = (1, 0.3,
0.5 (1 + 1e-6)); issue 29). Every figure is the best of
--repeats runs; the load average is printed with them.

Usage:
    python benchmarks/exact_ulps.py [--baseline REV] [--repeats N]

REV defaults to cfb3416, main before the ulp work.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CASES = {
    "general": ((1.0, 2.0, 3.0), (0.3, 0.5, 1.0)),
    "near_sphere": ((1.0, 1.001, 1.0025), (0.6, 0.7, 0.8)),
    "symmetric": ((2.0, 2.0, 3.0), (0.3, 0.4, 0.5)),
    "near_separatrix": ((3.0, 4.0, 6.0), (1.0, 0.3, 0.5 * (1.0 + 1e-6))),
}
Q0 = (0.5, -0.5, 0.5, 0.5)
N_TIMES = 20000
N_CALLS = 20000


def measure(repeats: int) -> dict[str, float]:
    """ns per evaluation of each (case, kind) in the tree on sys.path, best of ``repeats``."""
    import numpy as np
    from numba import njit

    from rigid_rot_sim.core.exact import free_flow, torque_free_solution

    @njit(cache=False)
    def build_and_evaluate(moments, q, omega, taus):
        total = 0.0
        for k in range(taus.size):
            qt, wt = free_flow(moments, q, omega, taus[k])
            total += qt[0] + wt[0]
        return total

    taus = np.linspace(0.0, 100.0, N_TIMES)
    steps = np.full(N_CALLS, 0.01)
    out = {}
    for name, (moments, omega0) in CASES.items():
        sol = torque_free_solution(moments, omega0, Q0)
        sol.state(taus)  # warm
        build_and_evaluate(moments, Q0, omega0, taus[:10])  # compile
        best_eval = best_build = best_step = float("inf")
        for _ in range(repeats):
            start = time.perf_counter()
            sol.state(taus)
            best_eval = min(best_eval, (time.perf_counter() - start) / N_TIMES)
            start = time.perf_counter()
            build_and_evaluate(moments, Q0, omega0, taus[:N_CALLS])
            best_build = min(best_build, (time.perf_counter() - start) / N_CALLS)
            start = time.perf_counter()
            build_and_evaluate(moments, Q0, omega0, steps)
            best_step = min(best_step, (time.perf_counter() - start) / N_CALLS)
        out[f"{name} evaluate"] = best_eval * 1e9
        out[f"{name} step"] = best_step * 1e9
        out[f"{name} build+evaluate"] = best_build * 1e9
    return out


def _run_tree(tree: Path, repeats: int) -> dict[str, float]:
    env = dict(os.environ, PYTHONPATH=str(tree))
    result = subprocess.run(
        [sys.executable, __file__, "--measure", "--repeats", str(repeats)],
        env=env,
        cwd=tree,
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(result.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default="cfb3416", help="the commit to compare with (default: %(default)s)")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--rounds", type=int, default=2, help="alternations of the two trees")
    parser.add_argument("--measure", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.measure:
        print(json.dumps(measure(args.repeats)))
        return
    here = Path(__file__).resolve().parent.parent
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "baseline"
        subprocess.run(
            ["git", "-C", str(here), "worktree", "add", "--detach", "-q", str(base), args.baseline], check=True
        )
        try:
            old: dict[str, float] = {}
            new: dict[str, float] = {}
            for _ in range(args.rounds):
                for tree, best in ((base, old), (here, new)):
                    for key, value in _run_tree(tree, args.repeats).items():
                        best[key] = min(best.get(key, float("inf")), value)
        finally:
            subprocess.run(["git", "-C", str(here), "worktree", "remove", "--force", str(base)], check=True)
    print(f"exact flow, ns per evaluation (best of {args.rounds} x {args.repeats}); baseline {args.baseline}")
    print(f"{'case':34s} {'baseline':>10s} {'this tree':>10s} {'ratio':>7s}")
    for key in old:
        print(f"{key:34s} {old[key]:10.1f} {new[key]:10.1f} {new[key] / old[key]:7.2f}")
    print("load average:", " ".join(Path("/proc/loadavg").read_text().split()[:3]))


if __name__ == "__main__":
    main()
