"""Tests for the Simulator's reports to its observers (rigid_rot_sim.core.observer)."""

import math

import numpy as np
import pytest

from rigid_rot_sim.core.observer import SimulationObserver
from rigid_rot_sim.core.scene import parse_scene_text
from rigid_rot_sim.core.simulator import APPLY_TORQUE_SOURCE, CommandRejected, Simulator

DRIVEN = """
body: {principal_moments: [2.0, 3.0, 4.0]}
frames: {world: world, body: body}
torque_inputs:
  - {topic: hold_in, frame: body}
  - {topic: timeout_in, frame: header, hold: {timeout: 0.05}}
  - {topic: world_in, type: Vector3Stamped, frame: world}
integrator: {method: rk4, dt: 0.01}
"""


def driven(**kwargs) -> Simulator:
    return Simulator(parse_scene_text(DRIVEN, "driven.yaml"), **kwargs)


class Recording(SimulationObserver):
    """Keeps every call as (name, arguments...)."""

    def __init__(self) -> None:
        self.calls: list[tuple] = []

    def command_accepted(self, step, command):
        self.calls.append(("command_accepted", step, command))

    def command_rejected(self, step, source, reason, frame_id, torque):
        self.calls.append(("command_rejected", step, source, reason, frame_id, torque))

    def torque_applied(self, step, command):
        self.calls.append(("torque_applied", step, command))

    def state_set(self, step, orientation, angular_velocity):
        self.calls.append(("state_set", step, orientation, angular_velocity))

    def reset(self, step):
        self.calls.append(("reset", step))

    def integrator_changed(self, step, method, dt, options):
        self.calls.append(("integrator_changed", step, method, dt, options))

    def failed(self, step, reason):
        self.calls.append(("failed", step, reason))

    def outputs_due(self, step, snapshot, names):
        self.calls.append(("outputs_due", step, snapshot, names))

    def names(self) -> list[str]:
        return [call[0] for call in self.calls]


def exercise(sim: Simulator) -> None:
    """Every kind of outside change, at distinct steps."""
    sim.advance(3)
    sim.receive_torque("hold_in", [0.0, 0.0, 0.2])
    sim.advance(2)
    sim.receive_torque("timeout_in", [0.1, 0.0, 0.0], "world", stamp=sim.t + 0.034)
    sim.submit_torque("world_in", [0.0, 0.3, 0.0], "world", sim.t + 0.02)
    sim.advance(4)
    sim.apply_torque([0.0, 0.0, 1.0], "body", 0.05)
    sim.advance(5)
    sim.set_integrator("rk4", 0.005)
    sim.advance(7)
    sim.set_state([0.0, 0.0, 0.6, 0.8], [0.1, 0.2, 0.3])
    sim.advance(6)
    sim.set_integrator("dop853", None, {"rtol": 1e-10, "atol": 1e-12})
    sim.advance(3)
    sim.reset()
    sim.advance(2)


def test_each_outside_change_is_reported_once_with_the_step_before_it():
    sim = driven()
    observer = Recording()
    sim.add_observer(observer)
    assert sim.observers == [observer]
    exercise(sim)
    assert observer.names() == [
        "command_accepted", "command_accepted", "command_accepted", "torque_applied",
        "integrator_changed", "state_set", "integrator_changed", "reset",
    ]
    held, stamped, submitted, applied, finer, state, dop853, reset = observer.calls
    assert held[1] == 3 and held[2].source == "hold_in" and held[2].torque == (0.0, 0.0, 0.2)
    assert held[2].frame == "body" and held[2].receipt_time == held[2].effective_time == 3 * 0.01 and held[2].stamp is None
    assert stamped[1] == 5 and stamped[2].frame == "world" and stamped[2].stamp == stamped[2].effective_time
    assert stamped[2].step == 9 and stamped[2].receipt_time == 5 * 0.01  # 0.034 s ahead: the 4th boundary after
    assert submitted[1] == 5 and submitted[2].receipt_time is None and submitted[2].effective_time == 5 * 0.01 + 0.02
    assert applied[1] == 9 and applied[2].source == APPLY_TORQUE_SOURCE and applied[2].duration == 0.05
    assert applied[2].torque == (0.0, 0.0, 1.0) and applied[2].effective_time == 9 * 0.01
    assert finer[1:] == (14, "rk4", 0.005, {})
    assert state[1:] == (21, (0.0, 0.0, 0.6, 0.8), (0.1, 0.2, 0.3))
    assert dop853[1:] == (27, "dop853", 0.005, {"rtol": 1e-10, "atol": 1e-12})
    assert reset == ("reset", 30)


def test_the_reports_re_simulate_the_run_bit_for_bit():
    """What an observer is told is enough to replay the run (resim's contract)."""
    sim = driven()
    observer = Recording()
    sim.add_observer(observer)
    exercise(sim)
    sim.advance(40)
    replay = driven()
    for name, step, *args in observer.calls:
        replay.advance_to(step)
        if name == "command_accepted":
            (command,) = args
            replay.submit_torque(command.source, command.torque, command.frame, command.effective_time,
                                 receipt_time=command.receipt_time, stamp=command.stamp)
        elif name == "torque_applied":
            (command,) = args
            replay.apply_torque(command.torque, command.frame, command.duration, effective_time=command.effective_time)
        elif name == "state_set":
            replay.set_state(*args)
        elif name == "reset":
            replay.reset()
        elif name == "integrator_changed":
            method, dt, options = args
            replay.set_integrator(method, dt, options)
    replay.advance_to(sim.step_index)
    a, b = sim.snapshot(), replay.snapshot()
    assert a.t == b.t and a.step == b.step
    for field in ("orientation", "angular_velocity_body", "torque_body"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field


@pytest.mark.parametrize(
    "source,torque,frame_id,force,reason",
    [
        ("hold_in", [0.0, math.nan, 0.0], "", None, "non-finite torque.y = nan"),
        ("hold_in", [0.0, 0.0, 1.0], "map", None, "frame 'map' is neither"),
        ("timeout_in", [0.0, 0.0, 1.0], "", None, "empty header.frame_id"),
        ("hold_in", [0.0, 0.0, 1.0], "body", [0.0, 1.0, 0.0], "non-zero force"),
        ("hold_in", [0.0, 0.0, 1.0], "", None, "ahead of sim time"),
    ],
)
def test_a_rejected_command_is_reported_then_raised(source, torque, frame_id, force, reason):
    sim = driven()
    sim.advance(2)
    observer = Recording()
    sim.add_observer(observer)
    stamp = 1.7e9 if reason == "ahead of sim time" else None
    with pytest.raises(CommandRejected) as info:
        sim.receive_torque(source, torque, frame_id, stamp=stamp, force=force)
    assert len(observer.calls) == 1
    name, step, got_source, got_reason, got_frame_id, got_torque = observer.calls[0]
    assert (name, step, got_source, got_frame_id) == ("command_rejected", 2, source, frame_id)
    assert got_reason == info.value.reason and reason in got_reason
    assert got_torque is torque  # as given, possibly not finite


@pytest.mark.parametrize(
    "torque,frame_id,duration,reason",
    [
        ([0, 0, math.inf], "", 1.0, "non-finite torque.z"),
        ([0, 0, 1], "map", 1.0, "neither the body frame"),
        ([0, 0, 1], "", 0.0, "duration must be finite and > 0"),
    ],
)
def test_a_rejected_apply_torque_is_reported_then_raised(torque, frame_id, duration, reason):
    sim = driven()
    observer = Recording()
    sim.add_observer(observer)
    with pytest.raises(CommandRejected, match=reason):
        sim.apply_torque(torque, frame_id, duration)
    assert [call[:3] for call in observer.calls] == [("command_rejected", 0, APPLY_TORQUE_SOURCE)]
    assert observer.calls[0][4:] == (frame_id, torque) and reason in observer.calls[0][3]


def test_refused_calls_that_are_not_commands_report_nothing():
    sim = driven()
    observer = Recording()
    sim.add_observer(observer)
    with pytest.raises(ValueError, match="not a torque input"):
        sim.receive_torque("nowhere", [0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="orientation"):
        sim.set_state([0, 0, 0, 0], [0, 0, 0])
    with pytest.raises(ValueError):
        sim.set_integrator("no_such_method")
    sim.check_integrator("rk4", 0.02)
    assert observer.calls == []


def test_a_failure_is_reported_at_the_last_good_step():
    sim = driven(method="euler")
    observer = Recording()
    sim.add_observer(observer)
    sim.set_state([0, 0, 0, 1], [50.0, 50.0, 50.0])  # euler at |omega| dt ~ 1: grows without bound
    sim.advance(10_000)
    assert sim.failure is not None
    assert observer.names() == ["state_set", "failed"]
    assert observer.calls[1][1:] == (sim.step_index, sim.failure)


def test_observers_change_nothing_and_hear_in_the_order_added():
    plain = driven()
    observed = driven()
    first, second = Recording(), Recording()
    observed.add_observer(first)
    observed.add_observer(second)
    observed.add_observer(SimulationObserver())  # the base class: every report a no-op
    exercise(plain)
    exercise(observed)
    plain.advance(25)
    observed.advance(25)
    a, b = plain.snapshot(), observed.snapshot()
    assert a.t == b.t and a.kinetic_energy == b.kinetic_energy
    for field in ("orientation", "angular_velocity_body", "angular_momentum_world", "torque_body"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
    assert first.names() == second.names() and len(first.calls) == 8
    assert plain.observers == []
