"""Run time and error of every registered integrator at three step sizes (issue 3's table).

Problem: I = diag(1, 2, 3) kg*m^2, omega0 = (1, 0.1, 0.5) rad/s, q0 = identity,
torque-free, T = 100 s (``--torque``: constant body torque (0.1, -0.05, 0.02) N*m, T = 20 s).
Each row is one ``simulate(...)`` call keeping only the final state (run time includes
set-up; best of ``--repeats``). Errors at T: |omega - omega_ref|_max (rad/s) and the attitude
error angle (rad). Reference: the exact elliptic solution (core/exact.py); with a torque,
scipy DOP853 at rtol = atol = 1e-14. Adaptive methods sweep their tolerance instead of dt.
The last rows are scipy's solve_ivp(DOP853) on a float right-hand side, for comparison.

Usage:
    python benchmarks/integrator_table.py [--torque] [--repeats R] [--quick]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.dynamics import euler_rhs_components
from rigid_rot_sim.core.exact import torque_free_solution
from rigid_rot_sim.core.integrators import METHODS
from rigid_rot_sim.core.quaternion import multiply
from rigid_rot_sim.core.simulate import simulate

MOMENTS = (1.0, 2.0, 3.0)
OMEGA0 = (1.0, 0.1, 0.5)
Q0 = (0.0, 0.0, 0.0, 1.0)
TORQUE = (0.1, -0.05, 0.02)
ONE_OUTPUT = 10**12  # save_every: keep only t = 0 and t = T

# (options, dt) per row; dt None means one output step of T (adaptive methods)
SWEEPS = {
    "euler": [({}, 1e-2), ({}, 1e-3), ({}, 1e-4)],
    "rk4": [({}, 0.1), ({}, 0.03), ({}, 0.01)],
    "lie_rk4": [({}, 0.1), ({}, 0.03), ({}, 0.01)],
    "implicit_midpoint": [({}, 1e-2), ({}, 3e-3), ({}, 1e-3)],
    "dop853": [({"rtol": r, "atol": r * 1e-2}, None) for r in (1e-6, 1e-9, 1e-12)],
    "taylor": [({"tol": tol}, None) for tol in (1e-8, 1e-10, 1e-12)],
    "exact": [({}, None), ({}, 1.0), ({}, 0.1)],
}
for name in ("splitting", "exact_split"):
    SWEEPS[name] = (
        [({"order": 2}, dt) for dt in (1e-2, 3e-3, 1e-3)]
        + [({"order": 4}, dt) for dt in (0.1, 0.03, 0.01)]
        + ([({"order": 6}, dt) for dt in (0.2, 0.1, 0.05)] if name == "splitting" else [])
    )


def sweep(name):
    if name in SWEEPS:
        return SWEEPS[name]
    if METHODS[name].fixed_step:
        return [({}, dt) for dt in (0.1, 0.01, 0.001)]
    return [({}, None)]


def reference(t_end, torque):
    if torque is None:
        exact = torque_free_solution(MOMENTS, OMEGA0, Q0)
        return exact.quaternion(t_end), exact.omega(t_end)
    sol = solve_ivp(float_rhs(torque), (0.0, t_end), [*Q0, *OMEGA0], method="DOP853", rtol=1e-14, atol=1e-14)
    y = sol.y[:, -1]
    return y[:4] / np.linalg.norm(y[:4]), y[4:]


def float_rhs(torque):
    i1, i2, i3 = MOMENTS
    n1, n2, n3 = torque if torque is not None else (0.0, 0.0, 0.0)

    def rhs(t, y):
        qx, qy, qz, qw, w1, w2, w3 = y.tolist()
        dq = multiply((qx, qy, qz, qw), (w1, w2, w3, 0.0))
        return [
            0.5 * dq[0],
            0.5 * dq[1],
            0.5 * dq[2],
            0.5 * dq[3],
            *euler_rhs_components(i1, i2, i3, w1, w2, w3, n1, n2, n3),
        ]

    return rhs


def errors(q, omega, q_ref, omega_ref):
    angle = (Rotation.from_quat(q).inv() * Rotation.from_quat(q_ref)).magnitude()
    return float(np.max(np.abs(np.asarray(omega) - omega_ref))), float(angle)


def best_time(run, repeats):
    best, result = math.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        best = min(best, time.perf_counter() - start)
    return best, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--torque", action="store_true")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="T / 10, one repeat (a smoke run)")
    args = parser.parse_args()
    torque = TORQUE if args.torque else None
    t_end = 20.0 if args.torque else 100.0
    repeats = args.repeats
    if args.quick:
        t_end, repeats = t_end / 10, 1
    q_ref, omega_ref = reference(t_end, torque)
    print(f"I = diag{MOMENTS} kg m^2, omega0 = {OMEGA0} rad/s, T = {t_end:g} s, torque = {torque}; best of {repeats}")
    print(f"{'method':18s}{'options':22s}{'dt (s)':>9s}{'run time (s)':>14s}{'omega err':>12s}{'att. err':>11s}")
    for name in METHODS:
        for options, dt in sweep(name):
            step = t_end if dt is None else dt
            label = " ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in options.items())

            def run(step=step, name=name, options=options):
                return simulate(MOMENTS, OMEGA0, t_end, step, name, Q0, torque, save_every=ONE_OUTPUT, **options)

            try:
                seconds, traj = best_time(run, repeats)
            except ValueError as error:
                print(f"{name:18s}{label:22s}   n/a: {str(error)[:80]}")
                break
            e_omega, e_att = errors(traj.q[-1], traj.omega[-1], q_ref, omega_ref)
            print(f"{name:18s}{label:22s}{step:9.3g}{seconds:14.4f}{e_omega:12.2e}{e_att:11.2e}")
    for rtol in (1e-6, 1e-9, 1e-12):
        rhs = float_rhs(torque)

        def run_scipy(rhs=rhs, rtol=rtol):
            return solve_ivp(rhs, (0.0, t_end), [*Q0, *OMEGA0], method="DOP853", rtol=rtol, atol=rtol * 1e-2)

        seconds, sol = best_time(run_scipy, repeats)
        y = sol.y[:, -1]
        e_omega, e_att = errors(y[:4] / np.linalg.norm(y[:4]), y[4:], q_ref, omega_ref)
        print(
            f"{'scipy solve_ivp':18s}{f'DOP853 rtol={rtol:g}':22s}{'':>9s}{seconds:14.4f}{e_omega:12.2e}{e_att:11.2e}"
        )


if __name__ == "__main__":
    main()
