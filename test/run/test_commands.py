"""Tests for rigid_rot_sim.run.commands: when a command, an applied torque or a schedule segment acts."""

import math

import pytest

from rigid_rot_sim.run.clock import StepClock
from rigid_rot_sim.run.commands import APPLY_TORQUE_SOURCE, STAMP_HORIZON, CommandRejected, CommandSchedule
from rigid_rot_sim.scene.scene import parse_scene_text

# three inputs: held for ever (body frame), held 0.05 s (frame from the header), world frame
SCENE = """
integrator: {method: rk4, dt: 0.01}
body: {principal_moments: [2.0, 3.0, 4.0]}
torque_inputs:
  - {topic: hold_in, frame: body}
  - {topic: timeout_in, frame: header, hold: {timeout: 0.05}}
  - {topic: world_in, type: Vector3Stamped, frame: world}
frames: {world: map, body: base}
"""

SCHEDULED = """
body: {principal_moments: [2.0, 3.0, 4.0]}
torque_inputs:
  - schedule:
      frame: world
      segments:
        - {start: 0.0, torque: [0.0, 0.0, 1.0]}
        - {start: 0.025, torque: [0.0, 2.0, 0.0]}
        - {start: 0.05, torque: [0.0, 0.0, 0.0]}
integrator: {method: rk4, dt: 0.01}
"""


def schedule(text: str = SCENE, dt: float = 0.01, max_torque: float | None = None) -> CommandSchedule:
    clock = StepClock(dt)
    commands = CommandSchedule(parse_scene_text(text, "commands.yaml"), clock)
    if max_torque is not None:
        commands.max_torque = max_torque
    return commands


def run_to(commands: CommandSchedule, k: int) -> list:
    """Step the clock to boundary k as a Simulator does; the (body, world) torque over each step."""
    sums = []
    while commands.clock.k < k:
        if commands.next_event is not None and commands.clock.k >= commands.next_event:
            commands.process_due()
        sums.append((commands.body_sum, commands.world_sum))
        commands.clock.k += 1
    return sums


def test_a_command_acts_from_its_step_and_holds_until_replaced():
    commands = schedule()
    commands.clock.k = 3
    first = commands.submit("hold_in", (0.0, 0.0, 0.5), "body", commands.clock.t)
    assert first.step == 3 and commands.body_sum == (0.0, 0.0, 0.0)  # not before it is processed
    commands.process_due()
    assert commands.body_sum == (0.0, 0.0, 0.5) and commands.world_sum is None
    run_to(commands, 1000)
    assert commands.held_torques() == {"hold_in": ((0.0, 0.0, 0.5), "body")}  # no timeout: held for ever
    commands.submit("hold_in", (1.0, 0.0, 0.0), "body", commands.clock.t)
    commands.process_due()
    assert commands.body_sum == (1.0, 0.0, 0.0)


def test_a_timeout_ends_the_hold_on_the_first_boundary_at_or_after_it():
    commands = schedule()
    commands.clock.k = 2
    commands.submit("timeout_in", (0.0, 0.0, 1.0), "body", 0.02)
    commands.process_due()
    sums = run_to(commands, 12)
    # held from boundary 2 until 0.02 + 0.05 = 0.07 s, boundary 7 (7.000000000000001 steps: on it)
    assert [body[2] for body, _ in sums] == [1.0] * 5 + [0.0] * 5
    assert commands.held_torques() == {}


def test_a_newer_command_outlives_the_older_ones_timeout():
    commands = schedule()
    commands.submit("timeout_in", (0.0, 0.0, 1.0), "body", 0.0)
    commands.process_due()
    run_to(commands, 3)
    commands.submit("timeout_in", (0.0, 0.0, 2.0), "body", commands.clock.t)
    sums = run_to(commands, 10)
    # the first command's expiry at boundary 5 does not end the second (serials differ); it ends at 3 + 5 = 8
    assert [body[2] for body, _ in sums] == [2.0] * 5 + [0.0] * 2


def test_future_commands_wait_and_the_later_effective_time_wins():
    commands = schedule()
    late = commands.submit("hold_in", (0.0, 0.0, 1.0), "body", 0.042)  # between boundaries: rounds up
    early = commands.submit("hold_in", (0.0, 0.0, 3.0), "body", 0.02)
    assert (late.step, early.step) == (5, 2)
    sums = run_to(commands, 6)
    assert [body[2] for body, _ in sums] == [0.0, 0.0, 3.0, 3.0, 3.0, 1.0]


def test_applied_torques_add_up_and_end_after_their_duration():
    commands = schedule()
    applied = commands.apply((0.0, 0.0, 1.0), "", 0.03)
    assert applied.source == APPLY_TORQUE_SOURCE and applied.frame == "body" and applied.receipt_time == 0.0
    commands.apply((0.0, 0.0, 2.0), "map", 0.05)  # the world frame by name
    commands.submit("hold_in", (0.0, 0.0, 4.0), "body", 0.0)
    commands.process_due()
    assert commands.body_sum == (0.0, 0.0, 5.0) and commands.world_sum == (0.0, 0.0, 2.0)
    sums = run_to(commands, 6)
    assert [(body[2], world and world[2]) for body, world in sums] == (
        [(5.0, 2.0)] * 3 + [(4.0, 2.0)] * 2 + [(4.0, None)]
    )


def test_schedule_segments_replace_each_other_at_their_start():
    commands = schedule(SCHEDULED)
    commands.process_due()
    assert commands.body_sum == (0.0, 0.0, 0.0) and commands.world_sum == (0.0, 0.0, 1.0)
    sums = run_to(commands, 6)
    # 0.025 s is 2.5 steps: the segment starts on boundary 3
    assert [world for _, world in sums] == [(0.0, 0.0, 1.0)] * 3 + [(0.0, 2.0, 0.0)] * 2 + [None]


def test_clear_forgets_commands_and_restarts_the_schedules():
    commands = schedule(SCHEDULED)
    run_to(commands, 4)
    commands.clock.reset()
    commands.clear()
    assert commands.world_sum is None and commands.next_event == 0
    commands.process_due()
    assert commands.world_sum == (0.0, 0.0, 1.0)


def test_reschedule_moves_pending_events_to_the_new_grid():
    commands = schedule()
    commands.clock.k = 1
    pending = commands.submit("hold_in", (0.0, 0.0, 1.0), "body", 0.05)
    assert pending.step == 5
    commands.clock.change_dt(0.02)  # from t = 0.01 on: boundaries 1 (0.01 s), 2 (0.03 s), 3 (0.05 s)
    commands.reschedule()
    assert commands.next_event == 3
    sums = run_to(commands, 4)
    assert [body[2] for body, _ in sums] == [0.0, 0.0, 1.0]


def test_admit_resolves_the_frame_and_the_effective_time():
    commands = schedule()
    commands.clock.k = 10
    assert commands.admit("hold_in", [0, 0, 1], "", None, None) == ((0.0, 0.0, 1.0), "body", 0.1, None)
    assert commands.admit("timeout_in", [0, 0, 1], "map", 0.0, [0, 0, 0]) == ((0.0, 0.0, 1.0), "world", 0.1, None)
    assert commands.admit("hold_in", [0, 0, 1], "base", 0.05, None)[2:] == (0.1, 0.05)  # a past stamp: now
    assert commands.admit("hold_in", [0, 0, 1], "base", 0.5, None)[2:] == (0.5, 0.5)
    with pytest.raises(CommandRejected, match="ahead of sim time"):
        commands.admit("hold_in", [0, 0, 1], "", 0.1 + STAMP_HORIZON + 1.0, None)
    with pytest.raises(ValueError, match=r"not a torque input of this scene \(inputs: \['hold_in'"):
        commands.admit("nowhere", [0, 0, 1], "", None, None)


@pytest.mark.parametrize(
    "call,reason",
    [
        (lambda c: c.admit("hold_in", [0, math.nan, 0], "", None, None), "non-finite torque.y = nan"),
        (lambda c: c.admit("hold_in", [0, 0, 1e30], "", None, None), "torque.z = 1e+30 beyond the limit"),
        (
            lambda c: c.admit("hold_in", [0, 0, 1], "odom", None, None),
            "neither the body frame 'base' nor the world frame 'map'",
        ),
        (
            lambda c: c.admit("hold_in", [0, 0, 1], "map", None, None),
            "frame 'map' given, but this input is expressed in 'base'",
        ),
        (lambda c: c.admit("timeout_in", [0, 0, 1], "", None, None), "empty header.frame_id"),
        (lambda c: c.admit("hold_in", [0, 0, 1], "x" * 1000, None, None), "frame_id of 1000 characters"),
        (lambda c: c.admit("hold_in", [0, 0, 1], "", None, [1, 0, 0]), "non-zero force"),
        (lambda c: c.admit("hold_in", [0, 3, 4], "", None, None), "|torque| = 5 N*m exceeds max_torque = 4.5 N*m"),
        (lambda c: c.apply([0, 0, 1], "", math.inf), "duration must be finite and > 0"),
        (lambda c: c.apply([0, 0, 1], "", 5e-324), "duration 5e-324 s is not one step of dt"),  # issue 29: no step
        (lambda c: c.apply([0, 0, math.inf], "", 1.0), "non-finite torque.z"),
    ],
)
def test_refused_commands_name_the_reason_and_change_nothing(call, reason):
    commands = schedule(max_torque=4.5)
    with pytest.raises(CommandRejected) as info:
        call(commands)
    assert reason in info.value.reason
    assert commands.next_event is None and commands.held_torques() == {}


def test_submit_checks_what_resim_feeds_it():
    commands = schedule()
    with pytest.raises(ValueError, match="frame must be 'body' or 'world'"):
        commands.submit("hold_in", (0.0, 0.0, 1.0), "map", 0.0)
    with pytest.raises(ValueError, match="effective_time"):
        commands.submit("hold_in", (0.0, 0.0, 1.0), "body", math.nan)
    with pytest.raises(CommandRejected, match="non-finite"):
        commands.submit("hold_in", (0.0, math.inf, 0.0), "body", 0.0)
