"""The JointState door's rule (run/joint_commands.py): which wheel efforts a sensor_msgs/JointState carries."""

from __future__ import annotations

import math

import pytest

from rigid_rot_sim.run.commands import CommandRejected
from rigid_rot_sim.run.joint_commands import effective_time, merged_torques, wheel_efforts
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import SceneError, parse_scene_text

WHEELS = ("rw_x", "rw_y", "rw_z")
SOURCE = "/rw_joint_commands"


def efforts(names, effort, position=(), velocity=()):
    return wheel_efforts(SOURCE, WHEELS, names, position, velocity, effort)


def test_any_subset_of_the_wheels_in_any_order():
    assert efforts(["rw_z", "rw_x"], [0.1, -0.2]) == {2: 0.1, 0: -0.2}
    assert efforts(["rw_y"], [0.05]) == {1: 0.05}
    # position and velocity beside effort are ignored (a joint may have more command interfaces)
    assert efforts(["rw_y"], [0.05], position=[math.nan], velocity=[1.0, 2.0]) == {1: 0.05}


@pytest.mark.parametrize(
    "names, effort, position, velocity, reason",
    [
        (["rw_x"], [], [], [1.0], "velocity only: this door takes the wheels' motor torques in effort"),
        (["rw_x"], [], [0.5], [], "position only"),
        (["rw_x"], [], [0.5], [1.0], "position and velocity only"),
        (["rw_x"], [], [], [], "no value"),
        ([], [], [], [], "names no joint"),
        (["rw_x", "rw_q"], [0.1, 0.1], [], [], "unknown joint 'rw_q' (the wheels: rw_x, rw_y, rw_z)"),
        (["rw_x", "rw_x"], [0.1, 0.1], [], [], "joint 'rw_x' is named twice"),
        (["rw_x", "rw_y"], [0.1], [], [], "mismatched array lengths: 2 name(s), 1 effort value(s)"),
        (["rw_x"], [math.nan], [], [], "non-finite effort for wheel 'rw_x': nan"),
        (["rw_x"], [math.inf], [], [], "non-finite effort"),
    ],
)
def test_a_malformed_command_is_rejected_whole_with_its_reason(names, effort, position, velocity, reason):
    with pytest.raises(CommandRejected) as raised:
        efforts(names, effort, position, velocity)
    assert reason in raised.value.reason
    assert raised.value.source == SOURCE


def test_a_scene_without_wheels_has_no_door():
    with pytest.raises(CommandRejected, match="no reaction wheels"):
        wheel_efforts(SOURCE, (), ["a"], (), (), [0.1])


def test_a_command_acts_at_its_stamp_on_receipt_or_is_refused_as_a_wall_clock_stamp():
    assert effective_time(SOURCE, 0.0, 5.0) is None  # no stamp: on receipt
    assert effective_time(SOURCE, 4.99, 5.0) is None  # in the past: on receipt
    assert effective_time(SOURCE, 5.5, 5.0) == 5.5
    with pytest.raises(CommandRejected, match="use_sim_time true"):
        effective_time(SOURCE, 1.7e9, 5.0)  # the interface's node on wall time


def test_the_named_wheels_change_the_others_keep_what_acts():
    assert merged_torques((0.1, 0.2, 0.3), {2: -0.5}) == [0.1, 0.2, -0.5]
    assert merged_torques((0.1, 0.2, 0.3), {}) == [0.1, 0.2, 0.3]


SCENE = """
body: {principal_moments: [10, 12, 15]}
actuators:
  reaction_wheels:
    - {name: rw_x, axis: [1, 0, 0], inertia: 0.5, max_torque: 0.1, max_speed: 1000}
    - {name: rw_z, axis: [0, 0, 1], inertia: 0.5, max_torque: 0.1, max_speed: 1000}
joint_state_topics: {commands: /rw_joint_commands, states: /rw_joint_states}
simulation_interfaces_namespace: /
lockstep: {period: 0.1, inputs: [/rw_joint_commands]}
integrator: {method: gyrostat_rk4, dt: 0.01}
"""


def test_the_scene_section_and_the_namespace_key():
    scene = parse_scene_text(SCENE)
    assert scene.joint_state_topics is not None
    assert (scene.joint_state_topics.commands, scene.joint_state_topics.states) == (
        "/rw_joint_commands",
        "/rw_joint_states",
    )
    assert scene.simulation_interfaces_namespace == "/"
    assert scene.lockstep is not None and scene.lockstep.inputs == ("/rw_joint_commands",)
    assert (
        parse_scene_text(SCENE.replace("simulation_interfaces_namespace: /", "")).simulation_interfaces_namespace == "~"
    )
    with pytest.raises(SceneError, match="no reaction wheels"):
        parse_scene_text("body: {principal_moments: [1, 2, 3]}\njoint_state_topics: {commands: /a, states: /b}\n")
    with pytest.raises(SceneError, match="states"):
        parse_scene_text(SCENE.replace(", states: /rw_joint_states", ""))


def test_a_held_command_acts_until_the_next_for_that_wheel():
    """No timeout: a command given once acts for as long as nothing replaces it."""
    sim = Simulator(parse_scene_text(SCENE.replace("lockstep: {period: 0.1, inputs: [/rw_joint_commands]}", "")))
    sim.submit_wheel_torques(SOURCE, merged_torques(sim.commands.wheel_torques, efforts_2(["rw_z"], [0.05])))
    sim.advance(10_000)  # 100 s
    snap = sim.snapshot()
    assert snap.wheel_torques.tolist() == [0.0, 0.05]
    assert snap.wheel_speeds[1] == pytest.approx(0.05 * 15.0 / (0.5 * 14.5) * 100.0, rel=1e-12)


def efforts_2(names, effort):
    return wheel_efforts(SOURCE, ("rw_x", "rw_z"), names, (), (), effort)
