"""End to end: the simulation node in its own process, driven and observed over DDS.

Each test starts ``python -m rigid_rot_sim.ros.node`` on a shipped scene (conftest fixtures:
private ROS_DOMAIN_ID, localhost discovery) and waits on conditions with timeouts.

No assertion depends on how many volatile messages the test process happened to receive (a
loaded machine drops some by design: keep-last QoS). What the node guarantees is asserted
instead: every message received equals the one the core predicts or the one recorded; counts
and coverage of a run come from its recording (every published message is in it); a state
after an action is awaited as a condition; the replies of services are deterministic.
"""

import math
import time
from pathlib import Path

import numpy as np
import pytest
from e2e_helpers import WAIT, wait_until_recorded  # beside this file

from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import load_scene

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"
NODE = "/rigid_rot_sim"


def scene_args(scene: str, **params) -> list[str]:
    args = ["--ros-args", "-p", f"scene:={SCENES / scene}.yaml"]
    for name, value in params.items():
        args += ["-p", f"{name}:={value}"]
    return args


def stamp(msg) -> float:
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


FIELDS = ("orientation", "angular_velocity_body", "angular_momentum_world", "kinetic_energy")


def resume_when_matched(collector, node, topic: str, messages: list) -> None:
    """Resume a node started paused once ``topic`` reaches this test (its t = 0 message has arrived)."""
    from std_srvs.srv import SetBool, Trigger

    collector.spin_until(lambda: collector.node.count_publishers(topic) > 0, WAIT, node, f"a publisher on {topic}")
    deadline = time.monotonic() + WAIT
    while not messages:  # a reset (still paused) republishes the t = 0 outputs; received once the match is complete
        assert time.monotonic() < deadline, f"no message on {topic} within {WAIT} s\n{node.log()}"
        assert collector.call(Trigger, "reset", Trigger.Request(), process=node).success
        try:
            collector.spin_until(lambda: len(messages) > 0, 1.0, node, f"the t = 0 message on {topic}")
        except AssertionError:
            continue
    assert collector.call(SetBool, "pause", SetBool.Request(data=False), process=node, idempotent=True).success


def recorded(bag: Path, topic: str) -> dict[float, object]:
    """{stamp: message} of ``topic`` in a finished recording, one per stamp (the last one)."""
    from rigid_rot_sim.recording.reader import BagReader

    reader = BagReader(bag)
    assert reader.complete, f"{bag} is not a finished recording"
    return {round(stamp(msg), 9): msg for _, msg in reader.decoded([topic])}


def same_fields(received, from_file, names: tuple[str, ...]) -> bool:
    """The named fields of a received message equal those decoded from the recording, bit for bit."""

    def value(msg, name):
        field = getattr(msg, name)
        return tuple(getattr(field, axis) for axis in "xyzw" if hasattr(field, axis)) or field

    return all(value(received, name) == value(from_file, name) for name in names)


def test_torque_commands_change_omega_exactly_as_the_core_predicts(launch_node, collector, tmp_path):
    from geometry_msgs.msg import WrenchStamped
    from std_srvs.srv import SetBool

    from rigid_rot_msgs.msg import RigidBodyState
    from rigid_rot_sim.conversions import seconds_to_time
    from rigid_rot_sim.ros.qos import COMMAND_QOS, STATE_QOS

    # started paused at t = 0; resumed once the node has received (and recorded) every command
    bag = tmp_path / "commands.mcap"
    node = launch_node(
        *scene_args("torque_driven", real_time_factor=2.0, integrator="rk4", start_paused="true", record_path=bag),
        name="torque_driven",
    )
    states = collector.subscribe(RigidBodyState, f"{NODE}/state", STATE_QOS)
    publisher = collector.node.create_publisher(WrenchStamped, f"{NODE}/torque", COMMAND_QOS)
    collector.spin_until(lambda: publisher.get_subscription_count() > 0, WAIT, node, "the torque subscription")
    # stamped commands ahead of the node's sim time: their effect is fixed by the stamps
    t1 = 1.0
    commands = [
        (t1, (0.0, 0.0, 0.004), "base_link"),
        (t1 + 0.2, (0.002, 0.0, 0.0), "odom"),
        (t1 + 0.45, (0.0, -0.001, 0.0), "base_link"),
    ]
    for when, torque, frame in commands:
        msg = WrenchStamped()
        msg.header.stamp = seconds_to_time(when)
        msg.header.frame_id = frame
        msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = torque
        publisher.publish(msg)
    wait_until_recorded(bag, f"{NODE}/torque", len(commands), node)
    assert collector.call(SetBool, "pause", SetBool.Request(data=False), process=node, idempotent=True).success
    t_end = t1 + 1.5  # after the 0.5 s hold timeout of the last command
    collector.spin_until(lambda: states and stamp(states[-1]) >= t_end, WAIT, node, f"state at t >= {t_end}")

    sim = Simulator(load_scene(SCENES / "torque_driven.yaml"), method="rk4")
    for when, torque, frame in commands:
        sim.submit_torque("~/torque", torque, sim.commands.resolve_frame("~/torque", frame, "header"), when)
    compared = 0
    for msg in states:
        t = stamp(msg)
        if t < t1 - 0.1:
            continue
        sim.advance_to(round(t / sim.clock.dt))
        expected = sim.snapshot()
        got = [msg.angular_velocity_body.x, msg.angular_velocity_body.y, msg.angular_velocity_body.z]
        assert got == expected.angular_velocity_body.tolist(), f"t = {t}"  # bit for bit
        q = msg.orientation
        assert [q.x, q.y, q.z, q.w] == expected.orientation.tolist(), f"t = {t}"
        compared += 1
    # every state received is the core's; the last one compared lies after all three commands ended
    assert compared >= 1 and stamp(states[-1]) >= t_end
    final = states[-1].angular_velocity_body
    assert abs(final.z) > 0.01 and abs(final.x) > 0.001  # the commands did act


def test_torque_free_run_conserves_momentum_and_energy_and_exits_cleanly(launch_node, collector, tmp_path):
    from rigid_rot_msgs.msg import RigidBodyState
    from rigid_rot_sim.ros.qos import STATE_QOS

    # started paused, resumed once this test's subscription is matched; the run is recorded
    bag = tmp_path / "flip.mcap"
    node = launch_node(
        *scene_args(
            "intermediate_axis_flip",
            real_time_factor=10.0,
            duration=40.0,
            start_paused="true",
            record_path=bag,
            **{"rates.state": 20.0},
        ),
        name="flip",
    )
    received = collector.subscribe(RigidBodyState, f"{NODE}/state", STATE_QOS)
    resume_when_matched(collector, node, f"{NODE}/state", received)
    collector.spin_until(lambda: not node.alive(), WAIT, None, "the node to finish its 40 s run")
    assert node.process.returncode == 0, node.log()
    assert "duration reached" in node.log()
    # what was published is in the recording: every state from t = 0 to the end, once each
    published = recorded(bag, f"{NODE}/state")
    assert sorted(published) == [round(0.05 * i, 9) for i in range(40 * 20 + 1)]
    # and what reached this process over DDS is exactly that (however many arrived)
    assert received and all(same_fields(m, published[round(stamp(m), 9)], FIELDS) for m in received)
    states = [published[t] for t in sorted(published)]
    reference = Simulator(load_scene(SCENES / "intermediate_axis_flip.yaml"))
    l0 = np.linalg.norm(reference.snapshot().angular_momentum_world)
    e0 = reference.snapshot().kinetic_energy
    momentum = np.array(
        [[m.angular_momentum_world.x, m.angular_momentum_world.y, m.angular_momentum_world.z] for m in states]
    )
    energy = np.array([m.kinetic_energy for m in states])
    # auto picks the exact flow: conserved to rounding
    assert np.max(np.abs(np.linalg.norm(momentum, axis=1) / l0 - 1.0)) < 1e-12
    assert np.max(np.abs(energy / e0 - 1.0)) < 1e-12
    assert np.max(np.abs(momentum - momentum[0])) < 1e-12 * l0  # L fixed in the world, not only |L|
    assert max(abs(m.energy_drift) for m in states) < 1e-12
    # the body did flip: omega_y about the intermediate axis changed sign
    omega_y = [m.angular_velocity_body.y for m in states]
    assert max(omega_y) > 3.9 and min(omega_y) < -3.9


def test_heavy_top_nutation_stays_between_the_turning_points(launch_node, collector, tmp_path):
    from rigid_rot_msgs.msg import HeavyTopState
    from rigid_rot_sim.core.heavy_top import HeavyTop, heavy_top_reference
    from rigid_rot_sim.ros.qos import STATE_QOS

    scene = load_scene(SCENES / "heavy_top.yaml")
    bag = tmp_path / "top.mcap"
    node = launch_node(
        *scene_args("heavy_top", real_time_factor=2.0, duration=4.0, start_paused="true", record_path=bag),
        name="heavy_top",
    )
    received = collector.subscribe(HeavyTopState, f"{NODE}/top_state", STATE_QOS)
    resume_when_matched(collector, node, f"{NODE}/top_state", received)
    collector.spin_until(lambda: not node.alive(), WAIT, None, "the 4 s heavy-top run")
    assert node.process.returncode == 0, node.log()
    published = recorded(bag, f"{NODE}/top_state")
    assert sorted(published) == [round(0.01 * i, 9) for i in range(4 * 100 + 1)]  # every top state, t = 0 to 4 s
    names = ("precession", "nutation", "spin", "p_phi", "p_psi", "energy")
    assert received and all(same_fields(m, published[round(stamp(m), 9)], names) for m in received)

    mass, arm = scene.body.mass, scene.body.center_of_mass[2]
    pivot = np.diag(scene.body.inertia_array)
    top = HeavyTop(
        mass=mass,
        gravity=scene.gravity.acceleration,
        com_distance=arm,
        com_moments=[pivot[0] - mass * arm * arm, pivot[1] - mass * arm * arm, pivot[2]],
    )
    reference = heavy_top_reference(top, scene.initial.orientation, scene.initial.angular_velocity)
    theta_min, theta_max = reference.theta_range
    top_states = [published[t] for t in sorted(published)]
    nutation = np.array([m.nutation for m in top_states])
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
    from std_srvs.srv import SetBool, Trigger

    from rigid_rot_msgs.msg import RejectedCommand, RigidBodyState
    from rigid_rot_msgs.srv import ApplyTorque, SetState, Step
    from rigid_rot_sim.ros.qos import COMMAND_QOS, REJECTED_QOS, STATE_QOS

    node = launch_node(*scene_args("torque_driven", real_time_factor=1.0, integrator="rk4"), name="services")
    rejected = collector.subscribe(RejectedCommand, f"{NODE}/rejected", REJECTED_QOS)
    states = collector.subscribe(RigidBodyState, f"{NODE}/state", STATE_QOS)
    publisher = collector.node.create_publisher(WrenchStamped, f"{NODE}/torque", COMMAND_QOS)
    collector.spin_until(lambda: states and publisher.get_subscription_count() > 0, WAIT, node, "the node")

    bad = []
    for frame, torque, force in (
        ("base_link", (math.nan, 0.0, 0.0), 0.0),
        ("map", (0.0, 0.0, 1.0), 0.0),
        ("base_link", (0.0, 0.0, 1.0), 5.0),
    ):
        msg = WrenchStamped()
        msg.header.frame_id = frame
        msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = torque
        msg.wrench.force.y = force
        bad.append(msg)
    expected = ("non-finite torque.x", "'map' is neither", "non-zero force")

    def all_reported() -> bool:
        reasons = " | ".join(r.reason for r in rejected)
        return all(text in reasons for text in expected)

    # ~/rejected is volatile: a report published before this test's subscription matched is not
    # delivered, so the bad commands are sent again until each rejection has been reported
    deadline = time.monotonic() + WAIT
    while not all_reported():
        assert time.monotonic() < deadline, f"rejections received: {[r.reason for r in rejected]}\n{node.log()}"
        for msg in bad:
            publisher.publish(msg)
        try:
            collector.spin_until(all_reported, 2.0, node, "the three rejections")
        except AssertionError:
            continue
    assert {r.source for r in rejected} == {f"{NODE}/torque"}

    response = collector.call(
        ApplyTorque,
        "apply_torque",
        ApplyTorque.Request(torque=Vector3(z=1.0), frame_id="map", duration=Duration(sec=1)),
        process=node,
    )
    assert not response.success and "neither" in response.message
    response = collector.call(Step, "step", Step.Request(steps=10), process=node)
    assert not response.success and "not paused" in response.message
    zero_q = SetState.Request()
    zero_q.orientation.w = 0.0
    assert not collector.call(SetState, "set_state", zero_q, process=node).success

    # none of it touched the state: still at rest, also in states published after the last rejection
    n = len(states)
    collector.spin_until(lambda: len(states) > n, WAIT, node, "more states")
    assert all(m.angular_velocity_body.z == 0.0 and m.angular_velocity_body.x == 0.0 for m in states)

    assert collector.call(SetBool, "pause", SetBool.Request(data=True), process=node, idempotent=True).success
    first = collector.call(Step, "step", Step.Request(steps=1), process=node)
    assert first.success
    applied = collector.call(
        ApplyTorque,
        "apply_torque",
        ApplyTorque.Request(torque=Vector3(z=0.004), duration=Duration(nanosec=50_000_000)),
        process=node,
    )
    assert applied.success, applied.message
    stepped = collector.call(Step, "step", Step.Request(steps=100), process=node)
    assert stepped.success
    assert stamp(stepped.state) == pytest.approx(stamp(first.state) + 0.1, abs=1e-9)
    # 0.004 N*m for 0.05 s on I3 = 0.04 kg*m^2
    assert stepped.state.angular_velocity_body.z == pytest.approx(0.005, rel=1e-9)
    again = collector.call(Step, "step", Step.Request(steps=1), process=node)
    assert stamp(again.state) == pytest.approx(
        stamp(stepped.state) + 0.001, abs=1e-9
    )  # still paused: nothing ran between

    # a reset while paused publishes the t = 0 state once; nothing else is published on ~/state
    # while paused, so the reliable subscription receives it
    n = len(states)
    assert collector.call(Trigger, "reset", Trigger.Request(), process=node).success
    collector.spin_until(
        lambda: any(stamp(m) == 0.0 for m in states[n:]), WAIT, node, "the t = 0 state after the reset"
    )
    after_reset = next(m for m in states[n:] if stamp(m) == 0.0)
    assert after_reset.angular_velocity_body.z == 0.0
    assert stamp(collector.call(Step, "step", Step.Request(steps=1), process=node).state) == pytest.approx(0.001)
    node.check_alive()


def test_shell_commands_run_and_torque(launch_node, collector, ros_env, tmp_path):
    """`rigid-rot torque` drives a running node; `rigid-rot run --echo` (the demo path) prints and exits 0."""
    import subprocess
    import sys

    from rigid_rot_msgs.msg import RigidBodyState
    from rigid_rot_sim.ros.qos import STATE_QOS

    node = launch_node(*scene_args("torque_driven", real_time_factor=1.0, integrator="rk4"), name="cli_target")
    states = collector.subscribe(RigidBodyState, f"{NODE}/state", STATE_QOS)
    collector.spin_until(lambda: len(states) > 0, WAIT, node, "the node's state")
    cli = [str(Path(sys.executable).with_name("rigid-rot"))]
    sent = subprocess.run(
        cli + ["torque", "0", "0", "0.004", "--frame", "base_link"],
        env=ros_env,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert sent.returncode == 0, sent.stdout + sent.stderr
    assert "1 command(s) [0.0, 0.0, 0.004]" in sent.stdout
    # held 0.5 s of sim time (the scene's timeout): omega_z = 0.004 * 0.5 / 0.04 = 0.05 rad/s
    collector.spin_until(lambda: states[-1].angular_velocity_body.z > 0.049, WAIT, node, "the torque to act")
    acting = stamp(states[-1])
    # the command is held for 0.5 s of sim time after it took effect: 1 s later it has ended for sure
    collector.spin_until(lambda: stamp(states[-1]) >= acting + 1.0, WAIT, node, "1 s of sim time more")
    assert states[-1].angular_velocity_body.z == pytest.approx(0.05, rel=1e-9)
    node.stop()

    demo = subprocess.run(
        cli + ["run", "free_tumble", "--duration", "1.5", "--echo", "0.5"],
        env=ros_env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert demo.returncode == 0, demo.stdout + demo.stderr
    # the echo prints what it received: at least one state (how many depends on the machine's load)
    lines = [line for line in demo.stdout.splitlines() if line.startswith("t=")]
    assert lines and all("|L|=" in line for line in lines)
    assert "duration reached" in demo.stderr
