"""The node loop's figures (issue 27), each beside a bare rclpy baseline measured in the same run.

    .venv/bin/python benchmarks/node_loop.py            # idle and with two busy processes (~4 min)
    .venv/bin/python benchmarks/node_loop.py --quick    # shorter windows, fewer commands

Every figure is taken twice: with the machine as it is ("idle") and with two extra processes
busy-looping (``python -c 'while True: pass'``). The node runs as ``python -m rigid_rot_sim.ros.node``
in a process of its own, as a user runs it; this process publishes and listens.

1. **Commands taken of sent** at 50, 200 and 1000/s, half valid (tiny torques, ``base_link``), half
   invalid (NaN), rclpy's default reliable QoS (depth 10), on the shipped ``torque_driven`` scene with
   recording on: taken = the command messages in the node's own recording (it records every command
   it takes), valid accepted = its ``torque`` events, invalid reported = its ``~/rejected``. Beside
   it, a bare rclpy subscriber process (SingleThreadedExecutor, depth 10) counting what it takes.
2. **CPU share and steps per wall second** at real-time factor 1, dt 1 ms (1 kHz physics),
   ``~/state`` and ``~/angular_velocity`` at 1 kHz (the scene's other outputs at theirs: ``~/orientation``,
   ``~/angular_momentum``, ``~/torque_breakdown`` and ``/clock`` 100 Hz, ``/tf`` 50 Hz) and commands at 1 kHz
   (no recording): the node's CPU time over wall time
   (``/proc/<pid>/stat``), steps per wall second from the sim time of the ``~/state`` received; then
   the same node paused (start_paused), and with ``use_sim_time:=true`` (steps per wall second, to
   see it never stalls). Beside it, a bare rclpy process that publishes the same messages (types, rates, QoS; each
   pre-built, only its stamp changed) and takes a WrenchStamped at 1 kHz (SingleThreadedExecutor, a 1 ms
   timer): the floor for this traffic.
3. **Lockstep turns/s** (node + shipped controller, ``benchmarks/lockstep_turns.py``: the node's own count of
   its turns, nothing else on the wire) against the bare rclpy round trip between two processes, measured
   around it.

Figures on a shared machine are noisy: the load average is printed with each block.
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 140))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import rclpy  # noqa: E402
from geometry_msgs.msg import WrenchStamped  # noqa: E402
from rclpy.qos import QoSProfile  # noqa: E402

from rigid_rot_msgs.msg import RigidBodyState  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import lockstep_turns  # noqa: E402  # beside this file

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "config" / "scenes" / "torque_driven.yaml"
TORQUE = "/rigid_rot_sim/torque"
TICKS = os.sysconf("SC_CLK_TCK")

BARE_SUBSCRIBER = r"""
import sys, rclpy
from geometry_msgs.msg import WrenchStamped
rclpy.init()
node = rclpy.create_node("bare_subscriber")
taken = [0]
node.create_subscription(WrenchStamped, sys.argv[1], lambda m: taken.__setitem__(0, taken[0] + 1), 10)
try:
    while True:
        rclpy.spin_once(node, timeout_sec=0.5)
        print(taken[0], flush=True)
except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
    pass
"""

BARE_NODE = r"""
import rclpy
from rclpy.executors import SingleThreadedExecutor
from geometry_msgs.msg import QuaternionStamped, Vector3Stamped, WrenchStamped
from rosgraph_msgs.msg import Clock
from tf2_msgs.msg import TFMessage
from geometry_msgs.msg import TransformStamped
from rigid_rot_msgs.msg import RigidBodyState, TorqueBreakdown
from rigid_rot_sim.ros.qos import CLOCK_QOS, STATE_QOS, TF_QOS
rclpy.init()
node = rclpy.create_node("bare_1khz")
# the node's outputs in this benchmark, same types, rates (per 1 ms tick) and QoS, each message pre-built
every = [(RigidBodyState, "state", 1), (Vector3Stamped, "angular_velocity", 1), (QuaternionStamped, "orientation", 10),
         (Vector3Stamped, "angular_momentum", 10), (TorqueBreakdown, "torque_breakdown", 10)]
outs = []
for kind, name, period in every:
    msg = kind()
    outs.append((node.create_publisher(kind, "/bare/" + name, STATE_QOS), msg, msg.header.stamp, period))
clock = Clock()
outs.append((node.create_publisher(Clock, "/bare/clock", CLOCK_QOS), clock, clock.clock, 10))
tf = TFMessage(transforms=[TransformStamped()])
outs.append((node.create_publisher(TFMessage, "/bare/tf", TF_QOS), tf, tf.transforms[0].header.stamp, 20))
tick = [0]
def on_tick():
    tick[0] += 1
    sec, nanosec = divmod(tick[0] * 1000000, 1000000000)
    for pub, msg, stamp, period in outs:
        if tick[0] % period == 0:
            stamp.sec, stamp.nanosec = sec, nanosec
            pub.publish(msg)
node.create_timer(0.001, on_tick)
node.create_subscription(WrenchStamped, "/bare/torque", lambda m: None, 10)
executor = SingleThreadedExecutor()
executor.add_node(node)
try:
    executor.spin()
except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
    pass
"""


@contextmanager
def busy(loaded: bool):
    loops = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2 if loaded else 0)]
    try:
        yield
    finally:
        for loop in loops:
            loop.kill()
            loop.wait()


def cpu_seconds(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS


def start_node(*params: str) -> subprocess.Popen:
    args = [sys.executable, "-m", "rigid_rot_sim.ros.node", "--ros-args", "--log-level", "warn"]
    for p in ("scene:=" + str(SCENE), *params):
        args += ["-p", p]
    return subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def stop(process: subprocess.Popen) -> None:
    process.send_signal(2)
    try:
        process.wait(timeout=15)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


def spin_for(node, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.01)


def wait_matched(node, publisher, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while publisher.get_subscription_count() == 0:
        if time.monotonic() > deadline:
            raise SystemExit("node_loop: nobody subscribed")
        rclpy.spin_once(node, timeout_sec=0.05)
    spin_for(node, 0.3)


def publish_paced(node, publisher, count: int, rate: float, make) -> None:
    start = time.monotonic()
    for i in range(count):
        publisher.publish(make(i))
        pause = start + (i + 1) / rate - time.monotonic()
        if pause > 0:
            time.sleep(pause)
    publisher.wait_for_all_acked(rclpy.duration.Duration(seconds=5.0))


def command(i: int) -> WrenchStamped:
    msg = WrenchStamped()
    msg.header.frame_id = "base_link"
    msg.wrench.torque.x = 1e-6 if i % 2 == 0 else math.nan
    return msg


def commands_taken(node, rate: float, count: int) -> tuple[int, int, int]:
    """(taken, valid accepted, invalid reported) by the node, from its own recording."""
    from rigid_rot_sim.recording.events import decode_event
    from rigid_rot_sim.recording.reader import BagReader

    with tempfile.TemporaryDirectory() as directory:
        bag = Path(directory) / "run.mcap"
        sim = start_node(f"record_path:={bag}")
        try:
            publisher = node.create_publisher(WrenchStamped, TORQUE, 10)
            wait_matched(node, publisher)
            publish_paced(node, publisher, count, rate, command)
            node.destroy_publisher(publisher)
            time.sleep(1.0)
        finally:
            stop(sim)
        taken = BagReader(bag).counts().get(TORQUE, 0)
        events = [decode_event(e) for _, e in BagReader(bag).decoded(["/rigid_rot_sim/sim_events"])]
        accepted = sum(1 for e in events if e.kind == "torque")
        rejected = BagReader(bag).counts().get("/rigid_rot_sim/rejected", 0)
    return taken, accepted, rejected


def bare_taken(node, rate: float, count: int) -> int:
    sub = subprocess.Popen([sys.executable, "-c", BARE_SUBSCRIBER, "/bare/cmd"], stdout=subprocess.PIPE, text=True)
    try:
        publisher = node.create_publisher(WrenchStamped, "/bare/cmd", 10)
        wait_matched(node, publisher)
        publish_paced(node, publisher, count, rate, command)
        node.destroy_publisher(publisher)
        time.sleep(1.0)
    finally:
        stop(sub)
    lines = (sub.stdout.read() if sub.stdout else "").split()
    return int(lines[-1]) if lines else 0


def cpu_share(pid: int, seconds: float) -> float:
    before, start = cpu_seconds(pid), time.monotonic()
    time.sleep(seconds)
    return (cpu_seconds(pid) - before) / (time.monotonic() - start)


def loop_figures(node, seconds: float) -> dict[str, float]:
    """Node CPU and steps per wall second at 1 kHz (playing, with commands), paused, and with use_sim_time."""
    figures: dict[str, float] = {}
    stamps: list[tuple[float, float]] = []
    node.create_subscription(
        RigidBodyState,
        "/rigid_rot_sim/state",
        lambda m: stamps.append((m.header.stamp.sec + m.header.stamp.nanosec * 1e-9, time.monotonic())),
        QoSProfile(depth=100),
    )
    rates = ["rates.state:=1000.0", "rates.angular_velocity:=1000.0", "rates.clock:=100.0"]
    for label, extra in (("playing", []), ("use_sim_time", ["use_sim_time:=true"])):
        sim = start_node(*rates, *extra)
        try:
            publisher = node.create_publisher(WrenchStamped, TORQUE, 10)
            wait_matched(node, publisher)
            spin_for(node, 1.0)  # warm: kernels loaded, pacing steady
            stamps.clear()
            before, start = cpu_seconds(sim.pid), time.monotonic()
            i = 0
            while time.monotonic() - start < seconds:  # commands at 1 kHz, valid, while ~/state comes in
                publisher.publish(command(0))
                i += 1
                pause = start + i / 1000.0 - time.monotonic()
                if pause > 0:
                    rclpy.spin_once(node, timeout_sec=pause)
            wall = time.monotonic() - start
            figures[f"{label} cpu"] = (cpu_seconds(sim.pid) - before) / wall
            if len(stamps) > 2:
                (t0, w0), (t1, w1) = stamps[0], stamps[-1]
                figures[f"{label} steps/s"] = (t1 - t0) / 0.001 / (w1 - w0)
            else:
                figures[f"{label} steps/s"] = 0.0
            node.destroy_publisher(publisher)
        finally:
            stop(sim)
    sim = start_node(*rates, "start_paused:=true")
    try:
        deadline = time.monotonic() + 60.0
        while node.count_publishers("/rigid_rot_sim/state") == 0 and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.05)  # wait for its outputs on the graph: started
        time.sleep(3.0)  # the start-up's tail (the last imports, the first state) is not the paused cost
        figures["paused cpu"] = cpu_share(sim.pid, seconds)
    finally:
        stop(sim)
    bare = subprocess.Popen([sys.executable, "-c", BARE_NODE])
    bare_states = node.create_subscription(RigidBodyState, "/bare/state", lambda m: None, QoSProfile(depth=100))
    try:
        publisher = node.create_publisher(WrenchStamped, "/bare/torque", 10)
        wait_matched(node, publisher)
        spin_for(node, 1.0)  # as the node: warm, and this process takes its ~/state as it takes the node's
        before, start = cpu_seconds(bare.pid), time.monotonic()
        i = 0
        while time.monotonic() - start < seconds:
            publisher.publish(command(0))
            i += 1
            pause = start + i / 1000.0 - time.monotonic()
            if pause > 0:
                rclpy.spin_once(node, timeout_sec=pause)
        figures["bare cpu"] = (cpu_seconds(bare.pid) - before) / (time.monotonic() - start)
        node.destroy_publisher(publisher)
    finally:
        node.destroy_subscription(bare_states)
        stop(bare)
    return figures


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="shorter windows, fewer commands")
    parser.add_argument("--only", choices=["commands", "loop", "lockstep"], action="append")
    args = parser.parse_args()
    parts = args.only or ["commands", "loop", "lockstep"]
    seconds = 3.0 if args.quick else 8.0
    rclpy.init()
    node = rclpy.create_node("bench_node_loop")
    try:
        for loaded in (False, True):
            with busy(loaded):
                time.sleep(0.5)
                print(f"== {'two busy processes' if loaded else 'idle'}: load average {os.getloadavg()[0]:.1f}")
                if "commands" in parts:
                    for rate in (50.0, 200.0, 1000.0):
                        count = int(rate * (2 if args.quick else 5))
                        taken, accepted, rejected = commands_taken(node, rate, count)
                        bare = bare_taken(node, rate, count)
                        print(
                            f"  {rate:6.0f}/s: node took {taken} of {count} (valid accepted {accepted} of "
                            f"{count - count // 2}, invalid reported {rejected} of {count // 2}); "
                            f"bare rclpy subscriber took {bare} of {count}",
                            flush=True,
                        )
                if "loop" in parts:
                    f = loop_figures(node, seconds)
                    print(
                        f"  1 kHz, ~/state and ~/angular_velocity 1 kHz, commands 1 kHz: node "
                        f"{100 * f['playing cpu']:.1f} % of a core, {f['playing steps/s']:.0f} steps per wall s; "
                        f"bare rclpy node (the same outputs, rates and QoS, 1 kHz in) {100 * f['bare cpu']:.1f} % "
                        f"of a core: ratio {f['playing cpu'] / f['bare cpu']:.2f} (aim <= 1.1)",
                        flush=True,
                    )
                    print(f"  paused: node {100 * f['paused cpu']:.1f} % of a core", flush=True)
                    print(
                        f"  use_sim_time:=true: node {100 * f['use_sim_time cpu']:.1f} % of a core, "
                        f"{f['use_sim_time steps/s']:.0f} steps per wall s",
                        flush=True,
                    )
                if "lockstep" in parts:
                    turns = 300 if args.quick else 1000
                    before = lockstep_turns.bare_round_trips(node, turns)
                    rate, timed = lockstep_turns.lockstep_turns(node, turns)
                    after = lockstep_turns.bare_round_trips(node, turns)
                    floor = (before + after) / 2
                    print(
                        f"  lockstep: {rate:.0f} turns/s over {timed} turns; bare rclpy round trip {floor:.0f}/s "
                        f"({before:.0f} before, {after:.0f} after): ratio {rate / floor:.2f} (aim >= 0.5)",
                        flush=True,
                    )
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
