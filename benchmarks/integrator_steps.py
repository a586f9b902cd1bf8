"""Cost of one step of every registered integrator, in microseconds.

Two figures per method, on I = diag(1, 2, 3) kg*m^2, omega0 = (1, 0.1, 0.5) rad/s, dt = 1 ms:
  advance  per-step cost inside ``Integrator.advance(n)`` (the loop ``simulate`` runs);
  step     per call of ``Integrator.step()`` (what a node calling once per tick pays).
Each is the best of several repeats; with a torque (``--torque``) a constant body torque
(0.1, -0.05, 0.02) N*m and a general callable torque (gravity + damping) are timed too.
Adaptive methods (dop853, taylor) report per *output* step of dt; their own steps are longer.

Usage:
    python benchmarks/integrator_steps.py [--steps N] [--repeats R] [--torque]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rigid_rot_sim.core.integrators import METHODS
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque

MOMENTS = np.array([1.0, 2.0, 3.0])
OMEGA0 = np.array([1.0, 0.1, 0.5])
DT = 1e-3
VARIANTS = {"splitting": [{"order": 2}, {"order": 4}, {"order": 6}], "exact_split": [{"order": 2}, {"order": 4}]}

_GRAVITY = GravityTorque(np.array([0.0, 0.0, 0.1]), 1.0)


def general_torque(t, q, omega):
    return _GRAVITY(t, q, omega) - 0.01 * omega


def time_per_step(name, options, torque, steps, repeats, use_step):
    best = float("inf")
    for _ in range(repeats):
        integrator = METHODS[name](MOMENTS, DT, torque, omega0=OMEGA0, **options)
        start = time.perf_counter()
        if use_step:
            for _ in range(steps):
                integrator.step()
        else:
            integrator.advance(steps)
        best = min(best, time.perf_counter() - start)
    return best / steps * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--torque", action="store_true", help="also time constant and general torques")
    args = parser.parse_args()
    torques = {"free": None}
    if args.torque:
        torques.update(constant=ConstantTorque(np.array([0.1, -0.05, 0.02])), general=general_torque)
    print(f"us/step, dt = {DT} s, {args.steps} steps, best of {args.repeats}")
    print(f"{'method':24s}{'torque':>9s}{'advance':>10s}{'step':>10s}")
    for name in METHODS:
        for options in VARIANTS.get(name, [{}]):
            label = name + "".join(f" {k}={v}" for k, v in options.items())
            for torque_name, torque in torques.items():
                try:
                    fast = time_per_step(name, options, torque, args.steps, args.repeats, False)
                    single = time_per_step(name, options, torque, args.steps, args.repeats, True)
                except ValueError as error:  # e.g. ``exact`` refuses a torque
                    print(f"{label:24s}{torque_name:>9s}   n/a: {error}")
                    continue
                print(f"{label:24s}{torque_name:>9s}{fast:10.2f}{single:10.2f}")


if __name__ == "__main__":
    main()
