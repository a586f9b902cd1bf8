"""End to end: reaction-wheel commands over DDS drive a spacecraft with gravity gradient; the run is recorded
(JointState, the torque breakdown, the wheel events) and re-simulates bit for bit.

What is checked comes from the recording (every message the node received and published is in it), so
the test does not depend on how many messages this process happened to receive.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from e2e_helpers import WAIT, wait_until_recorded  # beside this file

from rigid_rot_sim.message_fields import time_to_seconds
from rigid_rot_sim.recording.events import decode_event
from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.recording.resim import resimulate

WHEEL_TOPIC = "/rigid_rot_sim/wheel_torque"
MOMENTS = (10.0, 12.0, 15.0)
SPIN = 0.5  # kg*m^2, every wheel
OMEGA_Z0 = 0.05  # rad/s
SCENE = {
    "name": "wheels_e2e",
    "body": {"principal_moments": list(MOMENTS)},
    "initial": {"angular_velocity": [0.0, 0.0, OMEGA_Z0]},
    "actuators": {
        "reaction_wheels": [
            {"name": n, "axis": a, "inertia": SPIN, "max_torque": 0.2, "max_speed": 600.0}
            for n, a in (("rw_x", [1, 0, 0]), ("rw_y", [0, 1, 0]), ("rw_z", [0, 0, 1]))
        ]
    },
    "environment": {"gravity_gradient": {"mu": 3.986004418e14, "orbit": {"radius": 6778137.0, "inclination": 0.5}}},
    "integrator": {"method": "gyrostat_rk4", "dt": 0.01},
    "real_time_factor": 1.0,
    "outputs": {
        "state": 20,
        "orientation": 0,
        "angular_velocity": 0,
        "angular_momentum": 0,
        "tf": 0,
        "clock": 20,
        "wheels": 20,
        "torque_breakdown": 20,
    },
}


def publish_wheels(ros_node, process, bag: Path, torques_list) -> None:
    from rigid_rot_msgs.msg import WheelTorques

    publisher = ros_node.create_publisher(WheelTorques, WHEEL_TOPIC, 10)
    deadline = time.monotonic() + WAIT
    while publisher.get_subscription_count() == 0:
        process.check_alive()
        assert time.monotonic() < deadline, "the node never subscribed to ~/wheel_torque"
        time.sleep(0.05)
    for torques, pause in torques_list:
        msg = WheelTorques()
        msg.torques = [float(v) for v in torques]
        publisher.publish(msg)
        time.sleep(pause)
    wait_until_recorded(bag, WHEEL_TOPIC, len(torques_list), process)
    ros_node.destroy_publisher(publisher)


@pytest.fixture(scope="module")
def wheel_run(tmp_path_factory, launch_node_module, ros_node_module):
    directory = tmp_path_factory.mktemp("wheels")
    scene = directory / "scene.yaml"
    scene.write_text(yaml.safe_dump(SCENE, sort_keys=False))
    bag = directory / "run.mcap"
    node = launch_node_module("--ros-args", "-p", f"scene:={scene}", "-p", f"record_path:={bag}", name="wheels")
    wait_until_recorded(bag, "/rigid_rot_sim/state", 2, node)
    publish_wheels(
        ros_node_module,
        node,
        bag,
        [
            ([0.0, 0.0, 0.05], 1.0),  # spins rw_z up, the body down about z
            ([0.1], 0.2),  # rejected: one value for three wheels
            ([0.0, 0.0, 5.0], 1.0),  # clamped to rw_z's max_torque 0.2 N*m
        ],
    )
    wait_until_recorded(bag, "/rigid_rot_sim/sim_events", 2, node)
    log = node.log()
    assert node.stop() == 0, node.log()
    return bag, log


def messages(bag: Path, topic: str):
    return [decoded for message, decoded in BagReader(bag).decoded([topic])]


def test_the_node_lists_the_wheels_and_the_gravity_gradient_at_start_up(wheel_run):
    _, log = wheel_run
    assert "3 reaction wheel(s) [rw_x, rw_y, rw_z]" in log
    assert "gravity gradient (circular orbit" in log
    assert "clamped to its max_torque" in log  # said once


def test_wheel_commands_change_wheel_speed_and_body_rate_as_predicted(wheel_run):
    bag, _ = wheel_run
    events = [decode_event(e) for e in messages(bag, "/rigid_rot_sim/sim_events")]
    wheel_events = [e for e in events if e.kind == "wheel_torque"]
    assert [e.vector("torques") for e in wheel_events] == [(0.0, 0.0, 0.05), (0.0, 0.0, 0.2)]
    assert wheel_events[1].values["clamped"] == "[2]"
    t1, t2 = (e.number("effective_time") for e in wheel_events)
    states = messages(bag, "/rigid_rot_sim/state")
    joints = messages(bag, "/rigid_rot_sim/wheels")
    last = joints[-1]
    assert list(last.name) == ["rw_x", "rw_y", "rw_z"]
    t = time_to_seconds(last.header.stamp)
    state = next(s for s in states if time_to_seconds(s.header.stamp) == t)
    assert t > t2 > t1
    # single wheel on a principal axis: (I3 - J) dw/dt = -u, dOmega/dt = u I3 / (J (I3 - J)); the gravity
    # gradient adds ~1e-5 N*m, hence 1e-3 relative on the change
    impulse = 0.05 * (t2 - t1) + 0.2 * (t - t2)
    i3 = MOMENTS[2]
    assert state.angular_velocity_body.z - OMEGA_Z0 == pytest.approx(-impulse / (i3 - SPIN), rel=1e-3)
    assert last.velocity[2] == pytest.approx(impulse * i3 / (SPIN * (i3 - SPIN)), rel=1e-3)
    assert list(last.effort) == [0.0, 0.0, 0.2]
    rejected = messages(bag, "/rigid_rot_sim/rejected")
    assert any("1 torque(s) for 3 wheel(s)" in r.reason and r.source == WHEEL_TOPIC for r in rejected)


def test_the_torque_breakdown_is_published_and_sums_to_the_total(wheel_run):
    bag, _ = wheel_run
    breakdowns = messages(bag, "/rigid_rot_sim/torque_breakdown")
    assert breakdowns
    last = breakdowns[-1]
    assert list(last.names) == ["reaction_wheels", "gravity_gradient"]
    parts = np.array([[v.x, v.y, v.z] for v in last.torques])
    np.testing.assert_allclose(parts.sum(axis=0), [last.total.x, last.total.y, last.total.z], rtol=1e-12, atol=0)
    assert parts[0, 2] == pytest.approx(-0.2)  # the motor's reaction on the body
    assert 0.0 < np.linalg.norm(parts[1]) < 1e-3  # gravity gradient: small, not zero


def test_a_wheel_and_gravity_gradient_run_re_simulates_bit_exact(wheel_run):
    bag, _ = wheel_run
    report = resimulate(bag)
    assert report.events >= 2 and report.states > 10
    assert report.identical, report.format()
