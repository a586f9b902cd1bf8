"""Lockstep over real DDS: the shipped controller (a subprocess) closes the loop with the node.

* three runs of the shipped controller in lockstep, the third with 4 busy processes loading
  the CPU: the digests and every received state are bit-identical; the recording of the run
  under load re-simulates BIT-EXACT with the same digest;
* the test process as a controller: a command stamped for another turn is rejected with the
  reason on ~/rejected; a controller that stops answering pauses the run (the reason in the
  log), and with ``on_timeout: hold`` the run goes on.
"""

from __future__ import annotations

import subprocess
import sys
import time

from geometry_msgs.msg import WrenchStamped
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_srvs.srv import SetBool

from rigid_rot_msgs.msg import RejectedCommand, RigidBodyState
from rigid_rot_sim.recording.reader import BagReader, info
from rigid_rot_sim.recording.resim import resimulate
from rigid_rot_sim.run.digest import format_digest

# a namespace of its own: other tests of the session may leave nodes named rigid_rot_sim on this domain
NAMESPACE = "/lockstep_e2e"
NODE = f"{NAMESPACE}/rigid_rot_sim"
STATE = f"{NODE}/state"
TORQUE = f"{NODE}/torque"
NS_ARGS = ("-r", f"__ns:={NAMESPACE}")
DURATION = 2.0  # s of sim time: 100 turns of 0.02 s
QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
TARGET = "[0.0, 0.0, 0.5, 0.8660254037844386]"
TIMEOUT = 120.0


def _closed_loop(launch_node, collector, record=None):
    """One lockstep run of closed_loop_lockstep with the shipped controller: {stamp_ns: state bytes}."""
    controller = launch_node(
        "--ros-args",
        "-p",
        f"target:={TARGET}",
        "-p",
        f"state_topic:={STATE}",
        "-p",
        f"torque_topic:={TORQUE}",
        name="controller",
        module="rigid_rot_sim.ros.controller",
    )
    args = [
        "--ros-args",
        *NS_ARGS,
        "-p",
        "scene:=closed_loop_lockstep",
        "-p",
        f"duration:={DURATION}",
        "-p",
        "start_paused:=true",
    ]
    if record:
        args += ["-p", f"record_path:={record}"]
    node = launch_node(*args, name="sim")
    # every field at full precision: repr of a float reads back to the same bits (also -0.0); the
    # CDR bytes of a re-serialised message are not compared (padding is not part of the state)
    states: dict[int, list[str]] = {}

    def on_state(msg):
        stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        states.setdefault(stamp, []).append(repr(msg))
        LAST[stamp] = msg

    subscription = collector.node.create_subscription(RigidBodyState, STATE, on_state, QOS)
    # the controller and this process listen before the run starts: every state reaches both
    collector.spin_until(
        lambda: (
            collector.node.count_publishers(STATE) >= 1
            and collector.node.count_subscribers(STATE) >= 2
            and collector.node.count_subscribers(TORQUE) >= 1
            and collector.node.count_publishers(TORQUE) >= 1
        ),
        TIMEOUT,
        node,
        "the loop's graph",
    )
    reply = collector.call(SetBool, f"{NODE}/pause", SetBool.Request(data=False), process=node, idempotent=True)
    assert reply.success, reply.message
    last = round(DURATION * 1e9)
    collector.spin_until(lambda: last in states, TIMEOUT, node, "the last state")
    assert node.process.wait(timeout=30) == 0, node.log()
    controller.stop()
    collector.node.destroy_subscription(subscription)
    assert "LOCKSTEP on" in node.log()
    for stamp, copies in states.items():  # a turn's state sent again (before the match) is the same bits
        assert len(set(copies)) == 1, stamp
    return {stamp: copies[0] for stamp, copies in states.items()}, node


def _describe(differing, a, b):
    stamp = differing[0]
    return f"{len(differing)} states differ, first at {stamp} ns:\n{a[stamp]}\n{b[stamp]}"


#: The last message received for each stamp (of the latest run).
LAST: dict = {}


def _last_digest(states):
    """The run digest of the last state (its field, as in the repr)."""
    return int(states[max(states)].rsplit("digest=", 1)[1].rstrip(")"))


def test_the_closed_loop_is_bit_identical_on_every_repeat_even_under_load(launch_node, collector, tmp_path):
    first, _ = _closed_loop(launch_node, collector)
    second, _ = _closed_loop(launch_node, collector)
    busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(4)]
    try:
        bag = tmp_path / "loaded.mcap"
        third, _ = _closed_loop(launch_node, collector, record=bag)
    finally:
        for process in busy:
            process.kill()
            process.wait()
    expected_turns = round(DURATION / 0.02) + 1
    # t_0 may be answered (the controller gets it first) before this process's reader is matched:
    # the turns from t_1 on are published after the run is resumed, with everyone listening
    for states in (first, second, third):
        assert set(range(20_000_000, 2_000_000_001, 20_000_000)) <= set(states)
    for a, b in ((first, second), (first, third)):  # every state received in both runs, bit for bit
        differing = sorted(stamp for stamp in a.keys() & b.keys() if a[stamp] != b[stamp])
        assert not differing, _describe(differing, a, b)
    digest = _last_digest(first)
    assert digest == _last_digest(third) and digest != 0
    # the body is being slewed about z towards the target
    final = LAST[max(LAST)]  # the third run's, the same as the first's
    assert 0.1 < final.orientation.z < 0.5  # 2 s into the 60-degree slew (z = 0.5 at the target)
    report = resimulate(bag)
    assert report.identical, report.format()
    assert report.states >= expected_turns  # the recording has every turn, t_0 included
    assert report.digest == report.recorded_digest == digest
    assert BagReader(bag).metadata["digest"]["digest"] == format_digest(digest)  # the file's summary
    assert f"Digest:     {format_digest(digest)}" in info(bag)  # rigid-rot bag info


def _answer(collector, publisher, stamp, torque_z=0.001):
    command = WrenchStamped()
    command.header.stamp = stamp
    command.header.frame_id = "base_link"
    command.wrench.torque.z = torque_z
    publisher.publish(command)


def _manual_loop(launch_node, collector, *overrides):
    node = launch_node(
        "--ros-args",
        *NS_ARGS,
        "-p",
        "scene:=closed_loop_lockstep",
        "-p",
        "duration:=0.0",
        "-p",
        "lockstep.timeout:=1.0",
        "-p",
        "start_paused:=true",
        *overrides,
        name="sim",
    )
    states = collector.subscribe(RigidBodyState, STATE, QOS)
    rejected = collector.subscribe(RejectedCommand, f"{NODE}/rejected", QOS)
    publisher = collector.node.create_publisher(WrenchStamped, TORQUE, QoSProfile(depth=10))
    # paused at turn 0, whose state is sent again until answered: this process gets it once matched
    collector.spin_until(lambda: collector.node.count_subscribers(TORQUE) >= 1 and states, TIMEOUT, node, "turn 0")
    reply = collector.call(SetBool, f"{NODE}/pause", SetBool.Request(data=False), process=node, idempotent=True)
    assert reply.success, reply.message
    return node, states, rejected, publisher


def test_a_command_for_another_turn_is_rejected_and_a_silent_controller_pauses_the_run(launch_node, collector):
    node, states, rejected, publisher = _manual_loop(launch_node, collector)
    assert states[0].header.stamp.sec == 0 and states[0].header.stamp.nanosec == 0
    wrong = states[0].header.stamp.__class__(sec=0, nanosec=40_000_000)
    _answer(collector, publisher, wrong)
    collector.spin_until(lambda: rejected, TIMEOUT, node, "the rejection")
    assert "turn 0 waits for commands stamped 0 s" in rejected[0].reason, rejected[0].reason
    _answer(collector, publisher, states[0].header.stamp)
    collector.spin_until(lambda: states[-1].header.stamp.nanosec == 20_000_000, TIMEOUT, node, "turn 1")
    # no answer to turn 1: after the 1 s timeout the run pauses, with the reason in the log
    collector.spin_until(lambda: "no command stamped 0.02 s (turn 1)" in node.log(), TIMEOUT, node, "the pause")
    assert "paused" in node.log()
    count = len(states)
    deadline = time.monotonic() + 1.5
    collector.spin_until(lambda: time.monotonic() > deadline, 5.0, node)
    assert all(s.header.stamp.nanosec <= 20_000_000 and s.header.stamp.sec == 0 for s in states[count - 1 :])


def test_with_hold_a_silent_controller_only_slows_the_run(launch_node, collector):
    node, states, _, publisher = _manual_loop(
        launch_node, collector, "-p", "lockstep.on_timeout:=hold", "-p", "lockstep.timeout:=0.2"
    )
    _answer(collector, publisher, states[0].header.stamp)
    collector.spin_until(
        lambda: any(s.header.stamp.nanosec >= 80_000_000 for s in states),
        TIMEOUT,
        node,
        "turns going on without answers",
    )
    assert "holding" in node.log()
    # the held torque acts on: the body turns about z
    assert states[-1].angular_velocity_body.z > 0.0
