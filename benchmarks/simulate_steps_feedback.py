"""SimulateSteps: wall time of a goal with the bounded feedback, against one feedback per step (the baseline).

    .venv/bin/python benchmarks/simulate_steps_feedback.py              # ~1 min on a loaded 2-core machine
    .venv/bin/python benchmarks/simulate_steps_feedback.py --steps 5000

The node (torque_driven, rk4, dt 1 ms, started paused, real_time_factor 0) and an rclpy action client
share one process and one executor (as test/ros/test_step_services.py does); the goal is sent to
``~/simulate_steps`` and timed from the send to the result. Two runs in the same process, baseline
first: ``FEEDBACK_RATE = inf`` (a feedback after every step: what the action did before issue 30),
then the shipped ``FEEDBACK_RATE`` (at most 50 per second of wall time, the last always). Figures:
seconds per goal, steps per second, feedback messages sent, and the speed-up. Numbers are noisy on
a shared machine; the ratio of the two runs of one invocation is the figure.
"""

from __future__ import annotations

import argparse
import math
import os
import time

os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 101))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import rclpy
from rclpy.action import ActionClient
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from simulation_interfaces.action import SimulateSteps

from rigid_rot_sim.ros import simulate_steps
from rigid_rot_sim.ros.node import RigidRotSimNode
from rigid_rot_sim.share import ensure_ament_prefix_path, resolve_scene


def one_goal(steps: int, rate: float) -> tuple[float, int]:
    """(wall seconds from sending the goal to its result, feedback messages sent) at feedback ``rate``."""
    simulate_steps.FEEDBACK_RATE = rate
    context = rclpy.Context()
    rclpy.init(context=context)
    scene = resolve_scene("torque_driven")
    parameters = {"scene": scene, "real_time_factor": 0.0, "start_paused": True, "integrator": "rk4"}
    node = RigidRotSimNode(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in parameters.items()])
    client_node = rclpy.create_node("simulate_steps_benchmark", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(client_node)
    client = ActionClient(client_node, SimulateSteps, "/rigid_rot_sim/simulate_steps")
    feedback: list = []
    try:
        while not client.server_is_ready():
            executor.spin_once(timeout_sec=0.05)
        warm = client.send_goal_async(SimulateSteps.Goal(steps=1))  # matches the reply paths first
        executor.spin_until_future_complete(warm, timeout_sec=30.0)
        executor.spin_until_future_complete(warm.result().get_result_async(), timeout_sec=30.0)
        sent = FEEDBACK_SENT[0]
        began = time.perf_counter()
        future = client.send_goal_async(SimulateSteps.Goal(steps=steps), feedback_callback=feedback.append)
        executor.spin_until_future_complete(future, timeout_sec=60.0)
        result = future.result().get_result_async()
        executor.spin_until_future_complete(result, timeout_sec=600.0)
        elapsed = time.perf_counter() - began
        assert result.result().result.result.result == 1, result.result().result.result.error_message
        return elapsed, FEEDBACK_SENT[0] - sent
    finally:
        client.destroy()
        executor.shutdown()
        client_node.destroy_node()
        node.destroy_node()
        rclpy.try_shutdown(context=context)


#: Feedback messages published by any goal handle of this process (the wrapper below counts them).
FEEDBACK_SENT = [0]


def count_feedback() -> None:
    """Count each feedback the action publishes (through the goal handle's method)."""
    from rclpy.action.server import ServerGoalHandle

    publish = ServerGoalHandle.publish_feedback

    def counted(self: ServerGoalHandle, message: object) -> object:
        FEEDBACK_SENT[0] += 1
        return publish(self, message)

    ServerGoalHandle.publish_feedback = counted


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=3000, help="steps per goal (default 3000)")
    args = parser.parse_args()
    ensure_ament_prefix_path()
    count_feedback()
    shipped = simulate_steps.FEEDBACK_RATE
    print(f"SimulateSteps goal of {args.steps} steps (torque_driven, rk4, dt 1 ms), node and client in one process")
    figures = {}
    for label, rate in (("baseline: a feedback per step", math.inf), (f"bounded: <= {shipped:g} Hz", shipped)):
        elapsed, sent = one_goal(args.steps, rate)
        figures[label] = elapsed
        print(f"  {label:34s} {elapsed:7.2f} s  {args.steps / elapsed:9.0f} steps/s  {sent:6d} feedback messages")
    baseline, bounded = figures.values()
    print(f"  speed-up: {baseline / bounded:.1f}x (same process, same run; a shared machine makes both noisy)")


if __name__ == "__main__":
    main()
