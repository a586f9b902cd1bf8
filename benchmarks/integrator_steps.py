"""Cost of one step of every registered integrator, in nanoseconds, in one run.

On I = diag(1, 2, 3) kg*m^2, omega0 = (1, 0.1, 0.5) rad/s, dt = 1 ms, per method:
  advance      per step inside ``Integrator.advance(n)`` (the compiled loop ``simulate`` and
               the node run);
  step         per call of ``Integrator.step()`` (one step per call: call overhead included);
  interpreted  per step of the same kernel source run by CPython (what every step cost before
               the kernels were compiled, and what a Python-callable torque still costs);
  speed-up     interpreted / advance, measured in this run.
Then scipy's explicit solvers stepping the same problem (``RK45`` and ``DOP853`` objects,
``.step()`` per internal step, right-hand side in Python): the per-step cost of the usual
alternative. Adaptive methods (dop853, taylor) report per *output* step of dt. Each figure is
the best of ``--repeats``; with ``--torque`` also a constant body torque (data in the kernel)
and a general Python callable (gravity + damping: the interpreted path).

Usage:
    python benchmarks/integrator_steps.py [--steps N] [--repeats R] [--torque]

Printed, never asserted: on a shared machine compare the ratios of one run.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np
from scipy.integrate import DOP853, RK45

from rigid_rot_sim.core.dynamics import euler_rhs_components
from rigid_rot_sim.core.integrators import METHODS, kernels
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque, torque_data

MOMENTS = np.array([1.0, 2.0, 3.0])
OMEGA0 = np.array([1.0, 0.1, 0.5])
DT = 1e-3
VARIANTS = {"splitting": [{"order": 2}, {"order": 4}, {"order": 6}], "exact_split": [{"order": 2}, {"order": 4}]}

_GRAVITY = GravityTorque(np.array([0.0, 0.0, 0.1]), 1.0)


def general_torque(t, q, omega):
    return _GRAVITY(t, q, omega) - 0.01 * omega


def best_of(repeats, run):
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


def time_per_step(name, options, torque, steps, repeats, use_step):
    def run():
        integrator = METHODS[name](MOMENTS, DT, torque, omega0=OMEGA0, **options)
        if use_step:
            for _ in range(steps):
                integrator.step()
        else:
            integrator.advance(steps)

    return best_of(repeats, run) / steps * 1e9


def interpreted_per_step(name, options, torque, steps, repeats):
    """ns per step of the kernel source run by CPython (None: not a fixed-step kernel)."""
    integrator = METHODS[name](MOMENTS, DT, torque, omega0=OMEGA0, **options)
    kernel_name = getattr(integrator, "kernel_name", None)
    if kernel_name not in kernels.KERNEL_IDS:
        return None
    method = kernels.KERNEL_IDS[kernel_name]
    state = tuple(integrator.q.tolist() + integrator.omega.tolist())
    data = torque_data(torque)
    empty = np.empty((0, 7))
    return (
        best_of(
            repeats,
            lambda: kernels.advance_steps(method, 0.0, 0, DT, steps, state, tuple(MOMENTS.tolist()), data, 0, empty),
        )
        / steps
        * 1e9
    )


def scipy_per_step(solver_class, steps, repeats):
    """ns per internal step of a scipy solver on the free body (rhs on floats in Python)."""
    i1, i2, i3 = MOMENTS.tolist()

    def rhs(t, y):
        qx, qy, qz, qw, w1, w2, w3 = y.tolist()
        return np.array(
            [
                0.5 * (qw * w1 + qy * w3 - qz * w2),
                0.5 * (qw * w2 + qz * w1 - qx * w3),
                0.5 * (qw * w3 + qx * w2 - qy * w1),
                -0.5 * (qx * w1 + qy * w2 + qz * w3),
                *euler_rhs_components(i1, i2, i3, w1, w2, w3, 0.0, 0.0, 0.0),
            ]
        )

    def run():
        solver = solver_class(
            rhs, 0.0, np.r_[0.0, 0.0, 0.0, 1.0, OMEGA0], math.inf, rtol=1e-10, atol=1e-12, max_step=DT
        )
        for _ in range(steps):
            solver.step()

    return best_of(repeats, run) / steps * 1e9


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--torque", action="store_true", help="also time constant and general torques")
    args = parser.parse_args()
    torques = {"free": None}
    if args.torque:
        torques.update(constant=ConstantTorque(np.array([0.1, -0.05, 0.02])), general=general_torque)
    print(
        f"ns/step, dt = {DT} s, {args.steps} steps, best of {args.repeats}; "
        f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs (shared: compare ratios)"
    )
    print(f"{'method':24s}{'torque':>9s}{'advance':>11s}{'step':>11s}{'interpreted':>13s}{'speed-up':>10s}")
    slow_steps = max(200, args.steps // 20)  # the interpreted path and scipy are ~100x slower
    for name in METHODS:
        for options in VARIANTS.get(name, [{}]):
            label = name + "".join(f" {k}={v}" for k, v in options.items())
            for torque_name, torque in torques.items():
                general = torque_name == "general"
                try:
                    n = slow_steps if general or name == "dop853" else args.steps
                    fast = time_per_step(name, options, torque, n, args.repeats, False)
                    single = time_per_step(name, options, torque, min(n, slow_steps * 5), args.repeats, True)
                except ValueError as error:  # e.g. ``exact`` refuses a torque
                    print(f"{label:24s}{torque_name:>9s}   n/a: {error}"[:110])
                    continue
                slow = None if general else interpreted_per_step(name, options, torque, slow_steps, args.repeats)
                slow_text = f"{slow:13.0f}{slow / fast:9.0f}x" if slow else f"{'-':>13s}{'-':>10s}"
                print(f"{label:24s}{torque_name:>9s}{fast:11.0f}{single:11.0f}{slow_text}")
    for solver_class in (RK45, DOP853):
        cost = scipy_per_step(solver_class, slow_steps, args.repeats)
        print(f"{'scipy ' + solver_class.__name__ + '.step()':24s}{'free':>9s}{cost:11.0f}  (per internal step)")


if __name__ == "__main__":
    main()
