"""Throughput and command latency of the simulation node (prints figures; not a test).

    .venv/bin/python benchmarks/node_throughput.py            # full run (~1 min)
    .venv/bin/python benchmarks/node_throughput.py --quick    # shorter windows

Part 1, real-time factor 0: the node (in this process, real rclpy publishers) runs the
free_tumble body at dt = 1 ms, publishing ~/state, ~/orientation, ~/angular_velocity,
~/angular_momentum and /clock at 100 Hz of sim time each; physics steps per wall second,
per integrator. Nobody subscribes (publishing cost without network delivery).

Part 2, real-time factor 1, dt = 1 ms (1 kHz physics), ~/state at 1 kHz: the node runs in
a subprocess (torque_driven scene); this process publishes WrenchStamped commands whose
torque alternates in sign at 20 Hz and measures, for each, the wall time from publishing it
to receiving the first ~/state whose torque_body carries it (DDS both ways + waiting for
the next step boundary + the step + publication). Prints p50 / p99 / max, and the node
process's CPU use (user + system time over wall time, from /proc).
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

import numpy as np  # noqa: E402
import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "config" / "scenes"
METHODS_FREE = ["exact", "exact_split", "taylor", "rk4", "lie_rk4", "splitting", "implicit_midpoint", "dop853", "euler"]


def steps_per_second(method: str, seconds: float) -> tuple[float, int]:
    from rigid_rot_sim.node import RigidRotSimNode

    context = rclpy.Context()
    rclpy.init(context=context, args=["--ros-args", "--log-level", "warn"])
    rates = [Parameter(f"rates.{name}", value=100.0) for name in ("state", "orientation", "angular_velocity", "angular_momentum", "clock")]
    node = RigidRotSimNode(
        context=context,
        parameter_overrides=[
            Parameter("scene", value=str(SCENES / "free_tumble.yaml")),
            Parameter("integrator", value=method),
            Parameter("dt", value=0.001),
            Parameter("real_time_factor", value=0.0),
            *rates,
        ],
    )
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        executor.spin_once(timeout_sec=0.1)
        k0, t0 = node.sim.step_index, time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            executor.spin_once(timeout_sec=0.1)
        elapsed = time.perf_counter() - t0
        steps = node.sim.step_index - k0
        return steps / elapsed, steps
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown(context=context)


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def command_latency(n_commands: int, method: str) -> None:
    from geometry_msgs.msg import WrenchStamped
    from rigid_rot_msgs.msg import RigidBodyState

    from rigid_rot_sim.node import COMMAND_QOS, STATE_QOS

    command = [
        sys.executable, "-m", "rigid_rot_sim.node", "--ros-args",
        "-p", f"scene:={SCENES / 'torque_driven.yaml'}", "-p", f"integrator:={method}", "-p", "dt:=0.001",
        "-p", "real_time_factor:=1.0", "-p", "rates.state:=1000.0", "--log-level", "warn",
    ]
    process = subprocess.Popen(command, stdin=subprocess.DEVNULL)
    context = rclpy.Context()
    rclpy.init(context=context)
    client = rclpy.create_node("latency_client", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(client)
    pending: dict[float, float] = {}  # torque z -> publish time
    latencies: list[float] = []
    received = [0]

    def on_state(msg: RigidBodyState) -> None:
        received[0] += 1
        z = msg.torque_body.z
        if z in pending:
            latencies.append(time.perf_counter() - pending.pop(z))

    client.create_subscription(RigidBodyState, "/rigid_rot_sim/state", on_state, STATE_QOS)
    publisher = client.create_publisher(WrenchStamped, "/rigid_rot_sim/torque", COMMAND_QOS)
    try:
        deadline = time.monotonic() + 30.0
        while publisher.get_subscription_count() == 0 or received[0] == 0:
            if time.monotonic() > deadline or process.poll() is not None:
                raise SystemExit("node did not come up")
            executor.spin_once(timeout_sec=0.05)
        cpu0, wall0 = cpu_seconds(process.pid), time.perf_counter()
        for i in range(n_commands):
            # distinct values, alternating sign: each command changes the applied torque
            z = (1e-4 + 1e-8 * i) * (1 if i % 2 == 0 else -1)
            msg = WrenchStamped()
            msg.header.frame_id = "body"
            msg.wrench.torque.z = z
            pending[z] = time.perf_counter()
            publisher.publish(msg)
            next_at = time.perf_counter() + 0.05
            while time.perf_counter() < next_at:
                executor.spin_once(timeout_sec=max(0.0, next_at - time.perf_counter()))
        end = time.perf_counter() + 0.5
        while time.perf_counter() < end:
            executor.spin_once(timeout_sec=0.05)
        wall = time.perf_counter() - wall0
        cpu = (cpu_seconds(process.pid) - cpu0) / wall
        print(f"  ~/state received at {received[0] / wall:.0f} msg/s (published at 1000)")
    finally:
        process.terminate()
        process.wait(timeout=10)
        executor.shutdown()
        client.destroy_node()
        rclpy.shutdown(context=context)
    lat = np.array(latencies) * 1e3
    print(f"  integrator {method}: {len(lat)}/{n_commands} commands seen in ~/state")
    if len(lat):
        print(f"  latency command -> first state reflecting it: p50 {np.percentile(lat, 50):.2f} ms, "
              f"p99 {np.percentile(lat, 99):.2f} ms, max {lat.max():.2f} ms")
    print(f"  node CPU use: {100 * cpu:.0f} % of one core (1 kHz physics, ~/state at 1 kHz + 4 topics at 100 Hz)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="short measuring windows")
    parser.add_argument("--latency-integrator", default="rk4", help="integrator for part 2 (default rk4)")
    args = parser.parse_args()
    seconds = 0.5 if args.quick else 2.0
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, cpus {os.cpu_count()}, "
          f"load average {os.getloadavg()[0]:.2f} (other processes share the cores)")
    print("part 1: real-time factor 0, dt 1 ms, 5 outputs at 100 Hz (sim time), free_tumble")
    for method in METHODS_FREE:
        rate, steps = steps_per_second(method, seconds)
        print(f"  {method:18s} {rate:10.0f} steps/s  ({steps} steps, {rate * 0.001:.1f}x real time)")
    print("part 2: real-time factor 1, 1 kHz physics, torque_driven, commands at 20 Hz")
    command_latency(40 if args.quick else 200, args.latency_integrator)


if __name__ == "__main__":
    main()
