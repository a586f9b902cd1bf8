"""The B-dot detumble controller (``python -m rigid_rot_sim.ros.detumble_controller``, a subprocess) closes the
magnetic loop with the node over real DDS in lockstep: ``cubesat_detumble``'s magnetometer readings in, the rods'
dipoles out, one turn per reading. Two runs end on the same digest, the tumble slows, and the recording of the
second re-simulates BIT-EXACT (the rods' commands replayed, the magnetometer redrawn) with that digest."""

from __future__ import annotations

import math

from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_srvs.srv import SetBool

from rigid_rot_msgs.msg import RigidBodyState
from rigid_rot_sim.recording.events import decode_event
from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.recording.resim import resimulate

NAMESPACE = "/detumble_e2e"
NODE = f"{NAMESPACE}/rigid_rot_sim"
STATE = f"{NODE}/state"
MAGNETOMETER = f"{NODE}/magnetometer"
COMMAND = f"{NODE}/magnetorquer_command"
DURATION = 30.0  # s of sim time: 300 turns of 0.1 s, three duty cycles of B-dot every second
QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
TIMEOUT = 180.0


def _closed_loop(launch_node, collector, record=None) -> dict[int, RigidBodyState]:
    controller = launch_node(
        "--ros-args",
        "-p",
        f"magnetometer_topic:={MAGNETOMETER}",
        "-p",
        f"command_topic:={COMMAND}",
        "-p",
        f"state_topic:={STATE}",
        name="bdot",
        module="rigid_rot_sim.ros.detumble_controller",
    )
    node = launch_node(
        "--ros-args",
        "-r",
        f"__ns:={NAMESPACE}",
        "-p",
        "scene:=cubesat_detumble",
        "-p",
        f"duration:={DURATION}",
        "-p",
        "start_paused:=true",
        "-p",
        "lockstep.period:=0.1",
        "-p",
        "lockstep.inputs:=['~/magnetorquer_command']",
        *(["-p", f"record_path:={record}"] if record else []),
        name="sim",
    )
    states: dict[int, RigidBodyState] = {}

    def on_state(msg):
        states[msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec] = msg

    subscription = collector.node.create_subscription(RigidBodyState, STATE, on_state, QOS)
    collector.spin_until(
        lambda: (
            collector.node.count_publishers(STATE) >= 1
            and collector.node.count_subscribers(MAGNETOMETER) >= 1
            and collector.node.count_subscribers(STATE) >= 2
            and collector.node.count_publishers(COMMAND) >= 1
            and collector.node.count_subscribers(COMMAND) >= 1
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
    assert "LOCKSTEP on" in node.log(), node.log()
    return states


def _rate(msg: RigidBodyState) -> float:
    w = msg.angular_velocity_body
    return math.sqrt(w.x * w.x + w.y * w.y + w.z * w.z)


def test_bdot_in_lockstep_repeats_bit_for_bit_slows_the_tumble_and_resimulates(launch_node, collector, tmp_path):
    bag = tmp_path / "detumble.mcap"
    first = _closed_loop(launch_node, collector)
    second = _closed_loop(launch_node, collector, record=bag)
    end = max(first)
    assert end == max(second) == round(DURATION * 1e9)
    assert first[end].digest == second[end].digest != 0
    assert repr(first[end]) == repr(second[end])
    start = min(first)
    assert _rate(first[end]) < _rate(first[start]) - math.radians(0.1), (_rate(first[start]), _rate(first[end]))
    events = [decode_event(e) for _, e in BagReader(bag).decoded([f"{NODE}/sim_events"])]
    rods = [e for e in events if e.kind == "rod_dipoles"]
    assert len(rods) == round(DURATION / 0.1) + 1  # one command per turn, t = 0 included
    # the controller scales its dipoles to the rods' limits: the node never had to clamp, and the rods worked
    assert all(e.values["clamped"] == "[]" for e in rods)
    assert max(abs(v) for e in rods for v in e.vector("dipoles")) == 0.2
    report = resimulate(bag)
    assert report.identical, report.format()
    assert report.digest == report.recorded_digest == first[end].digest
