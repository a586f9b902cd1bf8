"""Long fuzz campaign against the simulation node over real DDS (prints figures; not a test).

    .venv/bin/python benchmarks/fuzz_node.py --seed 1 --duration 150 --scenes 60
    .venv/bin/python benchmarks/fuzz_node.py --quick          # ~30 s

Loopback only (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, a private ROS_DOMAIN_ID), randomised
from ``--seed``, bounded by ``--duration`` (s), ``--max-messages`` and ``--scenes``. The inputs
come from test/fuzz/generators.py (the classes of issue 9).

Part 1, a running node (torque_driven, rk4, real-time factor 1, ``commands.max_torque`` 0 so
that huge torques reach the physics): torque bursts (malformed, huge, non-finite, long frame
ids, wall-clock stamps), service requests (compute_inertia, set_state, step, apply_torque,
reset, pause) and parameter sets, interleaved; a liveness probe (~/compute_inertia) every
second. Counted: messages sent, rejections reported on ~/rejected, requests refused, hangs
(a request or probe unanswered within 5 s), non-finite fields in every ~/state received,
tracebacks in the node's log, the node's RSS before and after, and the time SIGTERM takes.

Part 2, scene files: ``--scenes`` mutated scenes, each given to a fresh node
(``duration`` 0.2 s, real-time factor 0): exit codes, tracebacks, hangs (20 s), and whether
every refusal is one line on stderr of at most MAX_ERROR_CHARS; then Ctrl-C while a scene
with the most point masses loads.
"""

from __future__ import annotations

import argparse
import math
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 1))
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ["PYTHONUNBUFFERED"] = "1"

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "test" / "fuzz"))

import generators  # noqa: E402
import rclpy  # noqa: E402
from builtin_interfaces.msg import Duration  # noqa: E402
from geometry_msgs.msg import Point, Vector3, WrenchStamped  # noqa: E402
from rcl_interfaces.srv import SetParameters  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from std_srvs.srv import SetBool, Trigger  # noqa: E402

from rigid_rot_msgs.msg import RejectedCommand, RigidBodyState  # noqa: E402
from rigid_rot_msgs.srv import ApplyTorque, ComputeInertia, SetState, Step  # noqa: E402
from rigid_rot_sim.core import limits  # noqa: E402
from rigid_rot_sim.ros.qos import COMMAND_QOS, REJECTED_QOS, STATE_QOS  # noqa: E402

SCENES = ROOT / "config" / "scenes"
NODE = "/rigid_rot_sim"
HANG = 5.0  # s without an answer counts as a hang


def rss_kib(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return -1


def signal_and_wait(process: subprocess.Popen, signum: int, timeout: float = 10.0) -> float:
    """Seconds from ``signum`` to the process's exit (inf, and SIGKILL, if it outlives ``timeout``)."""
    began = time.monotonic()
    process.send_signal(signum)
    try:
        process.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
        return math.inf
    return time.monotonic() - began


def finite_state(msg: RigidBodyState) -> bool:
    values = [
        msg.orientation.x,
        msg.orientation.y,
        msg.orientation.z,
        msg.orientation.w,
        msg.kinetic_energy,
        msg.potential_energy,
        msg.energy_drift,
        msg.angular_momentum_drift,
    ]
    for name in (
        "angular_velocity_body",
        "angular_velocity_world",
        "angular_momentum_body",
        "angular_momentum_world",
        "torque_body",
    ):
        v = getattr(msg, name)
        values += [v.x, v.y, v.z]
    return all(math.isfinite(x) for x in values)


class Client:
    def __init__(self) -> None:
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node("fuzz_client", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.clients = {}
        self.states = 0
        self.non_finite = 0
        self.rejected = 0
        self.node.create_subscription(RigidBodyState, f"{NODE}/state", self._on_state, STATE_QOS)
        self.node.create_subscription(RejectedCommand, f"{NODE}/rejected", self._on_rejected, REJECTED_QOS)
        self.torque = self.node.create_publisher(WrenchStamped, f"{NODE}/torque", COMMAND_QOS)

    def _on_state(self, msg) -> None:
        self.states += 1
        if not finite_state(msg):
            self.non_finite += 1
            if self.non_finite == 1:
                print(f"non-finite ~/state: {msg}", flush=True)

    def _on_rejected(self, msg) -> None:
        self.rejected += 1

    def spin(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.01)

    def call(self, srv_type, name: str, request, timeout: float = HANG):
        """The response, or None if none came within ``timeout`` s (a hang)."""
        client = self.clients.get(name)
        if client is None:
            client = self.clients[name] = self.node.create_client(srv_type, f"{NODE}/{name}")
            deadline = time.monotonic() + 30.0
            while not client.service_is_ready() and time.monotonic() < deadline:
                self.executor.spin_once(timeout_sec=0.05)
        future = client.call_async(request)
        deadline = time.monotonic() + timeout
        while not future.done() and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.01)
        return future.result() if future.done() else None

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def torque_message(rng: random.Random) -> WrenchStamped:
    fields = generators.torque_command(rng)
    msg = WrenchStamped()
    msg.header.frame_id = fields["frame_id"]
    msg.header.stamp.sec = int(fields["stamp"])
    msg.wrench.torque = Vector3(x=fields["torque"][0], y=fields["torque"][1], z=fields["torque"][2])
    msg.wrench.force = Vector3(x=fields["force"][0], y=fields["force"][1], z=fields["force"][2])
    return msg


def service_request(rng: random.Random):
    kind = rng.choice(["inertia", "set_state", "step", "apply", "reset", "pause"])
    if kind == "inertia":
        r = generators.inertia_request(rng)
        return (
            ComputeInertia,
            "compute_inertia",
            ComputeInertia.Request(
                masses=[float(m) for m in r["masses"]],
                positions=[Point(x=p[0], y=p[1], z=p[2]) for p in r["positions"]],
                origin=Point(x=r["origin"][0], y=r["origin"][1], z=r["origin"][2]),
                frame_id=r["frame_id"],
            ),
        )
    if kind == "set_state":
        r = generators.set_state_request(rng)
        request = SetState.Request(
            angular_velocity=Vector3(x=r["angular_velocity"][0], y=r["angular_velocity"][1], z=r["angular_velocity"][2])
        )
        request.orientation.x, request.orientation.y, request.orientation.z, request.orientation.w = r["orientation"]
        return SetState, "set_state", request
    if kind == "step":
        return Step, "step", Step.Request(steps=generators.step_count(rng))
    if kind == "apply":
        torque = [generators.number(rng) for _ in range(3)]
        return (
            ApplyTorque,
            "apply_torque",
            ApplyTorque.Request(
                torque=Vector3(x=torque[0], y=torque[1], z=torque[2]),
                frame_id=rng.choice(generators.FRAMES),
                duration=Duration(sec=rng.choice([0, 1, 100]), nanosec=rng.choice([0, 1000])),
            ),
        )
    if kind == "reset":
        return Trigger, "reset", Trigger.Request()
    return SetBool, "pause", SetBool.Request(data=rng.random() < 0.5)


def parameter_request(rng: random.Random) -> SetParameters.Request:
    name, value = generators.parameter(rng)
    return SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])


def running_node_campaign(args, rng: random.Random, log_dir: Path) -> dict:
    log_path = log_dir / "node.log"
    command = [
        sys.executable,
        "-m",
        "rigid_rot_sim.ros.node",
        "--ros-args",
        "-p",
        f"scene:={SCENES / 'torque_driven.yaml'}",
        "-p",
        "integrator:=rk4",
        "-p",
        "commands.max_torque:=0.0",
        "-p",
        "rates.state:=200.0",
    ]
    with open(log_path, "wb") as log:
        process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    client = Client()
    figures = {
        "sent": 0,
        "requests": 0,
        "refused": 0,
        "parameter_sets": 0,
        "parameters_refused": 0,
        "hangs": 0,
        "probe_max_s": 0.0,
    }
    try:
        probe = ComputeInertia.Request(masses=[1.0, 2.0], positions=[Point(x=1.0), Point(y=1.0)])
        if client.call(ComputeInertia, "compute_inertia", probe, timeout=30.0) is None:
            raise SystemExit(f"node did not start; log: {log_path}")
        client.spin(1.0)
        figures["rss_before_kib"] = rss_kib(process.pid)
        start = time.monotonic()
        next_probe = start
        figures["rss_mid_kib"] = -1
        while time.monotonic() - start < args.duration and figures["sent"] < args.max_messages:
            action = rng.random()
            if action < 0.6:  # a burst of torque commands, published as fast as possible
                for _ in range(rng.choice([1, 10, 100, 500])):
                    client.torque.publish(torque_message(rng))
                    figures["sent"] += 1
            elif action < 0.9:
                srv_type, name, request = service_request(rng)
                figures["requests"] += 1
                response = client.call(srv_type, name, request)
                if response is None:
                    figures["hangs"] += 1
                elif not response.success:
                    figures["refused"] += 1
            else:
                figures["parameter_sets"] += 1
                response = client.call(SetParameters, "set_parameters", parameter_request(rng))
                if response is None:
                    figures["hangs"] += 1
                elif not response.results[0].successful:
                    figures["parameters_refused"] += 1
            client.spin(0.005)
            if time.monotonic() >= next_probe:
                began = time.monotonic()
                if client.call(ComputeInertia, "compute_inertia", probe) is None:
                    figures["hangs"] += 1
                figures["probe_max_s"] = max(figures["probe_max_s"], time.monotonic() - began)
                next_probe = time.monotonic() + 1.0
            if figures["rss_mid_kib"] < 0 and time.monotonic() - start > 0.25 * args.duration:
                figures["rss_mid_kib"] = rss_kib(process.pid)  # after the warm-up: flat from here?
            if process.poll() is not None:
                break
        client.spin(1.0)
        figures["alive"] = process.poll() is None
        figures["rss_after_kib"] = rss_kib(process.pid) if figures["alive"] else -1
        figures["wall_s"] = time.monotonic() - start
        figures["sigterm_s"] = signal_and_wait(process, signal.SIGTERM)
        figures["hangs"] += figures["sigterm_s"] == math.inf
        figures["exit_code"] = process.returncode
    finally:
        if process.poll() is None:
            process.kill()
        figures["states"], figures["non_finite"], figures["reported"] = (
            client.states,
            client.non_finite,
            client.rejected,
        )
        client.close()
    text = log_path.read_text(errors="replace")
    figures["tracebacks"] = text.count("Traceback")
    if figures["tracebacks"]:
        print(text[text.index("Traceback") :][:3000], flush=True)
    return figures


def scene_campaign(args, rng: random.Random, work: Path) -> dict:
    figures = {
        "scenes": 0,
        "started": 0,
        "refused": 0,
        "other_exit": 0,
        "tracebacks": 0,
        "hangs": 0,
        "bad_error_lines": 0,
        "longest_error": 0,
    }
    deadline = time.monotonic() + args.duration
    for index in range(args.scenes):
        if time.monotonic() > deadline:
            break
        path = work / f"scene_{index}.yaml"
        # one in five a shipped scene as is: the started path is exercised too
        path.write_text(
            generators.mutated_scene(rng) if index % 5 else rng.choice(sorted(SCENES.glob("*.yaml"))).read_text()
        )
        command = [
            sys.executable,
            "-m",
            "rigid_rot_sim.ros.node",
            "--ros-args",
            "-p",
            f"scene:={path}",
            "-p",
            "duration:=0.2",
            "-p",
            "real_time_factor:=0.0",
        ]
        figures["scenes"] += 1
        try:
            # in the work directory: a mutated scene may name a relative recording path
            done = subprocess.run(
                command, capture_output=True, text=True, timeout=20.0, stdin=subprocess.DEVNULL, cwd=work
            )
        except subprocess.TimeoutExpired:
            figures["hangs"] += 1
            continue
        figures["tracebacks"] += ("Traceback" in done.stderr) + ("Traceback" in done.stdout)
        if done.returncode == 0:
            figures["started"] += 1
        elif done.returncode == 2:
            figures["refused"] += 1
            lines = [line for line in done.stderr.splitlines() if "[rcl]" not in line]
            figures["longest_error"] = max([figures["longest_error"]] + [len(line) for line in lines])
            if len(lines) != 1 or len(lines[0]) > limits.MAX_ERROR_CHARS or done.stdout.strip():
                figures["bad_error_lines"] += 1
        else:
            figures["other_exit"] += 1
    # Ctrl-C while the largest allowed scene loads
    n = limits.MAX_POINT_MASSES
    big = work / "largest.yaml"
    big.write_text(
        "body:\n  point_masses:\n    masses: ["
        + ", ".join("1" for _ in range(n))
        + "]\n    positions: ["
        + ", ".join(f"[{i % 7}, {i % 5}, {i % 3}]" for i in range(n))
        + "]\n"
    )
    process = subprocess.Popen(
        [sys.executable, "-m", "rigid_rot_sim.ros.node", "--ros-args", "-p", f"scene:={big}"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
    )
    time.sleep(1.0)
    figures["ctrl_c_during_load_s"] = signal_and_wait(process, signal.SIGINT)
    figures["hangs"] += figures["ctrl_c_during_load_s"] == math.inf
    return figures


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--duration", type=float, default=120.0, help="s of part 1, and at most that for part 2")
    parser.add_argument("--max-messages", type=int, default=1_000_000, help="most torque commands sent in part 1")
    parser.add_argument("--scenes", type=int, default=60, help="mutated scene files in part 2")
    parser.add_argument("--quick", action="store_true", help="15 s, 10 scenes")
    args = parser.parse_args()
    if args.quick:
        args.duration, args.scenes = 15.0, 10
    rng = random.Random(args.seed)
    print(
        f"fuzz_node: seed {args.seed}, ROS_DOMAIN_ID {os.environ['ROS_DOMAIN_ID']}, loopback only, "
        f"load average {os.getloadavg()[0]:.2f}",
        flush=True,
    )
    with tempfile.TemporaryDirectory(prefix="rigid_rot_fuzz_") as tmp:
        work = Path(tmp)
        node = running_node_campaign(args, rng, work)
        print("part 1, running node:")
        print(
            f"  torque messages sent {node['sent']}, rejections reported on ~/rejected {node['reported']} "
            "(the rest accepted, or dropped in bursts beyond torque_driven's commands.qos_depth 100)"
        )
        print(
            f"  service requests {node['requests']} (refused with a reason {node['refused']}), "
            f"parameter sets {node['parameter_sets']} (refused {node['parameters_refused']})"
        )
        print(
            f"  ~/state messages {node['states']}, non-finite {node['non_finite']}; tracebacks {node['tracebacks']}; "
            f"hangs {node['hangs']}; slowest liveness probe {node['probe_max_s']:.3f} s"
        )
        print(
            f"  node alive at the end {node['alive']}, RSS before {node['rss_before_kib'] / 1024:.1f} MiB, "
            f"at 1/4 {node['rss_mid_kib'] / 1024:.1f} MiB, after {node['rss_after_kib'] / 1024:.1f} MiB "
            f"over {node['wall_s']:.0f} s; "
            f"SIGTERM -> exit {node['exit_code']} in {node['sigterm_s']:.2f} s"
        )
        scenes = scene_campaign(args, rng, work)
        print("part 2, scene files:")
        print(
            f"  scenes {scenes['scenes']}: started and finished {scenes['started']}, "
            f"refused (exit 2) {scenes['refused']}, "
            f"other exit codes {scenes['other_exit']}; tracebacks {scenes['tracebacks']}, hangs {scenes['hangs']}; "
            f"refusals not one line <= {limits.MAX_ERROR_CHARS} chars on stderr: {scenes['bad_error_lines']} "
            f"(longest {scenes['longest_error']} chars)"
        )
        print(
            f"  Ctrl-C while loading {limits.MAX_POINT_MASSES} point masses: "
            f"exit in {scenes['ctrl_c_during_load_s']:.2f} s"
        )
    bad = node["tracebacks"] + node["hangs"] + node["non_finite"] + scenes["tracebacks"] + scenes["hangs"]
    bad += scenes["bad_error_lines"] + (not node["alive"])
    print("verdict:", "PASS" if bad == 0 else f"FAIL ({bad} problems)")
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
