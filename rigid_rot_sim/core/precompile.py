"""Compile every numba kernel of the core once, into the on-disk cache (``make setup``).

    python -m rigid_rot_sim.core.precompile

Each entry point is run once through the public API with the argument types it gets at
run time, so that the node, the CLI and the tests load compiled code instead of paying
JIT time. Prints what was compiled or loaded and how long it took; exits non-zero if an
entry point ended up with more than one compiled signature (a type that varies from call
to call would mean JIT time at run time).
"""

from __future__ import annotations

import sys
import time
from typing import Any

import numpy as np


def entry_points() -> dict[str, Any]:
    """The compiled entry points of the core (numba dispatchers, which numba does not type), by name."""
    from rigid_rot_sim.core import batch, exact
    from rigid_rot_sim.core.integrators import gyrostat, kernels, taylor

    return {
        "integrators.kernels.advance_compiled": kernels.advance_compiled,
        "integrators.taylor.taylor_advance": taylor.taylor_advance,
        "integrators.gyrostat.rk4_advance": gyrostat.rk4_advance,
        "integrators.gyrostat.dopri5_advance": gyrostat.dopri5_advance,
        "exact._build": exact._build,
        "exact.evaluate_flow": exact.evaluate_flow,
        "exact._free_flow_compiled": exact._free_flow_compiled,
        "batch._advance_bodies_serial": batch._advance_bodies_serial,
        "batch._advance_bodies_parallel": batch._advance_bodies_parallel,
        "batch._rk4_soa_serial": batch._rk4_soa_serial,
        "batch._rk4_soa_parallel": batch._rk4_soa_parallel,
    }


def exercise() -> None:
    """Run every entry point once, as the node, simulate and the batch core do."""
    from rigid_rot_sim.core.batch import BATCH_METHODS, FREE_BODY_METHODS, advance_batch
    from rigid_rot_sim.core.integrators import METHODS
    from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque, PolynomialTorque

    moments = np.array([1.0, 2.0, 3.0])
    torques = [
        None,
        ConstantTorque(np.array([0.1, -0.05, 0.02])),
        PolynomialTorque(np.array([[0.1, 0.0, 0.0], [0.0, 0.01, 0.0]])),
        GravityTorque(np.array([0.0, 0.0, 0.1]), 1.0),
    ]
    for cls in METHODS.values():
        for torque in torques:
            try:
                integrator = cls(moments, 1e-3, torque, omega0=(1.0, 0.1, 0.5))
            except ValueError:  # a method refusing this torque (exact, taylor with a callable)
                continue
            integrator.advance(2)
            integrator.advance_saving(2, 1)
            integrator.step()
    from rigid_rot_sim.core.integrators.gyrostat import GYROSTAT_METHODS
    from rigid_rot_sim.core.wheels import orbit_model, wheel_model

    wheels = wheel_model(np.diag(moments), ["w"], [[0.0, 0.0, 1.0]], [0.1], [0.1], [100.0])
    for cls in GYROSTAT_METHODS.values():
        gyrostat = cls(moments, 1e-3, ConstantTorque(np.ones(3)), wheels=wheels, orbit=orbit_model(4e14, 7e6))
        gyrostat.advance(2)
    from rigid_rot_sim.core.exact import torque_free_flow, torque_free_solution

    solution = torque_free_solution(moments, (1.0, 0.1, 0.5))
    solution.state(1.0)
    solution.state(np.linspace(0.0, 1.0, 3))
    torque_free_flow(moments, (0.0, 0.0, 0.0, 1.0), (1.0, 0.1, 0.5), 0.1)
    rng = np.random.default_rng(0)
    for method in BATCH_METHODS + FREE_BODY_METHODS:
        batch_torque = None if method in FREE_BODY_METHODS else np.ones(3) * 1e-3
        for n, steps in ((1, 2), (2, 100_000)):  # serial, then parallel
            advance_batch(method, moments, rng.normal(size=(n, 4)), rng.normal(size=(n, 3)), 1e-4, steps, batch_torque)
            if method == "rk4":
                advance_batch(
                    method,
                    moments,
                    rng.normal(size=(n, 4)),
                    rng.normal(size=(n, 3)),
                    1e-4,
                    steps,
                    batch_torque,
                    layout="per_body",
                )


def main() -> int:
    start = time.perf_counter()
    exercise()
    elapsed = time.perf_counter() - start
    status = 0
    for name, dispatcher in entry_points().items():
        signatures = dispatcher.signatures
        print(f"precompile: {name}: {len(signatures)} signature(s)")
        if len(signatures) != 1:
            print(f"precompile: {name} has {len(signatures)} signatures; expected 1: {signatures}", file=sys.stderr)
            status = 1
    print(f"precompile: every kernel compiled or loaded from the cache in {elapsed:.1f} s")
    return status


if __name__ == "__main__":
    sys.exit(main())
