"""Spacecraft scenes through the run engine (no ROS): wheel commands, schedules, gravity gradient, determinism."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rigid_rot_sim.run.commands import CommandRejected
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import SceneError, load_scene, parse_scene_text

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"

SINGLE_WHEEL = """
body: {principal_moments: [10, 12, 15]}
initial: {angular_velocity: [0.0, 0.0, 0.2]}
actuators:
  reaction_wheels:
    - {name: rw_z, axis: [0, 0, 1], inertia: 0.5, max_torque: 0.1, max_speed: 1000, initial_speed: 10}
  wheel_torque_schedule: {segments: [{start: 0.0, torques: [0.05]}, {start: 5.0, torques: [0.0]}]}
integrator: {method: %s, dt: 0.01}
"""

SPACECRAFT = """
body: {inertia_tensor: [[120, 2, -1.5], [2, 95, 3], [-1.5, 3, 140]]}
initial: {angular_velocity: [0.001, -0.002, 0.0011]}
torque_inputs: [{topic: ~/torque}]
actuators:
  reaction_wheels:
    - {name: a, axis: [1, 0, 0], inertia: 0.159, max_torque: 0.2, max_speed: 628.3, initial_speed: 10.47,
       friction: {coulomb: 0.0005, viscous: 1.0e-6}}
    - {name: b, axis: [0, 1, 0], inertia: 0.159, max_torque: 0.2, max_speed: 628.3}
    - {name: c, axis: [0.577, 0.577, 0.577], inertia: 0.159, max_torque: 0.2, max_speed: 628.3, initial_speed: -5}
environment:
  gravity_gradient: {mu: 3.986004418e+14, orbit: {radius: 6778137.0, inclination: 0.9}}
integrator: {method: %s, dt: 0.05}
"""


class Heard(SimulationObserver):
    def __init__(self) -> None:
        self.accepted: list = []
        self.rejected: list = []

    def wheel_command_accepted(self, step, source, torques, effective_time, clamped):
        self.accepted.append((step, source, tuple(torques), effective_time, tuple(clamped)))

    def command_rejected(self, step, source, reason, frame_id, torque):
        self.rejected.append((source, reason))


@pytest.mark.parametrize("method", ["gyrostat_rk4", "dopri5", "auto"])
def test_a_wheel_schedule_turns_body_and_wheel_as_the_closed_form_says(method):
    sim = Simulator(parse_scene_text(SINGLE_WHEEL % method))
    sim.advance(1000)
    snap = sim.snapshot()
    # (I3 - J) dw/dt = -u, J (dw/dt + dOmega/dt) = u for 5 s, then nothing
    assert snap.angular_velocity_body[2] == pytest.approx(0.2 - 0.05 * 5.0 / 14.5, rel=1e-12)
    assert snap.wheel_speeds[0] == pytest.approx(10.0 + 0.05 * 15.0 / (0.5 * 14.5) * 5.0, rel=1e-12)
    # total momentum (body + wheel) conserved: I3 w0 + J Omega0
    assert snap.angular_momentum_world[2] == pytest.approx(15.0 * 0.2 + 0.5 * 10.0, rel=1e-12)
    assert snap.angular_momentum_drift == pytest.approx(0.0, abs=1e-12)


def test_wheel_commands_are_clamped_and_a_wrong_count_is_rejected_with_the_reason():
    sim = Simulator(parse_scene_text(SPACECRAFT % "gyrostat_rk4"))
    heard = Heard()
    sim.add_observer(heard)
    step, torques, clamped = sim.submit_wheel_torques("~/wheel_torque", [0.5, -0.1, -1.0])
    assert torques == (0.2, -0.1, -0.2) and clamped == (0, 2)
    assert heard.accepted == [(0, "~/wheel_torque", (0.2, -0.1, -0.2), 0.0, (0, 2))]
    with pytest.raises(CommandRejected, match="2 torque"):
        sim.submit_wheel_torques("~/wheel_torque", [0.1, 0.1])
    with pytest.raises(CommandRejected, match="non-finite"):
        sim.submit_wheel_torques("~/wheel_torque", [0.1, float("nan"), 0.0])
    assert len(heard.rejected) == 2 and "3 wheel(s)" in heard.rejected[0][1]
    sim.advance(10)
    np.testing.assert_allclose(sim.snapshot().wheel_torques, [0.2, -0.1, -0.2])


@pytest.mark.parametrize("method", ["gyrostat_rk4", "dopri5"])
def test_commands_and_chunking_give_the_same_bits(method):
    """Two runs fed the same commands (body torque, wheel torques) give the same bits, however they are stepped."""
    scene = parse_scene_text(SPACECRAFT % method)
    runs = []
    for chunks in ([400], [1, 2, 3, 150, 44, 200]):
        sim = Simulator(scene)
        sim.submit_wheel_torques("~/wheel_torque", [0.01, -0.02, 0.03], effective_time=2.0)
        sim.submit_torque("~/torque", [0.0, 1e-3, 0.0], "body", 7.5)
        sim.submit_wheel_torques("~/wheel_torque", [0.0, 0.05, -0.01], effective_time=12.34)
        for n in chunks:
            assert sim.advance(n) == n
        runs.append(sim.snapshot())
    a, b = runs
    assert a.t == b.t == 20.0
    for field in ("orientation", "angular_velocity_body", "wheel_speeds", "wheel_angles", "angular_momentum_world"):
        assert getattr(a, field).tobytes() == getattr(b, field).tobytes(), field
    names = [name for name, _ in a.torque_sources]
    assert names == ["~/torque", "reaction_wheels", "gravity_gradient"]
    np.testing.assert_allclose(np.sum([v for _, v in a.torque_sources], axis=0), a.torque_body)


def test_reset_restores_the_wheel_speeds_and_drops_wheel_commands():
    sim = Simulator(parse_scene_text(SPACECRAFT % "gyrostat_rk4"))
    first = sim.snapshot()
    sim.submit_wheel_torques("~/wheel_torque", [0.1, 0.1, 0.1])
    sim.advance(100)
    assert not np.array_equal(sim.snapshot().wheel_speeds, first.wheel_speeds)
    sim.reset()
    np.testing.assert_array_equal(sim.snapshot().wheel_speeds, first.wheel_speeds)
    np.testing.assert_array_equal(sim.snapshot().wheel_torques, [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(sim.snapshot().wheel_angles, [0.0, 0.0, 0.0])  # a reset zeroes the angles


def test_wheel_angles_integrate_the_speeds_and_survive_set_state_and_an_integrator_change():
    sim = Simulator(parse_scene_text(SINGLE_WHEEL % "gyrostat_rk4"))
    assert sim.snapshot().wheel_angles.tolist() == [0.0]
    sim.advance(1000)  # 10 s: 5 s at 0.05 N*m, then coasting
    a = 0.05 * 15.0 / (0.5 * 14.5)
    angle = 10.0 * 10.0 + 0.5 * a * 5.0**2 + a * 5.0 * 5.0
    assert sim.snapshot().wheel_angles[0] == pytest.approx(angle, rel=1e-12)
    before = sim.snapshot().wheel_angles.copy()
    sim.set_state([0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.1])  # the body's state: the wheels keep speed and angle
    np.testing.assert_array_equal(sim.snapshot().wheel_angles, before)
    sim.set_integrator("dopri5", 0.01, {})
    np.testing.assert_array_equal(sim.snapshot().wheel_angles, before)
    sim.advance(100)
    assert sim.snapshot().wheel_angles[0] > before[0]


def test_a_topic_wheel_command_holds_until_the_next_schedule_segment_replaces_it():
    """The rule (docs/spacecraft.md): the latest wheel command, from the topic, the JointState door or a
    schedule segment starting, sets every wheel torque it gives; a segment gives all of them at its start."""
    sim = Simulator(parse_scene_text(SINGLE_WHEEL % "gyrostat_rk4"))  # segments: 0.05 N*m from t = 0, 0 from t = 5 s
    sim.advance(100)
    assert sim.snapshot().wheel_torques.tolist() == [0.05]
    sim.submit_wheel_torques("~/wheel_torque", [-0.08])  # replaces the schedule's torque from now on
    sim.advance(1)
    assert sim.snapshot().wheel_torques.tolist() == [-0.08]
    sim.advance(398)  # t = 4.99 s: still the topic's
    assert sim.snapshot().wheel_torques.tolist() == [-0.08]
    sim.advance(2)  # t = 5.01 s: the segment that starts at 5 s replaced it
    assert sim.snapshot().wheel_torques.tolist() == [0.0]
    sim.submit_wheel_torques("~/wheel_torque", [0.03])  # after the last segment: holds for good
    sim.advance(1000)
    assert sim.snapshot().wheel_torques.tolist() == [0.03]


@pytest.mark.parametrize(
    "change, message",
    [
        (("torques: [0.05]", "torques: [0.05, 0.1]"), "2 values for 1 wheel"),
        (("method: gyrostat_rk4", "method: taylor"), "cannot run wheels"),
        (("inertia: 0.5", "inertia: 20.0"), "positive definite"),
        (("initial_speed: 10", "initial_speed: 2000"), "exceeds max_speed"),
        (
            (
                "body: {principal_moments: [10, 12, 15]}",
                "body: {principal_moments: [10, 12, 15]}\ngravity: {mass: 1.0, center_of_mass: [0, 0, 0.1]}",
            ),
            "heavy top",
        ),
    ],
)
def test_invalid_spacecraft_scenes_are_refused_with_the_key(change, message):
    with pytest.raises(SceneError, match=message):
        parse_scene_text((SINGLE_WHEEL % "gyrostat_rk4").replace(*change))


@pytest.mark.parametrize("name", ["wheel_slew", "gravity_gradient_satellite"])
def test_the_shipped_spacecraft_scenes_run(name):
    scene = load_scene(SCENES / f"{name}.yaml")
    sim = Simulator(scene)
    start = sim.snapshot()
    steps = round(scene.duration / sim.clock.dt)
    assert sim.advance(steps) == steps and sim.failure is None
    end = sim.snapshot()
    if name == "wheel_slew":
        # the slew turned the body about z and the total momentum (zero) stayed zero
        assert end.orientation[2] > 0.2
        assert np.linalg.norm(end.angular_momentum_world) < 1e-9
    else:
        assert abs(end.angular_momentum_drift) < 0.2  # a libration: bounded
        assert start.torque_sources[0][0] == "gravity_gradient"
