"""The node's parameter table: what it declares is what the table says, and each name is written once."""

import ast
from pathlib import Path

import pytest
import rclpy  # make setup installs it: these tests always run
from rcl_interfaces.msg import ParameterType
from rclpy.parameter import Parameter

from rigid_rot_sim.ros import parameters
from rigid_rot_sim.ros.lockstep import LOCKSTEP_PARAMETERS  # noqa: E402
from rigid_rot_sim.ros.node import RigidRotSimNode  # noqa: E402
from rigid_rot_sim.scene.scene import OUTPUT_NAMES, load_scene  # noqa: E402
from rigid_rot_sim.share import resolve_scene  # noqa: E402

PACKAGE = Path(parameters.__file__).resolve().parents[1]
TYPES = {
    bool: ParameterType.PARAMETER_BOOL,
    int: ParameterType.PARAMETER_INTEGER,
    float: ParameterType.PARAMETER_DOUBLE,
    str: ParameterType.PARAMETER_STRING,
    list: ParameterType.PARAMETER_STRING_ARRAY,
}
#: String literals in ros/ and cli/ equal to a parameter name that are NOT that parameter:
#: the recording's integrator record and event kind, and argparse's names for the CLI options.
NOT_PARAMETERS = {
    ("ros/recording.py", "dt"),
    ("ros/recording.py", "integrator"),
    ("cli/run.py", "scene"),
    ("cli/run.py", "real_time_factor"),
    ("cli/run.py", "record_log_time"),
}


@pytest.fixture
def node():
    context = rclpy.Context()
    rclpy.init(context=context)
    made = RigidRotSimNode(context=context, parameter_overrides=[Parameter("scene", value="heavy_top")])
    yield made
    made.destroy_node()
    rclpy.shutdown(context=context)


def test_the_table_is_what_the_node_declares(node):
    names = [spec.name for spec in parameters.PARAMETERS]
    assert len(names) == len(set(names))
    assert [spec.name for spec in parameters.RATES.values()] == [f"rates.{name}" for name in OUTPUT_NAMES]
    declared = set(node.list_parameters([], 0).names)
    # lockstep.* are one block of their own (ros/lockstep.py): lockstep.inputs is a string array
    lockstep = set(LOCKSTEP_PARAMETERS)
    assert declared == set(names) | lockstep | {parameters.SCENE.name, "use_sim_time", "start_type_description_service"}
    assert lockstep == {spec.name for spec in parameters.LOCKSTEP}  # the table's entries
    scene = load_scene(resolve_scene("heavy_top"))
    for spec in parameters.ALL_PARAMETERS:
        described = node.describe_parameter(spec.name)
        assert described.type == TYPES[spec.type], spec.name
        assert described.read_only == spec.read_only and described.description == spec.description, spec.name
        assert node.get_parameter(spec.name).value == spec.default(scene), spec.name
        if spec.range is not None:
            (declared_range,) = described.floating_point_range or described.integer_range
            assert (declared_range.from_value, declared_range.to_value) == spec.range, spec.name
        if spec.choices:
            assert described.additional_constraints == "one of: " + ", ".join(spec.choices)


def test_settings_read_by_spec_are_typed_values(node):
    settings = parameters.read_settings(node, node.run.scene)
    assert settings[parameters.DT] == node.run.sim.clock.dt and isinstance(settings[parameters.DT], float)
    assert settings.rates() == {name: node.get_parameter(f"rates.{name}").value for name in OUTPUT_NAMES}


def test_run_time_checks_and_actions_run_once_per_change(node):
    # integrator and dt share their check and action: one set_integrator for both
    from rigid_rot_sim.run.observer import SimulationObserver

    changes = []

    class Spy(SimulationObserver):
        def integrator_changed(self, step, method, dt, options):
            changes.append((method, dt))

    node.run.sim.add_observer(Spy())
    result = node.set_parameters_atomically([Parameter("integrator", value="rk4"), Parameter("dt", value=0.002)])
    assert result.successful and changes == [("rk4", 0.002)]
    refused = node.set_parameters([Parameter("rates.odom", value=5.0)])[0]  # ~/odom was not built
    assert not refused.successful and "restart with rates.odom > 0" in refused.reason


def test_each_parameter_name_is_written_once_in_ros_and_cli():
    rates = {spec.name for spec in parameters.RATES.values()}  # written once, as f"rates.{output}"
    names = {spec.name for spec in parameters.PARAMETERS} - rates | {parameters.SCENE.name, "rates."}
    written: dict[str, list[str]] = {}
    for path in [*PACKAGE.joinpath("ros").glob("*.py"), *PACKAGE.joinpath("cli").glob("*.py")]:
        where = path.relative_to(PACKAGE).as_posix()
        for item in ast.walk(ast.parse(path.read_text())):
            if isinstance(item, ast.Constant) and item.value in names and (where, item.value) not in NOT_PARAMETERS:
                written.setdefault(item.value, []).append(f"{where}:{item.lineno}")
    assert {name: places for name, places in written.items() if len(places) != 1} == {}
    assert set(written) == names


def test_a_rate_with_no_period_in_steps_is_refused_at_run_time_and_at_start_up(node):
    """5e-324 Hz is within the descriptor's range but 1 / (rate * dt) overflows: refused with the reason
    (an OverflowError out of the parameter callback before, issue 29); the schedule is unchanged."""
    periods = dict(node.run.driver.schedule.periods)
    refused = node.set_parameters([Parameter("rates.state", value=5e-324)])[0]
    assert not refused.successful
    assert refused.reason.startswith("rates.state must be 0 (not published) or from 1e-09 to 1e+06 Hz"), refused.reason
    assert node.run.driver.schedule.periods == periods and node.get_parameter("rates.state").value > 1.0
    assert node.set_parameters([Parameter("rates.state", value=2e-9)])[0].successful  # slow, but a period
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        overrides = [Parameter("scene", value="free_tumble"), Parameter("rates.clock", value=1e-300)]
        with pytest.raises(ValueError, match=r"^rates.clock must be 0 .* got 1e-300$"):
            RigidRotSimNode(context=context, parameter_overrides=overrides)
    finally:
        rclpy.shutdown(context=context)


DOCS = PACKAGE.parent / "docs" / "node.md"


def test_the_parameter_table_of_docs_node_md_is_generated_from_the_table():
    """docs/node.md's table is ``markdown_table()`` verbatim: a parameter added, renamed or re-described
    fails here until the docs follow (paste the expected text printed below between the markers)."""
    text = DOCS.read_text(encoding="utf-8")
    start = text.index("-->\n", text.index("<!-- generated from rigid_rot_sim.ros.parameters.markdown_table()")) + 4
    end = text.index("<!-- end of the generated table -->")
    expected = parameters.markdown_table()
    assert text[start:end] == expected, f"docs/node.md's parameter table is stale; it should read:\n{expected}"
    for name in ("scene", *(spec.name for spec in parameters.ALL_PARAMETERS if not spec.name.startswith("rates."))):
        assert f"`{name}`" in text


def test_the_topic_table_of_docs_node_md_names_every_output():
    """Every output of the table (scene_schema's OUTPUTS, ros/outputs' publishers) has its row, and every
    row names an output, an input or a static topic."""
    from rigid_rot_sim.ros.outputs import output_topic

    text = DOCS.read_text(encoding="utf-8")
    section = text[text.index("## Topics") : text.index("## Frames")]
    rows = [line.split("|")[1].strip() for line in section.splitlines() if line.startswith("| `")]
    topics = {row.split("`")[1] for row in rows}
    outputs = {output_topic(name) for name in OUTPUT_NAMES}
    assert outputs <= topics, sorted(outputs - topics)
    # not rates.<output>: the static and event topics, the inputs, and the JointState door's (named by parameters)
    others = {"~/mass_properties", "~/rejected", "/tf_static", "~/wheel_torque", "~/sim_events"}
    others |= {"joint_state_topics.commands", "joint_state_topics.states"}
    assert topics - outputs == others, sorted(topics - outputs)


def test_a_real_time_factor_that_never_reaches_a_step_is_refused_at_run_time(node):
    """5e-324 is within the descriptor's range (0 to 1000) but the run would never advance (issue 40)."""
    pace = node.run.driver.pacer.real_time_factor
    refused = node.set_parameters([Parameter("real_time_factor", value=5e-324)])[0]
    assert not refused.successful
    assert refused.reason.startswith("real_time_factor must be 0 (as fast as possible) or from 1e-06"), refused.reason
    assert node.run.driver.pacer.real_time_factor == pace
    assert node.set_parameters([Parameter("real_time_factor", value=0.0)])[0].successful  # as fast as possible
