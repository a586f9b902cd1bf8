"""Scene files beyond the documented limits (issue 9, items 6 and 7): each is refused with one
short SceneError line, quickly, and never with another exception or a numpy warning."""

import time
import warnings

import pytest

from rigid_rot_sim.core import limits
from rigid_rot_sim.scene.bounded_yaml import BoundedYAMLError, load_bounded
from rigid_rot_sim.scene.names import check_topic_name
from rigid_rot_sim.scene.scene import SceneError, load_scene, parse_scene_text

MINIMAL = "body: {principal_moments: [1.0, 2.0, 2.5]}\n"

ALIAS_BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, "
    f"*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}]\n"
    for i in range(9)
)
STRING_BOMB = (
    'a: &a "' + "x" * 1000 + '"\nb: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a, *a]\nc: [*b, *b, *b, *b, *b, *b, *b, *b]\n'
)


def refused(text: str, source: str = "bad.yaml") -> str:
    """The one-line SceneError message for ``text``; the test fails on any other outcome."""
    start = time.monotonic()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a leaked numpy RuntimeWarning fails the test
        with pytest.raises(SceneError) as info:
            parse_scene_text(text, source=source)
    assert time.monotonic() - start < 5.0, "a refused scene must be refused quickly"
    message = str(info.value)
    assert "\n" not in message and len(message) <= 400, message
    return message


@pytest.mark.parametrize(
    "text, expected",
    [
        # RecursionError before: deeply nested YAML
        (MINIMAL + "description: " + "[" * 5000 + "]" * 5000 + "\n", "nested deeper than 16 levels"),
        (MINIMAL + "x:\n" + "".join("  " * i + f"k{i}:\n" for i in range(1, 40)), "nested deeper than 16 levels"),
        # OverflowError before: integers too large for a float
        (
            "body: {principal_moments: [1, 2, " + "9" * 400 + "]}\n",
            "body.principal_moments[2]: must be a number of magnitude",
        ),
        (MINIMAL + "real_time_factor: " + "1" * 330 + "\n", "real_time_factor: must be a number of magnitude"),
        # rclpy InvalidParameterValueException before: outside the parameters' ranges
        (MINIMAL + "integrator: {dt: 20}\n", "integrator.dt: must be <= 10"),
        (MINIMAL + "integrator: {dt: 1.0e-8}\n", "integrator.dt: must be >= 1e-07"),
        (MINIMAL + "real_time_factor: 5000\n", "real_time_factor: must be <= 1000"),
        (MINIMAL + "outputs: {state: 2.0e+6}\n", "outputs.state: must be <= 1e+06"),
        (MINIMAL + "duration: 2.0e+9\n", "duration: must be <= 1e+09"),
        # rclpy InvalidTopicName before
        (MINIMAL + "torque_inputs: [{topic: ~/tor-que}]\n", "character '-' not allowed"),
        (MINIMAL + "torque_inputs: [{topic: 9torque}]\n", "must not start with a digit"),
        (MINIMAL + "torque_inputs: [{topic: /a//b}]\n", "must not contain '//'"),
        (MINIMAL + "torque_inputs: [{topic: a/~/b}]\n", "'~' is allowed only as the leading"),
        (MINIMAL + "torque_inputs: [{topic: a/}]\n", "must not end with '/'"),
        # hangs before: alias bombs in a list and in a string
        (MINIMAL + ALIAS_BOMB, "YAML aliases (*a) are not accepted"),
        (MINIMAL + STRING_BOMB, "YAML aliases (*a) are not accepted"),
        # magnitudes that overflowed in numpy (RuntimeWarning) before
        (
            "body: {principal_moments: [1.0e+300, 1.0e+300, 1.0e+300]}\n",
            "body.principal_moments[0]: must be of magnitude <= 1e+12",
        ),
        (
            "body: {inertia_tensor: [[1.0e+300, 0, 0], [0, 1, 0], [0, 0, 1]]}\n",
            "body.inertia_tensor[0][0]: must be of magnitude",
        ),
        (
            MINIMAL + "initial: {angular_velocity: [1.0e+200, 0, 0]}\n",
            "initial.angular_velocity[0]: must be of magnitude",
        ),
        # new settings
        (MINIMAL + "commands: {max_torque: -1}\n", "commands.max_torque: must be >= 0"),
        (MINIMAL + "commands: {qos_depth: 0}\n", "commands.qos_depth: must be an integer from 1 to 10000"),
        (MINIMAL + "frames: {world: 'a b', body: body}\n", "frames.world: frame name 'a b' contains whitespace"),
        (
            MINIMAL + "integrator: {method: taylor, options: {tol: " + "9" * 400 + "}}\n",
            "integrator.options.tol: must be a number",
        ),
    ],
)
def test_scene_beyond_a_limit_is_one_short_scene_error(text, expected):
    message = refused(text)
    assert message.startswith("bad.yaml: ") and expected in message, message


def test_many_point_masses_are_refused_quickly():
    # 25 s to load before, hanging Ctrl-C; now the list limit stops it at the parser's events
    n = 100_000
    text = (
        "body:\n  point_masses:\n    masses: ["
        + ", ".join(["1"] * n)
        + "]\n    positions: ["
        + ", ".join(["[1, 2, 3]"] * n)
        + "]\n"
    )
    message = refused(text)
    assert f"more than the limit of {limits.MAX_SCENE_BYTES} bytes" in message, message


def test_point_masses_up_to_the_limit_load_in_reasonable_time():
    n = limits.MAX_POINT_MASSES
    masses = ", ".join(["1"] * n)
    positions = ", ".join(f"[{i % 7}, {i % 5}, {i % 3}]" for i in range(n))
    text = f"body:\n  point_masses:\n    masses: [{masses}]\n    positions: [{positions}]\n"
    assert len(text.encode()) < limits.MAX_SCENE_BYTES
    start = time.monotonic()
    scene = parse_scene_text(text)
    assert scene.body.masses is not None and len(scene.body.masses) == n
    assert time.monotonic() - start < 10.0
    too_many = text.replace("masses: [", "masses: [1, ", 1)
    assert "more than 10000" in refused(too_many)


def test_scene_file_size_is_bounded(tmp_path):
    path = tmp_path / "huge.yaml"
    path.write_text(MINIMAL + "description: '" + "x" * limits.MAX_SCENE_BYTES + "'\n")
    with pytest.raises(SceneError, match=r"huge.yaml: larger than the limit of 1048576 bytes"):
        load_scene(path)
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"body: \xff\xfe\n")
    with pytest.raises(SceneError, match="not UTF-8"):
        load_scene(binary)


def test_yaml_errors_are_one_line_with_the_position():
    message = refused("body: [1, 2\n")
    assert message.startswith("bad.yaml: not valid YAML: line 2, column 1:"), message
    message = refused("body: !!python/object:os.system {}\n")
    assert "not valid YAML" in message


def test_python_tags_are_never_constructed():
    with pytest.raises(BoundedYAMLError):
        load_bounded("!!python/object/apply:os.system ['echo hacked']\n")


def test_command_settings_are_kept():
    scene = parse_scene_text(MINIMAL + "commands: {max_torque: 2.5, qos_depth: 200}\n")
    assert scene.commands.max_torque == 2.5 and scene.commands.qos_depth == 200
    assert parse_scene_text(MINIMAL).commands.qos_depth == limits.DEFAULT_COMMAND_DEPTH


@pytest.mark.parametrize("name", ["~/torque", "torque", "/abs/torque", "ns/a_b/c9", "~"])
def test_valid_topic_names_pass(name):
    assert check_topic_name(name) == name


@pytest.mark.parametrize("name", ["", "/", "~torque", "a b", "a.b", "{node}/x", "a" * 300, "/9a"])
def test_invalid_topic_names_are_refused(name):
    with pytest.raises(ValueError, match="topic name"):
        check_topic_name(name)


def test_topic_name_rules_agree_with_rclpy():
    """rclpy (what the node calls when it subscribes) is the reference: the scene check agrees."""
    from rclpy.exceptions import InvalidTopicNameException
    from rclpy.expand_topic_name import expand_topic_name
    from rclpy.validate_full_topic_name import validate_full_topic_name

    def rclpy_validate(name):
        validate_full_topic_name(expand_topic_name(name, "rigid_rot_sim", "/"))

    names = [
        "~/torque",
        "torque",
        "/abs/torque",
        "~/tor-que",
        "9torque",
        "/a//b",
        "a/",
        "~torque",
        "a b",
        "/9a",
        "~/a//b",
        "x/9",
        "_a/_b",
        "~/",
    ]
    for name in names:
        try:
            check_topic_name(name)
            ours = True
        except ValueError:
            ours = False
        try:
            rclpy_validate(name)
            theirs = True
        except (InvalidTopicNameException, ValueError):
            theirs = False
        assert ours == theirs, name


# ---------------------------------------------------------------- what rates and durations imply (issue 29)

GYRO = "sensors: {gyro: {rate: %s}}\n"
STAR_TRACKER = "sensors: {star_tracker: {rate: %s, noise_equivalent_angle: [1.0e-5, 1.0e-5, 1.0e-4]}}\n"
ORBIT = "environment: {gravity_gradient: {orbit: {radius: %s}}}\n"


@pytest.mark.parametrize("rate", ["5.0e-324", "2.2250738585072014e-308", "1.0e-300", "9.0e-10"])
@pytest.mark.parametrize(
    "section, key",
    [
        ("outputs: {state: %s}\n", "outputs.state"),
        ("outputs: {imu: %s}\n", "outputs.imu"),
        (GYRO, "sensors.gyro.rate"),
        (STAR_TRACKER, "sensors.star_tracker.rate"),
    ],
)
def test_a_rate_with_no_period_in_steps_is_refused_naming_its_key(section, key, rate):
    """5e-324 Hz was an OverflowError traceback in period_steps: 1 / (rate * dt) is inf."""
    message = refused(MINIMAL + section % rate)
    assert f"{key}: must be 0 (not published) or from 1e-09 to 1e+06 Hz" in message, message
    assert f"got {float(rate)!r}" in message


def test_the_slowest_rate_loads_and_its_period_is_a_whole_number_of_steps():
    from rigid_rot_sim.run.pacing import OutputSchedule

    scene = parse_scene_text(MINIMAL + f"outputs: {{state: {limits.MIN_RATE:.17e}}}\nintegrator: {{dt: 1.0e-7}}\n")
    period = OutputSchedule.period_steps(scene.outputs["state"], scene.integrator.dt)
    assert isinstance(period, int) and period == round(1e9 / 1e-7)


@pytest.mark.parametrize("rate", [5e-324, 1e-300, float("nan"), float("inf"), -1.0, 2e6])
def test_period_steps_refuses_what_has_no_period_with_a_value_error(rate):
    from rigid_rot_sim.run.pacing import OutputSchedule

    with pytest.raises(ValueError, match="must be 0 .not published. or from 1e-09 to 1e.06 Hz"):
        OutputSchedule.period_steps(rate, 0.001)
    with pytest.raises(ValueError, match="not scheduled"):
        OutputSchedule.period_steps(0.0, 0.001)


@pytest.mark.parametrize("duration", ["5.0e-324", "1.0e-15"])
def test_a_duration_shorter_than_one_step_is_refused(duration):
    message = refused(MINIMAL + f"duration: {duration}\nintegrator: {{dt: 0.001}}\n")
    assert message.startswith("bad.yaml: duration: ") and "is not one step of integrator.dt 0.001 s" in message


@pytest.mark.parametrize("timeout", ["5.0e-324", "1.0e-300"])
def test_a_hold_timeout_shorter_than_one_step_is_refused(timeout):
    """The command would expire on the boundary where it takes effect: it would act for no step."""
    text = MINIMAL + f"torque_inputs: [{{topic: ~/torque, hold: {{timeout: {timeout}}}}}]\n"
    message = refused(text)
    assert "torque_inputs[0].hold.timeout: " in message and "(a command would act for no step)" in message


def test_a_duration_of_one_step_or_part_of_one_loads():
    assert parse_scene_text(MINIMAL + "duration: 4.0e-4\nintegrator: {dt: 0.001}\n").duration == 4e-4


@pytest.mark.parametrize("radius", ["5.0e-324", "1.0e-110", "1.0e-3"])
def test_an_orbit_whose_mean_motion_is_no_rate_is_refused(radius):
    """radius**3 underflowed to 0: mean_motion raised ZeroDivisionError when the run was built."""
    message = refused(MINIMAL + ORBIT % radius)
    assert "environment.gravity_gradient.orbit: radius" in message and "orbits per second" in message


def test_a_real_orbit_loads():
    scene = parse_scene_text(MINIMAL + ORBIT % "7.0e+6")
    assert scene.spacecraft.gravity_gradient is not None and scene.spacecraft.gravity_gradient.radius == 7e6
