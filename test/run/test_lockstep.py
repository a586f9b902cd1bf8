"""run.lockstep without DDS: turns, stamp matching, timeouts, pause/step/reset, on a fake wall clock.

A real Simulator and RunDriver; the wall clock is a number the test moves.
"""

import numpy as np
import pytest

from rigid_rot_sim.run.commands import CommandRejected
from rigid_rot_sim.run.lockstep import RESEND_WALL, Decision, Lockstep, period_steps, stamp_ns
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.run.pacing import OutputSchedule, Pacer, RunDriver
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import SceneError, parse_scene_text

SCENE = """
body: {principal_moments: [0.02, 0.03, 0.04]}
torque_inputs: [{topic: ~/torque, frame: body}]
integrator: {method: rk4, dt: 0.001}
lockstep: {period: 0.02, inputs: [~/torque], timeout: 2.0, on_timeout: %s}
"""


class Published(SimulationObserver):
    def __init__(self):
        self.states = []

    def outputs_due(self, step, snapshot, names):
        if "state" in names:
            self.states.append(snapshot)


class Rig:
    """A lockstep run: simulator, driver at r = 0 with ~/state once per turn, turns, fake clock."""

    def __init__(self, on_timeout="pause", real_time_factor=0.0):
        self.now = 0.0
        clock = lambda: self.now  # noqa: E731
        scene = parse_scene_text(SCENE % on_timeout)
        self.sim = Simulator(scene)
        self.published = Published()
        self.turns = Lockstep(scene.lockstep, self.sim, clock=clock)
        schedule = OutputSchedule({"state": self.turns.period_steps, "clock": 5})
        self.run = RunDriver(self.sim, schedule, Pacer(real_time_factor, clock=clock), observers=[self.published])
        self.sim.add_observer(self.turns)
        self.sim.command_gate = self.turns.admit

    def answer(self, torque=(0.0, 0.0, 0.01), stamp=None):
        stamp = self.sim.clock.t if stamp is None else stamp
        return self.sim.receive_torque("~/torque", np.array(torque), "", stamp)


def test_the_period_must_be_whole_steps_and_the_inputs_topic_inputs():
    assert period_steps(0.02, 0.001) == 20
    with pytest.raises(ValueError, match="whole number of steps"):
        period_steps(0.0205, 0.001)
    with pytest.raises(SceneError, match="whole number of steps"):
        parse_scene_text((SCENE % "pause").replace("period: 0.02", "period: 0.0205"))
    with pytest.raises(SceneError, match="not a topic of torque_inputs"):
        parse_scene_text((SCENE % "pause").replace("inputs: [~/torque]", "inputs: [/other]"))
    with pytest.raises(SceneError):
        parse_scene_text(SCENE % "sometimes")


def test_a_turn_waits_for_its_command_and_the_command_acts_from_t_k():
    rig = Rig()
    for _ in range(3):
        rig.turns.tick(rig.run)
    assert rig.sim.clock.k == 0 and rig.turns.waiting  # nothing answered: no step taken
    rig.answer(stamp=0.0)  # turn 0: a zero stamp is t_0
    rig.turns.tick(rig.run)
    assert rig.sim.clock.k == 20 and rig.turns.waiting and rig.turns.turns == 1
    command = rig.answer((0.0, 0.0, 0.02))
    assert command.step == 20  # acts from t_1, exactly
    rig.turns.tick(rig.run)
    assert rig.sim.clock.k == 40
    assert [s.step for s in rig.published.states] == [20, 40]  # the state once per turn, at t_k


def test_commands_stamped_for_another_turn_or_twice_are_rejected_with_the_reason():
    rig = Rig()
    rig.answer(stamp=0.0)
    rig.turns.tick(rig.run)  # at turn 1, t = 0.02
    with pytest.raises(CommandRejected, match=r"turn 1 waits for commands stamped 0.02 s"):
        rig.answer(stamp=0.04)
    with pytest.raises(CommandRejected, match="stamp 0 s is not the open turn's"):
        rig.answer(stamp=0.0)
    rig.answer()
    with pytest.raises(CommandRejected, match="already answered"):
        rig.answer()
    rig.turns.tick(rig.run)
    rig.sim.pause(True)
    rig.sim.step(3)  # between turns: no turn open
    with pytest.raises(CommandRejected, match="no turn is open"):
        rig.answer()


def test_a_controller_that_stops_answering_pauses_the_run_with_the_reason():
    rig = Rig("pause")
    rig.answer(stamp=0.0)
    rig.turns.tick(rig.run)
    rig.now += 1.9
    assert rig.turns.tick(rig.run).lockstep_timeout is None and not rig.sim.paused
    rig.now += 0.2
    progress = rig.turns.tick(rig.run)
    assert rig.sim.paused and rig.sim.clock.k == 20
    assert "no command stamped 0.02 s (turn 1) on ~/torque within the timeout of 2 s" in progress.lockstep_timeout
    # resumed: the turn is still open, and its timeout counts again from the resume
    rig.sim.pause(False)
    rig.now += 1.0
    rig.turns.tick(rig.run)
    assert not rig.sim.paused and rig.turns.waiting
    rig.answer()
    rig.turns.tick(rig.run)
    assert rig.sim.clock.k == 40


def test_hold_goes_on_with_the_last_command():
    rig = Rig("hold")
    rig.answer((0.0, 0.0, 0.01), stamp=0.0)
    rig.turns.tick(rig.run)
    rig.now += 2.5
    progress = rig.turns.tick(rig.run)
    assert "holding" in progress.lockstep_timeout and not rig.sim.paused
    assert rig.sim.clock.k == 40 and rig.turns.timeouts == 1
    np.testing.assert_array_equal(rig.published.states[-1].torque_body, [0.0, 0.0, 0.01])


def test_an_unanswered_turn_publishes_its_state_again():
    rig = Rig()
    rig.turns.tick(rig.run)
    assert rig.turns.decide() is Decision.WAIT
    rig.now += RESEND_WALL
    rig.turns.tick(rig.run)
    assert rig.turns.resends == 1 and [s.step for s in rig.published.states] == [0]


def test_reset_and_set_state_reopen_the_turn_and_step_passes_turns():
    rig = Rig()
    rig.answer(stamp=0.0)
    rig.turns.tick(rig.run)
    rig.answer()
    rig.turns.tick(rig.run)
    assert rig.sim.clock.k == 40
    rig.sim.reset()
    rig.turns.tick(rig.run)
    assert rig.sim.clock.k == 0 and rig.turns.waiting  # turn 0 again, its answer needed again
    rig.answer(stamp=0.0)
    rig.sim.set_state([0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.1])
    assert not rig.turns.answered
    rig.turns.tick(rig.run)
    assert rig.sim.clock.k == 0 and rig.turns.waiting  # the answer was to the old state
    rig.sim.pause(True)
    rig.run.run(rig.sim.clock.k + 45, None)  # ~/step: through turns without waiting
    assert rig.sim.clock.k == 45
    rig.sim.pause(False)
    rig.turns.tick(rig.run)
    assert rig.sim.clock.k == 60 and rig.turns.waiting


def test_states_do_not_depend_on_when_the_answers_arrive():
    def run(delays):
        rig = Rig()
        for turn, delay in enumerate(delays):
            rig.now += delay
            rig.turns.tick(rig.run)
            rig.answer((0.0, 0.0, 0.001 * (turn + 1)))
            rig.turns.tick(rig.run)
        return rig.sim.snapshot()

    a, b = run([0.0, 0.0, 0.0, 0.0]), run([0.3, 1.2, 0.0, 1.9])
    assert a.digest == b.digest and a.step == b.step == 80
    np.testing.assert_array_equal(a.orientation, b.orientation)


def test_stamps_compare_in_nanoseconds():
    assert stamp_ns(0.06) == stamp_ns(3 * 0.02) == 60_000_000
