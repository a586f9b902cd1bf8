"""The B-dot detumble controller (``python -m rigid_rot_sim.ros.detumble_controller``, a subprocess) closes the
magnetic loop with the node over real DDS in lockstep: ``cubesat_detumble``'s magnetometer readings in, the rods'
dipoles out, one turn per reading. Two runs end on the same digest, and the tumble slows."""

from __future__ import annotations

import math

from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_srvs.srv import SetBool

from rigid_rot_msgs.msg import RigidBodyState

NAMESPACE = "/detumble_e2e"
NODE = f"{NAMESPACE}/rigid_rot_sim"
STATE = f"{NODE}/state"
MAGNETOMETER = f"{NODE}/magnetometer"
COMMAND = f"{NODE}/magnetorquer_command"
DURATION = 30.0  # s of sim time: 300 turns of 0.1 s, three duty cycles of B-dot every second
QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
TIMEOUT = 180.0


def _closed_loop(launch_node, collector) -> dict[int, RigidBodyState]:
    controller = launch_node(
        "--ros-args",
        "-p",
        f"magnetometer_topic:={MAGNETOMETER}",
        "-p",
        f"command_topic:={COMMAND}",
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


def test_bdot_in_lockstep_repeats_bit_for_bit_and_slows_the_tumble(launch_node, collector):
    first = _closed_loop(launch_node, collector)
    second = _closed_loop(launch_node, collector)
    end = max(first)
    assert end == max(second) == round(DURATION * 1e9)
    assert first[end].digest == second[end].digest != 0
    assert repr(first[end]) == repr(second[end])
    start = min(first)
    assert _rate(first[end]) < _rate(first[start]) - math.radians(0.1), (_rate(first[start]), _rate(first[end]))
