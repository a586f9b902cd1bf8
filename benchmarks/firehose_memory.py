"""What grows in the node under a fuzz firehose (issue 41): RSS per round and tracemalloc's diff (prints figures).

    .venv/bin/python benchmarks/firehose_memory.py                       # 4 rounds of 20 000 commands, traced
    .venv/bin/python benchmarks/firehose_memory.py --rounds 3 --commands 5000 --no-trace

The node of benchmarks/fuzz_node.py's part 1 (``torque_driven``, rk4, real-time factor 1, ``commands.max_torque``
0, ``~/state`` at 200 Hz) gets rounds of the fuzz campaign's traffic from this process (its generators, its
``--seed``): torque bursts of 1 to 500 commands published as fast as possible, service requests and parameter
sets between them (none with ``--only-commands``), until ``--commands`` commands were sent in the round.
After each round (1 s of quiet):
the node's RSS (``VmRSS``) and, unless ``--no-trace``, a tracemalloc snapshot of the node's Python allocations
(the node runs with ``RIGID_ROT_TRACEMALLOC``, :func:`rigid_rot_sim.ros.node_process.trace_memory`; dumped on SIGUSR1).
At the end: the largest growths from the first round's snapshot to the last, by source line, and the total
traced. RSS counts what tracemalloc does not see (DDS, numba's compiled kernels, the allocator's free lists),
and tracing itself costs memory: compare rounds, not runs. The parameter sets that took effect are listed:
a new integrator loads its compiled kernels once (a step of RSS, then flat).
"""

from __future__ import annotations

import argparse
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import fuzz_node  # beside this file (it sets a private ROS domain on import)
from rcl_interfaces.srv import SetParameters


def load() -> str:
    return "load average " + " ".join(Path("/proc/loadavg").read_text().split()[:3])


def wait_for(path: Path, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while not path.exists():
        if time.monotonic() > deadline:
            raise SystemExit(f"firehose_memory: no snapshot {path.name} from the node")
        time.sleep(0.1)


def one_round(
    client: fuzz_node.Client, rng: random.Random, commands: int, applied: list[str], only_commands: bool
) -> float:
    """Fuzz traffic until ``commands`` commands were sent; the round's wall seconds."""
    began, sent = time.monotonic(), 0
    while sent < commands:
        action = 0.0 if only_commands else rng.random()
        if action < 0.6:
            for _ in range(min(rng.choice([1, 10, 100, 500]), commands - sent)):
                client.torque.publish(fuzz_node.torque_message(rng))
                sent += 1
        elif action < 0.9:
            srv_type, name, request = fuzz_node.service_request(rng)
            client.call(srv_type, name, request)
        else:
            request = fuzz_node.parameter_request(rng)
            response = client.call(SetParameters, "set_parameters", request)
            if response is not None and response.results[0].successful:
                parameter = request.parameters[0]
                applied.append(f"{parameter.name}={fuzz_node.Parameter.from_parameter_msg(parameter).value!r}")
        client.spin(0.005)
    client.spin(1.0)
    return time.monotonic() - began


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=4)
    parser.add_argument("--commands", type=int, default=20000, help="torque commands per round")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--depth", type=int, help="the node's commands.qos_depth (default: the scene's, 1000)")
    parser.add_argument("--no-trace", action="store_true", help="RSS only (no tracemalloc in the node)")
    parser.add_argument("--only-commands", action="store_true", help="torque bursts only: no requests, no parameters")
    parser.add_argument("--top", type=int, default=12, help="growths to print")
    args = parser.parse_args()
    rng = random.Random(args.seed)
    with tempfile.TemporaryDirectory() as scratch:
        work = Path(scratch)
        env = dict(os.environ)
        if not args.no_trace:
            env["RIGID_ROT_TRACEMALLOC"] = str(work)
        command = [
            sys.executable,
            "-m",
            "rigid_rot_sim.ros.node",
            "--ros-args",
            "-p",
            f"scene:={fuzz_node.SCENES / 'torque_driven.yaml'}",
            "-p",
            "integrator:=rk4",
            "-p",
            "commands.max_torque:=0.0",
            "-p",
            "rates.state:=200.0",
        ]
        if args.depth is not None:
            command += ["-p", f"commands.qos_depth:={args.depth}"]
        with open(work / "node.log", "wb") as log:
            process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, env=env)
        client = fuzz_node.Client()
        print(
            f"firehose: {args.rounds} rounds of {args.commands} commands "
            f"({'bursts only' if args.only_commands else 'fuzz mix'}, seed {args.seed}), command depth "
            f"{args.depth or 'of the scene (1000)'}, "
            f"tracemalloc {'off' if args.no_trace else 'on (8 frames)'}; {load()}",
            flush=True,
        )
        try:
            probe = fuzz_node.ComputeInertia.Request(masses=[1.0], positions=[fuzz_node.Point(x=1.0)])
            if client.call(fuzz_node.ComputeInertia, "compute_inertia", probe, timeout=60.0) is None:
                raise SystemExit("firehose_memory: the node did not start")
            client.spin(1.0)
            print(f"  start: RSS {fuzz_node.rss_kib(process.pid) / 1024:.1f} MiB", flush=True)
            for number in range(1, args.rounds + 1):
                applied: list[str] = []
                wall = one_round(client, rng, args.commands, applied, args.only_commands)
                if process.poll() is not None:
                    raise SystemExit(f"firehose_memory: the node exited ({process.returncode})")
                snapshot = ""
                if not args.no_trace:
                    process.send_signal(signal.SIGUSR1)
                    wait_for(work / f"snapshot_{number}.tracemalloc")
                    traced = tracemalloc.Snapshot.load(str(work / f"snapshot_{number}.tracemalloc"))
                    total = sum(stat.size for stat in traced.statistics("filename"))
                    snapshot = f", traced Python {total / 2**20:.1f} MiB"
                print(
                    f"  round {number}: {wall:.0f} s, RSS {fuzz_node.rss_kib(process.pid) / 1024:.1f} MiB{snapshot}; "
                    f"parameters applied: {', '.join(applied) or 'none'}; {load()}",
                    flush=True,
                )
        finally:
            client.close()
            fuzz_node.signal_and_wait(process, signal.SIGTERM, timeout=30.0)
        if not args.no_trace and args.rounds >= 2:
            first = tracemalloc.Snapshot.load(str(work / "snapshot_1.tracemalloc"))
            last = tracemalloc.Snapshot.load(str(work / f"snapshot_{args.rounds}.tracemalloc"))
            print(f"  the largest growths from round 1 to round {args.rounds} (by source line):")
            for stat in last.compare_to(first, "lineno")[: args.top]:
                print(f"    {stat.size_diff / 1024:+9.1f} KiB {stat.count_diff:+7d} blocks  {stat.traceback[0]}")
            print(f"  the largest growths, by the allocation's 8-frame traceback (top {min(3, args.top)}):")
            for stat in last.compare_to(first, "traceback")[: min(3, args.top)]:
                print(f"    {stat.size_diff / 1024:+9.1f} KiB {stat.count_diff:+7d} blocks")
                for line in stat.traceback.format()[-16:]:
                    print(f"      {line}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
