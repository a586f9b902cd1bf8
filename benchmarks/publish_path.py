"""CPU per step of the node's publishing path at 1 kHz, messages refilled against built anew (prints figures).

    .venv/bin/python benchmarks/publish_path.py                # 5 x 20 000 publishes of each, interleaved

The node in this process (``torque_driven``, real-time factor 0, nothing stepping it), its real publishers:
:meth:`~rigid_rot_sim.ros.outputs.Outputs.outputs_due` for ``~/state`` and ``~/angular_velocity`` (the step-rate
outputs of issue 41's 1 kHz node), once per snapshot, either as the node does it (one message per output,
refilled in place: ``Outputs.refilled``) or with every message built anew (the builders of ``OUTPUTS``, as
before issue 41). A subscriber in this process takes ``~/state`` (so the publish crosses to a reader, as in a
run that is watched); it is spun after each batch. Process CPU time per publishing step (both outputs), the
two ways interleaved in the same run, best and median of the repeats, with the load average.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 130))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import rclpy  # noqa: E402
from rclpy.qos import QoSProfile  # noqa: E402

from rigid_rot_msgs.msg import RigidBodyState  # noqa: E402
from rigid_rot_sim.ros.node import RigidRotSimNode  # noqa: E402

NAMES = ["state", "angular_velocity"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=20000, help="publishing steps per repeat")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = RigidRotSimNode(
            context=context,
            parameter_overrides=[
                rclpy.parameter.Parameter("scene", value="torque_driven"),
                rclpy.parameter.Parameter("real_time_factor", value=0.0),
                rclpy.parameter.Parameter("rates.state", value=1000.0),
                rclpy.parameter.Parameter("rates.angular_velocity", value=1000.0),
            ],
        )
        reader = rclpy.create_node("publish_path_reader", context=context)
        reader.create_subscription(RigidBodyState, "/rigid_rot_sim/state", lambda m: None, QoSProfile(depth=100))
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(reader)
        outputs, sim = node.run.outputs, node.run.sim
        refilled = dict(outputs.refilled)
        snapshots = []
        for _ in range(100):
            sim.advance(1)
            snapshots.append(sim.snapshot())
        figures: dict[str, list[float]] = {"refilled": [], "built anew": []}
        for _ in range(args.repeats):
            for way in figures:
                outputs.refilled = refilled if way == "refilled" else {}
                start = time.process_time()
                for i in range(args.steps):
                    outputs.outputs_due(i, snapshots[i % 100], NAMES)
                    if i % 100 == 99:
                        executor.spin_once(timeout_sec=0)
                figures[way].append((time.process_time() - start) / args.steps * 1e6)
        outputs.refilled = refilled
        node.destroy_node()
        reader.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    load = " ".join(open("/proc/loadavg").read().split()[:3])
    for way, values in figures.items():
        print(
            f"{way:>10}: {min(values):6.1f} us CPU per step (~/state + ~/angular_velocity), best of {args.repeats}; "
            f"median {statistics.median(values):6.1f} us"
        )
    ratio = min(figures["refilled"]) / min(figures["built anew"])
    print(f"refilled / built anew: {ratio:.2f} (best against best); load average {load} on {os.cpu_count()} cores")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
