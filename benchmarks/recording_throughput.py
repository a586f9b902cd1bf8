"""Recording throughput, and what recording costs the simulation loop.

    .venv/bin/python benchmarks/recording_throughput.py [--messages 50000] [--steps 20000]

1. Recorder throughput (messages/s and MB/s of serialised payload, best of three):
   pre-serialised bytes (the writer alone), RigidBodyState objects through
   ``rclpy.serialization`` (what the node records), and ``/tf`` encoded from its
   definition (mcap_ros2's dynamic encoder, used because tf2_msgs is not installed).
2. Step rate of the node's simulation loop with recording off and on: the pure
   Simulator of the free_tumble scene (rk4, dt = 10 ms) advancing one step at a time and
   building, as the node does, a RigidBodyState, a QuaternionStamped and a /tf transform
   every step or every 10th; recording on writes all three to MCAP (flush thread running).
   This is the node's work per step without DDS, so the difference is the recorder's.

3. The node itself (rclpy, in-process, no subscriber): torque_driven scene, rk4 at
   1 kHz, real-time factor 0, every output at its scene rate (100 Hz), spun like
   ``rigid_rot_sim.ros.node.main`` until ``--sim-seconds`` of sim time are done, with
   ``record_path`` unset and set.

Figures are printed, never asserted.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

from rclpy.serialization import serialize_message

from rigid_rot_msgs.msg import RigidBodyState
from rigid_rot_sim import conversions
from rigid_rot_sim.recording.session import RunRecorder
from rigid_rot_sim.recording.writer import Recorder
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import load_scene

SCENE = Path(__file__).resolve().parents[1] / "config" / "scenes" / "free_tumble.yaml"


def best_of_three(run) -> tuple[float, int, int]:
    """(seconds, messages, payload bytes) of the fastest of three runs."""
    best = None
    for _ in range(3):
        with tempfile.TemporaryDirectory() as tmp:
            start = time.perf_counter()
            messages, payload = run(Path(tmp) / "bench.mcap")
            elapsed = time.perf_counter() - start
        if best is None or elapsed < best[0]:
            best = (elapsed, messages, payload)
    assert best is not None
    return best


def writer_throughput(n: int) -> None:
    state = conversions.snapshot_to_state(Simulator(load_scene(SCENE), method="rk4").snapshot(), "world", "body")
    raw = serialize_message(state)

    def raw_bytes(path: Path) -> tuple[int, int]:
        with Recorder(path) as recorder:
            recorder.add_topic("/rigid_rot_sim/state", "rigid_rot_msgs/msg/RigidBodyState")
            for i in range(n):
                recorder.write("/rigid_rot_sim/state", raw, i)
        return n, n * len(raw)

    def rclpy_objects(path: Path) -> tuple[int, int]:
        with Recorder(path) as recorder:
            recorder.add_topic("/rigid_rot_sim/state", "rigid_rot_msgs/msg/RigidBodyState")
            for i in range(n):
                state.kinetic_energy = float(i)
                recorder.write_message("/rigid_rot_sim/state", state, i)
        return n, n * len(raw)

    tf_fields = {
        "transforms": [
            {
                "header": {"stamp": {"sec": 1, "nanosec": 2}, "frame_id": "world"},
                "child_frame_id": "body",
                "transform": {
                    "translation": {"x": 0.0, "y": 0.0, "z": 0.0},
                    "rotation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                },
            }
        ]
    }

    def tf_dynamic(path: Path) -> tuple[int, int]:
        m = n // 5
        with Recorder(path) as recorder:
            recorder.add_topic("/tf", "tf2_msgs/msg/TFMessage")
            for i in range(m):
                recorder.write_fields("/tf", tf_fields, i)
        return m, m * 120

    print(f"1. Recorder throughput (RigidBodyState payload {len(raw)} B; zstd chunks of 1 MiB; best of 3)")
    print(f"   {'what':<42} {'messages/s':>12} {'MB/s':>8}")
    for label, run in (
        ("pre-serialised bytes (Recorder.write)", raw_bytes),
        ("rclpy RigidBodyState (write_message)", rclpy_objects),
        ("/tf from its definition (write_fields)", tf_dynamic),
    ):
        seconds, messages, payload = best_of_three(run)
        print(f"   {label:<42} {messages / seconds:>12,.0f} {payload / seconds / 1e6:>8.2f}")


def loop_rate(steps: int, record: bool, publish_every: int) -> float:
    """Steps per second of the node-like loop (see module docstring), best of three."""
    scene = load_scene(SCENE)
    best = float("inf")
    for _ in range(3):
        sim = Simulator(scene, method="rk4")
        with tempfile.TemporaryDirectory() as tmp:
            run = None
            if record:
                run = RunRecorder(
                    Path(tmp) / "loop.mcap",
                    scene_text=SCENE.read_text(),
                    scene_file=str(SCENE),
                    parameters={},
                    integrator={"method": sim.stepper.method, "dt": sim.clock.dt, "options": sim.stepper.options},
                    events_topic="/rigid_rot_sim/sim_events",
                )
                run.add_topic("/rigid_rot_sim/state", RigidBodyState, role="state")
                from geometry_msgs.msg import QuaternionStamped

                run.add_topic("/rigid_rot_sim/orientation", QuaternionStamped)
            start = time.perf_counter()
            for k in range(steps):
                sim.advance(1)
                if k % publish_every:
                    continue
                snapshot = sim.snapshot()
                state = conversions.snapshot_to_state(snapshot, "world", "body")
                orientation = conversions.snapshot_to_orientation(snapshot, "world")
                transform = conversions.transform_stamped(snapshot, "world", "body")
                if run is not None:
                    run.record("/rigid_rot_sim/state", state)
                    run.record("/rigid_rot_sim/orientation", orientation)
                    stamp = transform.header.stamp
                    run.record_tf(stamp.sec, stamp.nanosec, snapshot.orientation, "world", "body")
            elapsed = time.perf_counter() - start
            if run is not None:
                run.close()
        best = min(best, elapsed)
    return steps / best


def node_rate(sim_seconds: float, record: Path | None) -> float:
    """Physics steps per wall second of the real node at real-time factor 0."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter

    from rigid_rot_sim.ros.node import RigidRotSimNode

    scene = SCENE.with_name("torque_driven.yaml")
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=(os.getpid() % 100) + 1)
    overrides = [
        Parameter("scene", value=str(scene)),
        Parameter("integrator", value="rk4"),
        Parameter("real_time_factor", value=0.0),
        Parameter("duration", value=float(sim_seconds)),
    ]
    if record is not None:
        overrides.append(Parameter("record_path", value=str(record)))
    node = RigidRotSimNode(context=context, parameter_overrides=overrides)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    start = time.perf_counter()
    while not node.finished:
        executor.spin_once(timeout_sec=0.1)
    elapsed = time.perf_counter() - start
    steps = node.run.sim.clock.k
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown(context=context)
    return steps / elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--messages", type=int, default=50_000, help="messages per throughput run")
    parser.add_argument("--steps", type=int, default=20_000, help="steps per loop-rate run")
    parser.add_argument("--sim-seconds", type=float, default=10.0, help="sim time per node run (1 kHz steps)")
    args = parser.parse_args()
    print(f"python {platform.python_version()}, {os.cpu_count()} CPUs, {platform.platform()}")
    writer_throughput(args.messages)
    print("2. Simulation loop (free_tumble, rk4, dt 10 ms; state + orientation + /tf built and, when on, recorded)")
    print(f"   {'publishing':<28} {'off (steps/s)':>14} {'on (steps/s)':>14} {'slowdown':>9}")
    for every, label in ((1, "every step (100 Hz sim)"), (10, "every 10th step (10 Hz sim)")):
        off = loop_rate(args.steps, record=False, publish_every=every)
        on = loop_rate(args.steps, record=True, publish_every=every)
        print(f"   {label:<28} {off:>14,.0f} {on:>14,.0f} {(off / on - 1.0) * 100:>8.0f}%")
    print(
        f"3. The node (torque_driven, rk4 at 1 kHz, rtf 0, outputs at 100 Hz, {args.sim_seconds:g} s of sim time; "
        "best of 3, interleaved)"
    )
    offs, ons = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(3):  # interleaved, so that a change in machine load hits both alike
            offs.append(node_rate(args.sim_seconds, None))
            ons.append(node_rate(args.sim_seconds, Path(tmp) / f"node{i}.mcap"))
    off, on = max(offs), max(ons)
    print(f"   recording off: {off:>10,.0f} steps/s")
    print(f"   recording on:  {on:>10,.0f} steps/s  ({(off / on - 1.0) * 100:.0f} % slower)")


if __name__ == "__main__":
    main()
