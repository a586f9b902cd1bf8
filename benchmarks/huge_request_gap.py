"""Does a huge ``~/compute_inertia`` request stop the ``~/state`` stream? (prints figures; not a test)

    .venv/bin/python benchmarks/huge_request_gap.py                 # 1e6 masses (32 MB), 2 requests each
    .venv/bin/python benchmarks/huge_request_gap.py --masses 300000 --requests 1

rclpy turns a request into Python objects in the executor thread that takes it (1e6
geometry_msgs/Point: ~2.4 s), and only then does the callback refuse it (more than
``limits.MAX_POINT_MASSES``). The node (``rigid_rot_sim.ros.node.main``) spins a
MultiThreadedExecutor with ``~/compute_inertia`` in a callback group of its own; the baseline,
measured in the same run, is the same node spun by a SingleThreadedExecutor (the main loop
before issue 19).

For each executor: the node runs free_tumble at real-time factor 1 with ``~/state`` at 100 Hz.
This process records the wall time at which each ``~/state`` arrives; a second process sends the
requests (its own serialisation must not stall the subscriber that measures). Printed: the
largest gap between two ``~/state`` arrivals in the quiet seconds before and while the requests
are served, the requests' round trips and replies, and the node's peak RSS.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 1))
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ["PYTHONUNBUFFERED"] = "1"

import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402

from rigid_rot_msgs.msg import RigidBodyState  # noqa: E402
from rigid_rot_sim.ros.qos import STATE_QOS  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "config" / "scenes" / "free_tumble.yaml"
NODE = "/rigid_rot_sim"

#: The node spun the way before issue 19: one thread for everything.
SINGLE_THREADED_NODE = textwrap.dedent("""
    import sys, rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rigid_rot_sim.ros.node import RigidRotSimNode
    rclpy.init(args=sys.argv)
    node = RigidRotSimNode()
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        executor.spin()
    except KeyboardInterrupt:
        pass
""")

SENDER = textwrap.dedent("""
    import sys, time, rclpy
    from geometry_msgs.msg import Point
    from rigid_rot_msgs.srv import ComputeInertia
    count, requests = int(sys.argv[1]), int(sys.argv[2])
    rclpy.init()
    node = rclpy.create_node("huge_request_sender")
    client = node.create_client(ComputeInertia, "/rigid_rot_sim/compute_inertia")
    assert client.wait_for_service(timeout_sec=30.0)
    request = ComputeInertia.Request(masses=[1.0] * count, positions=[Point(x=float(i)) for i in range(count)])
    print("READY", flush=True)
    sys.stdin.readline()
    for _ in range(requests):
        began = time.monotonic()
        future = client.call_async(request)
        rclpy.spin_until_future_complete(node, future, timeout_sec=60.0)
        reply = future.result()
        print(f"REPLY {time.monotonic() - began:.3f} {reply.success if reply else None} "
              f"{reply.message[:80] if reply else 'no reply within 60 s'}", flush=True)
    print("DONE", flush=True)
""")


def peak_rss_mib(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def largest_gap(times: list[float], start: float, end: float) -> float:
    inside = [t for t in times if start <= t <= end]
    return max((b - a for a, b in zip(inside, inside[1:], strict=False)), default=float("inf"))


def measure(label: str, node_command: list[str], masses: int, requests: int, quiet: float) -> None:
    node = subprocess.Popen(
        node_command
        + ["--ros-args", "-p", f"scene:={SCENE}", "-p", "real_time_factor:=1.0", "-p", "rates.state:=100.0"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    sender = subprocess.Popen(
        [sys.executable, "-c", SENDER, str(masses), str(requests)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    context = rclpy.Context()
    rclpy.init(context=context)
    listener = rclpy.create_node("huge_request_listener", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(listener)
    arrivals: list[float] = []
    listener.create_subscription(
        RigidBodyState, f"{NODE}/state", lambda msg: arrivals.append(time.monotonic()), STATE_QOS
    )
    try:
        deadline = time.monotonic() + 60.0
        while len(arrivals) < 50 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        assert sender.stdout.readline().strip() == "READY", "the sender did not start"
        quiet_start = time.monotonic()
        while time.monotonic() < quiet_start + quiet:
            executor.spin_once(timeout_sec=0.01)
        busy_start = time.monotonic()
        sender.stdin.write("go\n")
        sender.stdin.flush()
        lines: list[str] = []
        reader = threading.Thread(target=lambda: lines.extend(iter(sender.stdout.readline, "")), daemon=True)
        reader.start()
        while not any(line.startswith("DONE") for line in lines) and time.monotonic() < busy_start + 60.0 * requests:
            executor.spin_once(timeout_sec=0.01)
        busy_end = time.monotonic()
        while time.monotonic() < busy_end + 1.0:  # the stream after the last reply
            executor.spin_once(timeout_sec=0.01)
        replies = [line.strip() for line in lines if line.startswith("REPLY")]
        print(
            f"{label}: largest ~/state gap: quiet {largest_gap(arrivals, quiet_start, busy_start) * 1e3:.0f} ms, "
            f"while serving {largest_gap(arrivals, busy_start, busy_end + 1.0) * 1e3:.0f} ms; "
            f"node peak RSS {peak_rss_mib(node.pid):.0f} MiB; {len(replies)} of {requests} replies"
        )
        for line in replies:
            _, seconds, success, message = line.split(" ", 3)
            print(f"    round trip {float(seconds):.2f} s, success {success}: {message}")
    finally:
        sender.kill()
        node.send_signal(2)
        node.wait(timeout=10)
        executor.shutdown()
        listener.destroy_node()
        rclpy.try_shutdown(context=context)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--masses", type=int, default=1_000_000, help="point masses per request (1e6: 32 MB)")
    parser.add_argument("--requests", type=int, default=2, help="requests sent one after the other")
    parser.add_argument("--quiet", type=float, default=3.0, help="s of baseline stream before the requests")
    args = parser.parse_args()
    print(f"load average {open('/proc/loadavg').read().split()[:3]}, {args.masses} masses x {args.requests}")
    measure(
        "SingleThreadedExecutor (baseline)",
        [sys.executable, "-c", SINGLE_THREADED_NODE],
        args.masses,
        args.requests,
        args.quiet,
    )
    measure(
        "node main (MultiThreadedExecutor)",
        [sys.executable, "-m", "rigid_rot_sim.ros.node"],
        args.masses,
        args.requests,
        args.quiet,
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
