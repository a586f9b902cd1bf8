"""Failures of the Simulator are recoverable and never leave a non-finite number (issue 9,
items 1, 3, 8 and 9): each test first reproduces what the issue reported."""

import dataclasses
import math
import time
from pathlib import Path

import numpy as np
import pytest

from rigid_rot_sim.core import limits
from rigid_rot_sim.run.simulator import CommandRejected, Simulator
from rigid_rot_sim.scene.scene import CommandSettings, load_scene, parse_scene_text

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"

DRIVEN = """
body: {principal_moments: [0.02, 0.03, 0.04]}
torque_inputs:
  - {topic: ~/torque, frame: header, hold: {timeout: 0.5}}
integrator: {method: METHOD, dt: 0.001}
"""


def driven(method: str = "taylor", max_torque: float = 0.0) -> Simulator:
    scene = parse_scene_text(DRIVEN.replace("METHOD", method))
    return Simulator(dataclasses.replace(scene, commands=CommandSettings(max_torque=max_torque)))


def all_finite(snapshot) -> bool:
    values = []
    for field in dataclasses.fields(snapshot):
        value = getattr(snapshot, field.name)
        if field.name == "torque_sources":  # (name, vector) pairs
            value = [vector for _, vector in value or ()]
        if value is not None and field.name != "wheel_names":
            values.extend(np.ravel(np.asarray(value, dtype=float)).tolist())
    return all(math.isfinite(v) for v in values)


@pytest.mark.parametrize("method", ["taylor", "rk4", "euler", "exact_split", "dop853"])
def test_huge_torque_stops_the_run_quickly_with_a_reason_and_reset_resumes_it(method):
    sim = driven(method)
    sim.apply_torque([1e12, 0.0, 0.0], "", 10.0)  # the largest torque accepted, far beyond the body
    start = time.monotonic()
    sim.advance(1000)
    assert time.monotonic() - start < 2.0  # taylor took 0.2 s per step at 1e6 N*m before
    assert sim.paused and sim.failure is not None and "rotation limit" in sim.failure, sim.failure
    assert all_finite(sim.snapshot())
    # item 1: reset answered success but the run stayed paused until ~/pause false
    sim.reset()
    assert sim.failure is None and not sim.paused and sim.clock.k == 0
    assert sim.advance(10) == 10


def test_a_pause_asked_for_survives_reset_and_set_state():
    sim = driven("rk4")
    sim.pause(True)
    sim.apply_torque([1e12, 0.0, 0.0], "", 10.0)
    sim.step(5)  # stepping while paused runs into the limit
    assert sim.failure is not None
    sim.reset()
    assert sim.failure is None and sim.paused  # paused by the user, not by the failure
    sim.pause(False)
    sim.apply_torque([1e12, 0.0, 0.0], "", 10.0)
    sim.advance(5)
    assert sim.failure is not None and sim.paused
    sim.set_state([0, 0, 0, 1], [0.1, 0.0, 0.0])
    assert sim.failure is None and not sim.paused


def test_huge_finite_angular_velocity_is_refused_by_set_state():
    sim = driven("rk4")
    before = sim.snapshot()
    # item 3: accepted before, then kinetic_energy = inf and energy_drift = nan were published
    with pytest.raises(ValueError, match="rad per step"):
        sim.set_state([0, 0, 0, 1], [1e200, 0.0, 0.0])
    assert np.array_equal(sim.snapshot().angular_velocity_body, before.angular_velocity_body)
    sim.set_state([0, 0, 0, 1], [9.0e4, 0.0, 0.0])  # 90 rad per step: within the limit
    assert all_finite(sim.snapshot())


def test_a_tiny_drift_reference_never_gives_an_infinite_drift():
    sim = driven("rk4")
    sim.set_state([0, 0, 0, 1], [1e-160, 0.0, 0.0])  # E_ref ~ 1e-322
    sim.receive_torque("~/torque", [0.0, 0.0, 1.0], "base_link")
    sim.advance(50)
    snapshot = sim.snapshot()
    assert snapshot.kinetic_energy > 0.0 and all_finite(snapshot)


def test_initial_angular_velocity_beyond_the_rotation_limit_is_refused():
    scene = parse_scene_text("body: {principal_moments: [1, 1, 1]}\ninitial: {angular_velocity: [1.0e+6, 0, 0]}\n")
    with pytest.raises(ValueError, match="initial angular velocity: .*limit 100 rad per step"):
        Simulator(scene)


def test_max_torque_rejects_commands_above_it_with_the_reason():
    sim = driven("taylor", max_torque=2.0)
    with pytest.raises(CommandRejected, match=r"\|torque\| = 1e\+06 N\*m exceeds max_torque = 2 N\*m"):
        sim.receive_torque("~/torque", [1e6, 0.0, 0.0], "base_link")
    with pytest.raises(CommandRejected, match="exceeds max_torque"):
        sim.apply_torque([0.0, 3.0, 0.0], "", 1.0)
    sim.receive_torque("~/torque", [1.0, 1.0, 1.0], "base_link")  # |tau| = 1.73 N*m
    assert sim.commands.held_torques() == {} and sim.advance(2) == 2 and sim.commands.held_torques()


def test_torque_components_beyond_the_magnitude_limit_are_rejected():
    sim = driven("rk4")
    for torque in ([1e30, 0.0, 0.0], [0.0, -1e300, 0.0]):
        with pytest.raises(CommandRejected, match="beyond the limit of 1e\\+12"):
            sim.receive_torque("~/torque", torque, "base_link")


def test_long_frame_ids_are_rejected_without_echoing_them():
    sim = driven("rk4")
    frame_id = "x" * 1_000_000
    with pytest.raises(CommandRejected) as info:
        sim.receive_torque("~/torque", [0.0, 0.0, 1.0], frame_id)
    assert "exceeds the limit of 256" in info.value.reason and len(info.value.reason) < 200


def test_shipped_torque_driven_scene_bounds_its_commands():
    scene = load_scene(SCENES / "torque_driven.yaml")
    assert scene.commands.max_torque > 0.0
    assert limits.MAX_TORQUE_RANGE[0] <= scene.commands.max_torque <= limits.MAX_TORQUE_RANGE[1]


def test_a_quaternion_of_huge_components_is_normalised_not_zeroed():
    # found by the fuzz tests: |q| overflowed to inf and q / |q| gave the zero quaternion
    sim = driven("rk4")
    sim.set_state([1e308, 1e308, 0.0, 0.0], [0.0, 0.0, 0.0])
    q = sim.snapshot().orientation
    assert all_finite(sim.snapshot()) and np.linalg.norm(q) == pytest.approx(1.0)
    assert abs(q[0]) == pytest.approx(math.sqrt(0.5)) and abs(q[1]) == pytest.approx(math.sqrt(0.5))


@pytest.mark.parametrize("torque", [5e-324, 1e-320, 1e-300])
def test_a_torque_whose_effect_underflows_is_stepped_normally(torque):
    # found by the fuzz campaign: ZeroDivisionError (then OverflowError) sizing the slice
    sim = driven("rk4")
    sim.receive_torque("~/torque", [torque, 0.0, 0.0], "base_link")
    assert sim.advance(300) == 300 and sim.failure is None


def test_an_unstable_method_never_leaves_a_state_whose_energy_overflows():
    # found by the fuzz campaign: euler grew |omega| to ~1e200 inside one slice, the next step
    # overflowed, and the last good state (finite omega, infinite kinetic energy) was kept
    sim = driven("euler")
    sim.set_state([0, 0, 0, 1], [0.0, 3.0e4, 3.0e4])  # 42 rad per step: allowed, violently unstable
    sim.advance(5000)
    assert sim.failure is not None and sim.paused
    assert all_finite(sim.snapshot()), sim.failure
