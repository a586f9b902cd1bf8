"""Cross-path conformance: every path that runs a scene ends where the run engine ends, bit for bit.

The paths are those of :data:`rigid_rot_sim.scene.features.PATHS`: the engine
(:class:`~rigid_rot_sim.run.simulator.Simulator`), ``resim`` of a recording of it, the sweep's nominal
run (:func:`~rigid_rot_sim.sweep.chunks.run_nominal`: the batch kernel, or the engine per sample for
wheels and gravity gradient) and, where the scene maps onto their arguments (the features of
``PATHS["simulate"]``), :func:`~rigid_rot_sim.core.simulate.simulate` / ``simulate_gyrostat``. For the
same method and step each gives the same final attitude and rate bits (the attitude up to the sign of
the quaternion, which the engine's snapshot picks w >= 0), or refuses the scene in one line naming the
first feature it does not run. No documented exception: every pair agrees to the bit.

Scenes: every shipped scene (its method, or the grid's first for the scene, at its dt, at most
``MAX_STEPS`` steps), and scenes drawn by hypothesis over the kinds (free; schedules in the body and
the world frame; a full inertia tensor; reaction wheels with friction, torque and speed limits and a
wheel-torque schedule; the gravity gradient; sensors), each with a method the path runs.
"""

from __future__ import annotations

import math
import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rigid_rot_sim.core.batch import BATCH_METHODS
from rigid_rot_sim.core.simulate import simulate
from rigid_rot_sim.core.steps import step_grid
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.features import PATHS, features_of, refuse_unhonoured
from rigid_rot_sim.scene.scene import Scene, load_scene
from rigid_rot_sim.sweep.chunks import run_nominal
from rigid_rot_sim.sweep.spec import SweepSpecError, methods_for, parse_sweep_text

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"
SHIPPED = sorted(path.name for path in SCENES.glob("*.yaml"))
MAX_STEPS = 3000

State = tuple[np.ndarray, np.ndarray]  # q (x, y, z, w), omega (rad/s, body frame)


def same_state(a: State, b: State) -> bool:
    return np.array_equal(a[1], b[1]) and (np.array_equal(a[0], b[0]) or np.array_equal(a[0], -b[0]))


# ----------------------------------------------------------------------------- the paths


def engine_end(scene: Scene, method: str, dt: float, steps: int) -> State:
    sim = Simulator(scene, method=method, dt=dt)
    sim.advance_to(steps)
    assert sim.failure is None and sim.clock.k == steps, sim.failure
    snapshot = sim.snapshot()
    return np.asarray(snapshot.orientation), np.asarray(snapshot.angular_velocity_body)


def sweep_end(scene_file: str, method: str, dt: float, steps: int) -> State | str:
    """The sweep's nominal run of the scene file, or its one-line refusal."""
    text = (
        f"scene: {scene_file}\nseed: 1\nsamples: 1\nduration: {steps * dt!r}\n"
        f"grid: {{method: [{method}], dt: [{dt!r}]}}\nnominal: {{method: {method}, dt: {dt!r}}}\ncheckpoints: 3\n"
    )
    try:
        spec = parse_sweep_text(text, "conformance.yaml")
    except SweepSpecError as exc:
        return str(exc)
    assert step_grid(spec.duration, dt) == (steps, 0.0)
    outcome = run_nominal(spec, None)
    assert not outcome.errors, outcome.errors
    return outcome.q_body[0], outcome.omega_body[0]


def simulate_end(scene: Scene, method: str, dt: float, steps: int) -> State:
    """``simulate()`` with the scene's parts as its arguments (ValueError naming what it cannot take)."""
    refuse_unhonoured(scene, "simulate")
    spacecraft = scene.spacecraft
    arguments = {}
    if spacecraft.wheels:
        arguments["wheels"] = spacecraft.wheel_model(scene.body.inertia_array)
        arguments["wheel_speeds0"] = [wheel.initial_speed for wheel in spacecraft.wheels]
        if spacecraft.wheel_schedule is not None:
            arguments["wheel_torque"] = spacecraft.wheel_schedule.segments
    if spacecraft.gravity_gradient is not None:
        arguments["orbit"] = spacecraft.gravity_gradient.model()
    trajectory = simulate(
        scene.body.inertia_array,
        scene.initial.angular_velocity,
        steps * dt,
        dt,
        method,
        scene.initial.orientation,
        save_every=steps,
        **arguments,
    )
    return trajectory.q[-1], trajectory.omega[-1]


def resim_bit_exact(scene_file: Path, method: str, dt: float, steps: int, where: Path) -> str:
    """Record the engine's run as the node does (states at 4 steps, the last one included) and re-simulate it."""
    from rigid_rot_msgs.msg import RigidBodyState
    from rigid_rot_sim import conversions
    from rigid_rot_sim.recording.resim import resimulate
    from rigid_rot_sim.recording.session import RunRecorder
    from rigid_rot_sim.ros.recording import NodeRecording

    scene = load_scene(scene_file)
    sim = Simulator(scene, method=method, dt=dt)
    path = where / "run.mcap"
    with RunRecorder(
        path,
        scene_text=scene_file.read_text(),
        scene_file=str(scene_file),
        parameters={"integrator": method},
        events_topic="/rigid_rot_sim/sim_events",
        integrator={"method": sim.stepper.method, "dt": sim.clock.dt, "options": sim.stepper.options},
        sim_seconds=lambda: sim.clock.t,
    ) as run:
        run.add_topic("/rigid_rot_sim/state", RigidBodyState, role="state")
        sim.add_observer(NodeRecording(run, sim, None))
        for k in np.unique(np.linspace(0, steps, 4).round().astype(int)).tolist():
            sim.advance_to(k)
            snapshot = sim.snapshot()
            run.record("/rigid_rot_sim/state", conversions.snapshot_to_state(snapshot, "odom", "base_link"))
    report = resimulate(path)
    assert report.states == len(np.unique(np.linspace(0, steps, 4).round().astype(int)))
    return report.verdict


def check_every_path(scene_file: Path, method: str, dt: float, steps: int, resim_dir: Path | None) -> set[str]:
    """Every path's end against the engine's; returns the paths that ran the scene (the others refused it)."""
    scene = load_scene(scene_file)
    engine = engine_end(scene, method, dt, steps)
    ran = {"engine"}
    unrun = {path: [key for key in features_of(scene) if key not in PATHS[path]] for path in PATHS}

    swept = sweep_end(str(scene_file), method, dt, steps)
    if unrun["sweep"]:
        assert isinstance(swept, str) and f"scene: {unrun['sweep'][0]}: not run by the sweep path" in swept, swept
        assert "\n" not in swept
    else:
        assert not isinstance(swept, str), swept
        assert same_state(swept, engine), ("sweep", scene.name, swept[1] - engine[1])
        ran.add("sweep")

    if unrun["simulate"]:
        with pytest.raises(ValueError, match=f"^{unrun['simulate'][0]}: not run by the simulate path"):
            simulate_end(scene, method, dt, steps)
    else:
        assert same_state(simulate_end(scene, method, dt, steps), engine), ("simulate", scene.name)
        ran.add("simulate")

    if resim_dir is not None:
        assert not unrun["resim"]
        assert resim_bit_exact(scene_file, method, dt, steps, resim_dir).startswith("BIT-EXACT")
        ran.add("resim")
    return ran


# ----------------------------------------------------------------------------- shipped scenes


@pytest.mark.parametrize("name", SHIPPED)
def test_every_path_ends_where_the_engine_ends_on_a_shipped_scene(name, tmp_path):
    scene = load_scene(SCENES / name)
    method = scene.integrator.method
    if method == "auto" or (scene.spacecraft and method not in methods_for(scene)):
        method = methods_for(scene)[0] if not scene.is_top else "exact_split"
    dt = scene.integrator.dt
    steps = min(MAX_STEPS, round((scene.duration or 10.0) / dt))
    ran = check_every_path(SCENES / name, method, dt, steps, tmp_path if not scene.topic_inputs else None)
    if name in ("wheel_slew.yaml", "gravity_gradient_satellite.yaml", "cubesat_orbit.yaml"):
        assert ran == {"engine", "sweep", "simulate", "resim"}


# ----------------------------------------------------------------------------- drawn scenes

_unit = st.floats(-1.0, 1.0, allow_nan=False).map(lambda v: round(v, 6))


@st.composite
def _vector(draw, scale: float) -> list[float]:
    return [draw(_unit) * scale for _ in range(3)]


@st.composite
def scenes(draw) -> tuple[str, str, float, int, set[str]]:
    """(scene YAML, method, dt, steps, kinds): a scene over some kinds, with a method its paths run."""
    kinds = draw(
        st.sets(st.sampled_from(["body_schedule", "world_schedule", "tensor", "wheels", "gravity_gradient", "sensors"]))
    )
    moments = sorted(draw(st.floats(2.0, 10.0).map(lambda v: round(v, 3))) for _ in range(3))
    moments[2] = min(moments[2], moments[0] + moments[1] - 0.1)
    lines = []
    if "tensor" in kinds:
        from scipy.spatial.transform import Rotation

        rotation = Rotation.from_rotvec(draw(_vector(1.0))).as_matrix()
        tensor = rotation @ np.diag(moments) @ rotation.T
        tensor = 0.5 * (tensor + tensor.T)
        lines.append(f"body: {{inertia_tensor: {[[float(v) for v in row] for row in tensor]}}}")
    else:
        lines.append(f"body: {{principal_moments: {moments}}}")
    rotvec = draw(_vector(2.0))
    from scipy.spatial.transform import Rotation

    q0 = [float(v) for v in Rotation.from_rotvec(rotvec).as_quat()]
    lines.append(f"initial: {{orientation: {q0}, angular_velocity: {draw(_vector(0.8))}}}")
    schedules = []
    for frame in ("body", "world"):
        if f"{frame}_schedule" in kinds:
            starts = sorted(set(draw(st.lists(st.integers(0, 40), min_size=1, max_size=3))))
            segments = ", ".join(f"{{start: {s * 0.07!r}, torque: {draw(_vector(0.5))}}}" for s in starts)
            schedules.append(f"  - schedule: {{frame: {frame}, segments: [{segments}]}}")
    if schedules:
        lines += ["torque_inputs:", *schedules]
    if "wheels" in kinds:
        n = draw(st.integers(1, 3))
        wheels = []
        for i in range(n):
            axis = draw(_vector(1.0))
            if math.hypot(*axis) < 0.1:
                axis = [0.0, 0.0, 1.0]
            max_speed = draw(st.sampled_from([5.0, 50.0, 500.0]))  # 5 rad/s: the speed limit acts
            friction = {"coulomb": draw(st.sampled_from([0.0, 2e-3])), "viscous": draw(st.sampled_from([0.0, 1e-4]))}
            wheels.append(
                f"    - {{name: w{i}, axis: {axis}, inertia: 0.05, max_torque: 0.1, max_speed: {max_speed},"
                f" initial_speed: {draw(_unit) * max_speed!r}, friction: {{coulomb: {friction['coulomb']},"
                f" viscous: {friction['viscous']}}}}}"
            )
        lines += ["actuators:", "  reaction_wheels:", *wheels]
        starts = sorted(set(draw(st.lists(st.integers(0, 40), min_size=1, max_size=3))))
        # torques beyond max_torque (0.1 N*m) are clamped: the limit acts too
        segments = ", ".join(
            f"{{start: {s * 0.07!r}, torques: {[draw(_unit) * 0.15 for _ in range(n)]}}}" for s in starts
        )
        lines.append(f"  wheel_torque_schedule: {{segments: [{segments}]}}")
    if "gravity_gradient" in kinds:
        inclination = draw(st.floats(0.0, 1.5).map(lambda v: round(v, 3)))
        lines.append(f"environment: {{gravity_gradient: {{orbit: {{radius: 7.0e+6, inclination: {inclination}}}}}}}")
    if "sensors" in kinds:
        lines.append("sensors: {seed: 3, gyro: {rate: 50.0, angle_random_walk: 1.0e-4}}")
    spacecraft = bool({"wheels", "gravity_gradient"} & kinds)
    method = draw(st.sampled_from(["gyrostat_rk4", "dopri5"] if spacecraft else list(BATCH_METHODS)))
    dt = draw(st.sampled_from([0.01, 0.02, 0.05]))
    steps = draw(st.integers(1, 150))
    lines.append(f"integrator: {{method: {method}, dt: {dt}}}")
    # Python's 3e-07 is a string in YAML 1.1 (PyYAML): 3.0e-07 is a number in both
    text = re.sub(r"(?<![\w.])(-?\d+)e([-+]\d+)", r"\1.0e\2", "\n".join(lines) + "\n")
    return text, method, dt, steps, kinds


_DRAWN = Path(tempfile.mkdtemp(prefix="rigid-rot-conformance-"))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenes())
def test_every_path_ends_where_the_engine_ends_on_a_drawn_scene(drawn):
    text, method, dt, steps, kinds = drawn
    scene_file = _DRAWN / "drawn.yaml"
    scene_file.write_text(text)
    ran = check_every_path(scene_file, method, dt, steps, _DRAWN)
    assert {"engine", "sweep", "resim"} <= ran, text
    if not kinds & {"body_schedule", "world_schedule"}:
        assert "simulate" in ran, text


def test_the_drawn_kinds_reach_every_feature_the_issue_names():
    """A scene of every kind at once uses each of the features the suite is about."""
    from hypothesis import find

    every = find(scenes(), lambda d: len(d[4]) == 6 and "coulomb: 0.002" in d[0] and "max_speed: 5.0" in d[0])
    used = set(features_of(load_scene_text(every[0])))
    assert {
        "schedules.body",
        "schedules.world",
        "spacecraft.wheels",
        "spacecraft.wheels.friction",
        "spacecraft.wheel_schedule",
        "spacecraft.gravity_gradient",
        "sensors.gyro",
    } <= used


def load_scene_text(text: str) -> Scene:
    from rigid_rot_sim.scene.scene import parse_scene_text

    return parse_scene_text(text)
