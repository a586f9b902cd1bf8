"""End to end over DDS: the doors a ROS stack knocks on (issue 30), from this process against the node.

* ros2_control's topic hardware interface (``joint_state_topic_hardware_interface/JointStateTopicSystem``)
  is played by a client that does what it does: effort-only ``sensor_msgs/JointState`` commands on a
  ``QoS(1)`` publisher, sent once and never repeated (its changed-value threshold suppresses repeats),
  states read with ``SensorDataQoS``. A wheel on a principal axis, body at rest, under a constant motor
  torque u: speed and angle follow the closed form ``Omega = a t'``, ``theta = a t'^2 / 2`` with
  ``a = u I3 / (J (I3 - J))`` (t' since the command acted), so ``theta = Omega^2 / (2 a)`` at every state
  and ``dOmega/dt = a`` between states, for seconds after the only command; the angle is continuous
  (never wrapped). Each malformed command is rejected on ``~/rejected`` with its reason.
* A generic simulation_interfaces client finds the services and the action at root names
  (``simulation_interfaces_namespace: /``): features listing exactly what is served, state,
  step, reset, SimulateSteps with feedback (bounded rate, the last always sent); /clock while paused;
  ``~/sim_events`` live and latched.

Assertions are on what the node guarantees (closed forms on each message received, reasons, upper
bounds on feedback), never on how many volatile messages this process happened to receive.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import pytest
import yaml

from rigid_rot_sim.message_fields import time_to_seconds
from rigid_rot_sim.recording.events import decode_event
from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.recording.resim import resimulate

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_simulate_steps_e2e import _reply

MOMENTS = (10.0, 12.0, 15.0)
SPIN = 0.01  # kg*m^2
U = 0.05  # N*m
A = U * MOMENTS[2] / (SPIN * (MOMENTS[2] - SPIN))  # rad/s^2, about 5
COMMANDS, STATES = "/rw_joint_commands", "/rw_joint_states"
SCENE = {
    "name": "ros_doors_e2e",
    "body": {"principal_moments": list(MOMENTS)},
    "actuators": {
        "reaction_wheels": [
            {"name": "rw_x", "axis": [1, 0, 0], "inertia": SPIN, "max_torque": 0.1, "max_speed": 5000.0},
            {"name": "rw_z", "axis": [0, 0, 1], "inertia": SPIN, "max_torque": 0.1, "max_speed": 5000.0},
        ]
    },
    "joint_state_topics": {"commands": COMMANDS, "states": STATES},
    "integrator": {"method": "gyrostat_rk4", "dt": 0.001},
    "real_time_factor": 2.0,
    "outputs": {"state": 50, "wheels": 50, "clock": 50, "tf": 0, "orientation": 0, "angular_velocity": 0},
}


def scene_file(tmp_path: Path, **changes) -> Path:
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump({**SCENE, **changes}, sort_keys=False))
    return path


def joint_command(names, effort=(), velocity=(), position=()):
    from sensor_msgs.msg import JointState

    msg = JointState()
    msg.name = list(names)
    msg.effort = [float(v) for v in effort]
    msg.velocity = [float(v) for v in velocity]
    msg.position = [float(v) for v in position]
    return msg


def test_a_topic_hardware_interface_client_spins_a_wheel_by_one_held_effort_command(tmp_path, launch_node, collector):
    from rclpy.qos import QoSProfile, qos_profile_sensor_data
    from sensor_msgs.msg import JointState

    from rigid_rot_msgs.msg import RejectedCommand
    from rigid_rot_sim.ros.qos import REJECTED_QOS

    bag = tmp_path / "doors.mcap"
    node = launch_node("--ros-args", "-p", f"scene:={scene_file(tmp_path)}", "-p", f"record_path:={bag}", name="doors")
    states = collector.subscribe(JointState, STATES, qos_profile_sensor_data)  # as the interface reads them
    rejected = collector.subscribe(RejectedCommand, "/rigid_rot_sim/rejected", REJECTED_QOS)
    publisher = collector.node.create_publisher(JointState, COMMANDS, QoSProfile(depth=1))  # rclcpp::QoS(1)
    collector.spin_until(lambda: publisher.get_subscription_count() > 0, 60.0, node, "the commands subscription")
    collector.spin_until(lambda: len(states) >= 2, 60.0, node, "the states")
    first = states[-1]
    assert list(first.name) == ["rw_x", "rw_z"] and list(first.position) == [0.0, 0.0]

    publisher.publish(joint_command(["rw_z"], effort=[U]))  # once; never repeated
    sent = time.monotonic()
    collector.spin_until(lambda: states[-1].velocity[1] > 0.0, 30.0, node, "the wheel to move")
    moving = len(states) - 1
    collector.spin_until(lambda: time.monotonic() - sent > 4.0, 30.0, node, "4 s of wall time")
    driven = [s for s in states[moving:] if s.velocity[1] > 0.0]
    assert len(driven) >= 2
    for s in driven:  # theta = Omega^2 / (2 a): speed and angle of the same closed form, at each state
        assert list(s.effort) == [0.0, U]  # the command holds, seconds after it was sent once
        assert s.position[1] == pytest.approx(s.velocity[1] ** 2 / (2 * A), rel=1e-9)
        assert s.position[0] == 0.0 and s.velocity[0] == 0.0
    a, b = driven[0], driven[-1]
    t_a, t_b = time_to_seconds(a.header.stamp), time_to_seconds(b.header.stamp)
    assert t_b - t_a > 2.0  # seconds of sim time (rtf 2) under the one command
    assert (b.velocity[1] - a.velocity[1]) / (t_b - t_a) == pytest.approx(A, rel=1e-9)
    assert b.position[1] > 2 * math.pi  # more than a turn: unwrapped, continuous
    assert all(x.position[1] <= y.position[1] for x, y in zip(driven, driven[1:], strict=False))

    malformed = [
        (joint_command(["rw_z"], velocity=[3.0]), "velocity only"),
        (joint_command(["rw_q"], effort=[0.01]), "unknown joint 'rw_q'"),
        (joint_command(["rw_x", "rw_z"], effort=[0.01]), "mismatched array lengths"),
        (joint_command(["rw_z"], effort=[math.nan]), "non-finite effort"),
    ]
    for msg, reason in malformed:  # one at a time: the publisher keeps only the last (depth 1)
        count = len(rejected)
        publisher.publish(msg)
        collector.spin_until(lambda count=count: len(rejected) > count, 30.0, node, f"rejection: {reason}")
        assert reason in rejected[-1].reason and rejected[-1].source == COMMANDS
    count = len(states)
    collector.spin_until(lambda: len(states) > count + 2, 30.0, node, "more states")
    assert list(states[-1].effort) == [0.0, U]  # nothing of a rejected command acted
    assert "JointState door for ros2_control" in node.log()

    # the run, the door's command included, re-simulates bit for bit from its recording
    assert node.stop() == 0, node.log()
    report = resimulate(bag)
    assert report.identical and report.wheel_states > 0 and report.digest_verdict == "equal", report.format()
    events = [decode_event(e) for _, e in BagReader(bag).decoded(["/rigid_rot_sim/sim_events"])]
    door = [e for e in events if e.kind == "wheel_torque"]
    assert len(door) == 1 and door[0].values["source"] == COMMANDS and door[0].vector("torques", 2) == (0.0, U)


def test_a_generic_client_finds_the_standard_services_at_root_names(tmp_path, launch_node, collector):
    from diagnostic_msgs.msg import DiagnosticStatus
    from rclpy.action import ActionClient
    from rosgraph_msgs.msg import Clock
    from simulation_interfaces.action import SimulateSteps
    from simulation_interfaces.msg import Result, SimulationState, SimulatorFeatures
    from simulation_interfaces.srv import (
        GetSimulationState,
        GetSimulatorFeatures,
        ResetSimulation,
        SetSimulationState,
        StepSimulation,
    )

    from rigid_rot_sim.ros import sim_events
    from rigid_rot_sim.ros.qos import CLOCK_QOS
    from rigid_rot_sim.ros.simulation_services import FEATURE_INTERFACES

    path = scene_file(tmp_path, simulation_interfaces_namespace="/", real_time_factor=0.0)
    node = launch_node("--ros-args", "-p", f"scene:={path}", "-p", "start_paused:=true", name="root")

    def call(srv_type, name, request):
        return collector.call(srv_type, name, request, process=node, idempotent=True)

    # /clock while paused: the frozen time, again and again
    clocks = collector.subscribe(Clock, "/clock", CLOCK_QOS)
    collector.spin_until(lambda: len(clocks) >= 3, 30.0, node, "/clock while paused")
    assert {time_to_seconds(c.clock) for c in clocks} == {0.0}

    features = call(GetSimulatorFeatures, "/get_simulator_features", GetSimulatorFeatures.Request()).features
    listed = {name for name in FEATURE_INTERFACES if getattr(SimulatorFeatures, name) in features.features}
    assert len(listed) == len(features.features)  # every code listed is one this node knows

    # the graph learns a node's name and its services apart from answering a call: wait for both
    def node_services():
        if ("rigid_rot_sim", "/") not in collector.node.get_node_names_and_namespaces():
            return []
        return collector.node.get_service_names_and_types_by_node("rigid_rot_sim", "/")

    collector.spin_until(
        lambda: any(name == "/step_simulation" for name, _ in node_services()), 30.0, node, "the node's services"
    )
    services = node_services()
    served = {
        name
        for name, types in services
        if "/_action/" not in name and any(t.startswith("simulation_interfaces/") for t in types)
    }
    actions = {name.removesuffix("/_action/send_goal") for name, _ in services if name.endswith("/_action/send_goal")}
    # exactly what is served: each listed feature's interface at its root name, and no other
    assert {"/" + FEATURE_INTERFACES[name] for name in listed} == (served | actions) - {"/get_simulator_features"}
    assert "SIMULATION_RESET_TIME" not in listed and "STEP_SIMULATION_ACTION" in listed
    assert not any(name.startswith("/rigid_rot_sim/") for name in served)

    state = call(GetSimulationState, "/get_simulation_state", GetSimulationState.Request())
    assert state.state.state == SimulationState.STATE_PAUSED
    for world_state in (4, 5):  # STATE_NO_WORLD, STATE_LOADING_WORLD: never targets of SetSimulationState
        request = SetSimulationState.Request(state=SimulationState(state=world_state))
        refused = call(SetSimulationState, "/set_simulation_state", request).result
        assert refused.result == SetSimulationState.Response.INCORRECT_TRANSITION
        assert "LoadWorld" in refused.error_message
    assert call(StepSimulation, "/step_simulation", StepSimulation.Request(steps=10)).result.result == Result.RESULT_OK
    collector.spin_until(lambda: time_to_seconds(clocks[-1].clock) > 0.0, 30.0, node, "/clock after the steps")

    reset = call(ResetSimulation, "/reset_simulation", ResetSimulation.Request(scope=0)).result
    assert reset.result == Result.RESULT_OK
    # ~/sim_events: live, and latched (a subscriber that joins after the reset still gets it)
    events = collector.subscribe(DiagnosticStatus, "/rigid_rot_sim/sim_events", sim_events.QOS)
    collector.spin_until(lambda: any(e.name == "rigid_rot_sim/reset" for e in events), 30.0, node, "the reset event")

    state = call(GetSimulationState, "/get_simulation_state", GetSimulationState.Request())
    assert state.state.state in (SimulationState.STATE_PAUSED, SimulationState.STATE_STOPPED)

    # SimulateSteps at /simulate_steps: feedback at most 50 Hz of wall time, the last step's always
    client = ActionClient(collector.node, SimulateSteps, "/simulate_steps")
    collector.spin_until(lambda: client.server_is_ready(), 60.0, node, "the action server")
    warm = _reply(collector, lambda: client.send_goal_async(SimulateSteps.Goal(steps=1)), node, "a first goal")
    assert warm.accepted
    _reply(collector, warm.get_result_async, node, "the first goal's result")
    feedback = []
    steps = 20_000
    began = time.monotonic()
    sending = client.send_goal_async(SimulateSteps.Goal(steps=steps), feedback_callback=feedback.append)
    collector.spin_until(lambda: sending.done(), 60.0, node, "the goal's acceptance")
    goal = sending.result()
    assert goal.accepted
    done = _reply(collector, goal.get_result_async, node, "the goal's result", timeout=120.0)
    elapsed = time.monotonic() - began
    assert done.result.result.result == Result.RESULT_OK
    collector.spin_until(
        lambda: feedback and feedback[-1].feedback.remaining_steps == 0, 30.0, node, "the last feedback"
    )
    completed = [f.feedback.completed_steps for f in feedback]
    assert completed[-1] == steps and completed == sorted(set(completed))
    assert len(completed) <= 50 * elapsed + 2  # bounded: not one per step
    client.destroy()


def test_the_commands_topic_answers_lockstep_turns(tmp_path, launch_node, collector):
    """``lockstep.inputs: [/rw_joint_commands]``: each turn waits for one JointState stamped with its time."""
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState
    from std_srvs.srv import SetBool

    from rigid_rot_msgs.msg import RigidBodyState

    namespace, duration = "/doors_lockstep", 0.2
    lockstep = {"period": 0.01, "inputs": [COMMANDS], "timeout": 60.0, "on_timeout": "pause"}
    path = scene_file(tmp_path, lockstep=lockstep, real_time_factor=0.0, duration=duration)
    bag = tmp_path / "lockstep.mcap"
    args = ["-r", f"__ns:={namespace}", "-p", f"scene:={path}", "-p", "start_paused:=true"]
    node = launch_node("--ros-args", *args, "-p", f"record_path:={bag}", name="lockstep")
    publisher = collector.node.create_publisher(JointState, COMMANDS, QoSProfile(depth=10))
    answered = []

    def answer(state):  # the controller: one command per turn, stamped with the turn's state
        command = joint_command(["rw_z"], effort=[U if len(answered) % 2 == 0 else -U])
        command.header.stamp = state.header.stamp
        publisher.publish(command)
        answered.append(time_to_seconds(state.header.stamp))

    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    collector.node.create_subscription(RigidBodyState, f"{namespace}/rigid_rot_sim/state", answer, qos)
    collector.spin_until(
        lambda: (
            publisher.get_subscription_count() > 0
            and collector.node.count_publishers(f"{namespace}/rigid_rot_sim/state") > 0
        ),
        60.0,
        node,
        "the loop's graph",
    )
    reply = collector.call(SetBool, f"{namespace}/rigid_rot_sim/pause", SetBool.Request(data=False), process=node)
    assert reply.success, reply.message
    collector.spin_until(lambda: not node.alive(), 120.0, None, "the run to reach its duration")
    assert node.process.returncode == 0, node.log()
    assert "LOCKSTEP on" in node.log() and f"waits for {COMMANDS}" in node.log()
    events = [decode_event(e) for _, e in BagReader(bag).decoded([f"{namespace}/rigid_rot_sim/sim_events"])]
    turns = [e for e in events if e.kind == "wheel_torque"]
    # every turn before the last answered by the door, at its own time (no timeout: the run never paused)
    assert len(turns) >= round(duration / 0.01) and not any(e.kind == "lockstep_timeout" for e in events)
    assert [e.number("effective_time") for e in turns] == answered[: len(turns)]
    assert resimulate(bag).identical
