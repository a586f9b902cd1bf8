"""Compile every numba kernel of the core once, into the on-disk cache (``make setup``).

    python -m rigid_rot_sim.core.precompile

Each entry point is run once through the public API with the argument types it gets at
run time, so that the node, the CLI and the tests load compiled code instead of paying
JIT time. Prints what was compiled or loaded and how long it took; exits non-zero if an
entry point ended up with more than one compiled signature (a type that varies from call
to call would mean JIT time at run time).

A completed pass leaves a stamp keyed on the core's sources (:func:`kernels_cached`), so that a
node started on an install whose kernels were never compiled (a ``colcon build``, which does not
run this module) says it is compiling and compiles before its run starts
(:func:`ensure_compiled`), instead of spending its first seconds of paced time in the JIT.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np


def entry_points() -> dict[str, Any]:
    """The compiled entry points of the core (numba dispatchers, which numba does not type), by name."""
    from rigid_rot_sim.core import batch, batch_gyrostat, exact, geomagnetic, sensitivities, slew
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
        "batch_gyrostat._advance_serial": batch_gyrostat._advance_serial,
        "batch_gyrostat._advance_parallel": batch_gyrostat._advance_parallel,
        "slew.slew_update": slew.slew_update,
        "geomagnetic.field_eci_on_orbit_compiled": geomagnetic.field_eci_on_orbit_compiled,
        "sensitivities.integrate_segments": sensitivities.integrate_segments,
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
    from rigid_rot_sim.core.batch_gyrostat import advance_gyrostats
    from rigid_rot_sim.core.slew import slew_update

    for n, steps in ((1, 2), (2, 100_000)):  # serial, then parallel
        q0 = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
        advance_gyrostats(
            np.tile(moments, (n, 1)), wheels, q0, np.ones((n, 3)), np.zeros((n, 1)), np.ones((n, 1)), 1e-4, steps
        )
    slew_update(
        q0,
        np.ones((2, 3)),
        q0,
        np.ones((2, 3)),
        q0,
        np.zeros((2, 3)),
        np.ones(3),
        np.ones(3),
        np.zeros(2, dtype=np.int64),
        np.zeros((2, 10)),
        np.zeros(2),
        True,
    )
    import datetime

    from rigid_rot_sim.core.geomagnetic import orbit_field
    from rigid_rot_sim.core.orbit import kepler_orbit

    orbit_field("igrf14", kepler_orbit(7e6, 0.0, 1.0, 0.0, 0.0, 0.0), datetime.datetime(2025, 1, 1), None).eci(1.0)
    from rigid_rot_sim.core.sensitivities import integrate_segments

    for k, with_sens in ((6, True), (0, False)):  # rigid-rot identify's fit, then its validation replays
        integrate_segments(
            np.array([0.0, 0.1, 0.2]),
            np.zeros((3, 3)),
            np.arange(3, dtype=np.int64),
            np.array([0, 3], dtype=np.int64),
            np.diag(moments),
            np.zeros((k, 3, 3)),
            np.zeros(3),
            np.ones((1, 3)),
            np.array([[0.0, 0.0, 0.0, 1.0]]),
            3,
            with_sens,
        )
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


def stamp_path() -> Path:
    """Where a completed pass leaves its stamp: numba's cache of the core, named by the sources' fingerprint."""
    from numba.core import config

    from rigid_rot_sim.core.jit import _CORE, sources_fingerprint

    cache_dir = str(getattr(config, "CACHE_DIR", "") or "")  # NUMBA_CACHE_DIR, read by numba at import
    directory = Path(cache_dir) if cache_dir else _CORE / "__pycache__"
    return directory / f"rigid_rot_sim-kernels-{sources_fingerprint()[:16]}.stamp"


def kernels_cached() -> bool:
    """True when every kernel of these core sources was compiled into the cache (by :func:`main`)."""
    return stamp_path().is_file()


def _leave_stamp() -> None:
    path = stamp_path()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(f"compiled by rigid_rot_sim.core.precompile, pid {os.getpid()}\n", encoding="utf-8")
    except OSError:
        pass  # a read-only install: every run compiles in memory, as numba does without a cache


def ensure_compiled(say: Callable[[str], None]) -> float:
    """Compile every kernel unless the cache holds them; ``say`` is told first. Seconds spent (0: cached)."""
    if kernels_cached():
        return 0.0
    say(
        "compiling the numba kernels once for this install (about 1.5 min of CPU time, minutes more on a busy "
        "machine: docs/benchmarks.md; they are cached for later runs, "
        "`python -m rigid_rot_sim.core.precompile` does it ahead)"
    )
    start = time.perf_counter()
    exercise()
    _leave_stamp()
    return time.perf_counter() - start


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
    if status == 0:
        _leave_stamp()
    return status


if __name__ == "__main__":
    sys.exit(main())
