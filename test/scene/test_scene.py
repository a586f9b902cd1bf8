"""Tests for rigid_rot_sim.scene.scene: the shipped scenes load, bad files are named precisely."""

import math
from pathlib import Path

import numpy as np
import pytest

from rigid_rot_sim.scene.scene import SceneError, load_scene, parse_scene_text

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"
SHIPPED = {
    "free_tumble": "none",
    "intermediate_axis_flip": "none",
    "spacecraft_slew": "schedule",
    "torque_driven": "topic",
    "heavy_top": "gravity",
    "sleeping_top": "gravity",
    "thin_rod": "none",
    "from_point_masses": "none",
    "wheel_slew": "spacecraft",
    "gravity_gradient_satellite": "spacecraft",
    "closed_loop_lockstep": "topic",
    "excitation": "schedule",
    "excitation_gentle": "schedule",
    "cubesat_orbit": "spacecraft",
    "cubesat_detumble": "spacecraft",
}

MINIMAL = "body: {principal_moments: [1.0, 2.0, 3.0]}\n"


def parse(text: str, name: str = "bad.yaml"):
    return parse_scene_text(text, source=f"/somewhere/{name}")


@pytest.mark.parametrize("name,kind", sorted(SHIPPED.items()))
def test_shipped_scenes_load_with_their_torque_kind(name, kind):
    scene = load_scene(SCENES / f"{name}.yaml")
    assert scene.name == name
    assert scene.torque_kind == kind
    assert scene.is_top == (kind == "gravity")
    q = np.array(scene.initial.orientation)
    assert abs(np.linalg.norm(q) - 1.0) < 1e-15
    tensor = scene.body.inertia_array
    assert np.allclose(tensor, tensor.T)
    assert np.all(np.linalg.eigvalsh(tensor) > 0.0)


def test_every_scene_file_is_listed():
    assert {p.stem for p in SCENES.glob("*.yaml")} == set(SHIPPED)


def test_the_lockstep_section():
    scene = load_scene(SCENES / "closed_loop_lockstep.yaml")
    assert (scene.lockstep.period, scene.lockstep.inputs) == (0.02, ("~/torque",))
    assert (scene.lockstep.timeout, scene.lockstep.on_timeout) == (5.0, "pause")
    assert parse(MINIMAL).lockstep is None
    driven = MINIMAL + "torque_inputs: [{topic: ~/torque}]\n"
    assert parse(driven + "lockstep: {period: 0.01, inputs: [~/torque]}").lockstep.on_timeout == "pause"
    for section, message in [
        ("lockstep: {period: 0.0105, inputs: [~/torque]}", "lockstep.period: 0.0105 s is not a whole number of steps"),
        ("lockstep: {period: 0.01, inputs: [~/cmd]}", "lockstep.inputs[0]: '~/cmd' is not a topic of torque_inputs"),
        ("lockstep: {period: 0.01, inputs: [~/torque, ~/torque]}", "listed twice"),
        ("lockstep: {period: 0.01, inputs: []}", "lockstep.inputs"),
        ("lockstep: {period: 0.01, inputs: [~/torque], on_timeout: wait}", "lockstep.on_timeout"),
        ("lockstep: {inputs: [~/torque]}", "period"),
    ]:
        with pytest.raises(SceneError, match=message.replace("[", r"\[").replace("]", r"\]")):
            parse(driven + section)


def test_defaults_of_a_minimal_scene():
    scene = parse(MINIMAL, "minimal.yaml")
    assert scene.name == "minimal"
    assert (scene.frames.world, scene.frames.body) == ("odom", "base_link")  # REP 105
    assert scene.initial.orientation == (0.0, 0.0, 0.0, 1.0)
    assert scene.topic_inputs == () and scene.schedules == () and scene.gravity is None
    assert scene.integrator.method == "auto" and scene.duration is None and scene.recording is None
    assert scene.torque_kind == "none"
    assert (scene.qos.reliability, scene.qos.depth) == ("reliable", 10)
    assert scene.frames.principal == "base_link_principal"


def test_output_qos_is_read_and_validated():
    scene = parse(MINIMAL + "qos: {reliability: best_effort, depth: 500}\n", "q.yaml")
    assert (scene.qos.reliability, scene.qos.depth) == ("best_effort", 500)
    for bad, key in (
        ("{reliability: sometimes}", "qos.reliability"),
        ("{depth: 0}", "qos.depth"),
        ("{depth: 2.5}", "qos.depth"),
        ("{history: all}", "qos"),
    ):
        with pytest.raises(SceneError, match=f"q.yaml: {key}"):
            parse(MINIMAL + f"qos: {bad}\n", "q.yaml")


@pytest.mark.parametrize(
    "text,expected",
    [
        ("name: x\n", "bad.yaml: body: missing"),
        (MINIMAL + "colour: red\n", "bad.yaml: colour: unknown key"),
        ("body: {principal_moments: [1.0, 2.0, -3.0]}\n", "bad.yaml: body.principal_moments[2] must be > 0"),
        (
            "body: {principal_moments: [1.0, 2.0, 4.0]}\n",
            "bad.yaml: body.principal_moments = [1.0, 2.0, 4.0] violates the triangle",
        ),
        ("body: {principal_moments: [1.0, 2.0]}\n", "bad.yaml: body.principal_moments: must be a list of 3 numbers"),
        (
            "body: {principal_moments: [1, 2, 3], inertia_tensor: [[1,0,0],[0,1,0],[0,0,1]]}\n",
            "bad.yaml: body: must give exactly one",
        ),
        (
            "body: {inertia_tensor: [[2, 0.5, 0], [0, 2, 0], [0, 0, 2]]}\n",
            "bad.yaml: body.inertia_tensor must be symmetric",
        ),
        (
            "body: {point_masses: {masses: [1, 1], positions: [[1, 0, 0], [-1, 0, 0]]}}\n",
            "bad.yaml: body.point_masses: the masses are collinear",
        ),
        (
            "body: {point_masses: {masses: [1, -1], positions: [[1, 0, 0], [0, 1, 0]]}}\n",
            "bad.yaml: body.point_masses: masses[1]",
        ),
        (
            MINIMAL + "initial: {orientation: [0, 0, 0, 0]}\n",
            "bad.yaml: initial.orientation must be a non-zero quaternion",
        ),
        (
            MINIMAL + "initial: {orientation: [0, 0, 0, 1], euler_zxz: [0, 0, 0]}\n",
            "bad.yaml: initial: give orientation or euler_zxz",
        ),
        (
            MINIMAL + "initial: {angular_velocity: [0, .nan, 0]}\n",
            "bad.yaml: initial.angular_velocity[1]: must be finite",
        ),
        (
            MINIMAL + "torque_inputs: [{topic: a, frame: map}]\n",
            "bad.yaml: torque_inputs[0].frame: must be one of body, world, header",
        ),
        (
            MINIMAL + "torque_inputs: [{topic: a, type: Twist}]\n",
            "bad.yaml: torque_inputs[0].type: must be one of WrenchStamped",
        ),
        (
            MINIMAL + "torque_inputs: [{topic: a, hold: {timeout: 0}}]\n",
            "bad.yaml: torque_inputs[0].hold.timeout: must be > 0",
        ),
        (MINIMAL + "torque_inputs: [{topic: a, hold: forever}]\n", "bad.yaml: torque_inputs[0].hold: must be 'hold'"),
        (
            MINIMAL + "torque_inputs: [{topic: a}, {topic: a}]\n",
            "bad.yaml: torque_inputs[1].topic: topic 'a' is listed twice",
        ),
        (
            MINIMAL
            + "torque_inputs: [{schedule: {segments: [{start: 1, torque: [0, 0, 1]}, "
            + "{start: 1, torque: [0, 0, 0]}]}}]\n",
            "bad.yaml: torque_inputs[0].schedule.segments[1].start: must be later",
        ),
        (
            MINIMAL + "torque_inputs: [{schedule: {frame: header, segments: [{start: 0, torque: [0, 0, 1]}]}}]\n",
            "bad.yaml: torque_inputs[0].schedule.frame: must be body or world",
        ),
        (MINIMAL + "gravity: {acceleration: 9.81, mass: 1.0}\n", "bad.yaml: gravity: needs center_of_mass"),
        (
            MINIMAL + "gravity: {acceleration: 9.81, mass: 1.0, center_of_mass: [0, 0, 0]}\n",
            "bad.yaml: gravity.center_of_mass: must not be at the pivot",
        ),
        (
            MINIMAL + "gravity: {mass: 1.0, center_of_mass: [0, 0, 1]}\ntorque_inputs: [{topic: a}]\n",
            "bad.yaml: torque_inputs: not supported in a gravity",
        ),
        (
            MINIMAL + "integrator: {method: magic}\n",
            "bad.yaml: integrator.method: unknown integrator 'magic'; valid methods:",
        ),
        (MINIMAL + "integrator: {dt: -0.1}\n", "bad.yaml: integrator.dt: must be >= 1e-07"),
        (MINIMAL + "duration: 0\n", "bad.yaml: duration: must be > 0"),
        (MINIMAL + "real_time_factor: -1\n", "bad.yaml: real_time_factor: must be >= 0"),
        (MINIMAL + "outputs: {state: -5}\n", "bad.yaml: outputs.state: must be >= 0"),
        (MINIMAL + "outputs: {velocity: 5}\n", "bad.yaml: outputs.velocity: unknown key"),
        (MINIMAL + "frames: {world: a, body: a}\n", "bad.yaml: frames: world and body frames must differ"),
        ("body: [1, 2\n", "bad.yaml: not valid YAML"),
    ],
)
def test_errors_name_file_key_and_problem(text, expected):
    with pytest.raises(SceneError) as info:
        parse(text)
    assert str(info.value).startswith(expected), str(info.value)


def test_missing_file_is_named():
    with pytest.raises(SceneError, match="nope.yaml: cannot read scene file"):
        load_scene("/nonexistent/nope.yaml")


def _axis_quaternion(axis, angle):
    s = math.sin(angle / 2.0)
    return np.array([s * axis[0], s * axis[1], s * axis[2], math.cos(angle / 2.0)])


def _hamilton(p, q):
    px, py, pz, pw = p
    qx, qy, qz, qw = q
    return np.array(
        [
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
            pw * qw - px * qx - py * qy - pz * qz,
        ]
    )


def test_euler_zxz_is_intrinsic_z_x_z():
    phi, theta, psi = 0.3, 1.1, -2.0
    scene = parse(MINIMAL + f"initial: {{euler_zxz: [{phi}, {theta}, {psi}]}}\n")
    expected = _hamilton(
        _hamilton(_axis_quaternion((0, 0, 1), phi), _axis_quaternion((1, 0, 0), theta)),
        _axis_quaternion((0, 0, 1), psi),
    )
    q = np.array(scene.initial.orientation)
    assert min(np.max(np.abs(q - expected)), np.max(np.abs(q + expected))) < 1e-15


def test_orientation_is_normalised():
    scene = parse(MINIMAL + "initial: {orientation: [0, 0, 2, 2]}\n")
    assert np.allclose(scene.initial.orientation, [0, 0, math.sqrt(0.5), math.sqrt(0.5)], rtol=0, atol=1e-15)


def test_point_masses_give_the_hand_computed_tensor_about_the_centre_of_mass():
    # masses m at (+-a, 0, 0), n at (0, +-b, 0), p at (0, 0, +-c), shifted by (1, 2, 3): centre of mass there
    m, n, p, a, b, c = 1.0, 2.0, 0.5, 0.4, 0.3, 0.2
    positions = [[1 + a, 2, 3], [1 - a, 2, 3], [1, 2 + b, 3], [1, 2 - b, 3], [1, 2, 3 + c], [1, 2, 3 - c]]
    text = f"body: {{point_masses: {{masses: [{m}, {m}, {n}, {n}, {p}, {p}], positions: {positions}}}}}\n"
    scene = parse(text)
    expected = np.diag([2 * n * b**2 + 2 * p * c**2, 2 * m * a**2 + 2 * p * c**2, 2 * m * a**2 + 2 * n * b**2])
    assert np.allclose(scene.body.inertia_array, expected, rtol=1e-12, atol=1e-14)
    assert scene.body.mass == pytest.approx(2 * (m + n + p))
    assert np.allclose(scene.body.center_of_mass, [1, 2, 3])


def test_point_masses_under_gravity_use_the_tensor_about_the_pivot():
    text = (
        "body: {point_masses: {masses: [1.0, 1.0, 1.0], positions: [[0.1, 0, 1.0], [-0.1, 0, 1.0], [0, 0.1, 1.0]]}}\n"
        "gravity: {acceleration: 9.81}\n"
    )
    scene = parse(text)
    com = np.array([0.0, 0.1 / 3, 1.0])
    assert np.allclose(scene.body.center_of_mass, com)
    # about the origin, I_zz = sum m (x^2 + y^2) = 0.01 * 3; I_xx = sum m (y^2 + z^2)
    assert scene.body.inertia_array[2, 2] == pytest.approx(0.03)
    assert scene.body.inertia_array[0, 0] == pytest.approx(3.0 + 0.01)
    assert scene.is_top and scene.body.mass == pytest.approx(3.0)


def test_topic_inputs_schedules_and_options_are_kept():
    text = MINIMAL + (
        "torque_inputs:\n"
        "  - {topic: /cmd, type: Vector3Stamped, frame: world, hold: {timeout: 0.25}}\n"
        "  - {topic: ~/torque}\n"
        "  - schedule: {frame: world, segments: [{start: 0.5, torque: [1, 0, 0]}, {start: 2, torque: [0, 0, 0]}]}\n"
        "integrator: {method: taylor, dt: 0.002, options: {tol: 1.0e-10}}\n"
    )
    scene = parse(text)
    first, second = scene.topic_inputs
    assert (first.topic, first.message_type, first.frame, first.timeout) == ("/cmd", "Vector3Stamped", "world", 0.25)
    assert (second.topic, second.message_type, second.frame, second.timeout) == (
        "~/torque",
        "WrenchStamped",
        "body",
        None,
    )
    (schedule,) = scene.schedules
    assert schedule.frame == "world"
    assert schedule.change_steps(0.002) == (250, 1000)
    assert schedule.torque_at_step(249, 0.002) == (0.0, 0.0, 0.0)
    assert schedule.torque_at_step(250, 0.002) == (1.0, 0.0, 0.0)
    assert schedule.torque_at_step(999, 0.002) == (1.0, 0.0, 0.0)
    assert schedule.torque_at_step(2500, 0.002) == (0.0, 0.0, 0.0)
    assert scene.integrator.method == "taylor" and scene.integrator.dt == 0.002
    assert dict(scene.integrator.options) == {"tol": 1e-10}
    assert scene.torque_kind == "topic"


def test_a_schedule_switches_on_the_engines_boundary_not_a_step_late():
    # 30 * 0.03 = 0.8999999999999999 < 0.9, yet 0.9 s counts as on boundary 30 (as the engine's clock says)
    scene = parse(
        "body: {principal_moments: [1, 2, 3]}\n"
        "torque_inputs:\n"
        "  - schedule: {segments: [{start: 0, torque: [1, 0, 0]}, {start: 0.9, torque: [0, 0, 0]}]}\n"
    )
    (schedule,) = scene.schedules
    assert schedule.change_steps(0.03) == (0, 30)
    assert schedule.torque_at_step(29, 0.03) == (1.0, 0.0, 0.0)
    assert schedule.torque_at_step(30, 0.03) == (0.0, 0.0, 0.0)
    assert schedule.change_steps(0.009) == (0, 100)


def test_mass_properties_about_com_undo_the_pivot_shift_of_a_gravity_scene():
    from rigid_rot_sim.core.inertia import parallel_axis_shift

    top = load_scene(SCENES / "heavy_top.yaml")
    mass, com, tensor = top.mass_properties_about_com()
    assert mass == top.body.mass and com == top.body.center_of_mass
    assert not np.allclose(tensor, top.body.inertia_array)  # the scene's tensor is about the pivot
    assert np.allclose(parallel_axis_shift(tensor, mass, com), top.body.inertia_array, rtol=1e-14, atol=0.0)
    free = load_scene(SCENES / "free_tumble.yaml")  # no gravity: the tensor is already about the COM
    free_mass, free_com, free_tensor = free.mass_properties_about_com()
    assert free_com == (0.0, 0.0, 0.0) and np.array_equal(free_tensor, free.body.inertia_array)


def test_yaml_1_2_numbers_are_numbers_everywhere_a_scene_reads_them():
    """``1e-3`` is a float in YAML 1.2 (ROS params files, ``-p``, JSON Schema), a string in YAML 1.1 (issue 40)."""
    text = """
body: {principal_moments: [8e-1, 1.2E0, 15e-1]}
initial: {angular_velocity: [1e-3, -2e-1, 2E+0]}
integrator: {method: rk4, dt: 5e-4}
duration: 1e1
"""
    scene = parse(text, "yaml12.yaml")
    assert np.array_equal(np.diag(scene.body.inertia_array), [0.8, 1.2, 1.5])
    assert scene.initial.angular_velocity == (0.001, -0.2, 2.0)
    assert scene.integrator.dt == 5e-4 and scene.duration == 10.0
    assert parse('body: {principal_moments: [1, 2, 3]}\nname: "1e-3"\n', "q.yaml").name == "1e-3"  # quoted: a string


def test_a_subnormal_real_time_factor_is_refused_naming_the_key():
    with pytest.raises(SceneError, match=r"real_time_factor: must be 0 \(as fast as possible\) or from 1e-06"):
        parse(MINIMAL + "real_time_factor: 5.0e-324\n", "slow.yaml")
    assert parse(MINIMAL + "real_time_factor: 1.0e-6\n").real_time_factor == 1e-6
