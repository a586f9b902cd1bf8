"""Tests for rigid_rot_sim.run.simulator: command timing, hold policies, determinism, frames, invariants,
the reports to observers."""

import math
from pathlib import Path

import numpy as np
import pytest

from rigid_rot_sim.core.integrators import METHODS
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.run.simulator import APPLY_TORQUE_SOURCE, CommandRejected, Simulator
from rigid_rot_sim.scene.scene import load_scene, parse_scene_text

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"

# A body driven about its principal z axis from rest: omega_z(t) = (integral of N_z) / I3,
# and every method integrates this linear ODE exactly (up to rounding).
DRIVEN = """
body: {principal_moments: [2.0, 3.0, 4.0]}
frames: {world: world, body: body}
torque_inputs:
  - {topic: hold_in, frame: body}
  - {topic: timeout_in, frame: header, hold: {timeout: 0.05}}
  - {topic: world_in, type: Vector3Stamped, frame: world}
integrator: {method: rk4, dt: 0.01}
"""
I3 = 4.0


def driven(**kwargs) -> Simulator:
    return Simulator(parse_scene_text(DRIVEN, "driven.yaml"), **kwargs)


def omega(sim):
    return sim.snapshot().angular_velocity_body


def states_equal(a, b) -> bool:
    return (
        all(
            np.array_equal(getattr(a, name), getattr(b, name))
            for name in ("orientation", "angular_velocity_body", "angular_momentum_world", "torque_body")
        )
        and a.t == b.t
        and a.kinetic_energy == b.kinetic_energy
    )


def test_time_is_step_count_times_dt():
    sim = driven()
    sim.advance(7)
    assert sim.clock.k == 7 and sim.clock.t == 7 * 0.01
    sim.advance(993)
    assert sim.clock.t == 1000 * 0.01  # not an accumulated sum of 0.01s


def test_command_takes_effect_at_the_next_boundary_and_holds():
    sim = driven()
    sim.advance(3)
    command = sim.receive_torque("hold_in", [0.0, 0.0, 0.2])
    assert command.receipt_time == command.effective_time == sim.clock.t and command.step == 3
    sim.advance(10)
    assert omega(sim)[2] == pytest.approx(0.2 * 10 * 0.01 / I3, rel=1e-12)
    sim.advance(10)  # held until replaced
    assert omega(sim)[2] == pytest.approx(0.2 * 20 * 0.01 / I3, rel=1e-12)
    sim.receive_torque("hold_in", [0.0, 0.0, 0.0])
    sim.advance(10)
    assert omega(sim)[2] == pytest.approx(0.2 * 20 * 0.01 / I3, rel=1e-12)


def test_timeout_input_falls_back_to_zero_after_its_sim_time_timeout():
    sim = driven()
    sim.receive_torque("timeout_in", [0.0, 0.0, 1.0], "body")
    sim.advance(20)
    # the command lasted 0.05 s = 5 steps
    assert omega(sim)[2] == pytest.approx(1.0 * 0.05 / I3, rel=1e-12)
    assert sim.commands.held_torques() == {}


def test_a_new_command_restarts_the_timeout():
    sim = driven()
    sim.receive_torque("timeout_in", [0.0, 0.0, 1.0], "body")
    sim.advance(4)
    sim.receive_torque("timeout_in", [0.0, 0.0, 1.0], "body")
    sim.advance(20)
    assert omega(sim)[2] == pytest.approx(1.0 * (0.04 + 0.05) / I3, rel=1e-12)


def test_future_stamp_delays_the_command_and_past_stamp_means_now():
    sim = driven()
    future = sim.receive_torque("hold_in", [0.0, 0.0, 1.0], stamp=0.1)
    assert future.effective_time == 0.1 and future.step == 10 and future.stamp == 0.1
    sim.advance(10)
    assert omega(sim)[2] == 0.0
    sim.advance(5)
    assert omega(sim)[2] == pytest.approx(0.05 / I3, rel=1e-12)
    past = sim.receive_torque("hold_in", [0.0, 0.0, 0.0], stamp=0.01)
    assert past.effective_time == sim.clock.t and past.step == sim.clock.k


def test_stamp_between_boundaries_rounds_up_to_the_next_one():
    sim = driven()
    assert sim.receive_torque("hold_in", [0, 0, 1], stamp=0.031).step == 4
    assert sim.receive_torque("hold_in", [0, 0, 1], stamp=0.3).step == 30  # 0.3 / 0.01 = 29.999999999999996


def test_wall_clock_stamp_is_rejected():
    sim = driven()
    with pytest.raises(CommandRejected, match="ahead of sim time"):
        sim.receive_torque("hold_in", [0, 0, 1], stamp=1.7e9)


@pytest.mark.parametrize(
    "source,torque,frame_id,force,reason",
    [
        ("hold_in", [0.0, math.nan, 0.0], "", None, "non-finite torque.y = nan"),
        ("hold_in", [0.0, 0.0, math.inf], "", None, "non-finite torque.z = inf"),
        (
            "hold_in",
            [0.0, 0.0, 1.0],
            "map",
            None,
            "frame 'map' is neither the body frame 'body' nor the world frame 'world'",
        ),
        ("hold_in", [0.0, 0.0, 1.0], "world", None, "frame 'world' given, but this input is expressed in 'body'"),
        ("timeout_in", [0.0, 0.0, 1.0], "", None, "empty header.frame_id"),
        ("hold_in", [0.0, 0.0, 1.0], "body", [0.0, 1.0, 0.0], "non-zero force"),
        ("hold_in", [0.0, 0.0, 1.0], "body", [math.nan, 0.0, 0.0], "non-finite force.x"),
    ],
)
def test_rejected_commands_name_the_reason_and_leave_the_state_alone(source, torque, frame_id, force, reason):
    sim = driven()
    reference = driven()
    with pytest.raises(CommandRejected) as info:
        sim.receive_torque(source, torque, frame_id, force=force)
    assert reason in info.value.reason and info.value.source == source
    sim.advance(10)
    reference.advance(10)
    assert states_equal(sim.snapshot(), reference.snapshot())
    assert omega(sim)[2] == 0.0


def test_zero_force_wrench_is_accepted():
    sim = driven()
    sim.receive_torque("hold_in", [0.0, 0.0, 1.0], "body", force=[0.0, 0.0, 0.0])
    sim.advance(1)
    assert omega(sim)[2] > 0.0


def test_inputs_add_up():
    sim = driven()
    sim.receive_torque("hold_in", [0.0, 0.0, 0.3])
    sim.receive_torque("timeout_in", [0.0, 0.0, 0.1], "body")
    sim.advance(5)
    assert omega(sim)[2] == pytest.approx(0.4 * 0.05 / I3, rel=1e-12)
    assert sim.snapshot().torque_body == pytest.approx([0.0, 0.0, 0.4])


def _run_sequence(sim, chunks, feed):
    """Drive ``sim`` through 300 steps in the given chunk pattern, feeding commands at fixed steps."""
    snapshots = {}
    schedule = {
        0: ("hold_in", [0.1, 0.0, 0.3], "", 0.0),
        50: ("timeout_in", [0.0, -0.2, 0.0], "body", 0.75),
        120: ("world_in", [0.05, 0.0, 0.0], "world", 0.0),
        200: ("hold_in", [0.0, 0.0, 0.0], "", 2.5),
    }
    while sim.clock.k < 300:
        k = sim.clock.k
        if k in schedule:
            feed(sim, *schedule[k])
        n = min(chunks(k), 300 - k)
        nxt = min([s for s in schedule if s > k] + [300])
        sim.advance(min(n, nxt - k))
        snapshots[sim.clock.k] = sim.snapshot()
    return snapshots


def test_same_commands_give_bit_identical_states_whatever_the_chunking():
    def feed(sim, source, torque, frame_id, stamp):
        sim.receive_torque(source, torque, frame_id, stamp=stamp)

    a = _run_sequence(driven(), lambda k: 1, feed)
    b = _run_sequence(driven(), lambda k: 37, feed)
    c = _run_sequence(driven(), lambda k: 1000, feed)
    assert states_equal(a[300], b[300]) and states_equal(a[300], c[300])
    for k in set(a) & set(b):
        assert states_equal(a[k], b[k])


@pytest.mark.parametrize("method", sorted(METHODS))
def test_every_method_gives_the_same_bits_whatever_the_chunking(method):
    if method == "exact":  # torque-free only: refused for a scene with torque inputs
        with pytest.raises(ValueError, match="cannot run this scene's torque inputs"):
            driven(method=method)
        return

    def run(chunk):
        sim = driven(method=method)
        sim.set_state([0.1, 0.2, 0.3, 0.9], [0.5, -0.3, 1.0])
        sim.receive_torque("hold_in", [0.0, 0.1, 0.2])
        sim.submit_torque("world_in", [0.05, 0.0, 0.0], "world", 0.555)
        while sim.clock.k < 120:
            assert sim.advance(min(chunk, 120 - sim.clock.k)) > 0, sim.failure
        return sim.snapshot()

    one, seven, all_at_once = run(1), run(7), run(1000)
    assert states_equal(one, seven) and states_equal(one, all_at_once)


def test_resubmitting_recorded_commands_reproduces_the_run_bit_for_bit():
    recorded = []

    def feed(sim, source, torque, frame_id, stamp):
        recorded.append(sim.receive_torque(source, torque, frame_id, stamp=stamp))

    original = _run_sequence(driven(), lambda k: 7, feed)
    replay = driven()
    for command in recorded:  # all up front, by effective time: no timing involved
        replay.submit_torque(command.source, command.torque, command.frame, command.effective_time)
    replay.advance(300)
    assert states_equal(original[300], replay.snapshot())
    assert np.any(original[300].angular_velocity_body != 0.0)


def test_world_frame_torque_stays_fixed_in_the_world():
    # spinning about body z, torque fixed along world x: dL_world/dt = N_world exactly;
    # the zero-order hold per step re-expresses it at each boundary (error ~ omega dt)
    sim = driven()
    sim.set_state([0, 0, 0, 1], [0.0, 0.0, 2.0])
    l0 = sim.snapshot().angular_momentum_world
    sim.receive_torque("world_in", [0.5, 0.0, 0.0], "")
    sim.advance(300)
    dl = sim.snapshot().angular_momentum_world - l0
    assert dl == pytest.approx([0.5 * 3.0, 0.0, 0.0], abs=0.5 * 3.0 * 2.0 * 0.01)
    # had it been frozen in the body frame, it would have turned with the body (6 rad)
    frozen = 0.5 * np.array([math.sin(6.0), 1.0 - math.cos(6.0), 0.0]) / 2.0
    assert np.linalg.norm(dl - frozen) > 0.5


def test_schedule_segments_switch_on_their_start_times():
    text = """
body: {principal_moments: [1.0, 1.0, 2.0]}
torque_inputs:
  - schedule: {frame: body, segments: [{start: 0.1, torque: [0, 0, 1.0]}, {start: 0.35, torque: [0, 0, 0]}]}
integrator: {method: rk4, dt: 0.05}
"""
    sim = Simulator(parse_scene_text(text))
    sim.advance(2)
    assert omega(sim)[2] == 0.0
    sim.advance(20)
    assert omega(sim)[2] == pytest.approx(1.0 * 0.25 / 2.0, rel=1e-12)
    sim.reset()  # the schedule restarts
    sim.advance(22)
    assert omega(sim)[2] == pytest.approx(1.0 * 0.25 / 2.0, rel=1e-12)


def test_apply_torque_acts_for_its_duration_on_top_of_inputs():
    sim = driven()
    command = sim.apply_torque([0.0, 0.0, 2.0], "", 0.1)
    assert command.source == APPLY_TORQUE_SOURCE and command.frame == "body"
    sim.apply_torque([0.0, 0.0, 1.0], "body", 0.05)
    sim.advance(30)
    assert omega(sim)[2] == pytest.approx((2.0 * 0.1 + 1.0 * 0.05) / I3, rel=1e-12)


@pytest.mark.parametrize(
    "torque,frame,duration,reason",
    [
        ([0, 0, math.nan], "", 1.0, "non-finite torque.z"),
        ([0, 0, 1], "map", 1.0, "neither the body frame"),
        ([0, 0, 1], "", 0.0, "duration must be finite and > 0"),
        ([0, 0, 1], "", -1.0, "duration must be finite and > 0"),
    ],
)
def test_apply_torque_rejects_bad_requests(torque, frame, duration, reason):
    sim = driven()
    with pytest.raises(CommandRejected, match=reason):
        sim.apply_torque(torque, frame, duration)


def test_reset_restores_the_initial_state_and_clears_commands():
    sim = driven()
    initial = sim.snapshot()
    sim.receive_torque("hold_in", [0.0, 0.3, 0.0])
    sim.apply_torque([1.0, 0.0, 0.0], "", 10.0)
    sim.advance(50)
    sim.reset()
    assert sim.clock.k == 0 and sim.commands.held_torques() == {}
    assert states_equal(sim.snapshot(), initial)
    sim.advance(50)
    assert np.all(omega(sim) == 0.0)


def test_set_state_in_a_non_principal_body_frame_round_trips_and_restarts_drift():
    sim = Simulator(load_scene(SCENES / "spacecraft_slew.yaml"), method="rk4")
    q = np.array([0.1, -0.2, 0.3, 0.9]) / np.linalg.norm([0.1, -0.2, 0.3, 0.9])
    w = np.array([0.01, -0.02, 0.03])
    sim.set_state(q, w)
    snap = sim.snapshot()
    assert snap.orientation == pytest.approx(q, abs=1e-15)
    assert snap.angular_velocity_body == pytest.approx(w, abs=1e-17)
    tensor = sim.scene.body.inertia_array
    assert snap.angular_momentum_body == pytest.approx(tensor @ w, rel=1e-13)
    assert snap.kinetic_energy == pytest.approx(0.5 * w @ tensor @ w, rel=1e-13)
    assert snap.energy_drift == 0.0 and snap.angular_momentum_drift == 0.0
    with pytest.raises(ValueError, match="orientation"):
        sim.set_state([0, 0, 0, 0], w)
    with pytest.raises(ValueError, match=r"angular_velocity\[1\]"):
        sim.set_state(q, [0, math.nan, 0])
    assert sim.snapshot().orientation == pytest.approx(q, abs=1e-15)


def test_torque_free_products_of_inertia_body_conserves_world_momentum():
    text = (SCENES / "spacecraft_slew.yaml").read_text().split("torque_inputs:")[0]
    text += "integrator: {method: exact, dt: 0.1}\n"
    sim = Simulator(parse_scene_text(text))
    sim.set_state([0, 0, 0, 1], [0.02, -0.05, 0.1])
    l0 = sim.snapshot().angular_momentum_world
    sim.advance(2000)
    snap = sim.snapshot()
    assert snap.angular_momentum_world == pytest.approx(l0, rel=1e-10, abs=1e-12)
    assert abs(snap.energy_drift) < 1e-12


def test_step_requires_pause():
    sim = driven()
    with pytest.raises(ValueError, match="not paused"):
        sim.step(3)
    sim.pause(True)
    assert sim.step(3) == 3 and sim.clock.k == 3
    with pytest.raises(ValueError, match="steps must be an integer >= 1"):
        sim.step(0)


def test_changing_dt_keeps_time_continuous_and_recomputes_pending_steps():
    sim = driven()
    sim.advance(10)
    pending = sim.receive_torque("hold_in", [0, 0, 1.0], stamp=0.5)
    assert pending.step == 50
    sim.set_integrator(dt=0.02)
    assert sim.clock.t == pytest.approx(0.1, abs=0) and sim.clock.dt == 0.02
    sim.advance(20)
    assert sim.clock.t == pytest.approx(0.5, rel=1e-15) and omega(sim)[2] == 0.0
    sim.advance(5)
    assert omega(sim)[2] == pytest.approx(0.1 / I3, rel=1e-12)
    with pytest.raises(ValueError, match="unknown integrator"):
        sim.set_integrator("magic")
    with pytest.raises(ValueError, match="cannot run"):
        sim.check_integrator("exact", 0.01)
    with pytest.raises(ValueError, match="cannot run"):
        sim.set_integrator("exact")
    assert sim.stepper.method == "rk4"


@pytest.mark.parametrize(
    "scene,expected",
    [
        ("free_tumble", "exact"),
        ("torque_driven", "taylor"),
        ("heavy_top", "exact_split"),
        ("spacecraft_slew", "taylor"),
    ],
)
def test_auto_choice_follows_the_scene(scene, expected):
    assert Simulator(load_scene(SCENES / f"{scene}.yaml")).stepper.method == expected


def test_auto_integrator_takes_commands_from_rest():
    # the torque_driven scene's use: at rest, then commanded (auto = taylor)
    sim = Simulator(load_scene(SCENES / "torque_driven.yaml"))
    sim.advance(100)
    sim.receive_torque("~/torque", [0.0, 0.0, 0.004], "base_link")
    assert sim.advance(100) == 100, sim.failure
    assert omega(sim)[2] == pytest.approx(0.004 * 0.1 / 0.04, rel=1e-12)


def test_heavy_top_invariants_and_euler_angles():
    sim = Simulator(load_scene(SCENES / "heavy_top.yaml"))
    start = sim.snapshot()
    assert start.euler_zxz == pytest.approx([0.0, 0.5236, 0.0], abs=1e-12)
    sim.advance(2000)
    snap = sim.snapshot()
    assert snap.p_phi == pytest.approx(start.p_phi, rel=1e-9)
    assert snap.p_psi == pytest.approx(start.p_psi, rel=1e-9)
    assert abs(snap.energy_drift) < 1e-5  # exact_split at dt = 1 ms: bounded, second order
    # nutation is the tilt of the body z axis (pivot -> centre of mass) from world z
    x, y, z, w = snap.orientation
    axis_z_world = 1.0 - 2.0 * (x * x + y * y)
    assert snap.euler_zxz[1] == pytest.approx(math.acos(axis_z_world), abs=1e-12)
    assert snap.potential_energy == pytest.approx(0.5 * 9.81 * 0.04 * axis_z_world, rel=1e-12)


def test_divergence_pauses_and_keeps_a_finite_state():
    sim = driven(method="euler")
    sim.set_state([0, 0, 0, 1], [50.0, 50.0, 50.0])  # euler at |omega| dt ~ 1: grows without bound
    sim.advance(10_000)
    assert sim.failure is not None and sim.paused
    snap = sim.snapshot()
    assert np.all(np.isfinite(snap.orientation))
    sim.reset()
    assert sim.failure is None and not sim.paused  # the failure paused it: reset resumes


# -- reports to observers (rigid_rot_sim.run.observer) ------------------------------------


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
    sim.receive_torque("timeout_in", [0.1, 0.0, 0.0], "world", stamp=sim.clock.t + 0.034)
    sim.submit_torque("world_in", [0.0, 0.3, 0.0], "world", sim.clock.t + 0.02)
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
        "command_accepted",
        "command_accepted",
        "command_accepted",
        "torque_applied",
        "integrator_changed",
        "state_set",
        "integrator_changed",
        "reset",
    ]
    held, stamped, submitted, applied, finer, state, dop853, reset = observer.calls
    assert held[1] == 3 and held[2].source == "hold_in" and held[2].torque == (0.0, 0.0, 0.2)
    assert (
        held[2].frame == "body" and held[2].receipt_time == held[2].effective_time == 3 * 0.01 and held[2].stamp is None
    )
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
            replay.submit_torque(
                command.source,
                command.torque,
                command.frame,
                command.effective_time,
                receipt_time=command.receipt_time,
                stamp=command.stamp,
            )
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
    replay.advance_to(sim.clock.k)
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
    assert observer.calls[1][1:] == (sim.clock.k, sim.failure)


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
