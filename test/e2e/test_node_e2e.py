"""End to end: the simulation node in its own process, driven and observed over DDS.

Each test starts ``python -m rigid_rot_sim.node`` on a shipped scene (conftest fixtures:
private ROS_DOMAIN_ID, localhost discovery) and waits on conditions with timeouts.
"""

import math
import time
from pathlib import Path

import numpy as np
import pytest

from rigid_rot_sim.core.scene import load_scene
from rigid_rot_sim.core.simulator import Simulator

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"
NODE = "/rigid_rot_sim"


def scene_args(scene: str, **params) -> list[str]:
    args = ["--ros-args", "-p", f"scene:={SCENES / scene}.yaml"]
    for name, value in params.items():
        args += ["-p", f"{name}:={value}"]
    return args


def stamp(msg) -> float:
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


class Collector:
    """Subscribes in the test's rclpy node and spins until a condition holds."""

    def __init__(self, ros_node):
        from rclpy.executors import SingleThreadedExecutor

        self.node = ros_node
        self.executor = SingleThreadedExecutor(context=ros_node.context)
        self.executor.add_node(ros_node)
        self.messages: dict[str, list] = {}

    def subscribe(self, msg_type, topic: str, qos):
        self.messages[topic] = []
        self.node.create_subscription(msg_type, topic, self.messages[topic].append, qos)
        return self.messages[topic]

    def spin_until(self, condition, timeout: float, process=None, what: str = "condition"):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if condition():
                return
            if process is not None:
                process.check_alive()
            self.executor.spin_once(timeout_sec=0.05)
        raise AssertionError(f"timed out after {timeout} s waiting for {what}" + (f"\n{process.log()}" if process else ""))

    def call(self, srv_type, name: str, request, timeout: float = 10.0, process=None):
        client = self.node.create_client(srv_type, f"{NODE}/{name}")
        self.spin_until(lambda: client.service_is_ready(), 30.0, process, f"service {name}")
        future = client.call_async(request)
        self.spin_until(future.done, timeout, process, f"reply of {name}")
        return future.result()

    def close(self):
        self.executor.remove_node(self.node)
        self.executor.shutdown()


def by_stamp(messages: list) -> list:
    """One message per stamp (a reset while paused republishes the t = 0 state), in time order."""
    unique = {}
    for msg in messages:
        unique.setdefault(stamp(msg), msg)
    return [unique[t] for t in sorted(unique)]


def resume_when_matched(collector, node, topic: str, messages: list) -> None:
    """Resume a node started paused once ``topic`` reaches this test: every message from t = 0 arrives."""
    from std_srvs.srv import SetBool, Trigger

    collector.spin_until(lambda: collector.node.count_publishers(topic) > 0, 30.0, node, f"a publisher on {topic}")
    for _ in range(20):  # a reset (still paused) republishes the t = 0 outputs once the match is complete
        assert collector.call(Trigger, "reset", Trigger.Request(), process=node).success
        try:
            collector.spin_until(lambda: len(messages) > 0, 0.5, node, f"the t = 0 message on {topic}")
            break
        except AssertionError:
            continue
    assert collector.call(SetBool, "pause", SetBool.Request(data=False), process=node).success


@pytest.fixture
def collector(ros_node):
    c = Collector(ros_node)
    yield c
    c.close()


def test_torque_commands_change_omega_exactly_as_the_core_predicts(launch_node, collector):
    from geometry_msgs.msg import WrenchStamped
    from rigid_rot_msgs.msg import RigidBodyState

    from rigid_rot_sim.conversions import seconds_to_time
    from rigid_rot_sim.node import COMMAND_QOS, STATE_QOS

    node = launch_node(*scene_args("torque_driven", real_time_factor=2.0, integrator="rk4"), name="torque_driven")
    states = collector.subscribe(RigidBodyState, f"{NODE}/state", STATE_QOS)
    publisher = collector.node.create_publisher(WrenchStamped, f"{NODE}/torque", COMMAND_QOS)
    collector.spin_until(lambda: states and publisher.get_subscription_count() > 0, 30.0, node, "state and subscription")
    # stamped commands, well ahead of the node's sim time: their effect is fixed by the stamps
    t1 = math.ceil(stamp(states[-1])) + 1.0
    commands = [(t1, (0.0, 0.0, 0.004), "base_link"), (t1 + 0.2, (0.002, 0.0, 0.0), "odom"), (t1 + 0.45, (0.0, -0.001, 0.0), "base_link")]
    for when, torque, frame in commands:
        msg = WrenchStamped()
        msg.header.stamp = seconds_to_time(when)
        msg.header.frame_id = frame
        msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = torque
        publisher.publish(msg)
    t_end = t1 + 1.5  # after the 0.5 s hold timeout of the last command
    collector.spin_until(lambda: stamp(states[-1]) >= t_end, 20.0, node, f"state at t >= {t_end}")

    sim = Simulator(load_scene(SCENES / "torque_driven.yaml"), method="rk4")
    for when, torque, frame in commands:
        sim.submit_torque("~/torque", torque, sim.resolve_frame("~/torque", frame, "header"), when)
    compared = 0
    for msg in states:
        t = stamp(msg)
        if t < t1 - 0.1:
            continue
        sim.advance_to(round(t / sim.dt))
        expected = sim.snapshot()
        got = [msg.angular_velocity_body.x, msg.angular_velocity_body.y, msg.angular_velocity_body.z]
        assert got == expected.angular_velocity_body.tolist(), f"t = {t}"  # bit for bit
        q = msg.orientation
        assert [q.x, q.y, q.z, q.w] == expected.orientation.tolist(), f"t = {t}"
        compared += 1
    assert compared >= 100
    final = states[-1].angular_velocity_body
    assert abs(final.z) > 0.01 and abs(final.x) > 0.001  # the commands did act


def test_torque_free_run_conserves_momentum_and_energy_and_exits_cleanly(launch_node, collector):
    from rigid_rot_msgs.msg import RigidBodyState

    from rigid_rot_sim.node import STATE_QOS

    # started paused, resumed once this test's subscription is matched: every state arrives
    node = launch_node(*scene_args("intermediate_axis_flip", real_time_factor=10.0, duration=40.0, start_paused="true",
                                   **{"rates.state": 20.0}), name="flip")
    states = collector.subscribe(RigidBodyState, f"{NODE}/state", STATE_QOS)
    resume_when_matched(collector, node, f"{NODE}/state", states)
    collector.spin_until(lambda: not node.alive(), 30.0, None, "the node to finish its 40 s run")
    assert node.process.returncode == 0, node.log()
    assert "duration reached" in node.log()
    # the node waits for reliable subscribers to acknowledge before it exits: the last state arrives
    collector.spin_until(lambda: states and stamp(states[-1]) >= 40.0 - 1e-9, 5.0, None, "the last state")
    states = by_stamp(states)
    # keep-last-10 QoS may drop a few under load; the run is covered from t = 0 to the end
    assert len(states) >= 0.95 * (40 * 20 + 1) and stamp(states[0]) == 0.0
    reference = Simulator(load_scene(SCENES / "intermediate_axis_flip.yaml"))
    l0 = np.linalg.norm(reference.snapshot().angular_momentum_world)
    e0 = reference.snapshot().kinetic_energy
    momentum = np.array([[m.angular_momentum_world.x, m.angular_momentum_world.y, m.angular_momentum_world.z] for m in states])
    energy = np.array([m.kinetic_energy for m in states])
    # auto picks the exact flow: conserved to rounding
    assert np.max(np.abs(np.linalg.norm(momentum, axis=1) / l0 - 1.0)) < 1e-12
    assert np.max(np.abs(energy / e0 - 1.0)) < 1e-12
    assert np.max(np.abs(momentum - momentum[0])) < 1e-12 * l0  # L fixed in the world, not only |L|
    assert max(abs(m.energy_drift) for m in states) < 1e-12
    # the body did flip: omega_y about the intermediate axis changed sign
    omega_y = [m.angular_velocity_body.y for m in states]
    assert max(omega_y) > 3.9 and min(omega_y) < -3.9


def test_heavy_top_nutation_stays_between_the_turning_points(launch_node, collector):
    from rigid_rot_msgs.msg import HeavyTopState

    from rigid_rot_sim.core.heavy_top import HeavyTop, heavy_top_reference
    from rigid_rot_sim.node import STATE_QOS

    scene = load_scene(SCENES / "heavy_top.yaml")
    node = launch_node(*scene_args("heavy_top", real_time_factor=2.0, duration=4.0, start_paused="true"), name="heavy_top")
    top_states = collector.subscribe(HeavyTopState, f"{NODE}/top_state", STATE_QOS)
    resume_when_matched(collector, node, f"{NODE}/top_state", top_states)
    collector.spin_until(lambda: not node.alive(), 30.0, None, "the 4 s heavy-top run")
    collector.spin_until(lambda: top_states and stamp(top_states[-1]) >= 4.0 - 1e-9, 5.0, None, "the last top state")
    assert node.process.returncode == 0, node.log()

    mass, l = scene.body.mass, scene.body.center_of_mass[2]
    pivot = np.diag(scene.body.inertia_array)
    top = HeavyTop(mass=mass, gravity=scene.gravity.acceleration, com_distance=l,
                   com_moments=[pivot[0] - mass * l * l, pivot[1] - mass * l * l, pivot[2]])
    reference = heavy_top_reference(top, scene.initial.orientation, scene.initial.angular_velocity)
    theta_min, theta_max = reference.theta_range
    top_states = by_stamp(top_states)
    nutation = np.array([m.nutation for m in top_states])
    assert len(nutation) >= 0.95 * (4 * 100 + 1) and stamp(top_states[0]) == 0.0
    assert np.all(nutation >= theta_min - 1e-6) and np.all(nutation <= theta_max + 1e-6)
    # and it does nutate across the range, at least once in 4 s
    assert nutation.min() < theta_min + 0.05 * (theta_max - theta_min)
    assert nutation.max() > theta_max - 0.05 * (theta_max - theta_min)
    p_phi = np.array([m.p_phi for m in top_states])
    p_psi = np.array([m.p_psi for m in top_states])
    assert np.ptp(p_phi) < 1e-9 * abs(reference.p_phi) + 1e-15 and np.ptp(p_psi) < 1e-9 * abs(reference.p_psi)


def test_bad_commands_and_requests_are_rejected_and_pause_step_reset_work(launch_node, collector):
    from builtin_interfaces.msg import Duration
    from geometry_msgs.msg import Vector3, WrenchStamped
    from rigid_rot_msgs.msg import RejectedCommand, RigidBodyState
    from rigid_rot_msgs.srv import ApplyTorque, SetState, Step
    from std_srvs.srv import SetBool, Trigger

    from rigid_rot_sim.node import COMMAND_QOS, REJECTED_QOS, STATE_QOS

    node = launch_node(*scene_args("torque_driven", real_time_factor=1.0, integrator="rk4"), name="services")
    rejected = collector.subscribe(RejectedCommand, f"{NODE}/rejected", REJECTED_QOS)
    states = collector.subscribe(RigidBodyState, f"{NODE}/state", STATE_QOS)
    publisher = collector.node.create_publisher(WrenchStamped, f"{NODE}/torque", COMMAND_QOS)
    collector.spin_until(lambda: states and publisher.get_subscription_count() > 0, 30.0, node, "the node")

    bad = []
    for frame, torque, force in (("base_link", (math.nan, 0.0, 0.0), 0.0), ("map", (0.0, 0.0, 1.0), 0.0), ("base_link", (0.0, 0.0, 1.0), 5.0)):
        msg = WrenchStamped()
        msg.header.frame_id = frame
        msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = torque
        msg.wrench.force.y = force
        bad.append(msg)
        publisher.publish(msg)
    collector.spin_until(lambda: len(rejected) >= 3, 10.0, node, "three RejectedCommand messages")
    reasons = " | ".join(r.reason for r in rejected)
    assert "non-finite torque.x" in reasons and "'map' is neither" in reasons and "non-zero force" in reasons
    assert {r.source for r in rejected} == {f"{NODE}/torque"}

    response = collector.call(ApplyTorque, "apply_torque", ApplyTorque.Request(torque=Vector3(z=1.0), frame_id="map", duration=Duration(sec=1)), process=node)
    assert not response.success and "neither" in response.message
    response = collector.call(Step, "step", Step.Request(steps=10), process=node)
    assert not response.success and "not paused" in response.message
    zero_q = SetState.Request()
    zero_q.orientation.w = 0.0
    assert not collector.call(SetState, "set_state", zero_q, process=node).success

    # none of it touched the state: still at rest
    collector.spin_until(lambda: len(states) > 5, 5.0, node, "more states")
    assert all(m.angular_velocity_body.z == 0.0 and m.angular_velocity_body.x == 0.0 for m in states)

    assert collector.call(SetBool, "pause", SetBool.Request(data=True), process=node).success
    first = collector.call(Step, "step", Step.Request(steps=1), process=node)
    assert first.success
    applied = collector.call(ApplyTorque, "apply_torque", ApplyTorque.Request(torque=Vector3(z=0.004), duration=Duration(nanosec=50_000_000)), process=node)
    assert applied.success, applied.message
    stepped = collector.call(Step, "step", Step.Request(steps=100), process=node)
    assert stepped.success
    assert stamp(stepped.state) == pytest.approx(stamp(first.state) + 0.1, abs=1e-9)
    # 0.004 N*m for 0.05 s on I3 = 0.04 kg*m^2
    assert stepped.state.angular_velocity_body.z == pytest.approx(0.005, rel=1e-9)
    again = collector.call(Step, "step", Step.Request(steps=1), process=node)
    assert stamp(again.state) == pytest.approx(stamp(stepped.state) + 0.001, abs=1e-9)  # still paused: nothing ran between

    n = len(states)
    assert collector.call(Trigger, "reset", Trigger.Request(), process=node).success
    collector.spin_until(lambda: len(states) > n and stamp(states[-1]) < 0.5, 10.0, node, "a state after the reset")
    assert states[-1].angular_velocity_body.z == 0.0
    node.check_alive()


def test_shell_commands_run_and_torque(launch_node, collector, ros_env, tmp_path):
    """`rigid-rot torque` drives a running node; `rigid-rot run --echo` (the demo path) prints and exits 0."""
    import subprocess
    import sys

    from rigid_rot_msgs.msg import RigidBodyState

    from rigid_rot_sim.node import STATE_QOS

    node = launch_node(*scene_args("torque_driven", real_time_factor=1.0, integrator="rk4"), name="cli_target")
    states = collector.subscribe(RigidBodyState, f"{NODE}/state", STATE_QOS)
    collector.spin_until(lambda: len(states) > 0, 30.0, node, "the node's state")
    cli = [str(Path(sys.executable).with_name("rigid-rot"))]
    sent = subprocess.run(cli + ["torque", "0", "0", "0.004", "--frame", "base_link"], env=ros_env,
                          capture_output=True, text=True, timeout=30)
    assert sent.returncode == 0, sent.stdout + sent.stderr
    assert "1 command(s) [0.0, 0.0, 0.004]" in sent.stdout
    # held 0.5 s of sim time (the scene's timeout): omega_z = 0.004 * 0.5 / 0.04 = 0.05 rad/s
    collector.spin_until(lambda: states[-1].angular_velocity_body.z > 0.049, 10.0, node, "the torque to act")
    collector.spin_until(lambda: len(states) > 80 and states[-1].angular_velocity_body.z == states[-80].angular_velocity_body.z,
                         10.0, node, "the timeout to end the torque")
    assert states[-1].angular_velocity_body.z == pytest.approx(0.05, rel=1e-9)
    node.stop()

    demo = subprocess.run(cli + ["run", "free_tumble", "--duration", "1.5", "--echo", "0.5"], env=ros_env,
                          capture_output=True, text=True, timeout=60)
    assert demo.returncode == 0, demo.stdout + demo.stderr
    lines = [line for line in demo.stdout.splitlines() if line.startswith("t=")]
    assert len(lines) >= 2 and "|L|=" in lines[0]
    assert "duration reached" in demo.stderr
