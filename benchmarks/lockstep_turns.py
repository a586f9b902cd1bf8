"""Lockstep turns per second with the shipped controller over DDS, next to a bare rclpy round trip.

    .venv/bin/python benchmarks/lockstep_turns.py               # ~20 s
    .venv/bin/python benchmarks/lockstep_turns.py --turns 2000

Part 1, the floor, measured in this run before and after part 2 (their mean is the floor):
a bare rclpy publish/subscribe round trip between
this process and an echo process (a second Python process with one subscription that
publishes a WrenchStamped back for every RigidBodyState it gets), reliable, depth 10, one
message in flight. Round trips per second over ``--turns`` trips.

Part 2: the simulation node (``rigid_rot_sim_node``, closed_loop_lockstep scene: rk4, dt 1 ms,
a turn every 0.02 s = 20 physics steps, real_time_factor 0) and the shipped controller
(``rigid-rot-controller``), each its own process, as a user runs them. This process only
unpauses the run once the graph is matched and then stays off the wire, as in part 1 (a third
process listening to every state took a share of the 2 cores at every turn). Turns per second =
the node's own count: its end-of-run line, turns from the first released to the duration reached.

Figures: turns/s, the real-time multiple of a 50 Hz controller (turns/s / 50), and the ratio
to the bare round trip (aim: at least 0.5). Both parts pass the same messages through the
same rmw, so the ratio says what lockstep adds on top of DDS: the physics of a turn, the
checks, the executor wake-up.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import time

os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 101))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import rclpy
from geometry_msgs.msg import WrenchStamped
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_srvs.srv import SetBool

from rigid_rot_msgs.msg import RigidBodyState

QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
PERIOD = 0.02  # s of sim time per turn in closed_loop_lockstep
ECHO = """
import rclpy
from geometry_msgs.msg import WrenchStamped
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rigid_rot_msgs.msg import RigidBodyState
rclpy.init()
node = rclpy.create_node("bench_echo")
qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
pub = node.create_publisher(WrenchStamped, "/bench/pong", qos)
def echo(msg):
    out = WrenchStamped()
    out.header.stamp = msg.header.stamp
    out.wrench.torque.z = msg.orientation.z
    pub.publish(out)
node.create_subscription(RigidBodyState, "/bench/ping", echo, qos)
try:
    rclpy.spin(node)
except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
    pass
"""


def wait(node, condition, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise SystemExit(f"lockstep_turns: timed out waiting for {what}")
        rclpy.spin_once(node, timeout_sec=0.05)


def bare_round_trips(node, trips: int) -> float:
    """Round trips per second, this process <-> an echo process, one message in flight."""
    echo = subprocess.Popen([sys.executable, "-c", ECHO])
    try:
        pongs: list[int] = []
        pub = node.create_publisher(RigidBodyState, "/bench/ping", QOS)
        node.create_subscription(WrenchStamped, "/bench/pong", lambda m: pongs.append(m.header.stamp.nanosec), QOS)
        ping = RigidBodyState()
        # warm-up: until the echo is matched both ways
        wait(node, lambda: node.count_subscribers("/bench/ping") and node.count_publishers("/bench/pong"), 60, "echo")
        while not pongs:
            pub.publish(ping)
            wait(node, lambda: True, 1, "")
            rclpy.spin_once(node, timeout_sec=0.2)
        pongs.clear()
        start = time.perf_counter()
        for k in range(trips):
            ping.header.stamp.nanosec = k
            pub.publish(ping)
            while len(pongs) <= k:
                rclpy.spin_once(node, timeout_sec=1.0)
        return trips / (time.perf_counter() - start)
    finally:
        echo.send_signal(2)
        echo.wait(timeout=10)


def lockstep_turns(node, turns: int) -> tuple[float, int]:
    """Turns per second of node + shipped controller (two processes); (turns/s, turns timed).

    Nothing else is on the wire while the turns run (as in the bare round trip): the figure is the node's
    own, from its end-of-run line ("lockstep: N turns in W s of wall time since the first, ..."), counted
    from the first turn released to the duration reached. A third process listening to ~/state would
    take a share of the 2 cores at every turn and time itself, not the loop.
    """
    bindir = os.path.dirname(sys.executable)
    duration = turns * PERIOD
    controller = subprocess.Popen(
        [
            os.path.join(bindir, "rigid-rot-controller"),
            "--ros-args",
            "--log-level",
            "warn",
            "-p",
            "target:=[0.0, 0.0, 0.5, 0.8660254037844386]",
        ]
    )
    sim = subprocess.Popen(
        [
            os.path.join(bindir, "rigid_rot_sim_node"),
            "--ros-args",
            "--log-level",
            "info",
            "-p",
            "scene:=closed_loop_lockstep",
            "-p",
            f"duration:={duration!r}",
            "-p",
            "start_paused:=true",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        wait(
            node,
            lambda: (
                node.count_subscribers("/rigid_rot_sim/state") >= 1
                and node.count_publishers("/rigid_rot_sim/torque") >= 1
            ),
            60,
            "the node and the controller",
        )
        client = node.create_client(SetBool, "/rigid_rot_sim/pause")
        wait(node, client.service_is_ready, 60, "~/pause")
        client.call_async(SetBool.Request(data=False))  # the turns it starts are the answer
        try:
            out, _ = sim.communicate(timeout=600)  # the node ends at its duration
        except subprocess.TimeoutExpired:
            raise SystemExit("lockstep_turns: timed out waiting for the last turn") from None
        found = re.search(r"lockstep: (\d+) turns in ([0-9.]+) s of wall time since the first", out)
        if found is None:
            raise SystemExit(f"lockstep_turns: the node did not report its turns:\n{out[-2000:]}")
        done, wall = int(found.group(1)), float(found.group(2))
        node.destroy_client(client)
        if done < turns:
            raise SystemExit(f"lockstep_turns: only {done} of {turns} turns were answered:\n{out[-2000:]}")
        return done / wall, done
    finally:
        for process in (sim, controller):
            if process.poll() is None:
                process.send_signal(2)
            process.wait(timeout=10)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--turns", type=int, default=1000, help="turns (and bare round trips) to time")
    args = parser.parse_args()
    rclpy.init()
    node = rclpy.create_node("bench_lockstep")
    try:
        before = bare_round_trips(node, args.turns)
        rate, timed = lockstep_turns(node, args.turns)
        after = bare_round_trips(node, args.turns)  # the load of a shared machine drifts: the floor around it
        floor = (before + after) / 2
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    with open("/proc/loadavg") as f:
        load = f.read().split()[:3]
    print(
        f"bare rclpy round trip (this process <-> echo process): {floor:8.0f} round trips/s (the floor; "
        f"{before:.0f} before, {after:.0f} after)"
    )
    print(f"lockstep, node + rigid-rot-controller over DDS:       {rate:8.0f} turns/s over {timed} turns")
    print(f"  real-time multiple of a 50 Hz controller:            {rate * PERIOD:8.1f}x")
    print(f"  ratio to the bare round trip:                        {rate / floor:8.2f} (aim >= 0.5)")
    print(f"load average {' '.join(load)} on {os.cpu_count()} cores")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
