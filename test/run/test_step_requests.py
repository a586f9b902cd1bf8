"""rigid_rot_sim.run.step_requests: a torque over exactly the next N steps equals a topic command
taking effect now, followed by N steps, bit for bit (body and world frames, every boundary)."""

import numpy as np
import pytest

from rigid_rot_sim.run.simulator import CommandRejected, Simulator
from rigid_rot_sim.run.step_requests import torque_for_steps
from rigid_rot_sim.scene.scene import parse_scene_text

# A tumbling asymmetric body, so that a world-frame torque changes in the body frame at every step.
SCENE = """
body: {principal_moments: [0.020, 0.030, 0.040]}
frames: {world: odom, body: base_link}
initial: {orientation: [0.1, -0.2, 0.3, 0.9], angular_velocity: [0.4, -1.1, 2.3]}
torque_inputs:
  - {topic: torque, frame: header}
integrator: {method: rk4, dt: 0.001}
"""


def _bits(sim: Simulator) -> bytes:
    snap = sim.snapshot()
    return b"".join(
        np.asarray(a, dtype=float).tobytes()
        for a in ([snap.t], snap.orientation, snap.angular_velocity_body, snap.angular_momentum_world, snap.torque_body)
    )


def _paused(method: str = "rk4") -> Simulator:
    sim = Simulator(parse_scene_text(SCENE, "tumble.yaml"), method=method)
    sim.pause(True)
    return sim


@pytest.mark.parametrize("method", ["rk4", "splitting"])
@pytest.mark.parametrize("frame", ["base_link", "odom"])
def test_torque_for_steps_then_steps_equals_a_topic_command_then_steps_bit_for_bit(frame, method):
    torque = (0.003, -0.0071, 0.0123)
    topic, applied = _paused(method), _paused(method)
    for sim in (topic, applied):
        sim.step(37)  # start away from t = 0
    topic.receive_torque("torque", torque, frame)
    command = torque_for_steps(applied, torque, frame, 250)
    assert command.step == applied.clock.k
    for _ in range(5):  # compared at every 50th boundary, and the stepping split differently
        topic.step(50)
        applied.step(25)
        applied.step(25)
        assert _bits(applied) == _bits(topic)
    assert applied.snapshot().torque_body.tolist() == topic.snapshot().torque_body.tolist() != [0.0, 0.0, 0.0]


def test_the_torque_ends_on_the_boundary_after_the_last_step():
    sim = _paused()
    sim.step(1000)  # t = 1 s: t + N dt is not a multiple of dt in floating point
    torque_for_steps(sim, (0.0, 0.0, 0.004), "", 3)
    for _ in range(3):
        sim.step(1)
        assert sim.snapshot().torque_body.tolist() == [0.0, 0.0, 0.004]
    sim.step(1)
    assert sim.snapshot().torque_body.tolist() == [0.0, 0.0, 0.0]


def test_refused_requests_apply_nothing():
    sim = _paused()
    with pytest.raises(ValueError, match="steps must be an integer >= 1"):
        torque_for_steps(sim, (0.0, 0.0, 0.004), "", 0)
    with pytest.raises(CommandRejected, match="neither the body frame"):
        torque_for_steps(sim, (0.0, 0.0, 0.004), "map", 5)
    with pytest.raises(CommandRejected, match="non-finite"):
        torque_for_steps(sim, (float("nan"), 0.0, 0.0), "", 5)
    sim.step(5)
    assert sim.snapshot().torque_body.tolist() == [0.0, 0.0, 0.0]
