"""A sweep's nominal body is the run engine's body: same steps, same torque on each, same bits.

With no dispersions, the sweep's nominal run (:func:`rigid_rot_sim.sweep.chunks.run_nominal`,
the batch core) and :class:`rigid_rot_sim.run.simulator.Simulator` (the node's engine) step
the same scene with rk4, whose batch kernel is the single-body kernel (core/batch.py): so
they must agree bit for bit at every checkpoint, which holds only if they switch each
schedule segment on the same step and express each torque and state with the same
formulas. Every shipped scene with a torque schedule is checked, plus scenes that switch
at 0.9 s, where ``k * dt`` falls a rounding short of the start for dt = 0.03 and 0.009 s.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from rigid_rot_sim.core.steps import step_at_or_after, step_grid
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.run.timeline import stretches
from rigid_rot_sim.scene.features import PATHS, features_of
from rigid_rot_sim.scene.scene import load_scene
from rigid_rot_sim.sweep.chunks import run_nominal
from rigid_rot_sim.sweep.spec import SweepSpec, SweepSpecError, methods_for, parse_sweep_text, runs_per_sample

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"
SHIPPED_WITH_SCHEDULE = sorted(path.name for path in SCENES.glob("*.yaml") if load_scene(str(path)).schedules)
DTS = (0.03, 0.009, 0.01)
CHECKPOINTS = 8

# a switch at 0.9 s, body and world frame; the inertia is not principal, so torques are rotated
SWITCHING = """
name: switch_at_0_9_{frame}
body:
  inertia_tensor: [[2.0, 0.1, -0.05], [0.1, 3.0, 0.2], [-0.05, 0.2, 4.0]]
initial:
  orientation: [0.1, -0.2, 0.3, 0.9273618495495703]
  angular_velocity: [0.3, -0.2, 1.1]
torque_inputs:
  - schedule:
      frame: {frame}
      segments:
        - {{start: 0.0, torque: [0.2, -0.1, 0.4]}}
        - {{start: 0.9, torque: [0.0, 0.0, 0.0]}}
        - {{start: 1.8, torque: [-0.3, 0.05, 0.1]}}
integrator: {{method: rk4, dt: 0.01}}
duration: 3.0
"""


def _spec(scene: str, dt: float, duration: float | None) -> SweepSpec:
    return parse_sweep_text(
        f"scene: {scene}\nseed: 1\nsamples: 1\n"
        + (f"duration: {duration!r}\n" if duration is not None else "")
        + f"grid: {{method: [rk4], dt: [{dt!r}]}}\nnominal: {{method: rk4, dt: {dt!r}}}\ncheckpoints: {CHECKPOINTS}\n",
        "sweep.yaml",
    )


def _check_equal_at_checkpoints(spec: SweepSpec, dt: float) -> None:
    n_full, _ = step_grid(spec.duration, dt)
    checkpoints = np.unique(np.linspace(0, n_full, CHECKPOINTS + 1).round().astype(int))[1:]
    sim = Simulator(spec.scene, method="rk4", dt=dt)
    for k in checkpoints.tolist():
        sim.advance_to(k)
        assert sim.failure is None and sim.clock.k == k
        engine = sim.snapshot()
        # the sweep run over exactly k steps (a run's bits do not depend on how its steps are chunked)
        sweep = run_nominal(dataclasses.replace(spec, duration=k * dt), None)
        assert not sweep.errors
        q, omega = sweep.q_body[0], sweep.omega_body[0]
        where = f"{spec.scene.name}, dt = {dt}, step {k}"
        assert np.array_equal(omega, engine.angular_velocity_body), (where, omega - engine.angular_velocity_body)
        # the same quaternion bits, up to the sign the engine's snapshot picks (w >= 0)
        assert np.array_equal(q, engine.orientation) or np.array_equal(-q, engine.orientation), where


@pytest.mark.parametrize("dt", DTS)
@pytest.mark.parametrize("scene", SHIPPED_WITH_SCHEDULE)
def test_the_nominal_body_of_a_shipped_scene_is_the_engines(scene, dt):
    _check_equal_at_checkpoints(_spec(scene, dt, None), dt)


def test_shipped_scenes_with_a_schedule_are_checked():
    assert SHIPPED_WITH_SCHEDULE  # the test above must not pass on an empty list


@pytest.mark.parametrize("dt", DTS)
@pytest.mark.parametrize("frame", ["body", "world"])
def test_a_switch_at_0_9_s_happens_on_the_engines_step(tmp_path, frame, dt):
    path = tmp_path / f"switch_{frame}.yaml"
    path.write_text(SWITCHING.format(frame=frame))
    _check_equal_at_checkpoints(_spec(str(path), dt, None), dt)


def _engine_changes(scene, dt: float, end: int) -> list[tuple[int, tuple[float, ...], tuple[float, ...]]]:
    """(step, body sum, world sum) at each step where the engine's command schedule changes the torque."""
    sim = Simulator(scene, method="rk4", dt=dt)
    changes = []
    for k in range(1, end + 1):
        sim.advance_to(k)  # the sums now are those that acted over step k - 1
        world = sim.commands.world_sum or (0.0, 0.0, 0.0)
        if not changes or changes[-1][1:] != (sim.commands.body_sum, world):
            changes.append((k - 1, sim.commands.body_sum, world))
    return changes


def _timeline_changes(scene, dt: float, end: int) -> list[tuple[int, tuple[float, ...], tuple[float, ...]]]:
    changes = []
    for stretch in stretches(scene.schedules, dt, end):
        world = stretch.world or (0.0, 0.0, 0.0)
        if not changes or changes[-1][1:] != (stretch.body, world):
            changes.append((stretch.start, stretch.body, world))
    return changes


@pytest.mark.parametrize("dt", DTS)
@pytest.mark.parametrize("scene", [*SHIPPED_WITH_SCHEDULE, "switch_body", "switch_world"])
def test_the_timeline_changes_the_torque_where_the_engines_command_schedule_does(tmp_path, scene, dt):
    """run/timeline.stretches, which the sweep runs on, against the steps the node's CommandSchedule switches on."""
    if scene.startswith("switch_"):
        path = tmp_path / f"{scene}.yaml"
        path.write_text(SWITCHING.format(frame=scene.removeprefix("switch_")))
        loaded = load_scene(str(path))
    else:
        loaded = load_scene(str(SCENES / scene))
    end = step_at_or_after(loaded.duration, dt)
    assert len(_engine_changes(loaded, dt, end)) > 1  # the scene does switch
    assert _timeline_changes(loaded, dt, end) == _engine_changes(loaded, dt, end)


# ------------------------------------------------------------------ every shipped scene: the engine's end, or refused

ALL_SHIPPED = sorted(path.name for path in SCENES.glob("*.yaml"))
#: At most this many steps per scene (gravity_gradient_satellite runs 20000 steps of 1 s: all of them).
MAX_STEPS = 20_000


@pytest.mark.parametrize("scene", ALL_SHIPPED)
def test_a_shipped_scenes_nominal_sweep_ends_where_the_engine_ends_or_is_refused_in_one_line(scene):
    """The sweep's nominal run, with the grid's first method of the engine's registry for the scene (gyrostat_rk4 for
    wheels and gravity gradient) at the scene's dt, against Simulator with the same method and dt: the same bits at
    the end, or a one-line refusal naming the first feature the sweep does not run."""
    loaded = load_scene(str(SCENES / scene))
    dt = loaded.integrator.dt
    duration = min(loaded.duration or 10.0, MAX_STEPS * dt)
    method = methods_for(loaded)[0]
    text = (
        f"scene: {scene}\nseed: 1\nsamples: 1\nduration: {duration!r}\n"
        f"grid: {{method: [{method}], dt: [{dt!r}]}}\nnominal: {{method: {method}, dt: {dt!r}}}\ncheckpoints: 4\n"
    )
    unrun = [key for key in features_of(loaded) if key not in PATHS["sweep"]]
    if unrun:
        with pytest.raises(SweepSpecError) as refused:
            parse_sweep_text(text, "sweep.yaml")
        assert str(refused.value).startswith(f"sweep.yaml: scene: {unrun[0]}: ") and "\n" not in str(refused.value)
        return
    spec = parse_sweep_text(text, "sweep.yaml")
    sweep = run_nominal(spec, None)
    assert not sweep.errors
    sim = Simulator(spec.scene, method=method, dt=dt)
    n_full, last = step_grid(duration, dt)
    assert last == 0.0
    sim.advance_to(n_full)
    engine = sim.snapshot()
    assert sim.failure is None and sim.clock.k == n_full
    assert np.array_equal(sweep.omega_body[0], engine.angular_velocity_body), scene
    q = sweep.q_body[0]
    assert np.array_equal(q, engine.orientation) or np.array_equal(-q, engine.orientation), scene
    # the field at the end: the engine's true field (as ~/magnetic_field publishes it), or NaN without one
    field = spec.scene.orbit_field()
    if field is None:
        assert np.isnan(sweep.field_body[0]).all(), scene
    else:
        assert np.array_equal(sweep.field_body[0], field.body(engine.t, engine.orientation)), scene


def test_the_shipped_scenes_cover_both_paths_and_the_refusals():
    kinds = {runs_per_sample(load_scene(str(SCENES / s))) for s in ALL_SHIPPED if s not in ("heavy_top.yaml",)}
    assert kinds == {True, False}
    refused = [s for s in ALL_SHIPPED if not set(features_of(load_scene(str(SCENES / s)))) <= PATHS["sweep"]]
    assert "heavy_top.yaml" in refused and "torque_driven.yaml" in refused
    assert "wheel_slew.yaml" not in refused and "gravity_gradient_satellite.yaml" not in refused


WHEELS = """
scene: wheel_slew
seed: 4
samples: 5
duration: 20.0
grid: {method: [gyrostat_rk4], dt: [0.05]}
dispersions:
  principal_moments: {relative: 0.02}
  axis_misalignment: {sigma: 1.0e-3}
  initial_omega: {sigma: 1.0e-4}
  initial_attitude: {sigma: 1.0e-3}
checkpoints: 10
"""


def test_a_dispersed_wheel_sweep_runs_each_sample_in_the_engine_on_its_own_scene():
    from rigid_rot_sim.sweep.chunks import Chunk, _bodies, run_chunk
    from rigid_rot_sim.sweep.engine_runs import dispersed_scene

    spec = parse_sweep_text(WHEELS, "wheels.yaml")
    rows = run_chunk(spec, Chunk(0, 0, spec.samples))
    assert rows["error"] == [None] * spec.samples and set(rows["verdict"]) == {"stable"}
    assert np.all(rows["final_attitude_error"] > 0.0)  # every sample is dispersed
    bodies = _bodies(spec, None, range(0, spec.samples))
    for i in (0, 3):
        scene = dispersed_scene(spec, bodies, i)
        sim = Simulator(scene, method="gyrostat_rk4", dt=0.05)
        sim.advance_to(400)
        assert np.array_equal(sim.snapshot().angular_velocity_body, [rows[f"final_omega_{a}"][i] for a in "xyz"])
        # the dispersed body: its principal moments are the row's (the engine diagonalises the tensor again)
        assert np.allclose(np.sort(sim.body.principal_moments), np.sort([rows[f"I{j}"][i] for j in (1, 2, 3)]))
    # the nominal body is the scene itself, bits included
    nominal = dispersed_scene(spec, _bodies(spec, None, None), 0)
    assert nominal.body == spec.scene.body and nominal.initial == spec.scene.initial


def test_a_run_by_the_engine_per_sample_ends_on_the_duration_with_a_last_shorter_step():
    """1.005 s at dt = 0.01 s: 100 steps, then the engine's dt changed to the remainder for one last step, as a
    node's set_integrator does."""
    spec = parse_sweep_text(
        "scene: wheel_slew\nseed: 1\nsamples: 1\nduration: 1.005\n"
        "grid: {method: [gyrostat_rk4], dt: [0.01]}\nnominal: {method: gyrostat_rk4, dt: 0.01}\ncheckpoints: 4\n",
        "short.yaml",
    )
    sweep = run_nominal(spec, None)
    sim = Simulator(spec.scene, method="gyrostat_rk4", dt=0.01)
    n_full, last = step_grid(1.005, 0.01)  # the remainder, as the batch's last step: 1.005 - 100 x 0.01
    assert n_full == 100 and last == pytest.approx(0.005, abs=1e-15)
    sim.advance_to(100)
    sim.set_integrator(dt=last)
    sim.advance(1)
    assert sim.clock.t == pytest.approx(1.005, abs=1e-15)
    assert np.array_equal(sweep.omega_body[0], sim.snapshot().angular_velocity_body)
    assert not sweep.errors and np.isfinite(sweep.max_omega[0]) and sweep.max_omega[0] > 0.0


ORBIT = """
scene: cubesat_orbit
seed: 7
samples: 4
duration: 3.005
grid: {method: [gyrostat_rk4], dt: [0.01]}
dispersions:
  orbit_phase: {distribution: uniform, sigma: 3.0}
  epoch: {sigma: 86400.0}
  initial_omega: {sigma: 1.0e-3}
checkpoints: 4
"""


def test_an_orbit_sweep_runs_each_sample_on_its_phase_and_epoch_and_reports_the_field_at_the_end():
    """orbit_phase shifts the true anomaly at t = 0 (the gravity gradient's orbit with it), epoch the scene's epoch;
    each row ends where the engine ends on the sample's scene, its field the engine's true field there."""
    from rigid_rot_sim.core.orbit import mean_to_true_anomaly
    from rigid_rot_sim.scene.orbit import epoch_datetime
    from rigid_rot_sim.sweep.chunks import Chunk, _bodies, run_chunk
    from rigid_rot_sim.sweep.engine_runs import dispersed_scene

    spec = parse_sweep_text(ORBIT, "orbit.yaml")
    rows = run_chunk(spec, Chunk(0, 0, spec.samples))
    assert rows["error"] == [None] * spec.samples
    phases, offsets = np.asarray(rows["orbit_phase"]), np.asarray(rows["epoch_offset"])
    assert np.all(np.abs(phases) > 0.0) and np.all(np.abs(phases) <= 3.0)
    assert np.all(offsets != 0.0) and np.array_equal(offsets, np.round(offsets, 6))
    fields = np.column_stack([rows[f"final_field_{a}"] for a in "xyz"])
    assert np.all(np.isfinite(fields)) and np.all(np.linalg.norm(fields, axis=1) > 1.5e-5)  # LEO: 20-60 uT
    assert len({tuple(f) for f in fields.tolist()}) == spec.samples
    bodies = _bodies(spec, None, range(0, spec.samples))
    base = spec.scene.orbit
    assert base is not None
    for i in range(spec.samples):
        scene = dispersed_scene(spec, bodies, i)
        assert scene.orbit is not None and scene.spacecraft.gravity_gradient is not None
        assert scene.spacecraft.gravity_gradient.kepler == scene.orbit
        shift = mean_to_true_anomaly(scene.orbit.mean_anomaly, scene.orbit.e) - mean_to_true_anomaly(
            base.mean_anomaly, base.e
        )
        assert np.angle(np.exp(1j * (shift - phases[i]))) == pytest.approx(0.0, abs=1e-12)
        assert (scene.orbit.raan_dot, scene.orbit.a, scene.orbit.i) == (base.raan_dot, base.a, base.i)
        delta = (epoch_datetime(scene.epoch) - epoch_datetime(spec.scene.epoch)).total_seconds()
        assert delta == pytest.approx(offsets[i], abs=1e-9)
        sim = Simulator(scene, method="gyrostat_rk4", dt=0.01)
        sim.advance_to(300)
        sim.set_integrator(dt=step_grid(3.005, 0.01)[1])
        sim.advance(1)
        end = sim.snapshot()
        assert np.array_equal(end.angular_velocity_body, [rows[f"final_omega_{a}"][i] for a in "xyz"])
        field = scene.orbit_field()
        assert field is not None and np.array_equal(field.body(end.t, end.orientation), fields[i])
    # the nominal body is the scene itself: its orbit and epoch, bits included
    nominal = dispersed_scene(spec, _bodies(spec, None, None), 0)
    assert nominal.orbit is spec.scene.orbit and nominal.epoch == spec.scene.epoch


def test_a_phase_or_epoch_dispersion_on_a_scene_without_them_is_refused_in_one_line():
    for key, feature in (("orbit_phase", "orbit"), ("epoch", "environment.magnetic_field")):
        text = (
            "scene: gravity_gradient_satellite\nseed: 1\nsamples: 2\nduration: 1.0\n"
            f"grid: {{method: [gyrostat_rk4]}}\ndispersions: {{{key}: {{sigma: 1.0}}}}\n"
        )
        with pytest.raises(SweepSpecError, match=f"^g.yaml: dispersions.{key}: maps onto {feature}, which") as refused:
            parse_sweep_text(text, "g.yaml")
        assert "\n" not in str(refused.value)


def test_a_sweep_without_a_field_reports_nan_for_the_field_at_the_end():
    from rigid_rot_sim.sweep.chunks import Chunk, run_chunk

    rows = run_chunk(parse_sweep_text(WHEELS, "wheels.yaml"), Chunk(0, 0, 2))
    assert all(np.isnan(rows[f"final_field_{a}"]).all() for a in "xyz")
    assert np.array_equal(rows["orbit_phase"], np.zeros(2)) and np.array_equal(rows["epoch_offset"], np.zeros(2))
