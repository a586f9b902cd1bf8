"""The node's parameters: declared once with descriptors, checked, then applied.

:func:`declare_parameters` declares every parameter with a ``ParameterDescriptor`` (ranges
from :mod:`rigid_rot_sim.core.limits`, ``read_only`` for what is set at start-up), the
scene's values as defaults; :func:`read_settings` reads them back once into
:class:`Settings`. :class:`ParameterCallbacks` refuses bad run-time values with a reason
(``validate_parameters_callback``) and applies good ones to the run
(``apply_parameters_callback``), as ros2/demos' ``set_parameters_callback.py`` does.

Double parameters that accept integers:

``ros2 param set /rigid_rot_sim real_time_factor 2`` sends an INTEGER; rclpy refuses it
for a parameter declared DOUBLE ("expected DOUBLE got INTEGER"), and so does a params file
or ``-p dt:=1`` at start-up. Users type integers, so the node converts them, and the value is
stored as a float (the parameter stays statically typed DOUBLE, as ``ros2 param describe``
shows).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, ParameterType, SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter

from rigid_rot_sim.core import limits
from rigid_rot_sim.run.pacing import RunDriver
from rigid_rot_sim.scene.scene import MAX_QOS_DEPTH, Frames, OutputQos, Scene
from rigid_rot_sim.recording import LOG_TIME_BASES  # the package itself is light (no mcap)
from rigid_rot_sim.ros.outputs import output_topic
from rigid_rot_sim.ros.qos import output_qos

USE_SIM_TIME_REFUSAL = (
    "use_sim_time true is refused: this node is the source of sim time (it publishes /clock and "
    "stamps every output with sim time); its pacing runs on the steady clock"
)


def _as_double(parameter: Parameter) -> Parameter:
    return Parameter(parameter.name, Parameter.Type.DOUBLE, float(parameter.value))


def accept_integers_for_doubles(node: Node) -> None:
    """Convert INTEGER values set at run time for declared DOUBLE parameters (a pre-set callback)."""

    def convert(parameters: list[Parameter]) -> list[Parameter]:
        converted = []
        for parameter in parameters:
            if (
                parameter.type_ == Parameter.Type.INTEGER
                and node.has_parameter(parameter.name)
                and node.describe_parameter(parameter.name).type == ParameterType.PARAMETER_DOUBLE
            ):
                parameter = _as_double(parameter)
            converted.append(parameter)
        return converted

    node.add_pre_set_parameters_callback(convert)


def integer_overrides_as_doubles(node: Node, names: list[str]) -> None:
    """Before declaring the DOUBLE parameters ``names``: integer start-up values become floats.

    Start-up values (``-p``, ``--params-file``, ``parameter_overrides``) are checked against the
    declared type inside ``declare_parameter``, without the pre-set callbacks, so they are
    converted here, in rclpy's table of overrides.
    """
    overrides = getattr(node, "_parameter_overrides", None)
    if not isinstance(overrides, dict):  # pragma: no cover - a future rclpy; test_node covers it
        return
    for name in names:
        override = overrides.get(name)
        if override is not None and override.type_ == Parameter.Type.INTEGER:
            overrides[name] = _as_double(override)


def _float_range(low: float, high: float) -> list[FloatingPointRange]:
    return [FloatingPointRange(from_value=low, to_value=high, step=0.0)]


def declare_scene_parameter(node: Node) -> str:
    """The read-only ``scene`` parameter (a path or a shipped scene's name; empty: no simulation)."""
    return node.declare_parameter(
        "scene",
        "",
        ParameterDescriptor(
            description="Scene YAML path, or the name of a shipped scene (e.g. free_tumble); "
            "empty: serve ~/compute_inertia only",
            read_only=True,
        ),
    ).value


def declare_parameters(node: Node, scene: Scene) -> None:
    """Declare every parameter once, with the scene's values as defaults."""
    doubles = ["dt", "real_time_factor", "duration", "commands.max_torque", "ground_truth_variance",
               *(f"rates.{name}" for name in scene.outputs.as_dict())]
    integer_overrides_as_doubles(node, doubles)  # `-p dt:=1` or `dt: 1` in a params file: 1.0
    declare = node.declare_parameter
    declare(
        "integrator",
        scene.integrator.method,
        ParameterDescriptor(description="Integrator name from the registry, or 'auto' (the scene's choice)"),
    )
    declare(
        "dt",
        scene.integrator.dt,
        ParameterDescriptor(description="Physics step, s of sim time", floating_point_range=_float_range(*limits.DT_RANGE)),
    )
    declare(
        "real_time_factor",
        scene.real_time_factor,
        ParameterDescriptor(
            description="Sim seconds per wall second; 0 = as fast as possible",
            floating_point_range=_float_range(*limits.REAL_TIME_FACTOR_RANGE),
        ),
    )
    declare(
        "duration",
        scene.duration if scene.duration is not None else 0.0,
        ParameterDescriptor(
            description="Sim time (s) after which the node stops and exits; 0 = unbounded",
            floating_point_range=_float_range(*limits.DURATION_RANGE),
        ),
    )
    declare(
        "start_paused",
        False,
        ParameterDescriptor(
            description="Start paused at t = 0 (resume with ~/pause data=false, e.g. once a controller is up)",
            read_only=True,
        ),
    )
    declare(
        "record_path",
        scene.recording or "",
        ParameterDescriptor(description="MCAP file to record the run to; empty = no recording", read_only=True),
    )
    declare(
        "record_log_time",
        "sim",
        ParameterDescriptor(
            description="MCAP log time of the recording: 'sim' (sim time in ns, as ros2 bag record "
            "--use-sim-time; continued across resets) or 'wall' (wall clock)",
            read_only=True,
            additional_constraints="one of: " + ", ".join(LOG_TIME_BASES),
        ),
    )
    declare(
        "world_frame",
        scene.frames.world,
        ParameterDescriptor(description="Fixed frame of the attitude (header.frame_id of the outputs, /tf parent); "
                            "default: the scene's frames.world (odom)", read_only=True),
    )
    declare(
        "body_frame",
        scene.frames.body,
        ParameterDescriptor(description="Body frame (child frame of /tf, ~/state and ~/odom, frame of ~/imu); "
                            "default: the scene's frames.body (base_link)", read_only=True),
    )
    declare(
        "ground_truth_variance",
        1e-12,
        ParameterDescriptor(
            description="Variance on the covariance diagonals of ~/imu and ~/odom (the values are exact; "
            "0 would read as 'unknown' to sensor_msgs consumers)",
            floating_point_range=_float_range(0.0, 1e6),
            read_only=True,
        ),
    )
    declare(
        "qos.reliability",
        scene.qos.reliability,
        ParameterDescriptor(
            description="Reliability of the state-like outputs (~/state ... ~/top_state): reliable | best_effort "
            "(set at start-up; /tf, /tf_static, /clock keep their standard profiles)",
            read_only=True,
            additional_constraints="reliable | best_effort",
        ),
    )
    declare(
        "qos.depth",
        scene.qos.depth,
        ParameterDescriptor(
            description="Keep-last depth of the state-like outputs (set at start-up)",
            read_only=True,
            integer_range=[IntegerRange(from_value=1, to_value=MAX_QOS_DEPTH, step=1)],
        ),
    )
    for name, rate in scene.outputs.as_dict().items():
        declare(
            f"rates.{name}",
            float(rate),
            ParameterDescriptor(
                description=f"Publish rate of {output_topic(name)}, Hz of sim time (rounded to whole steps); "
                "0 = not built (set at start-up)",
                floating_point_range=_float_range(*limits.RATE_RANGE),
            ),
        )
    declare(
        "commands.max_torque",
        float(scene.commands.max_torque),
        ParameterDescriptor(
            description="Largest accepted |torque| (N*m) of a command or ~/apply_torque; 0 = no limit",
            floating_point_range=_float_range(*limits.MAX_TORQUE_RANGE),
        ),
    )
    declare(
        "commands.qos_depth",
        int(scene.commands.qos_depth),
        ParameterDescriptor(
            description="Keep-last depth of the torque subscriptions (a larger burst loses its oldest commands)",
            integer_range=[IntegerRange(from_value=limits.COMMAND_DEPTH_RANGE[0], to_value=limits.COMMAND_DEPTH_RANGE[1], step=1)],
            read_only=True,
        ),
    )


@dataclass(frozen=True)
class Settings:
    """The parameters' values at start-up (the scene with the parameters' frames in ``scene``)."""

    scene: Scene
    integrator: str
    dt: float
    real_time_factor: float
    duration: float | None
    start_paused: bool
    record_path: str | None
    record_log_time: str
    ground_truth_variance: float
    state_qos: Any
    rates: dict[str, float]
    max_torque: float
    command_depth: int


def read_settings(node: Node, scene: Scene) -> Settings:
    """The declared parameters' values; ValueError for bad frame names or log time base."""
    value = lambda name: node.get_parameter(name).value  # noqa: E731
    # the frame parameters override the scene's names everywhere (simulator included)
    frames = Frames(value("world_frame"), value("body_frame"))
    scene = dataclasses.replace(scene, frames=frames.checked())
    if value("record_log_time") not in LOG_TIME_BASES:
        raise ValueError(f"record_log_time must be one of {', '.join(LOG_TIME_BASES)}, got {value('record_log_time')!r}")
    return Settings(
        scene=scene,
        integrator=value("integrator"),
        dt=value("dt"),
        real_time_factor=float(value("real_time_factor")),
        duration=float(value("duration")) if value("duration") > 0.0 else None,
        start_paused=value("start_paused"),
        record_path=value("record_path") or None,
        record_log_time=value("record_log_time"),
        ground_truth_variance=float(value("ground_truth_variance")),
        state_qos=output_qos(OutputQos(value("qos.reliability"), value("qos.depth"))),
        rates={name: value(f"rates.{name}") for name in scene.outputs.as_dict()},
        max_torque=float(value("commands.max_torque")),
        command_depth=value("commands.qos_depth"),
    )


class ParameterCallbacks:
    """Run-time parameter changes: refused with a reason, or applied to the run.

    Registered at once, so that ``use_sim_time`` true is refused even without a scene;
    :meth:`attach` gives it the run (and the timer whose period follows ``dt`` and r).
    """

    def __init__(self, node: Node) -> None:
        self.node = node
        self.run: RunDriver | None = None
        self.timer: Any = None
        node.add_on_set_parameters_callback(self.validate_parameters_callback)

    def attach(self, run: RunDriver, timer: Any) -> None:
        self.run = run
        self.timer = timer
        self.node.add_post_set_parameters_callback(self.apply_parameters_callback)

    def validate_parameters_callback(self, parameters: list[Parameter]) -> SetParametersResult:
        """Refuse bad values with a reason; nothing changes then (applied after, if all are valid)."""
        values = {p.name: p.value for p in parameters}
        try:
            if values.get("use_sim_time") is True:
                raise ValueError(USE_SIM_TIME_REFUSAL)
            if self.run is None:
                return SetParametersResult(successful=True)
            sim, periods = self.run.sim, self.run.schedule.periods
            if "integrator" in values or "dt" in values:
                method = values.get("integrator", self.node.get_parameter("integrator").value)
                dt = values.get("dt", sim.dt)
                if dt != sim.dt and getattr(self.node, "lockstep", None) is not None:
                    raise ValueError("dt is fixed in lockstep (the turns are whole steps of it); restart to change it")
                if not isinstance(dt, float) or not (math.isfinite(dt) and dt > 0.0):
                    raise ValueError(f"dt must be a finite number > 0 s, got {dt!r}")
                sim.check_integrator(method, dt)
            for name, value in values.items():
                if name.startswith("rates."):
                    output = name[len("rates."):]
                    if value > 0.0 and output not in periods:
                        raise ValueError(f"{output_topic(output)} was not built at start-up; restart with {name} > 0")
                    if value <= 0.0 and output in periods:
                        raise ValueError(f"{name} must be > 0 for a built output (publishers are not destroyed at run time)")
        except ValueError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def apply_parameters_callback(self, parameters: list[Parameter]) -> None:
        values = {p.name: p.value for p in parameters}
        run, log = self.run, self.node.get_logger()
        sim = run.sim
        if "integrator" in values or "dt" in values:
            try:
                sim.set_integrator(
                    method=values.get("integrator", self.node.get_parameter("integrator").value), dt=values.get("dt", sim.dt)
                )
            except ValueError as exc:  # e.g. a method that cannot take this scene's torque
                log.error(f"integrator unchanged ({sim.method}, dt {sim.dt:g} s): {exc}")
            else:
                log.info(f"integrator {sim.method}, dt {sim.dt:g} s from t = {sim.t:.9g} s")
                for warning in sim.warnings():
                    log.warning(warning)
        if "real_time_factor" in values:
            run.pacer.real_time_factor = float(values["real_time_factor"])
            run.pacer.anchor(sim.t)
        if "duration" in values:
            run.duration = values["duration"] if values["duration"] > 0.0 else None
        if "commands.max_torque" in values:
            sim.max_torque = float(values["commands.max_torque"])
        if {"integrator", "dt", "real_time_factor"} & values.keys():
            self.timer.timer_period_ns = int(run.pacer.tick_period(sim.dt) * 1e9)
        if {"integrator", "dt"} & values.keys() or any(name.startswith("rates.") for name in values):
            # periods in steps depend on dt; get_parameter already returns the new values here
            run.schedule.set_rates({name: self.node.get_parameter(f"rates.{name}").value
                                    for name in run.schedule.periods}, sim.dt)
