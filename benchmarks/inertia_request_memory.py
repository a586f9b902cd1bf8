"""What a huge ``~/compute_inertia`` request costs the node's memory before it is refused (prints figures; not a test)

    .venv/bin/python benchmarks/inertia_request_memory.py                      # 1e4, 1e5, 1e6 masses
    .venv/bin/python benchmarks/inertia_request_memory.py --masses 300000

The callback refuses more than ``limits.MAX_POINT_MASSES`` masses before converting anything,
but rclpy has by then taken the request: the middleware deserialised its CDR bytes (32 bytes a
mass) and rclpy turned them into Python objects (a ``geometry_msgs/Point`` a mass). Neither can be
bounded from Python in rclpy 7.1 (a service has no raw, serialised take, unlike a subscription),
so the cost is measured here, against a baseline in the same run: for each size, a fresh node
(no scene: it serves ``~/compute_inertia`` only) is started, its peak RSS (VmHWM) read once the
service answers a one-mass request, then after each of ``--repeat`` requests of that size (does the
cost add up?); and its RSS after.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 1))
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"

import rclpy
from geometry_msgs.msg import Point

from rigid_rot_msgs.srv import ComputeInertia

SERVICE = "/rigid_rot_sim/compute_inertia"


def status_mib(pid: int, field: str) -> float:
    """A memory field of /proc/PID/status (VmHWM: peak RSS, VmRSS: RSS now), MiB."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) / 1024.0
    raise RuntimeError(f"no {field} in /proc/{pid}/status")


def request(count: int) -> ComputeInertia.Request:
    msg = ComputeInertia.Request()
    msg.masses = [1.0] * count
    msg.positions = [Point(x=float(i % 7), y=float(i % 5), z=float(i % 3)) for i in range(count)]
    return msg


def call(node, client, msg, timeout: float = 300.0):
    future = client.call_async(msg)
    rclpy.spin_until_future_complete(node, future, timeout_sec=timeout)
    if not future.done():
        raise RuntimeError(f"no reply within {timeout} s")
    return future.result()


def measure(node, count: int, repeat: int) -> tuple[float, list[float], float, float, str]:
    """(baseline peak, peak after each request, RSS after (MiB), last round trip (s), last reply) for
    ``repeat`` requests of ``count`` masses, one after the other."""
    server = subprocess.Popen(
        [sys.executable, "-m", "rigid_rot_sim.ros.node"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        client = node.create_client(ComputeInertia, SERVICE)
        while not client.wait_for_service(timeout_sec=1.0):
            if server.poll() is not None:
                raise RuntimeError("the node exited")
        call(node, client, request(1))
        baseline = status_mib(server.pid, "VmHWM")
        msg = request(count)
        peaks = []
        for _ in range(repeat):
            began = time.monotonic()
            reply = call(node, client, msg)
            seconds = time.monotonic() - began
            peaks.append(status_mib(server.pid, "VmHWM"))
        now = status_mib(server.pid, "VmRSS")
        node.destroy_client(client)
        return baseline, peaks, now, seconds, f"success {reply.success}: {reply.message}"
    finally:
        server.terminate()
        server.wait(timeout=30)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--masses", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])
    parser.add_argument("--repeat", type=int, default=2, help="requests of each size, one after the other")
    args = parser.parse_args()
    print(f"load average {open('/proc/loadavg').read().split()[:3]}")
    rclpy.init()
    node = rclpy.create_node("inertia_request_memory")
    try:
        for count in args.masses:
            baseline, peaks, now, seconds, reply = measure(node, count, args.repeat)
            print(
                f"{count:>9} masses ({count * 32 / 1e6:.1f} MB) x {args.repeat}: node peak RSS {baseline:.0f} -> "
                f"{' -> '.join(f'{p:.0f}' for p in peaks)} MiB (+{peaks[-1] - baseline:.0f}), RSS after {now:.0f} MiB; "
                f"round trip {seconds:.2f} s; {reply}"
            )
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
