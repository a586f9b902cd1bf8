"""Cost of the orbit and the Earth's field: the node's steps/s on a field scene against the same body without
orbit, field and magnetometer (same run), and the field evaluation's cost per call (prints figures; not a test).

    .venv/bin/python benchmarks/orbit_field.py            # 600 s of sim time per scene
    .venv/bin/python benchmarks/orbit_field.py --quick    # 120 s

Part 1: the node in this process (real rclpy publishers, nobody subscribing), real-time factor 0, classical
RK4 at dt = 10 ms (``gyrostat_rk4`` where the gravity gradient acts, ``rk4`` without), the body, initial state
and default outputs of config/scenes/cubesat_orbit.yaml, ~/state and /tf at 10 Hz, ~/torque_breakdown off (an
output of every torque scene, not of the field). Four scenes, one run, each run three times interleaved
(the best kept):

* ``plain``: the body alone;
* ``field``: + the 500 km sun-synchronous orbit with J2, IGRF-14, the magnetometer at 10 Hz, ~/magnetic_field
  and ~/orbit at 10 Hz, /tf with the orbit: the issue's bar is field / plain >= 0.5;
* ``circular_gg``: the body with the circular gravity gradient of the same radius and inclination (the
  gravity-gradient stepper as it was);
* ``field_gg``: the shipped scene, ``field`` + the gravity gradient on the orbit: against ``circular_gg``, the
  cost of the orbit and field on that stepper (against ``plain`` it also holds the stepper's own cost).

Part 2: one evaluation of the field along the orbit (compiled ``field_eci_on_orbit``: the Kepler position,
the Earth rotation, the spherical harmonics, back to ECI) per model, and the pure-Python ``field_ned``.
"""

from __future__ import annotations

import argparse
import datetime
import os
import time
from pathlib import Path

os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 1))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import rclpy  # noqa: E402
import yaml  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FIELD_SCENE = ROOT / "config" / "scenes" / "cubesat_orbit.yaml"


def scenes(tmp: Path, duration: float) -> dict[str, Path]:
    """The four scenes of Part 1 at ``duration`` s of sim time."""
    shipped = yaml.safe_load(FIELD_SCENE.read_text())
    plain = {key: shipped[key] for key in ("name", "body", "initial", "real_time_factor")}
    plain.update(duration=duration, outputs={"state": 10, "tf": 10, "torque_breakdown": 0})
    plain["integrator"] = {"method": "rk4", "dt": 0.01}
    field = {**plain, "epoch": shipped["epoch"], "orbit": shipped["orbit"], "sensors": shipped["sensors"]}
    field["environment"] = {"magnetic_field": shipped["environment"]["magnetic_field"]}
    field["outputs"] = {**plain["outputs"], "magnetic_field": 10, "orbit": 10}
    gyrostat = {"method": "gyrostat_rk4", "dt": 0.01}
    field_gg = {**field, "environment": shipped["environment"], "integrator": gyrostat}
    circle = {"radius": shipped["orbit"]["elements"]["semi_major_axis"], "inclination": 1.7}
    circular_gg = {**plain, "environment": {"gravity_gradient": {"orbit": circle}}, "integrator": gyrostat}
    paths = {}
    for name, spec in (("plain", plain), ("field", field), ("circular_gg", circular_gg), ("field_gg", field_gg)):
        paths[name] = tmp / f"{name}.yaml"
        paths[name].write_text(yaml.safe_dump({**spec, "name": name}))
    return paths


def steps_per_second(scene: Path) -> tuple[float, int]:
    """(physics steps per wall second of the node's run loop, steps)."""
    from rigid_rot_sim.ros.node import RigidRotSimNode

    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = RigidRotSimNode(
            context=context,
            parameter_overrides=[Parameter("scene", value=str(scene)), Parameter("real_time_factor", value=0.0)],
        )
        start = time.perf_counter()
        while not node.finished:
            node.run.tick()
        elapsed = time.perf_counter() - start
        steps = node.run.sim.clock.k
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    return steps / elapsed, steps


def field_call_costs(calls: int) -> dict[str, float]:
    """Microseconds per call of the compiled field along an orbit (per model) and of ``field_ned``."""
    from rigid_rot_sim.core import geomagnetic
    from rigid_rot_sim.core.orbit import kepler_orbit

    kepler = kepler_orbit(6878137.0, 0.001, 1.7, 0.3, 0.2, 0.1)
    costs = {}
    for name in geomagnetic.MODELS:
        along = geomagnetic.orbit_field(name, kepler, datetime.datetime(2026, 6, 21), None)
        along.eci(0.0)  # compiled (or loaded from the cache) before the clock starts
        m, k = along.model, kepler.compiled()
        start = time.perf_counter()
        for i in range(calls):
            geomagnetic.field_eci_on_orbit_compiled(k, m.epochs, m.g, m.h, along.epoch_days, along.epoch_year, i * 0.1)
        costs[f"field_eci_on_orbit ({name}, compiled)"] = (time.perf_counter() - start) / calls * 1e6
    start = time.perf_counter()
    for i in range(calls // 20):
        geomagnetic.field_ned("igrf14", 45.0, i * 0.01, 500e3, 2026.5)
    costs["field_ned (igrf14, pure Python)"] = (time.perf_counter() - start) / (calls // 20) * 1e6
    return costs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="120 s of sim time per scene instead of 600 s")
    args = parser.parse_args()
    import tempfile

    duration = 120.0 if args.quick else 600.0
    with tempfile.TemporaryDirectory() as tmp:
        paths = scenes(Path(tmp), duration)
        for path in paths.values():
            steps_per_second(path)  # warm-up: kernels loaded, the field compiled, DDS settled
        # the best of three, the scenes interleaved: a shared machine's load hits them alike
        runs = [{name: steps_per_second(path) for name, path in paths.items()} for _ in range(3)]
        rates = {name: max((run[name] for run in runs), key=lambda r: r[0]) for name in paths}
    print(f"Part 1: the node, rtf 0, RK4 dt 10 ms, {duration:g} s of sim time per scene")
    for name, (rate, steps) in rates.items():
        print(f"  {name:12s} {rate:10.0f} steps/s ({steps} steps)")
    ratio = rates["field"][0] / rates["plain"][0]
    print(f"  field / plain = {ratio:.2f} (required >= 0.5: {'PASS' if ratio >= 0.5 else 'FAIL'})")
    print(f"  field_gg / circular_gg = {rates['field_gg'][0] / rates['circular_gg'][0]:.2f}")
    print(f"  field_gg / plain = {rates['field_gg'][0] / rates['plain'][0]:.2f} (with the gyrostat stepper's own cost)")
    print("Part 2: the field's cost per call")
    for name, micros in field_call_costs(20000).items():
        print(f"  {name:42s} {micros:8.2f} us")


if __name__ == "__main__":
    main()
