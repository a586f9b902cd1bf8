"""Quick, bounded fuzz cases (issue 9): the classes of the long campaign
(benchmarks/fuzz_node.py), a few hundred each, from fixed seeds."""

import dataclasses
import math
import random
import time
import warnings

import numpy as np
import pytest
from generators import inertia_request, mutated_scene, number, parameter, set_state_request, step_count, torque_command

from rigid_rot_sim.core.inertia import mass_properties
from rigid_rot_sim.run.simulator import CommandRejected, Simulator
from rigid_rot_sim.scene.scene import SceneError, parse_scene_text

pytestmark = pytest.mark.slow


def snapshot_finite(snapshot) -> bool:
    for field in dataclasses.fields(snapshot):
        value = getattr(snapshot, field.name)
        if field.name == "wheel_names":
            continue
        if field.name == "torque_sources":  # (name, vector) pairs
            value = [vector for _, vector in value or ()] or None
        if value is not None and not np.all(np.isfinite(np.asarray(value, dtype=float))):
            return False
    return True


@pytest.mark.parametrize("seed", [9, 10])
def test_mutated_scenes_load_or_fail_with_one_line(seed):
    rng = random.Random(seed)
    outcomes = {"loaded": 0, "refused": 0}
    for case in range(100):
        text = mutated_scene(rng)
        start = time.process_time()  # CPU seconds of this process: a loaded machine does not count
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a leaked numpy RuntimeWarning is a failure
            try:
                scene = parse_scene_text(text, source=f"case{case}.yaml")
                sim = Simulator(dataclasses.replace(scene, integrator=dataclasses.replace(scene.integrator, dt=0.01)))
                sim.advance(20)
                assert snapshot_finite(sim.snapshot()), case
                outcomes["loaded"] += 1
            except (SceneError, ValueError) as exc:  # SceneError, or a scene the integrator refuses
                message = str(exc)
                assert "\n" not in message and len(message) <= 600, (case, message[:1000])
                outcomes["refused"] += 1
        assert time.process_time() - start < 5.0, f"case {case} took {time.process_time() - start:.1f} s of CPU"
    assert outcomes["refused"] > 0


DRIVEN = """
body: {principal_moments: [0.02, 0.03, 0.04]}
torque_inputs:
  - {topic: ~/torque, frame: header, hold: {timeout: 0.5}}
  - {topic: ~/world, frame: world}
integrator: {method: METHOD, dt: 0.001}
commands: {max_torque: MAX}
"""


@pytest.mark.parametrize("method, max_torque", [("rk4", 0), ("taylor", 0), ("exact_split", 100.0), ("dop853", 0)])
def test_random_commands_and_requests_keep_every_snapshot_finite(method, max_torque):
    rng = random.Random(hash(method) % 1000)
    sim = Simulator(parse_scene_text(DRIVEN.replace("METHOD", method).replace("MAX", str(max_torque))))
    start = time.monotonic()
    for _ in range(300):
        action = rng.random()
        try:
            if action < 0.5:
                command = torque_command(rng)
                sim.receive_torque(
                    rng.choice(["~/torque", "~/world"]),
                    command["torque"],
                    command["frame_id"],
                    command["stamp"],
                    command["force"],
                )
            elif action < 0.6:
                sim.apply_torque(
                    [number(rng) for _ in range(3)],
                    rng.choice(["", "base_link", "odom", "body", "world", "map"]),
                    rng.choice([0.01, 1.0, -1.0, math.inf, math.nan]),
                )
            elif action < 0.7:
                request = set_state_request(rng)
                sim.set_state(request["orientation"], request["angular_velocity"])
            elif action < 0.75:
                sim.reset()
            else:
                sim.pause(False)
                sim.advance(rng.choice([1, 5, 50]))
        except (CommandRejected, ValueError):
            pass
        assert snapshot_finite(sim.snapshot()), sim.failure
    assert time.monotonic() - start < 30.0


def test_random_inertia_requests_are_finite_or_refused():
    rng = random.Random(3)
    for _ in range(200):
        request = inertia_request(rng)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            try:
                props = mass_properties(request["masses"], request["positions"], request["origin"])
            except ValueError:
                continue
        for value in (
            props.total_mass,
            props.center_of_mass,
            props.inertia_origin,
            props.inertia_com,
            props.principal_moments,
            props.principal_axes,
        ):
            assert np.all(np.isfinite(value))


def test_node_survives_random_commands_requests_and_parameters(harness):
    from geometry_msgs.msg import Point, Vector3, WrenchStamped
    from rclpy.parameter import Parameter
    from std_srvs.srv import SetBool
    from test_node_hardening import finite_state

    from rigid_rot_msgs.msg import RigidBodyState
    from rigid_rot_msgs.srv import ComputeInertia, SetState, Step
    from rigid_rot_sim.ros.qos import COMMAND_QOS, STATE_QOS

    rng = random.Random(11)
    h = harness("torque_driven", real_time_factor=0.0, integrator="rk4", **{"commands.max_torque": 0.0})
    states = []
    h.client.create_subscription(RigidBodyState, "/rigid_rot_sim/state", states.append, STATE_QOS)
    publisher = h.client.create_publisher(WrenchStamped, "/rigid_rot_sim/torque", COMMAND_QOS)
    assert h.spin_until(lambda: publisher.get_subscription_count() > 0)
    for round_ in range(20):
        for _ in range(10):
            command = torque_command(rng)
            msg = WrenchStamped()
            msg.header.frame_id = command["frame_id"]
            msg.header.stamp.sec = int(command["stamp"])
            msg.wrench.torque = Vector3(x=command["torque"][0], y=command["torque"][1], z=command["torque"][2])
            msg.wrench.force = Vector3(x=command["force"][0], y=command["force"][1], z=command["force"][2])
            publisher.publish(msg)
        kind = round_ % 4
        if kind == 0:
            request = inertia_request(rng)
            call = ComputeInertia.Request(
                masses=[float(m) for m in request["masses"]],
                positions=[Point(x=p[0], y=p[1], z=p[2]) for p in request["positions"]],
                frame_id=request["frame_id"],
            )
            h.call(ComputeInertia, "compute_inertia", call)
        elif kind == 1:
            request = set_state_request(rng)
            call = SetState.Request(angular_velocity=Vector3(x=request["angular_velocity"][0]))
            call.orientation.x, call.orientation.y, call.orientation.z, call.orientation.w = request["orientation"]
            h.call(SetState, "set_state", call)
        elif kind == 2:
            h.call(SetBool, "pause", SetBool.Request(data=True))
            h.call(Step, "step", Step.Request(steps=step_count(rng)))
            h.call(SetBool, "pause", SetBool.Request(data=False))
        else:
            name, value = parameter(rng)
            try:
                h.node.set_parameters([Parameter(name, value=value)])
            except Exception as exc:  # rclpy refuses a wrong type by raising: the node is unaffected
                assert type(exc).__module__.startswith("rclpy"), repr(exc)
        h.spin_until(lambda: False, timeout=0.05)
    assert h.call(ComputeInertia, "compute_inertia", ComputeInertia.Request(masses=[1.0], positions=[Point()])).success
    assert states and all(finite_state(msg) for msg in states)
