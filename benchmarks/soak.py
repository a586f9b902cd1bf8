"""Soak runs of the node (issue 41): memory, commands and recordings over minutes (prints figures; not a test).

    .venv/bin/python benchmarks/soak.py                      # 2 minutes per part (~7 min)
    .venv/bin/python benchmarks/soak.py --minutes 10         # the figures in docs/benchmarks.md
    .venv/bin/python benchmarks/soak.py --minutes 1 --only commands

Three parts, each a real node process (``rigid_rot_sim_node``) over DDS on loopback, in a ROS domain of its own:

(a) ``lockstep``: the closed loop of ``make demo`` (``closed_loop_lockstep``: rk4, dt 1 ms, a turn every
    0.02 s) with the shipped controller (``rigid-rot-controller``), recording on, paced at real-time factor 1 for
    ``--minutes`` of sim time; two identical runs side by side (each pair node + controller in its own domain,
    started paused and released together) whose run digests must be equal.
(b) ``commands``: the free-running ``torque_driven`` node (dt 1 ms: 1 kHz physics, real-time factor 1),
    recording on, taking 200 commands/s from this process, half valid (1 µN·m about x, ``base_link``), half
    invalid (NaN): taken = the commands in the node's recording (it records every command it takes),
    accepted = its ``torque`` events, reported = its ``~/rejected`` messages (as benchmarks/node_loop.py counts).
(c) ``viewers``: (b) with a web page nobody opens (``web:=127.0.0.1:0``) and the Foxglove live server
    (``foxglove:=127.0.0.1:0``) with a WebSocket client (test/e2e/foxglove_client.py) subscribed to ``~/state``.

Each prints, every minute, the node's RSS (``VmRSS`` of /proc/<pid>/status) and the steps per wall second over
that minute (from the sim time on ``/clock``), with the load average; then the RSS growth after the warm-up
(the first 5 minutes; in a run shorter than 10 minutes the first third, said so) and the largest RSS after it;
the recording's size and whether it reads back whole (``BagReader``: it has its summary, a pass over it finds
the summary's count on every channel, every message decodes from the definitions in the file).
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import rclpy  # noqa: E402
from geometry_msgs.msg import WrenchStamped  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.qos import QoSProfile  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from std_srvs.srv import SetBool  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
NODE = "/rigid_rot_sim"
TORQUE = f"{NODE}/torque"
LOOP_TARGET = "target:=[0.0, 0.0, 0.5, 0.8660254037844386]"  # the Makefile's demo loop
COMMAND_RATE = 200.0  # commands per second in (b) and (c)
DT = 0.001  # s: the physics step of both scenes
SAMPLE = 5.0  # s of wall time between RSS / clock samples


def load() -> str:
    return "load average " + " ".join(Path("/proc/loadavg").read_text().split()[:3])


def rss_mib(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return math.nan


def domain(offset: int) -> int:
    return (os.getpid() + offset) % 100 + 150


class Graph:
    """An rclpy context and node in one ROS domain (this process watches each run in its own domain)."""

    def __init__(self, domain_id: int) -> None:
        self.domain_id = domain_id
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node(f"soak_{domain_id}", context=self.context)
        self.executor = rclpy.executors.SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.sim_time = math.nan
        self.node.create_subscription(Clock, "/clock", self._on_clock, QoSProfile(depth=10))

    def _on_clock(self, msg: Clock) -> None:
        self.sim_time = msg.clock.sec + msg.clock.nanosec * 1e-9

    def spin(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return
            self.executor.spin_once(timeout_sec=left)

    def wait(self, condition: Callable[[], object], what: str, timeout: float = 90.0) -> None:
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                raise SystemExit(f"soak: timed out waiting for {what}")
            self.executor.spin_once(timeout_sec=0.05)

    def close(self) -> None:
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@dataclass
class Watch:
    """RSS and sim time of one node every SAMPLE s; a line every minute."""

    label: str
    pid: int
    graph: Graph
    minutes: float
    start: float = field(default_factory=time.monotonic)
    samples: list[tuple[float, float, float]] = field(default_factory=list)  # (wall s, RSS MiB, sim s)
    printed: int = 0
    stepping: bool = True  # False: a process with no steps of its own (the controller)

    def sample(self) -> None:
        wall = time.monotonic() - self.start
        if self.samples and wall - self.samples[-1][0] < SAMPLE:
            return
        rss = rss_mib(self.pid)
        if math.isnan(rss):
            return  # the process has ended (a zombie has no VmRSS): its last sample stands
        self.samples.append((wall, rss, self.graph.sim_time))
        if wall >= 60.0 * (self.printed + 1):
            self.printed += 1
            earlier = next((s for s in self.samples if s[0] >= wall - 60.0), self.samples[0])
            rate = (self.samples[-1][2] - earlier[2]) / DT / max(wall - earlier[0], 1e-9)
            steps = f", {rate:.0f} steps per wall s over the minute" if self.stepping else ""
            print(
                f"  {self.label} minute {self.printed}: RSS {self.samples[-1][1]:.1f} MiB{steps}; {load()}",
                flush=True,
            )

    def summary(self) -> str:
        warm_minutes = 5.0 if self.minutes >= 10 else self.minutes / 3
        warm = warm_minutes * 60.0
        after = [s for s in self.samples if s[0] >= warm]
        if len(after) < 2:
            return f"{self.label}: too short for a growth figure"
        first, last = after[0], self.samples[-1]
        peak = max(s[1] for s in after)
        rate = (last[2] - first[2]) / DT / (last[0] - first[0])
        said = "the first 5 minutes" if self.minutes >= 10 else f"the first third ({warm_minutes:.1f} min; a short run)"
        return (
            f"{self.label}: RSS {self.samples[0][1]:.1f} MiB at the start, {first[1]:.1f} after {said}, "
            f"{last[1]:.1f} at the end: growth after the warm-up {last[1] - first[1]:+.2f} MiB (largest after it "
            f"{peak:.1f})" + (f"; {rate:.0f} steps per wall s after the warm-up" if self.stepping else "")
        )


def start(command: list[str], env_domain: int, log: Path) -> subprocess.Popen:
    env = dict(os.environ, ROS_DOMAIN_ID=str(env_domain), PYTHONUNBUFFERED="1")
    with open(log, "w") as out:
        return subprocess.Popen(command, env=env, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)


def stop(process: subprocess.Popen) -> None:
    if process.poll() is None:
        process.send_signal(2)
    try:
        process.wait(timeout=20)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


def node_command(*params: str) -> list[str]:
    command = [str(BIN / "rigid_rot_sim_node"), "--ros-args", "--log-level", "info"]
    for param in params:
        command += ["-p", param]
    return command


def read_back(bag: Path) -> str:
    """The recording's size and whether it reads back whole, in one line."""
    from rigid_rot_sim.recording.definitions import dynamic_decoder
    from rigid_rot_sim.recording.reader import BagReader

    size = bag.stat().st_size / 2**20
    reader = BagReader(bag)
    if not reader.complete:
        return f"recording {size:.1f} MiB: NOT whole (no summary: the node did not close it)"
    with open(bag, "rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None and summary.statistics is not None
    expected = {summary.channels[c].topic: n for c, n in summary.statistics.channel_message_counts.items()}
    decoders = {t.name: dynamic_decoder(t.type_name, t.definition) for t in reader.topics.values()}
    found: dict[str, int] = {}
    undecodable = 0
    for message in reader.messages():
        found[message.topic] = found.get(message.topic, 0) + 1
        try:
            decoders[message.topic](message.data)
        except Exception:  # noqa: BLE001  (any decode failure counts against the file)
            undecodable += 1
    whole = found == expected and undecodable == 0
    return (
        f"recording {size:.1f} MiB, {sum(found.values())} messages on {len(found)} topics: "
        + (
            "reads back WHOLE"
            if whole
            else f"NOT whole (counts {found} vs summary {expected}, {undecodable} undecodable)"
        )
        + " (summary present, every channel's count matches the summary, every message decodes)"
    )


def soak_lockstep(minutes: float, work: Path) -> None:
    """(a): two identical lockstep runs side by side, each in its own domain."""
    from rigid_rot_sim.recording.reader import BagReader

    seconds = 60.0 * minutes
    runs = []
    for k in (1, 2):
        graph = Graph(domain(k))
        bag = work / f"lockstep_{k}.mcap"
        controller = start(
            [str(BIN / "rigid-rot-controller"), "--ros-args", "--log-level", "warn", "-p", LOOP_TARGET],
            graph.domain_id,
            work / f"controller_{k}.log",
        )
        sim = start(
            node_command(
                "scene:=closed_loop_lockstep",
                f"duration:={seconds!r}",
                "real_time_factor:=1.0",
                "start_paused:=true",
                f"record_path:={bag}",
            ),
            graph.domain_id,
            work / f"lockstep_{k}.log",
        )
        runs.append((graph, bag, controller, sim))
    try:
        for graph, _, _, _ in runs:
            node = graph.node
            graph.wait(
                lambda n=node: n.count_subscribers(f"{NODE}/state") >= 1 and n.count_publishers(TORQUE) >= 1,
                "the node and the controller",
            )
            client = node.create_client(SetBool, f"{NODE}/pause")
            graph.wait(client.service_is_ready, "~/pause")
        for graph, _, _, _ in runs:
            graph.node.create_client(SetBool, f"{NODE}/pause").call_async(SetBool.Request(data=False))
            graph.spin(0.1)
        watches = [Watch(f"(a) run {k}", sim.pid, graph, minutes) for k, (graph, _, _, sim) in enumerate(runs, 1)]
        controllers = [
            Watch(f"(a) controller {k}", c.pid, g, minutes, stepping=False) for k, (g, _, c, _) in enumerate(runs, 1)
        ]
        while any(sim.poll() is None for _, _, _, sim in runs):
            for graph, _, _, _ in runs:
                graph.spin(0.25)
            for watch in watches + controllers:
                if Path(f"/proc/{watch.pid}").exists():
                    watch.sample()
            if time.monotonic() - watches[0].start > seconds * 3 + 120:
                raise SystemExit("soak: the lockstep runs did not end (3x their duration)")
    finally:
        for graph, _, controller, sim in runs:
            stop(sim)
            stop(controller)
            graph.close()
    for watch in watches + controllers:
        print("  " + watch.summary(), flush=True)
    digests = []
    for k, (_, bag, _, sim) in enumerate(runs, 1):
        log = (work / f"lockstep_{k}.log").read_text(errors="replace")
        turns = next((line.split("]: ", 1)[-1] for line in log.splitlines() if "lockstep:" in line), "no lockstep line")
        digest = BagReader(bag).metadata.get("digest", {}).get("digest")
        digests.append(digest)
        print(f"  (a) run {k}: exit {sim.returncode}; {turns}; digest {digest}", flush=True)
        print(f"  (a) run {k}: {read_back(bag)}", flush=True)
    same = digests[0] is not None and digests[0] == digests[1]
    print(f"  (a) the two runs' digests: {'EQUAL' if same else 'DIFFER'}; {load()}", flush=True)


class FoxgloveWatcher(threading.Thread):
    """A Foxglove WebSocket client subscribed to ``~/state``, counting what it receives (stores nothing)."""

    def __init__(self, url: str) -> None:
        super().__init__(daemon=True)
        sys.path.insert(0, str(ROOT / "test" / "e2e"))
        from foxglove_client import FoxgloveClient

        self.client = FoxgloveClient(url)
        self.client.until(lambda: self.client.channel_of(f"{NODE}/state"), 60, "~/state advertised")
        self.client.subscribe(f"{NODE}/state")
        self.received = 0
        self.halt = threading.Event()

    def run(self) -> None:
        while not self.halt.is_set():
            self.client.pump(0.5)
            self.received += len(self.client.messages)
            self.client.messages.clear()
            self.client.times.clear()
            self.client.json_ops.clear()

    def close(self) -> None:
        self.halt.set()
        self.join(timeout=5)
        self.client.close()


def soak_commands(minutes: float, work: Path, viewers: bool) -> None:
    """(b), or (c) with ``viewers``: 200 commands/s (half invalid) to a free-running recorded 1 kHz node."""
    from rigid_rot_sim.recording.events import decode_event
    from rigid_rot_sim.recording.reader import BagReader

    label = "(c)" if viewers else "(b)"
    graph = Graph(domain(3 if viewers else 4))
    bag = work / f"commands_{label[1]}.mcap"
    log = work / f"commands_{label[1]}.log"
    params = ["scene:=torque_driven", f"record_path:={bag}"]
    if viewers:
        params += ["web:=127.0.0.1:0", "foxglove:=127.0.0.1:0"]
    sim = start(node_command(*params), graph.domain_id, log)
    foxglove: FoxgloveWatcher | None = None
    count = int(COMMAND_RATE * 60.0 * minutes)
    try:
        publisher = graph.node.create_publisher(WrenchStamped, TORQUE, 10)
        graph.wait(lambda: publisher.get_subscription_count() > 0, "the node's torque subscription")
        graph.wait(lambda: not math.isnan(graph.sim_time), "/clock")
        if viewers:
            graph.wait(lambda: "Foxglove live server ws://" in log.read_text(), "the Foxglove line")
            text = log.read_text()
            port = text.split("Foxglove live server ws://127.0.0.1:", 1)[1].split()[0].rstrip(")")
            foxglove = FoxgloveWatcher(f"ws://127.0.0.1:{int(port)}")
            foxglove.start()
            page = (
                "web page http" + text.split("web page http", 1)[-1].split(";", 1)[0] if "web page http" in text else ""
            )
            print(f"  {label} {page or 'no web page line'}", flush=True)
        watch = Watch(label, sim.pid, graph, minutes)
        message = WrenchStamped()
        message.header.frame_id = "base_link"
        began = time.monotonic()
        for i in range(count):
            message.wrench.torque.x = 1e-6 if i % 2 == 0 else math.nan
            publisher.publish(message)
            watch.sample()
            pause = began + (i + 1) / COMMAND_RATE - time.monotonic()
            if pause > 0:
                graph.spin(pause)
            if sim.poll() is not None:
                raise SystemExit(f"soak: the node exited ({sim.returncode}):\n{log.read_text()[-2000:]}")
        publisher.wait_for_all_acked(rclpy.duration.Duration(seconds=10.0))
        graph.spin(1.0)  # the last commands reach the run loop and the recorder
        watch.sample()
    finally:
        if foxglove is not None:
            foxglove.close()
        stop(sim)
        graph.close()
    print("  " + watch.summary(), flush=True)
    reader = BagReader(bag)
    counts = reader.counts()
    events = [decode_event(e) for _, e in reader.decoded([f"{NODE}/sim_events"])]
    accepted = sum(1 for e in events if e.kind == "torque")
    reasons = [m.reason for _, m in reader.decoded([f"{NODE}/rejected"])]
    lost = [r for r in reasons if r.startswith("lost:")]
    print(
        f"  {label} commands sent {count}: taken {counts.get(TORQUE, 0)} (in the recording), valid accepted "
        f"{accepted} of {count - count // 2}, invalid reported {len(reasons) - len(lost)} of {count // 2}; "
        f"loss reports {len(lost)} {lost[:2]}; node exit {sim.returncode}"
        + (f"; Foxglove client received {foxglove.received} ~/state" if foxglove is not None else ""),
        flush=True,
    )
    print(f"  {label} {read_back(bag)}; {load()}", flush=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=2.0, help="minutes per part (default 2)")
    parser.add_argument("--only", choices=["lockstep", "commands", "viewers"], action="append")
    parser.add_argument("--keep", type=Path, help="keep the recordings and logs in this directory")
    args = parser.parse_args()
    if args.minutes <= 0:
        parser.error("--minutes must be > 0")
    parts = args.only or ["lockstep", "commands", "viewers"]
    with tempfile.TemporaryDirectory() as scratch:
        work = args.keep or Path(scratch)
        work.mkdir(parents=True, exist_ok=True)
        print(f"soak: {args.minutes:g} min per part, {os.cpu_count()} CPUs, {load()}", flush=True)
        if "lockstep" in parts:
            print("(a) lockstep closed loop, node + rigid-rot-controller, two identical runs side by side", flush=True)
            soak_lockstep(args.minutes, work)
        if "commands" in parts:
            print(
                f"(b) free-running 1 kHz node, {COMMAND_RATE:.0f} commands/s (half invalid), recording on", flush=True
            )
            soak_commands(args.minutes, work, viewers=False)
        if "viewers" in parts:
            print("(c) as (b), with a web page (no browser) and the Foxglove live server (one client)", flush=True)
            soak_commands(args.minutes, work, viewers=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
