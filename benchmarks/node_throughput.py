"""Throughput and command latency of the simulation node (prints figures; not a test).

    .venv/bin/python benchmarks/node_throughput.py            # full run (~1 min)
    .venv/bin/python benchmarks/node_throughput.py --quick    # shorter windows

Part 1, real-time factor 0: the node (in this process, real rclpy publishers) runs the
free_tumble body at dt = 1 ms, publishing ~/state, ~/orientation, ~/angular_velocity,
~/angular_momentum and /clock at 100 Hz of sim time each; physics steps per wall second,
per integrator. Nobody subscribes (publishing cost without network delivery). Next to it,
the same scene's physics alone (``Simulator.advance`` in chunks of 10 steps, as the node
takes them between 100 Hz outputs) in the same run, and the split of the node's time per
step into physics and everything else (publishing, executor, timers).

Part 2, real-time factor 1, dt = 1 ms (1 kHz physics), ~/state at 1 kHz, torque_driven
scene: the node runs in this process, instrumented; a separate process publishes
WrenchStamped commands at 20 Hz (torque alternating in sign, a distinct value each time).
For each command: the wall time from its arrival in the node's subscription callback to the
publication of the first ~/state whose torque_body carries it (waiting for the next step
boundary, the step, the message). Prints p50 / p99 / max and the process's CPU use
(process time over wall time; the command publisher is another process).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 1))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import numpy as np
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "config" / "scenes"
# Part 1 figures before the compiled kernels (README, load average ~4): steps/s per method.
OLD_STEPS_PER_SECOND = {
    "exact": 41e3,
    "exact_split": 11e3,
    "taylor": 25e3,
    "rk4": 34e3,
    "lie_rk4": 41e3,
    "splitting": 38e3,
    "implicit_midpoint": 35e3,
    "dop853": 23e3,
    "euler": 40e3,
}
METHODS_FREE = ["exact", "exact_split", "taylor", "rk4", "lie_rk4", "splitting", "implicit_midpoint", "dop853", "euler"]


def make_node(scene: str, method: str, **params: float):
    """(context, node): the simulation node in this process at dt = 1 ms, warnings only."""
    from rigid_rot_sim.ros.node import RigidRotSimNode

    context = rclpy.Context()
    rclpy.init(context=context, args=["--ros-args", "--log-level", "warn"])
    overrides = [
        Parameter("scene", value=str(SCENES / f"{scene}.yaml")),
        Parameter("integrator", value=method),
        Parameter("dt", value=0.001),
    ]
    overrides += [Parameter(name, value=value) for name, value in params.items()]
    return context, RigidRotSimNode(context=context, parameter_overrides=overrides)


def steps_per_second(method: str, seconds: float) -> tuple[float, int]:
    rates = {
        f"rates.{name}": 100.0 for name in ("state", "orientation", "angular_velocity", "angular_momentum", "clock")
    }
    context, node = make_node("free_tumble", method, real_time_factor=0.0, **rates)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        executor.spin_once(timeout_sec=0.1)
        k0, t0 = node.run.sim.clock.k, time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            executor.spin_once(timeout_sec=0.1)
        elapsed = time.perf_counter() - t0
        steps = node.run.sim.clock.k - k0
        return steps / elapsed, steps
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown(context=context)


def physics_steps_per_second(method: str, seconds: float) -> float:
    """Steps per wall second of the free_tumble scene's Simulator alone, 10 steps a call."""
    from rigid_rot_sim.run.simulator import Simulator
    from rigid_rot_sim.scene.scene import load_scene

    sim = Simulator(load_scene(SCENES / "free_tumble.yaml"), method=method, dt=0.001)
    sim.advance(10)
    k0, t0 = sim.clock.k, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        for _ in range(100):
            sim.advance(10)
    return (sim.clock.k - k0) / (time.perf_counter() - t0)


# The command source: a separate process publishing WrenchStamped at 20 Hz, the torque
# alternating in sign with a distinct magnitude each time (so each command is recognisable).
PUBLISHER_SCRIPT = """
import sys, time, rclpy
from geometry_msgs.msg import WrenchStamped
from rigid_rot_sim.ros.qos import COMMAND_QOS
n = int(sys.argv[1])
rclpy.init()
node = rclpy.create_node("latency_commands")
pub = node.create_publisher(WrenchStamped, "/rigid_rot_sim/torque", COMMAND_QOS)
while pub.get_subscription_count() == 0:
    rclpy.spin_once(node, timeout_sec=0.05)
time.sleep(1.0)
for i in range(n):
    msg = WrenchStamped()
    msg.header.frame_id = "base_link"
    msg.wrench.torque.z = (1e-4 + 1e-8 * i) * (1 if i % 2 == 0 else -1)
    pub.publish(msg)
    time.sleep(0.05)
pub.wait_for_all_acked(rclpy.duration.Duration(seconds=2.0))
"""


def command_latency(n_commands: int, method: str) -> None:
    """Node in this process (instrumented), commands from another process; arrival -> publication."""
    context, node = make_node("torque_driven", method, real_time_factor=1.0, **{"rates.state": 1000.0})
    arrivals: dict[float, float] = {}
    latencies: list[float] = []
    received = node.run.inputs.torque_callback
    state_publisher = node.run.outputs.publishers["state"]
    publish = state_publisher.publish

    def timed_callback(msg, source, topic):
        arrivals.setdefault(msg.wrench.torque.z, time.perf_counter())
        received(msg, source, topic)

    def timed_publish(msg):
        publish(msg)
        arrived = arrivals.pop(msg.torque_body.z, None)
        if arrived is not None:
            latencies.append(time.perf_counter() - arrived)

    node.run.inputs.torque_callback = timed_callback
    state_publisher.publish = timed_publish
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    source = subprocess.Popen([sys.executable, "-c", PUBLISHER_SCRIPT, str(n_commands)], stdin=subprocess.DEVNULL)
    try:
        while not arrivals and source.poll() is None:
            executor.spin_once(timeout_sec=0.05)
        cpu0, wall0, k0 = time.process_time(), time.perf_counter(), node.run.sim.clock.k
        while source.poll() is None:
            executor.spin_once(timeout_sec=0.05)
        wall = time.perf_counter() - wall0
        cpu = (time.process_time() - cpu0) / wall
        steps = node.run.sim.clock.k - k0
    finally:
        if source.poll() is None:
            source.terminate()
        source.wait(timeout=10)
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown(context=context)
    lat = np.array(latencies) * 1e3
    print(
        f"  integrator {method}: {len(lat)}/{n_commands} commands reflected in ~/state; "
        f"{steps / wall:.0f} steps per wall second (target 1000)"
    )
    if len(lat):
        print(
            f"  latency command arrival -> first ~/state reflecting it: p50 {np.percentile(lat, 50):.2f} ms, "
            f"p99 {np.percentile(lat, 99):.2f} ms, max {lat.max():.2f} ms"
        )
    print(f"  node CPU use: {100 * cpu:.0f} % of one core (1 kHz physics, ~/state at 1 kHz + 4 outputs at 100 Hz)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="short measuring windows")
    parser.add_argument("--latency-integrator", default="rk4", help="integrator for part 2 (default rk4)")
    args = parser.parse_args()
    seconds = 0.5 if args.quick else 2.0
    print(
        f"python {sys.version.split()[0]}, numpy {np.__version__}, cpus {os.cpu_count()}, "
        f"load average {os.getloadavg()[0]:.2f} (other processes share the cores)"
    )
    print("part 1: real-time factor 0, dt 1 ms, 5 outputs at 100 Hz (sim time), free_tumble")
    print(f"  {'method':18s} {'node':>16s} {'physics alone':>22s}   split of the node's time per step")
    for method in METHODS_FREE:
        rate, steps = steps_per_second(method, seconds)
        physics = physics_steps_per_second(method, seconds / 2)
        per_step, physics_per_step = 1e6 / rate, 1e6 / physics
        print(
            f"  {method:18s} {rate:10.0f} steps/s {physics:12.0f} steps/s   "
            f"{per_step:6.2f} us = physics {physics_per_step:5.2f} us + rest {per_step - physics_per_step:5.2f} us "
            f"({steps} steps; {rate / OLD_STEPS_PER_SECOND[method]:.1f}x the old "
            f"{OLD_STEPS_PER_SECOND[method] / 1e3:.0f}k)"
        )
    print("part 2: real-time factor 1, 1 kHz physics, torque_driven, commands at 20 Hz")
    command_latency(40 if args.quick else 200, args.latency_integrator)


if __name__ == "__main__":
    main()
