"""Where torque commands were lost: the old node loop rebuilt from bare rclpy (prints figures; not a test).

    .venv/bin/python benchmarks/command_loss_probe.py                 # 200/s and 1000/s, both executors
    .venv/bin/python benchmarks/command_loss_probe.py --rate 200 --work-us 300

The node before issue 27 ran every run callback in its default (mutually exclusive) callback
group under a two-thread ``MultiThreadedExecutor``: a steady timer every millisecond (the
stepping tick) and the torque subscriptions (reliable, keep last 10). This probe rebuilds
exactly that arrangement with no simulator code: a timer whose callback busies the CPU for
``--work-us`` µs (a tick's stepping and publishing), a keep-last-10 subscription counting what
its callback takes, and a publisher in another process sending ``--count`` WrenchStamped
messages at ``--rate`` per second (rclpy's default reliable QoS, depth 10), each numbered in
``header.frame_id``. It prints, per executor:

* taken of sent, and the numbers lost;
* how often the executor handed the subscription's handler to a worker thread that could not
  start it (``beginning_execution`` refused: the tick held the group), so the handler returned
  without taking a message (measured 0 here: the subscription is rather never yielded, because the
  timer, yielded first, already holds the group when the executor gets to it);
* the longest stretch of wall time without a take, against the depth's worth of arrivals
  (depth / rate): a loss happens exactly when a stretch exceeds it (the reader's keep-last
  history overwrites its oldest sample; reliability does not help, the history is the reader's);
* the losses the stretches predict (messages sent during each stretch beyond the depth) next to
  those observed: at least those (more under load: the publisher's own keep-last-10 history then also
  overwrites what the starved reader process has not yet acknowledged).

The same probe with ``--executor run-loop`` takes the subscription the way the node does now
(:mod:`rigid_rot_sim.ros.intake`: its own wait set, drained completely between steps).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import threading
import time

os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 120))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import rclpy
from geometry_msgs.msg import WrenchStamped
from rclpy.clock import Clock
from rclpy.clock_type import ClockType
from rclpy.executors import MultiThreadedExecutor, SingleThreadedExecutor
from rclpy.qos import QoSProfile

TOPIC = "/probe_torque"
DEPTH = 10

PUBLISHER = r"""
import sys, time
import rclpy
from geometry_msgs.msg import WrenchStamped
rate, count, topic = float(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
rclpy.init()
node = rclpy.create_node("probe_publisher")
pub = node.create_publisher(WrenchStamped, topic, 10)
deadline = time.monotonic() + 20.0
while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
    time.sleep(0.01)
time.sleep(0.5)
msg = WrenchStamped()
start = time.monotonic()
for i in range(count):
    msg.header.frame_id = str(i)
    msg.wrench.torque.x = 1e-3
    pub.publish(msg)
    pause = start + (i + 1) / rate - time.monotonic()
    if pause > 0:
        time.sleep(pause)
pub.wait_for_all_acked(rclpy.duration.Duration(seconds=2.0))
print("sent", count, flush=True)
node.destroy_node()
rclpy.shutdown()
"""


def busy(seconds: float) -> None:
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass


def probe(executor_kind: str, rate: float, count: int, work: float) -> dict[str, float]:
    """One run: the old arrangement under ``executor_kind``; what was taken and why the rest was lost."""
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("probe_sim", context=context)
    takes: list[tuple[int, float]] = []
    refused = [0]
    ticks = [0]

    def tick() -> None:
        ticks[0] += 1
        busy(work)

    def on_command(msg: WrenchStamped) -> None:
        takes.append((int(msg.header.frame_id), time.monotonic()))

    qos = QoSProfile(depth=DEPTH)
    stop = threading.Event()
    if executor_kind == "run-loop":
        from rigid_rot_sim.ros.intake import CommandIntake

        intake = CommandIntake(node)
        intake.subscribe(WrenchStamped, TOPIC, lambda msg, received_ns: on_command(msg), qos)
        runner = threading.Thread(target=_run_loop, args=(intake, tick, stop))
    else:
        node.create_timer(0.001, tick, clock=Clock(clock_type=ClockType.STEADY_TIME))
        sub = node.create_subscription(WrenchStamped, TOPIC, on_command, qos)
        group = node.default_callback_group
        original = group.beginning_execution

        def counting(entity: object) -> bool:
            began = original(entity)
            if not began and entity is sub:
                refused[0] += 1
            return began

        group.beginning_execution = counting  # type: ignore[method-assign]
        executor = MultiThreadedExecutor(num_threads=2, context=context)
        if executor_kind == "single":
            executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        runner = threading.Thread(target=_spin, args=(executor, stop))
    runner.start()
    publisher = subprocess.run(
        [sys.executable, "-c", PUBLISHER, str(rate), str(count), TOPIC], capture_output=True, text=True, timeout=120
    )
    time.sleep(0.5)
    stop.set()
    runner.join()
    node.destroy_node()
    rclpy.shutdown(context=context)
    if "sent" not in publisher.stdout:
        raise SystemExit(f"publisher failed: {publisher.stderr[-400:]}")
    return _analyse(takes, rate, count, refused[0], ticks[0])


def _spin(executor: object, stop: threading.Event) -> None:
    while not stop.is_set():
        executor.spin_once(timeout_sec=0.05)  # type: ignore[attr-defined]
    executor.shutdown(timeout_sec=1.0)  # type: ignore[attr-defined]


def _run_loop(intake: object, tick: object, stop: threading.Event) -> None:
    """The new arrangement: wait on the commands or the next step (1 ms), drain them all, then step."""
    next_step = time.monotonic()
    with intake.waiting() as wait:  # type: ignore[attr-defined]
        while not stop.is_set():
            wait(max(0.0, next_step - time.monotonic()))
            intake.drain()  # type: ignore[attr-defined]
            if time.monotonic() >= next_step:
                tick()  # type: ignore[operator]
                next_step += 0.001


def _analyse(takes: list[tuple[int, float]], rate: float, count: int, refused: int, ticks: int) -> dict[str, float]:
    taken = {index for index, _ in takes}
    lost = count - len(taken)
    gaps = [b - a for (_, a), (_, b) in zip(takes, takes[1:], strict=False)]
    # a stretch of g s without a take lets g * rate messages arrive; beyond DEPTH the oldest are overwritten
    predicted = sum(max(0, round(g * rate) - DEPTH) for g in gaps)
    return {
        "taken": len(taken),
        "lost": lost,
        "refused": refused,
        "ticks": ticks,
        "longest_gap_ms": 1e3 * max(gaps, default=0.0),
        "gaps_over_depth": sum(1 for g in gaps if g * rate > DEPTH),
        "predicted": predicted,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rate", type=float, action="append", help="commands per second (repeatable)")
    parser.add_argument("--count", type=int, default=1000)
    parser.add_argument("--work-us", type=float, default=300.0, help="CPU per timer tick (µs)")
    parser.add_argument("--executor", action="append", choices=["multi", "single", "run-loop"])
    args = parser.parse_args()
    rates = args.rate or [200.0, 1000.0]
    kinds = args.executor or ["multi", "single", "run-loop"]
    print(
        f"depth {DEPTH}, a 1 ms steady timer doing {args.work_us:g} µs of work; load average {os.getloadavg()[0]:.1f}"
    )
    print(
        f"{'executor':>9} {'rate/s':>7} {'taken':>11} {'refused':>8} {'longest gap':>12} {'gaps>depth':>10} "
        f"{'lost: predicted / seen':>23}"
    )
    for rate in rates:
        for kind in kinds:
            r = probe(kind, rate, args.count, args.work_us * 1e-6)
            print(
                f"{kind:>9} {rate:7.0f} {r['taken']:5d}/{args.count:<5d} {r['refused']:8d} "
                f"{r['longest_gap_ms']:9.1f} ms {r['gaps_over_depth']:10d} {r['predicted']:11d} / {r['lost']:<5d}",
                flush=True,
            )


if __name__ == "__main__":
    main()
