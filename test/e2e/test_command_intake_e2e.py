"""End to end (issue 27): every command DDS delivers is taken, idle and with two busy processes.

A publisher in this process (another process than the node) sends 2000 commands, half of them
invalid (NaN), at 200/s and at 1000/s, with the machine idle and with two busy-looping processes.
What the node guarantees is checked in its own recording, which holds every command message it
took (as received), every command it accepted (``~/sim_events``) and every ``~/rejected`` it
published: all 2000 taken, every valid one accepted, every invalid one reported on
``~/rejected``, and nothing reported lost. The same for ``~/wheel_torque`` in a wheel scene.
Each burst is told apart by a marker value in every command (torque y, or the third wheel's torque).
"""

from __future__ import annotations

import math
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from e2e_helpers import WAIT, wait_until_recorded  # beside this file

from rigid_rot_sim.recording.events import decode_event
from rigid_rot_sim.recording.reader import BagReader

COUNT = 2000
RATES = (200.0, 1000.0)
TORQUE_TOPIC = "/rigid_rot_sim/torque"
WHEEL_TOPIC = "/rigid_rot_sim/wheel_torque"
REJECTED = "/rigid_rot_sim/rejected"
EVENTS = "/rigid_rot_sim/sim_events"
ROOT = Path(__file__).resolve().parents[2]
WHEEL_SCENE = {
    "name": "wheel_intake_e2e",
    "body": {"principal_moments": [10.0, 12.0, 15.0]},
    "actuators": {
        "reaction_wheels": [
            {"name": n, "axis": a, "inertia": 0.5, "max_torque": 0.2, "max_speed": 600.0}
            for n, a in (("rw_x", [1, 0, 0]), ("rw_y", [0, 1, 0]), ("rw_z", [0, 0, 1]))
        ]
    },
    "integrator": {"method": "gyrostat_rk4", "dt": 0.001},
    "real_time_factor": 1.0,
    "commands": {"qos_depth": 1000},  # as torque_driven: 1 s of commands at 1 kHz while the node has no core
    "outputs": {"state": 100, "orientation": 0, "angular_velocity": 0, "angular_momentum": 0, "tf": 0, "clock": 100},
}


@pytest.fixture
def busy():
    """Two processes that each keep a core busy, for as long as the test runs."""
    loops = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    yield
    for loop in loops:
        loop.kill()
        loop.wait()


def _start(launch_node_module, directory: Path, scene: Path, name: str):
    bag = directory / f"{name}.mcap"
    node = launch_node_module("--ros-args", "-p", f"scene:={scene}", "-p", f"record_path:={bag}", name=name)
    wait_until_recorded(bag, "/rigid_rot_sim/state", 2, node)
    return node, bag


@pytest.fixture(scope="module")
def torque_node(tmp_path_factory, launch_node_module):
    directory = tmp_path_factory.mktemp("intake")
    return _start(launch_node_module, directory, ROOT / "config" / "scenes" / "torque_driven.yaml", "torque")


@pytest.fixture(scope="module")
def wheel_node(tmp_path_factory, launch_node_module):
    directory = tmp_path_factory.mktemp("wheel_intake")
    scene = directory / "scene.yaml"
    scene.write_text(yaml.safe_dump(WHEEL_SCENE, sort_keys=False))
    return _start(launch_node_module, directory, scene, "wheels")


def _publish(ros_node, process, msg_type, topic: str, make, rate: float) -> None:
    """``COUNT`` messages ``make(i)`` at ``rate`` per second (catching up when late), reliable.

    The publisher keeps all ``COUNT`` in its history: on a loaded machine a keep-last-10 writer may
    overwrite a command before DDS delivered it, which is the publisher's loss, not the node's (the node
    reports such a gap as lost too, see intake.py). Here DDS delivers every command; the node must take them.
    """
    publisher = ros_node.create_publisher(msg_type, topic, COUNT)
    deadline = time.monotonic() + WAIT
    while publisher.get_subscription_count() == 0:
        process.check_alive()
        assert time.monotonic() < deadline, f"the node never subscribed to {topic}"
        time.sleep(0.05)
    time.sleep(0.2)  # matched both ways
    start = time.monotonic()
    for i in range(COUNT):
        publisher.publish(make(i))
        pause = start + (i + 1) / rate - time.monotonic()
        if pause > 0:
            time.sleep(pause)
    from rclpy.duration import Duration

    publisher.wait_for_all_acked(Duration(seconds=10.0))
    ros_node.destroy_publisher(publisher)


#: Bursts published so far per topic (the tests of a topic share one node and its recording).
BURSTS: dict[str, int] = {}


def _marker(rate: float, loaded: bool) -> float:
    return rate + (0.5 if loaded else 0.0)


def _is(value: float, marker: float) -> bool:
    return abs(value * 1e9 - marker) < 1e-3


def _check(bag: Path, topic: str, marker: float, values, accepted_kind: str, accepted_values, process) -> None:
    """In the recording: every command of the burst taken, the valid accepted, the invalid rejected, none lost."""
    BURSTS[topic] = BURSTS.get(topic, 0) + 1
    sent, invalid = BURSTS[topic] * COUNT, BURSTS[topic] * COUNT // 2  # by this node so far
    deadline = time.monotonic() + WAIT
    while True:  # the counts first (cheap): every command taken, every invalid one reported
        counts = recorded_counts(bag)
        if counts.get(topic, 0) >= sent and counts.get(REJECTED, 0) >= invalid:
            break
        process.check_alive()
        if time.monotonic() > deadline:
            said = [r.reason for _, r in BagReader(bag).decoded([REJECTED]) if r.reason.startswith("lost")]
            raise AssertionError(
                f"{topic} at marker {marker}: {counts.get(topic, 0)} of {sent} taken, "
                f"{counts.get(REJECTED, 0)} of {invalid} rejected so far; the node said: {said}"
            )
        time.sleep(0.25)
    received = [msg for _, msg in BagReader(bag).decoded([topic]) if _is(values(msg)[1], marker)]
    rejected = [msg for _, msg in BagReader(bag).decoded([REJECTED]) if msg.source == topic]
    lost = [r.reason for r in rejected if r.reason.startswith("lost")]
    assert not lost, f"the node reported lost commands: {lost}"
    valid = [float(i) for i in range(0, COUNT, 2)]
    assert len(received) == COUNT  # every command the publisher sent was taken
    assert sorted(round(values(msg)[0] * 1e9) for msg in received if math.isfinite(values(msg)[0])) == valid
    assert len(rejected) == BURSTS[topic] * COUNT // 2  # every invalid one reported, nothing else
    events = [decode_event(e) for _, e in BagReader(bag).decoded([EVENTS])]
    accepted = [e for e in events if e.kind == accepted_kind and _is(accepted_values(e)[1], marker)]
    assert sorted(round(accepted_values(e)[0] * 1e9) for e in accepted) == valid


def recorded_counts(bag: Path) -> dict[str, int]:
    """Messages per topic in the recording while it is written (its flushed part)."""
    try:
        return dict(BagReader(bag).counts())
    except Exception:
        return {}


def _torque(marker: float):
    from geometry_msgs.msg import WrenchStamped

    def make(i: int) -> WrenchStamped:
        msg = WrenchStamped()
        msg.header.frame_id = "base_link"
        # valid: a tiny torque numbered i in x (1e-9 N*m steps); invalid: NaN; the burst's marker in y
        msg.wrench.torque.x = float(i) * 1e-9 if i % 2 == 0 else math.nan
        msg.wrench.torque.y = marker * 1e-9
        return msg

    return make


def _wheels(marker: float):
    from rigid_rot_msgs.msg import WheelTorques

    def make(i: int) -> WheelTorques:
        msg = WheelTorques()
        msg.torques = [float(i) * 1e-9 if i % 2 == 0 else math.nan, marker * 1e-9, 0.0]
        return msg

    return make


def _torque_values(msg):
    return msg.wrench.torque.x, msg.wrench.torque.y


def _torque_event_values(event):
    return event.vector("torque")[:2]


def _wheel_values(msg):
    return msg.torques[0], msg.torques[1]


def _wheel_event_values(event):
    return event.vector("torques")[:2]


@pytest.mark.parametrize("loaded", [False, True], ids=["idle", "two-busy-processes"])
@pytest.mark.parametrize("rate", RATES, ids=[f"{r:g}/s" for r in RATES])
def test_every_torque_command_is_taken(torque_node, ros_node_module, rate, loaded, request):
    from geometry_msgs.msg import WrenchStamped

    if loaded:
        request.getfixturevalue("busy")
    process, bag = torque_node
    marker = _marker(rate, loaded)
    _publish(ros_node_module, process, WrenchStamped, TORQUE_TOPIC, _torque(marker), rate)
    _check(bag, TORQUE_TOPIC, marker, _torque_values, "torque", _torque_event_values, process)


@pytest.mark.parametrize(("rate", "loaded"), [(200.0, True), (1000.0, False), (1000.0, True)])
def test_every_wheel_command_is_taken(wheel_node, ros_node_module, rate, loaded, request):
    from rigid_rot_msgs.msg import WheelTorques

    if loaded:
        request.getfixturevalue("busy")
    process, bag = wheel_node
    marker = _marker(rate, loaded)
    _publish(ros_node_module, process, WheelTorques, WHEEL_TOPIC, _wheels(marker), rate)
    _check(bag, WHEEL_TOPIC, marker, _wheel_values, "wheel_torque", _wheel_event_values, process)
