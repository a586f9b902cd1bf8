"""The node's parameters as data: one table drives declaration, reading, validation and application.

:data:`PARAMETERS` holds one :class:`ParamSpec` per parameter: name, type, default (read
from the scene), description, range or choices, ``read_only`` and, for those that change a
running simulation, ``check`` (refuse a bad value with a reason) and ``apply`` (act on the
run). Everything else is a loop over the table:

* :func:`declare_parameters` declares each with a ``ParameterDescriptor`` (ranges from
  :mod:`rigid_rot_sim.core.limits`), the scene's value as default;
* :func:`read_settings` reads them back once into :class:`NodeSettings`, frozen and read
  by spec (``settings[DT]`` is a float), refusing a value outside its choices;
* :class:`RunParameters` refuses bad run-time values (``validate``) and applies good ones
  (``apply``), each check and apply function called once per change, as ros2/demos'
  ``set_parameters_callback.py`` does. rclpy itself enforces types, ranges and read-only.

Adding a parameter is one entry in :data:`PARAMETERS` (plus, where it acts at run time, its
``apply``), and reading it where it is used: ``settings[NEW]``.

Scene or node?
--------------
The *scene* describes the world: the body (inertia, mass, centre of mass), the initial
state, the torques (topic inputs, schedules), gravity and the frame names. These are not
parameters, except the frame names (``world_frame``, ``body_frame``), which a deployment
may have to rename to fit its tf tree. The *node* settings say how one run of that world is
served: integrator and step, pacing (``real_time_factor``, ``duration``,
``start_paused``), publish rates, QoS, command limits and recording. They are parameters;
a scene may carry a default for most of them (keys ``integrator``, ``real_time_factor``,
``duration``, ``outputs``, ``qos``, ``commands``, ``recording``) so that a scene file runs
as its author meant, and a parameter (``-p``, a params file, ``ros2 param set``) wins.

Where the parameter names appear besides this table
---------------------------------------------------
* :mod:`rigid_rot_sim.scene.scene_schema`: the scene keys that give the defaults, named
  for a scene file (``integrator.dt``, ``outputs.state``, ...), not for the node;
* :mod:`rigid_rot_sim.cli.run` turns its options into ``-p`` arguments, by the specs here;
* ``launch/rigid_rot_sim.launch.py`` (``scene``, ``record_path``), ``config/params/*.yaml``,
  the docs and the tests: interfaces that users type, which must name them.

Double parameters that accept integers
--------------------------------------
``ros2 param set /rigid_rot_sim real_time_factor 2`` sends an INTEGER; rclpy refuses it
for a parameter declared DOUBLE ("expected DOUBLE got INTEGER"), and so does a params file
or ``-p dt:=1`` at start-up. Users type integers, so the node converts them for every
``float`` entry of the table, and the value is stored as a float (the parameter stays
statically typed DOUBLE, as ``ros2 param describe`` shows).
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import math
import types
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter

from rigid_rot_sim.core import limits
from rigid_rot_sim.recording import LOG_TIME_BASES  # the package itself is light (no mcap)
from rigid_rot_sim.ros.outputs import output_topic
from rigid_rot_sim.run.lockstep import Lockstep
from rigid_rot_sim.run.pacing import RunDriver
from rigid_rot_sim.scene.scene import MAX_QOS_DEPTH, OUTPUT_NAMES, QOS_RELIABILITIES, Frames, LockstepSpec, Scene
from rigid_rot_sim.scene.scene_schema import LOCKSTEP_ON_TIMEOUT

#: Logged when ``use_sim_time`` is set true (a launch-wide ``use_sim_time:=true``, as Nav2 and
#: Gazebo bringups set it): accepted, since nothing in this node reads its ROS clock.
USE_SIM_TIME_NOTE = (
    "use_sim_time true accepted, but this node is the clock: it publishes /clock from its own simulation, "
    "stamps every output with sim time and paces itself on the steady clock, so nothing here changes; "
    "only its ROS clock now follows the /clock it publishes itself (the other nodes of the launch are "
    "the ones that need use_sim_time)"
)

V = TypeVar("V", bool, int, float, str, list)  # list: a string array


class Change:
    """A set of new parameter values, read by spec; a parameter not in it reads as it is now."""

    def __init__(self, new: Mapping[str, Any], current: Callable[[str], Any]) -> None:
        self.new = new
        self.current = current

    def __contains__(self, spec: ParamSpec[Any]) -> bool:
        return spec.name in self.new

    def __getitem__(self, spec: ParamSpec[V]) -> V:
        return self.new[spec.name] if spec.name in self.new else self.current(spec.name)


#: What a parameter does to the running simulation (``apply``) or how it refuses a value
#: (``check``: ValueError with the reason). Called once per change, however many of the
#: parameters sharing the function it holds.
Action = Callable[["RunParameters", Change], None]


@dataclass(frozen=True)
class ParamSpec(Generic[V]):
    """One node parameter: what :func:`declare_parameters` declares and the callbacks act on.

    ``type``: bool, int, float, str or list (a string array; an integer given for a float is stored as a float).
    ``default``: its default from the scene. ``range``: inclusive (low, high), for int and
    float. ``choices``: the accepted strings. ``read_only``: set at start-up only.
    """

    name: str
    type: type[V]
    default: Callable[[Scene], V]
    description: str
    range: tuple[float, float] | None = None
    choices: tuple[str, ...] = ()
    read_only: bool = False
    check: Action | None = None
    apply: Action | None = None

    def descriptor(self) -> ParameterDescriptor:
        descriptor = ParameterDescriptor(description=self.description, read_only=self.read_only)
        if self.range is not None and self.type is float:
            descriptor.floating_point_range = [
                FloatingPointRange(from_value=float(self.range[0]), to_value=float(self.range[1]), step=0.0)
            ]
        elif self.range is not None and self.type is int:
            descriptor.integer_range = [
                IntegerRange(from_value=int(self.range[0]), to_value=int(self.range[1]), step=1)
            ]
        if self.choices:
            descriptor.additional_constraints = "one of: " + ", ".join(self.choices)
        return descriptor

    def check_choice(self, value: Any) -> None:
        """ValueError naming the parameter when ``value`` is not one of its choices."""
        if self.choices and value not in self.choices:
            raise ValueError(f"{self.name} must be one of {', '.join(self.choices)}, got {value!r}")


# ---------------------------------------------------------------- run-time checks and actions


def _check_integrator(run: RunParameters, change: Change) -> None:
    dt = change[DT] if DT in change else run.driver.sim.clock.dt
    if not isinstance(dt, float) or not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be a finite number > 0 s, got {dt!r}")
    if dt != run.driver.sim.clock.dt and any(isinstance(o, Lockstep) for o in run.driver.sim.observers):
        raise ValueError("dt is fixed in lockstep (the turns are whole steps of it); restart to change it")
    run.driver.sim.check_integrator(change[INTEGRATOR], dt)


def _set_integrator(run: RunParameters, change: Change) -> None:
    sim, log = run.driver.sim, run.logger
    try:
        sim.set_integrator(method=change[INTEGRATOR], dt=change[DT] if DT in change else sim.clock.dt)
    except ValueError as exc:  # e.g. a method that cannot take this scene's torque
        log.error(f"integrator unchanged ({sim.stepper.method}, dt {sim.clock.dt:g} s): {exc}")
    else:
        log.info(f"integrator {sim.stepper.method}, dt {sim.clock.dt:g} s from t = {sim.clock.t:.9g} s")
        for warning in sim.warnings():
            log.warning(warning)
    run.retime()
    _set_rates(run, change)  # periods in steps depend on dt


def _check_real_time_factor_value(value: float) -> None:
    """ValueError outside :func:`limits.check_real_time_factor`'s range (5e-324 would never step)."""
    try:
        limits.check_real_time_factor(value)
    except ValueError as exc:
        raise ValueError(f"{REAL_TIME_FACTOR.name} {exc}") from None


def _check_real_time_factor(run: RunParameters, change: Change) -> None:
    _check_real_time_factor_value(change[REAL_TIME_FACTOR])


def _set_real_time_factor(run: RunParameters, change: Change) -> None:
    run.driver.pacer.real_time_factor = change[REAL_TIME_FACTOR]
    run.driver.pacer.anchor(run.driver.sim.clock.t)
    run.retime()


def _set_duration(run: RunParameters, change: Change) -> None:
    run.driver.duration = change[DURATION] or None


def _set_max_torque(run: RunParameters, change: Change) -> None:
    run.driver.sim.commands.max_torque = float(change[MAX_TORQUE])


def _check_rate_values(values: Iterable[tuple[ParamSpec[float], float]]) -> None:
    """ValueError naming the first rate outside :func:`limits.check_rate`'s range (5e-324 Hz has no period)."""
    for spec, rate in values:
        try:
            limits.check_rate(rate)
        except ValueError as exc:
            raise ValueError(f"{spec.name} {exc}") from None


def _check_rates(run: RunParameters, change: Change) -> None:
    periods = run.driver.schedule.periods
    _check_rate_values((spec, change[spec]) for spec in RATES.values() if spec in change)
    for output, spec in RATES.items():
        if spec in change and change[spec] > 0.0 and output not in periods:
            raise ValueError(f"{output_topic(output)} was not built at start-up; restart with {spec.name} > 0")
        if spec in change and change[spec] <= 0.0 and output in periods:
            raise ValueError(f"{spec.name} must be > 0 for a built output (publishers are not destroyed at run time)")


def _set_rates(run: RunParameters, change: Change) -> None:
    schedule = run.driver.schedule
    schedule.set_rates({output: change[RATES[output]] for output in schedule.periods}, run.driver.sim.clock.dt)


# ---------------------------------------------------------------- the table

INTEGRATOR = ParamSpec(
    "integrator",
    str,
    lambda scene: scene.integrator.method,
    "Integrator name from the registry, or 'auto' (the scene's choice)",
    check=_check_integrator,
    apply=_set_integrator,
)
DT = ParamSpec(
    "dt",
    float,
    lambda scene: scene.integrator.dt,
    "Physics step, s of sim time",
    range=limits.DT_RANGE,
    check=_check_integrator,
    apply=_set_integrator,
)
REAL_TIME_FACTOR = ParamSpec(
    "real_time_factor",
    float,
    lambda scene: scene.real_time_factor,
    "Sim seconds per wall second; 0 = as fast as possible",
    range=limits.REAL_TIME_FACTOR_RANGE,
    check=_check_real_time_factor,
    apply=_set_real_time_factor,
)
DURATION = ParamSpec(
    "duration",
    float,
    lambda scene: scene.duration or 0.0,
    "Sim time (s) after which the node stops and exits; 0 = unbounded",
    range=limits.DURATION_RANGE,
    apply=_set_duration,
)
START_PAUSED = ParamSpec(
    "start_paused",
    bool,
    lambda scene: False,
    "Start paused at t = 0 (resume with ~/pause data=false, e.g. once a controller is up)",
    read_only=True,
)
RECORD_PATH = ParamSpec(
    "record_path",
    str,
    lambda scene: scene.recording or "",
    "MCAP file to record the run to; empty = no recording",
    read_only=True,
)
RECORD_LOG_TIME = ParamSpec(
    "record_log_time",
    str,
    lambda scene: "sim",
    "MCAP log time of the recording: 'sim' (sim time in ns, as ros2 bag record --use-sim-time; "
    "continued across resets) or 'wall' (wall clock)",
    choices=LOG_TIME_BASES,
    read_only=True,
)
FOXGLOVE = ParamSpec(
    "foxglove",
    str,
    lambda scene: scene.foxglove or "",
    "Foxglove live server address [HOST:]PORT (host default 127.0.0.1); empty = no server "
    "(needs foxglove-sdk: pip install rigid_rot_sim[viewer])",
    read_only=True,
)
WEB = ParamSpec(
    "web",
    str,
    lambda scene: scene.web or "",
    "Web page address [HOST:]PORT (host default 127.0.0.1): the body in any browser, offline; empty = no page "
    "(needs viser: pip install rigid_rot_sim[web])",
    read_only=True,
)
WORLD_FRAME = ParamSpec(
    "world_frame",
    str,
    lambda scene: scene.frames.world,
    "Fixed frame of the attitude (header.frame_id of the outputs, /tf parent); "
    "default: the scene's frames.world (odom)",
    read_only=True,
)
BODY_FRAME = ParamSpec(
    "body_frame",
    str,
    lambda scene: scene.frames.body,
    "Body frame (child frame of /tf, ~/state and ~/odom, frame of ~/imu); default: the scene's frames.body (base_link)",
    read_only=True,
)
GROUND_TRUTH_VARIANCE = ParamSpec(
    "ground_truth_variance",
    float,
    lambda scene: 1e-12,
    "Variance on the covariance diagonals of ~/imu and ~/odom (the values are exact; "
    "0 would read as 'unknown' to sensor_msgs consumers)",
    range=(0.0, 1e6),
    read_only=True,
)
QOS_RELIABILITY = ParamSpec(
    "qos.reliability",
    str,
    lambda scene: scene.qos.reliability,
    "Reliability of the state-like outputs (~/state ... ~/top_state): reliable | best_effort "
    "(set at start-up; /tf, /tf_static, /clock keep their standard profiles)",
    choices=QOS_RELIABILITIES,
    read_only=True,
)
QOS_DEPTH = ParamSpec(
    "qos.depth",
    int,
    lambda scene: scene.qos.depth,
    "Keep-last depth of the state-like outputs (set at start-up)",
    range=(1, MAX_QOS_DEPTH),
    read_only=True,
)


def _scene_rate(output: str) -> Callable[[Scene], float]:
    return lambda scene: scene.outputs[output]


#: ``rates.<output>``: one per scene output, keyed on the output's name.
RATES: dict[str, ParamSpec[float]] = {
    output: ParamSpec(
        f"rates.{output}",
        float,
        _scene_rate(output),
        f"Publish rate of {output_topic(output)}, Hz of sim time (rounded to whole steps); "
        "0 = not built (set at start-up)",
        range=limits.RATE_RANGE,
        check=_check_rates,
        apply=_set_rates,
    )
    for output in OUTPUT_NAMES
}
MAX_TORQUE = ParamSpec(
    "commands.max_torque",
    float,
    lambda scene: scene.commands.max_torque,
    "Largest accepted |torque| (N*m) of a command or ~/apply_torque; 0 = no limit",
    range=limits.MAX_TORQUE_RANGE,
    apply=_set_max_torque,
)
COMMAND_DEPTH = ParamSpec(
    "commands.qos_depth",
    int,
    lambda scene: scene.commands.qos_depth,
    "Keep-last depth of the torque subscriptions (a larger burst loses its oldest commands)",
    range=limits.COMMAND_DEPTH_RANGE,
    read_only=True,
)
SIMULATION_INTERFACES_NAMESPACE = ParamSpec(
    "simulation_interfaces_namespace",
    str,
    lambda scene: scene.simulation_interfaces_namespace,
    "Where the simulation_interfaces services and the SimulateSteps action are served: '~' (the node's "
    "private names, ~/step_simulation), '/' (root names, /step_simulation, as generic clients look for them) "
    "or any namespace",
    read_only=True,
)
JOINT_STATE_COMMANDS = ParamSpec(
    "joint_state_topics.commands",
    str,
    lambda scene: scene.joint_state_topics.commands if scene.joint_state_topics else "",
    "Topic of the wheels' sensor_msgs/JointState commands (effort, N*m, per named wheel; ros2_control's "
    "topic hardware interface); empty = not built (docs/ros2_control.md)",
    read_only=True,
)
JOINT_STATE_STATES = ParamSpec(
    "joint_state_topics.states",
    str,
    lambda scene: scene.joint_state_topics.states if scene.joint_state_topics else "",
    "Topic of the wheels' sensor_msgs/JointState states (position rad, velocity rad/s, effort N*m; "
    "SensorDataQoS, at rates.wheels); empty = not built",
    read_only=True,
)

#: Every parameter of a node with a scene, in declaration order (``scene`` itself: :data:`SCENE`).
PARAMETERS: tuple[ParamSpec[Any], ...] = (
    INTEGRATOR,
    DT,
    REAL_TIME_FACTOR,
    DURATION,
    START_PAUSED,
    RECORD_PATH,
    RECORD_LOG_TIME,
    FOXGLOVE,
    WEB,
    WORLD_FRAME,
    BODY_FRAME,
    GROUND_TRUTH_VARIANCE,
    QOS_RELIABILITY,
    QOS_DEPTH,
    *RATES.values(),
    MAX_TORQUE,
    COMMAND_DEPTH,
    SIMULATION_INTERFACES_NAMESPACE,
    JOINT_STATE_COMMANDS,
    JOINT_STATE_STATES,
)


def _lockstep_inputs(scene: Scene) -> list[str]:
    if scene.lockstep is not None:
        return list(scene.lockstep.inputs)
    return [t.topic for t in scene.topic_inputs] or ["~/torque"]


#: ``lockstep.*``: read-only, the scene's ``lockstep`` section (or off) as defaults; declared by
#: :func:`rigid_rot_sim.ros.lockstep.declare_lockstep_parameters` and checked by the scene loader's rules
#: (:func:`rigid_rot_sim.ros.lockstep.lockstep_from_parameters`).
LOCKSTEP_PERIOD = ParamSpec(
    "lockstep.period",
    float,
    lambda scene: scene.lockstep.period if scene.lockstep else 0.0,
    "Lockstep: s of sim time between controller turns, a whole number of steps; 0 = off",
    range=(0.0, limits.DURATION_RANGE[1]),
    read_only=True,
)
LOCKSTEP_INPUTS = ParamSpec(
    "lockstep.inputs",
    list,
    _lockstep_inputs,
    "Lockstep: the torque topic inputs (or joint_state_topics.commands) waited for at every turn",
    read_only=True,
)
LOCKSTEP_TIMEOUT = ParamSpec(
    "lockstep.timeout",
    float,
    lambda scene: scene.lockstep.timeout if scene.lockstep else LockstepSpec.timeout,
    "Lockstep: s of wall time to wait for a turn's commands",
    range=(1e-3, limits.DURATION_RANGE[1]),
    read_only=True,
)
LOCKSTEP_ON_TIMEOUT_PARAM = ParamSpec(
    "lockstep.on_timeout",
    str,
    lambda scene: scene.lockstep.on_timeout if scene.lockstep else LockstepSpec.on_timeout,
    "Lockstep: pause | hold, what a turn that timed out does",
    choices=LOCKSTEP_ON_TIMEOUT,
    read_only=True,
)
LOCKSTEP: tuple[ParamSpec[Any], ...] = (LOCKSTEP_PERIOD, LOCKSTEP_INPUTS, LOCKSTEP_TIMEOUT, LOCKSTEP_ON_TIMEOUT_PARAM)
#: The whole table: the run's parameters, then ``lockstep.*`` (docs/node.md's parameter table is tested
#: against it).
ALL_PARAMETERS: tuple[ParamSpec[Any], ...] = PARAMETERS + LOCKSTEP


def markdown_table(specs: Iterable[ParamSpec[Any]] = ALL_PARAMETERS) -> str:
    """The parameter table of docs/node.md, generated from the specs (``test/ros/test_parameters.py`` compares)."""
    names = {bool: "bool", int: "int", float: "double", str: "string", list: "string[]"}
    rows = ["| parameter | type | read only | range or choices | description |", "|---|---|---|---|---|"]
    for spec in specs:
        bounds = ""
        if spec.range is not None:
            bounds = f"[{spec.range[0]:g}, {spec.range[1]:g}]"
        elif spec.choices:
            bounds = ", ".join(spec.choices)
        description = spec.description.replace("|", "\\|")
        read_only = "yes" if spec.read_only else ""
        rows.append(f"| `{spec.name}` | {names[spec.type]} | {read_only} | {bounds} | {description} |")
    return "\n".join(rows) + "\n"


#: Declared first, with or without a scene (default empty: no simulation); not in the table.
SCENE = ParamSpec(
    "scene",
    str,
    lambda scene: "",
    "Scene YAML path, or the name of a shipped scene (e.g. free_tumble); empty: serve ~/compute_inertia only",
    read_only=True,
)

_DOUBLES = frozenset(spec.name for spec in PARAMETERS if spec.type is float)


# ---------------------------------------------------------------- declaring and reading


def _as_double(parameter: Parameter) -> Parameter:
    return Parameter(parameter.name, Parameter.Type.DOUBLE, float(parameter.value))


def accept_integers_for_doubles(node: Node) -> None:
    """Convert INTEGER values set at run time for the table's float parameters (a pre-set callback)."""

    def convert(parameters: list[Parameter]) -> list[Parameter]:
        return [_as_double(p) if p.type_ == Parameter.Type.INTEGER and p.name in _DOUBLES else p for p in parameters]

    node.add_pre_set_parameters_callback(convert)


#: rclpy major versions whose private ``Node._parameter_overrides`` (name -> Parameter) we
#: convert in place; Jazzy ships rclpy 7. Elsewhere an integer start-up value for a float
#: parameter gets rclpy's own error (one line, exit code 2).
_OVERRIDES_TABLE_RCLPY_MAJORS = (7,)


def _startup_overrides(node: Node) -> dict[str, Parameter] | None:
    """rclpy's table of start-up values (``-p``, ``--params-file``, ``parameter_overrides``).

    They are checked against the declared type inside ``declare_parameter``, without the
    pre-set callbacks, and rclpy offers no public hook before that check: this reads the
    private table, only on the rclpy versions where we know it.
    """
    try:
        major = int(importlib.metadata.version("rclpy").split(".")[0])
    except (importlib.metadata.PackageNotFoundError, ValueError):  # pragma: no cover - installation
        return None
    overrides = getattr(node, "_parameter_overrides", None)
    if major not in _OVERRIDES_TABLE_RCLPY_MAJORS or not isinstance(overrides, dict):  # pragma: no cover
        return None
    return overrides


def declare_scene_parameter(node: Node) -> str:
    """The read-only ``scene`` parameter's value (empty: no simulation)."""
    return node.declare_parameter(SCENE.name, "", SCENE.descriptor()).value


def declare_parameters(node: Node, scene: Scene, specs: Iterable[ParamSpec[Any]] = PARAMETERS) -> None:
    """Declare ``specs`` once, the scene's values as defaults; integer start-up values of floats become floats."""
    specs = tuple(specs)
    overrides = _startup_overrides(node) or {}
    for spec in specs:
        override = overrides.get(spec.name)
        if spec.type is float and override is not None and override.type_ == Parameter.Type.INTEGER:
            overrides[spec.name] = _as_double(override)  # `-p dt:=1` or `dt: 1` in a params file: 1.0
        node.declare_parameter(spec.name, spec.type(spec.default(scene)), spec.descriptor())


@dataclass(frozen=True)
class NodeSettings:
    """The parameters' values at start-up, read by spec (``settings[DT]``), and the scene
    they configure (with the frame parameters' names: they override the scene's everywhere)."""

    scene: Scene
    values: Mapping[str, Any]

    def __getitem__(self, spec: ParamSpec[V]) -> V:
        return self.values[spec.name]

    def rates(self) -> dict[str, float]:
        """Publish rate by output name, Hz of sim time."""
        return {output: self[spec] for output, spec in RATES.items()}


def read_settings(node: Node, scene: Scene, specs: Iterable[ParamSpec[Any]] = PARAMETERS) -> NodeSettings:
    """The declared parameters' values; ValueError for a value outside its choices or bad frame names."""
    values = {spec.name: node.get_parameter(spec.name).value for spec in specs}
    settings = NodeSettings(scene, types.MappingProxyType(values))
    for spec in specs:
        spec.check_choice(settings[spec])
    _check_rate_values((spec, settings[spec]) for spec in RATES.values() if spec.name in values)
    if REAL_TIME_FACTOR.name in values:
        _check_real_time_factor_value(settings[REAL_TIME_FACTOR])
    frames = Frames(settings[WORLD_FRAME], settings[BODY_FRAME]).checked()
    return dataclasses.replace(settings, scene=dataclasses.replace(scene, frames=frames))


# ---------------------------------------------------------------- run-time changes


def explain_use_sim_time(node: Node) -> None:
    """Accept ``use_sim_time`` true at start-up and at run time, with or without a scene, and log
    :data:`USE_SIM_TIME_NOTE`: the node is the time source, nothing in it reads its ROS clock."""
    if node.get_parameter("use_sim_time").value is True:
        node.get_logger().warning(USE_SIM_TIME_NOTE)

    def validate(parameters: list[Parameter]) -> SetParametersResult:
        if any(p.name == "use_sim_time" and p.value is True for p in parameters):
            node.get_logger().warning(USE_SIM_TIME_NOTE)
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(validate)


def _once(actions: Iterable[Action | None]) -> list[Action]:
    """The distinct actions, in table order."""
    return list(dict.fromkeys(action for action in actions if action is not None))


class RunParameters:
    """Run-time parameter changes of a running scene: refused with a reason, or applied.

    ``driver``: the run; ``wake``: wakes the run loop, whose next turn follows dt and the
    real-time factor.
    """

    def __init__(
        self, node: Node, driver: RunDriver, wake: Callable[[], None], specs: Iterable[ParamSpec[Any]] = PARAMETERS
    ) -> None:
        self.node = node
        self.driver = driver
        self.wake = wake
        self.logger = node.get_logger()
        self.specs = tuple(specs)
        node.add_on_set_parameters_callback(self.validate)
        node.add_post_set_parameters_callback(self.apply)

    def _change(self, parameters: list[Parameter]) -> tuple[Change, list[ParamSpec[Any]]]:
        change = Change({p.name: p.value for p in parameters}, lambda name: self.node.get_parameter(name).value)
        return change, [spec for spec in self.specs if spec in change]

    def validate(self, parameters: list[Parameter]) -> SetParametersResult:
        """Refuse bad values with a reason; nothing changes then (applied after, if all are valid)."""
        change, changed = self._change(parameters)
        try:
            for spec in changed:
                spec.check_choice(change[spec])
            for check in _once(spec.check for spec in changed):
                check(self, change)
        except ValueError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def apply(self, parameters: list[Parameter]) -> None:
        """Apply the accepted values to the run (``get_parameter`` already returns them)."""
        change, changed = self._change(parameters)
        for action in _once(spec.apply for spec in changed):
            action(self, change)

    def retime(self) -> None:
        """After a change of dt or of the real-time factor: the run loop's next turn is timed anew."""
        self.wake()
