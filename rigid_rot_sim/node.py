"""The rigid_rot_sim ROS 2 node: a scene simulated by :class:`~rigid_rot_sim.core.simulator.Simulator`.

The node only wires ROS interfaces to the core: physics happens in
``rigid_rot_sim.core`` (the Simulator), message conversions in ``rigid_rot_sim.conversions``.
It builds only what the scene needs and logs one start-up line saying what was built
and what was left out. Without a ``scene`` parameter it serves ``~/compute_inertia`` only.

Topics (names relative to the node; QoS in the README, section "The simulation node")
-----------------------------------------------------------------------------------
~/state (rigid_rot_msgs/RigidBodyState), ~/orientation (geometry_msgs/QuaternionStamped),
~/angular_velocity (Vector3Stamped, body frame), ~/angular_momentum (Vector3Stamped,
world frame), ~/mass_properties (geometry_msgs/InertiaStamped, transient local, once),
~/top_state (rigid_rot_msgs/HeavyTopState, gravity scenes), ~/rejected
(rigid_rot_msgs/RejectedCommand), ~/imu (sensor_msgs/Imu) and ~/odom (nav_msgs/Odometry)
when the scene asks for them, /tf (world -> body) and /tf_static (body -> principal
frame, where it differs from the body frame), both where tf2_msgs imports (``make setup``
builds it into the venv), /clock (sim time). QoS: rigid_rot_sim.qos.
Every header stamp is sim time. Frame names: the ``world_frame`` / ``body_frame``
parameters (default: the scene's ``frames``, REP 105 ``odom`` / ``base_link``), used by
every output, /tf and the recording. Torque inputs: the scene's topics (WrenchStamped or
Vector3Stamped).

Services
--------
~/compute_inertia, ~/set_state, ~/reset (std_srvs/Trigger), ~/pause (std_srvs/SetBool),
~/step (rigid_rot_msgs/Step, while paused; at most ``limits.MAX_STEPS_PER_REQUEST`` steps,
run in the service callback for at most ``STEP_REQUEST_WALL`` s: the reply says how many
were done), ~/apply_torque. A bad request gets ``success = false`` and the reason; nothing
raises out of a callback. Where simulation_interfaces is installed, also the standard
simulator services (:mod:`rigid_rot_sim.simulation_services`), through the same actions
(``~/step_simulation`` runs ``~/step``'s code, limits included).
Every limit is in :mod:`rigid_rot_sim.core.limits` (README, "Limits and failure behaviour").

Pacing
------
``real_time_factor`` r > 0: a wall-clock timer advances the simulation to
``r * (wall time since the anchor)`` each tick (at most ``MAX_TICK_WALL`` of work per
tick, so commands and services are served in between); r = 0: as fast as possible, in
batches of at most ``MAX_TICK_WALL`` wall time per tick. The states do not depend on r
or on the publish rates (see the Simulator's determinism notes). The timer runs on the
steady clock: the node is the source of sim time (/clock), so ``use_sim_time`` true is
refused (at start-up and at run time).
"""

from __future__ import annotations

import dataclasses
import math
import signal
import sys
import threading
import time
from typing import Any

import rclpy
from rclpy.clock import Clock as SteadyClock
from rclpy.clock_type import ClockType
from rclpy.exceptions import NameValidationException, ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from rclpy.signals import SignalHandlerOptions
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from geometry_msgs.msg import InertiaStamped, QuaternionStamped, Vector3Stamped, WrenchStamped
from nav_msgs.msg import Odometry
from rigid_rot_msgs.msg import HeavyTopState, RejectedCommand, RigidBodyState
from rigid_rot_msgs.srv import ApplyTorque, ComputeInertia, SetState, Step
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu
from std_srvs.srv import SetBool, Trigger

from rigid_rot_sim import conversions, simulation_services
from rigid_rot_sim.core import limits
from rigid_rot_sim.core.inertia import mass_properties, parallel_axis_shift, principal_frame_pose
from rigid_rot_sim.core.pacing import StepCost, falling_behind_message
from rigid_rot_sim.core.scene import MAX_QOS_DEPTH, OUTPUT_NAMES, Frames, OutputQos, Scene, load_scene
from rigid_rot_sim.core.simulator import CommandRejected, Simulator
from rigid_rot_sim.parameters import accept_integers_for_doubles, integer_overrides_as_doubles
from rigid_rot_sim.qos import (  # noqa: F401 (the profiles are part of this module's API)
    CLOCK_QOS,
    COMMAND_QOS,
    LATCHED_QOS,
    REJECTED_QOS,
    STATE_QOS,
    TF_QOS,
    TF_STATIC_QOS,
    describe as describe_qos,
    output_qos,
)
from rigid_rot_sim.share import ensure_ament_prefix_path, resolve_scene
from rigid_rot_sim.recording import LOG_TIME_BASES  # the package itself is light (no mcap)

try:  # never required: /tf exists only where tf2_msgs is installed
    from tf2_msgs.msg import TFMessage
except ImportError:  # pragma: no cover - depends on the installation
    TFMessage = None

NODE_NAME = "rigid_rot_sim"

#: Most wall time (s) one timer tick spends stepping, so the executor serves commands between.
MAX_TICK_WALL = 0.02
#: Most steps between two checks of the wall-clock deadline (fewer when steps are slow: core.pacing).
MAX_CHUNK = 256
#: Most wall time (s) one ~/step request spends stepping; the reply says if it stopped short.
STEP_REQUEST_WALL = 0.25
#: Wall-clock timer period bounds (s).
MIN_TICK = 0.001
MAX_TICK = 0.02
#: At r > 0, a backlog beyond this much wall time is dropped (the run re-anchors), with a warning.
MAX_BACKLOG_WALL = 0.5
#: Seconds between two warnings about rejected commands from the same source.
REJECT_WARN_PERIOD = 2.0

_OUTPUT_TYPES = {
    "state": RigidBodyState,
    "orientation": QuaternionStamped,
    "angular_velocity": Vector3Stamped,
    "angular_momentum": Vector3Stamped,
    "top_state": HeavyTopState,
    "imu": Imu,
    "odom": Odometry,
}


def _float_range(low: float, high: float) -> list[FloatingPointRange]:
    return [FloatingPointRange(from_value=low, to_value=high, step=0.0)]


USE_SIM_TIME_REFUSAL = (
    "use_sim_time true is refused: this node is the source of sim time (it publishes /clock and "
    "stamps every output with sim time); its pacing runs on the steady clock"
)


class RigidRotSimNode(Node):
    """Node ``rigid_rot_sim``; keyword arguments go to :class:`rclpy.node.Node`."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(NODE_NAME, **kwargs)
        log = self.get_logger()
        accept_integers_for_doubles(self)  # `ros2 param set ... real_time_factor 2` stores 2.0
        self.sim: Simulator | None = None
        self.add_on_set_parameters_callback(self.validate_parameters_callback)  # also for use_sim_time
        self.compute_inertia_service = self.create_service(
            ComputeInertia, "~/compute_inertia", self.compute_inertia_callback
        )
        self.finished = False
        self.recorder = None  # the recording wiring (rigid_rot_sim.recording) sets this
        scene_path = self.declare_parameter(
            "scene",
            "",
            ParameterDescriptor(
                description="Scene YAML path, or the name of a shipped scene (e.g. free_tumble); "
                "empty: serve ~/compute_inertia only",
                read_only=True,
            ),
        ).value
        if not scene_path:
            log.info("no scene parameter: serving ~/compute_inertia only (rigid-rot run SCENE starts a simulation)")
            return
        if self.get_parameter("use_sim_time").value is True:
            raise ValueError(USE_SIM_TIME_REFUSAL)
        scene = load_scene(resolve_scene(scene_path))  # SceneError names the file, key and problem
        self.scene = scene
        self.step_cost = StepCost()
        self._declare_parameters(scene)
        # the frame parameters override the scene's names everywhere (simulator included)
        frames = Frames(self.get_parameter("world_frame").value, self.get_parameter("body_frame").value)
        scene = dataclasses.replace(scene, frames=frames.checked())
        self.scene = scene
        if self.get_parameter("record_log_time").value not in LOG_TIME_BASES:
            raise ValueError(f"record_log_time must be one of {', '.join(LOG_TIME_BASES)}, "
                             f"got {self.get_parameter('record_log_time').value!r}")
        params = {name: self.get_parameter(name).value for name in ("integrator", "dt", "real_time_factor", "duration")}
        self.sim = Simulator(scene, method=params["integrator"], dt=params["dt"])
        self.sim.max_torque = float(self.get_parameter("commands.max_torque").value)
        self.real_time_factor = float(params["real_time_factor"])
        self.duration = float(params["duration"]) if params["duration"] > 0.0 else None
        self.record_path = self.get_parameter("record_path").value or None
        self.frames = scene.frames
        self.ground_truth_variance = float(self.get_parameter("ground_truth_variance").value)
        self.state_qos = output_qos(
            OutputQos(self.get_parameter("qos.reliability").value, self.get_parameter("qos.depth").value)
        )
        built: list[str] = [f"integrator {self.sim.method} (dt {self.sim.dt:g} s{', auto' if params['integrator'] == 'auto' else ''})"]
        left_out: list[str] = []

        # --- outputs: only those with a rate > 0, and the heavy-top one only for top scenes
        self.publishers_by_output: dict[str, Any] = {}
        self.output_periods: dict[str, int] = {}
        for name in OUTPUT_NAMES:
            rate = self.get_parameter(f"rates.{name}").value if self.has_parameter(f"rates.{name}") else 0.0
            if name == "top_state" and not scene.is_top:
                continue  # listed with gravity below
            if name == "tf" and TFMessage is None:
                left_out.append("/tf (tf2_msgs not installed)")
                continue
            if rate <= 0.0:
                left_out.append(f"{self._output_topic(name)} (rate 0)")
                continue
            if name == "tf":
                publisher = self.create_publisher(TFMessage, "/tf", TF_QOS)
            elif name == "clock":
                publisher = self.create_publisher(Clock, "/clock", CLOCK_QOS)
            else:
                publisher = self.create_publisher(_OUTPUT_TYPES[name], f"~/{name}", self.state_qos)
            self.publishers_by_output[name] = publisher
            self.output_periods[name] = self._period_steps(rate)
            built.append(f"{self._output_topic(name)} {rate:g} Hz ({describe_qos(publisher.qos_profile)})")
        self._create_tf_static(built, left_out)
        self.mass_properties_publisher = self.create_publisher(InertiaStamped, "~/mass_properties", LATCHED_QOS)
        self.rejected_publisher = self.create_publisher(RejectedCommand, "~/rejected", REJECTED_QOS)
        built += ["~/mass_properties (transient local)", "~/rejected"]

        # --- torque inputs: one subscription per topic input, none for a torque-free scene
        self.torque_subscriptions = []
        self._reject_warned: dict[str, tuple[float, int]] = {}
        command_qos = QoSProfile(
            depth=self.get_parameter("commands.qos_depth").value,
            reliability=COMMAND_QOS.reliability,
            durability=COMMAND_QOS.durability,
        )
        for spec in scene.topic_inputs:
            msg_type = WrenchStamped if spec.message_type == "WrenchStamped" else Vector3Stamped
            subscription = self.create_subscription(
                msg_type, spec.topic, lambda msg, source=spec.topic: self.torque_callback(msg, source), command_qos
            )
            self.torque_subscriptions.append(subscription)
            hold = "hold until replaced" if spec.timeout is None else f"zero {spec.timeout:g} s after the last command"
            built.append(
                f"torque input {subscription.topic_name} ({spec.message_type}, frame {spec.frame}, {hold}, "
                f"depth {command_qos.depth})"
            )
            if spec.message_type == "WrenchStamped":
                log.info(
                    f"{subscription.topic_name}: only wrench.torque acts on the body; "
                    "a command with a non-zero wrench.force is rejected"
                )
        if not scene.topic_inputs:
            left_out.append("torque subscriptions (no topic input)")
        if scene.schedules:
            built.append(f"{len(scene.schedules)} torque schedule(s)")
        if scene.gravity is None:
            left_out.append("gravity (no potential energy, no ~/top_state)")
        else:
            built.append(f"gravity {scene.gravity.acceleration:g} m/s^2 about the pivot")

        # --- services
        self.set_state_service = self.create_service(SetState, "~/set_state", self.set_state_callback)
        self.reset_service = self.create_service(Trigger, "~/reset", self.reset_callback)
        self.pause_service = self.create_service(SetBool, "~/pause", self.pause_callback)
        self.step_service = self.create_service(Step, "~/step", self.step_callback)
        self.apply_torque_service = self.create_service(ApplyTorque, "~/apply_torque", self.apply_torque_callback)
        self.simulation_services = None
        if simulation_services.AVAILABLE:
            self.simulation_services = simulation_services.SimulationServices(self)
            built.append("simulation_interfaces services (~/step_simulation, ~/reset_simulation, ...)")
        else:
            left_out.append("simulation_interfaces services (package not installed)")

        if self.record_path:
            self.recorder = self._start_recording()
            built.append(
                f"recording to {self.record_path} (log time: {self.get_parameter('record_log_time').value})"
                if self.recorder else "no recording (see the error above)"
            )
        else:
            left_out.append("recorder (nothing recorded)")

        try:
            self.add_post_set_parameters_callback(self.apply_parameters_callback)

            self.sim.pause(self.get_parameter("start_paused").value)
            self._anchor()
            # steady clock: the pacing never depends on /clock, which this node itself publishes
            self.timer = self.create_timer(
                self._tick_period(), self.timer_callback, clock=SteadyClock(clock_type=ClockType.STEADY_TIME)
            )
            log.info(
                f"scene {scene.name!r} ({scene.source}), rtf {self.real_time_factor:g}, "
                f"{'paused, ' if self.sim.paused else ''}"
                f"duration {'unbounded' if self.duration is None else f'{self.duration:g} s'}; "
                f"built: {'; '.join(built)}; left out: {'; '.join(left_out) or 'nothing'}"
            )
            for warning in self.sim.warnings():
                log.warning(warning)
            self._publish_mass_properties()
            if self.tf_static_publisher is not None:
                self.tf_static_publisher.publish(TFMessage(transforms=self.static_transforms))
            self._publish_due(force=True)
        except BaseException:  # e.g. Ctrl-C / SIGTERM while starting (main's start-up handler)
            if self.recorder is not None:
                self.recorder.close()  # the recording started above ends as a complete file
            raise

    # ------------------------------------------------------------------ set-up helpers

    def _start_recording(self) -> Any:
        """The recording wiring, or None (error logged) when it cannot start: the run goes on."""
        try:
            from rigid_rot_sim.recording.node_recording import attach  # imported only when recording
        except ImportError as exc:  # the mcap packages are optional at run time
            missing = (exc.name or "").split(".")[0] or str(exc)
            self.get_logger().error(f"recording disabled: {missing} is not installed (pip install mcap mcap-ros2-support)")
            return None
        # wraps self.sim and the publishers so that what changes the run and what is published
        # is recorded; None (error logged) when the file cannot be created
        return attach(self, self.record_path, log_time=self.get_parameter("record_log_time").value)

    def _declare_parameters(self, scene: Scene) -> None:
        """Declare every parameter once, with the scene's values as defaults."""
        doubles = ["dt", "real_time_factor", "duration", "commands.max_torque", "ground_truth_variance",
                   *(f"rates.{name}" for name in scene.outputs.as_dict())]
        integer_overrides_as_doubles(self, doubles)  # `-p dt:=1` or `dt: 1` in a params file: 1.0
        self.declare_parameter(
            "integrator",
            scene.integrator.method,
            ParameterDescriptor(description="Integrator name from the registry, or 'auto' (the scene's choice)"),
        )
        self.declare_parameter(
            "dt",
            scene.integrator.dt,
            ParameterDescriptor(description="Physics step, s of sim time", floating_point_range=_float_range(*limits.DT_RANGE)),
        )
        self.declare_parameter(
            "real_time_factor",
            scene.real_time_factor,
            ParameterDescriptor(
                description="Sim seconds per wall second; 0 = as fast as possible",
                floating_point_range=_float_range(*limits.REAL_TIME_FACTOR_RANGE),
            ),
        )
        self.declare_parameter(
            "duration",
            scene.duration if scene.duration is not None else 0.0,
            ParameterDescriptor(
                description="Sim time (s) after which the node stops and exits; 0 = unbounded",
                floating_point_range=_float_range(*limits.DURATION_RANGE),
            ),
        )
        self.declare_parameter(
            "start_paused",
            False,
            ParameterDescriptor(
                description="Start paused at t = 0 (resume with ~/pause data=false, e.g. once a controller is up)",
                read_only=True,
            ),
        )
        self.declare_parameter(
            "record_path",
            scene.recording or "",
            ParameterDescriptor(description="MCAP file to record the run to; empty = no recording", read_only=True),
        )
        self.declare_parameter(
            "record_log_time",
            "sim",
            ParameterDescriptor(
                description="MCAP log time of the recording: 'sim' (sim time in ns, as ros2 bag record "
                "--use-sim-time; continued across resets) or 'wall' (wall clock)",
                read_only=True,
                additional_constraints="one of: " + ", ".join(LOG_TIME_BASES),
            ),
        )
        self.declare_parameter(
            "world_frame",
            scene.frames.world,
            ParameterDescriptor(description="Fixed frame of the attitude (header.frame_id of the outputs, /tf parent); "
                                "default: the scene's frames.world (odom)", read_only=True),
        )
        self.declare_parameter(
            "body_frame",
            scene.frames.body,
            ParameterDescriptor(description="Body frame (child frame of /tf, ~/state and ~/odom, frame of ~/imu); "
                                "default: the scene's frames.body (base_link)", read_only=True),
        )
        self.declare_parameter(
            "ground_truth_variance",
            1e-12,
            ParameterDescriptor(
                description="Variance on the covariance diagonals of ~/imu and ~/odom (the values are exact; "
                "0 would read as 'unknown' to sensor_msgs consumers)",
                floating_point_range=_float_range(0.0, 1e6),
                read_only=True,
            ),
        )
        self.declare_parameter(
            "qos.reliability",
            scene.qos.reliability,
            ParameterDescriptor(
                description="Reliability of the state-like outputs (~/state ... ~/top_state): reliable | best_effort "
                "(set at start-up; /tf, /tf_static, /clock keep their standard profiles)",
                read_only=True,
                additional_constraints="reliable | best_effort",
            ),
        )
        self.declare_parameter(
            "qos.depth",
            scene.qos.depth,
            ParameterDescriptor(
                description="Keep-last depth of the state-like outputs (set at start-up)",
                read_only=True,
                integer_range=[IntegerRange(from_value=1, to_value=MAX_QOS_DEPTH, step=1)],
            ),
        )
        for name, rate in scene.outputs.as_dict().items():
            self.declare_parameter(
                f"rates.{name}",
                float(rate),
                ParameterDescriptor(
                    description=f"Publish rate of {self._output_topic(name)}, Hz of sim time (rounded to whole steps); "
                    "0 = not built (set at start-up)",
                    floating_point_range=_float_range(*limits.RATE_RANGE),
                ),
            )
        self.declare_parameter(
            "commands.max_torque",
            float(scene.commands.max_torque),
            ParameterDescriptor(
                description="Largest accepted |torque| (N*m) of a command or ~/apply_torque; 0 = no limit",
                floating_point_range=_float_range(*limits.MAX_TORQUE_RANGE),
            ),
        )
        self.declare_parameter(
            "commands.qos_depth",
            int(scene.commands.qos_depth),
            ParameterDescriptor(
                description="Keep-last depth of the torque subscriptions (a larger burst loses its oldest commands)",
                integer_range=[IntegerRange(from_value=limits.COMMAND_DEPTH_RANGE[0], to_value=limits.COMMAND_DEPTH_RANGE[1], step=1)],
                read_only=True,
            ),
        )

    def _create_tf_static(self, built: list[str], left_out: list[str]) -> None:
        """Fixed frames on /tf_static (latched), with /tf: the principal-axes frame where it is not the body frame."""
        self.tf_static_publisher = None
        self.static_transforms = []
        if "tf" not in self.publishers_by_output:
            return
        _, com, tensor = self._inertia_about_com()
        pose = principal_frame_pose(tensor, com)
        if pose is None:
            left_out.append(f"/tf_static (the body axes are the principal axes, {self.frames.principal} not needed)")
            return
        self.static_transforms.append(conversions.static_transform(*pose, self.frames.body, self.frames.principal))
        self.tf_static_publisher = self.create_publisher(TFMessage, "/tf_static", TF_STATIC_QOS)
        built.append(f"/tf_static {self.frames.body} -> {self.frames.principal} ({describe_qos(TF_STATIC_QOS)})")

    @staticmethod
    def _output_topic(name: str) -> str:
        return {"tf": "/tf", "clock": "/clock"}.get(name, f"~/{name}")

    def _period_steps(self, rate: float) -> int:
        assert self.sim is not None
        return max(1, int(round(1.0 / (rate * self.sim.dt))))

    def _tick_period(self) -> float:
        if self.real_time_factor <= 0.0:
            return MIN_TICK
        assert self.sim is not None
        return min(max(self.sim.dt / self.real_time_factor, MIN_TICK), MAX_TICK)

    def _anchor(self) -> None:
        """Restart wall-clock pacing from the current step."""
        assert self.sim is not None
        self._anchor_wall = time.monotonic()
        self._anchor_t = self.sim.t

    # ------------------------------------------------------------------ stepping

    def timer_callback(self) -> None:
        try:
            self._tick()
        except Exception as exc:  # never out of a callback: the run pauses with the reason, the node serves on
            self.get_logger().error(f"simulation paused: internal error {exc!r} (reset or set_state to continue)")
            if self.sim is not None:
                self.sim.fail(f"internal error: {exc!r}")

    def _tick(self) -> None:
        sim = self.sim
        if sim is None or sim.paused or self.finished:
            return
        now = time.monotonic()
        deadline = now + MAX_TICK_WALL
        if self.real_time_factor > 0.0:
            target_t = self._anchor_t + (now - self._anchor_wall) * self.real_time_factor
            behind_wall = (target_t - sim.t) / self.real_time_factor
            if behind_wall > MAX_BACKLOG_WALL:
                snapshot = sim.snapshot()
                self.get_logger().warning(
                    falling_behind_message(
                        self.real_time_factor, behind_wall, sim.method, sim.dt, self.step_cost.per_step,
                        math.hypot(*snapshot.angular_velocity_body.tolist()), math.hypot(*snapshot.torque_body.tolist()),
                    ),
                    throttle_duration_sec=5.0,
                )
                self._anchor_wall = now - MAX_TICK_WALL * 0.5
                self._anchor_t = sim.t
                target_t = sim.t + MAX_TICK_WALL * 0.5 * self.real_time_factor
            target = max(sim.step_at_or_before(target_t), sim.step_index)
        else:
            target = None
        self._run(target, deadline)

    def _run(self, target: int | None, deadline: float | None) -> None:
        """Step (publishing what is due) up to step ``target`` (None: unbounded) or the wall deadline."""
        sim = self.sim
        assert sim is not None
        end_step = sim.step_at_or_after(self.duration) if self.duration is not None else None
        while True:
            k = sim.step_index
            if end_step is not None and k >= end_step:
                self._finish()
                return
            stop = min(self._next_due(k), k + MAX_CHUNK)
            if deadline is not None:  # as many steps as the measured cost per step lets fit
                stop = min(stop, k + self.step_cost.steps_within(deadline - time.monotonic()))
            if target is not None:
                stop = min(stop, target)
            if end_step is not None:
                stop = min(stop, end_step)
            if stop <= k:
                break
            began = time.monotonic()
            self.step_cost.record(sim.advance_to(stop), time.monotonic() - began)
            if sim.failure is not None:
                self.get_logger().error(f"simulation paused: {sim.failure} (reset or set_state to continue)")
                self._publish_due(force=True)
                return
            self._publish_due()
            if deadline is not None and time.monotonic() >= deadline:
                break

    def _next_due(self, k: int) -> int:
        """The first step after k at which some output is due (k + 10**9 if none)."""
        periods = self.output_periods.values()
        return min(((k // n) + 1) * n for n in periods) if periods else k + 10**9

    def _finish(self) -> None:
        assert self.sim is not None
        self._publish_due(rest=True)  # every output ends on the final state, none twice
        self.finished = True
        self.get_logger().info(
            f"duration reached: t = {self.sim.t:.9g} s after {self.sim.step_index} steps; stopping"
        )

    # ------------------------------------------------------------------ publishing

    def _publish_due(self, force: bool = False, rest: bool = False) -> None:
        """Publish the outputs due at the current step (all of them when ``force``; with
        ``rest`` only those not due, i.e. not yet published at this step)."""
        sim = self.sim
        assert sim is not None
        k = sim.step_index
        due = [name for name, n in self.output_periods.items() if force or (k % n != 0 if rest else k % n == 0)]
        if not due:
            return
        snapshot = sim.snapshot()
        world, body = self.frames.world, self.frames.body
        for name in due:
            publisher = self.publishers_by_output[name]
            if name == "state":
                msg = conversions.snapshot_to_state(snapshot, world, body)
            elif name == "orientation":
                msg = conversions.snapshot_to_orientation(snapshot, world)
            elif name == "angular_velocity":
                msg = conversions.vector_stamped(snapshot.angular_velocity_body, snapshot.t, body)
            elif name == "angular_momentum":
                msg = conversions.vector_stamped(snapshot.angular_momentum_world, snapshot.t, world)
            elif name == "top_state":
                msg = conversions.snapshot_to_top_state(snapshot, world)
            elif name == "tf":
                msg = TFMessage(transforms=[conversions.transform_stamped(snapshot, world, body)])
            elif name == "imu":
                msg = conversions.snapshot_to_imu(snapshot, body, self.ground_truth_variance)
            elif name == "odom":
                msg = conversions.snapshot_to_odometry(snapshot, world, body, self.ground_truth_variance)
            else:
                msg = conversions.clock_message(snapshot.t)
            publisher.publish(msg)

    def flush_publishers(self, timeout: float = 1.0) -> None:
        """Wait (at most ``timeout`` s each) until reliable subscribers acknowledged what was published."""
        for publisher in self.publishers:
            publisher.wait_for_all_acked(rclpy.duration.Duration(seconds=timeout))

    def _inertia_about_com(self) -> tuple[float, Any, Any]:
        """Mass (kg; 0 when the scene gives none), centre of mass (m, body frame), tensor about it."""
        body = self.scene.body
        tensor = body.inertia_array
        mass = body.mass or 0.0
        com = body.center_of_mass or (0.0, 0.0, 0.0)
        if self.scene.gravity is not None:
            # the scene's tensor is about the pivot
            tensor = tensor - parallel_axis_shift(tensor * 0.0, mass, com)
        return mass, com, tensor

    def _publish_mass_properties(self) -> None:
        assert self.sim is not None
        mass, com, tensor = self._inertia_about_com()
        self.mass_properties_publisher.publish(conversions.inertia_stamped(mass, com, tensor, self.sim.t, self.frames.body))

    def _reject(self, source: str, reason: str, frame_id: str, torque: Any) -> None:
        """Publish a RejectedCommand and warn (at most every REJECT_WARN_PERIOD s per source)."""
        assert self.sim is not None
        # the frame_id is echoed, but never more than MAX_NAME_LENGTH characters of it
        frame_id = limits.clip_text(frame_id)
        reason = limits.clip_text(reason, limits.MAX_TEXT_LENGTH)
        self.rejected_publisher.publish(conversions.rejected_command(source, reason, self.sim.t, frame_id, torque))
        now = time.monotonic()
        last, suppressed = self._reject_warned.get(source, (-math.inf, 0))
        if now - last >= REJECT_WARN_PERIOD:
            more = f" ({suppressed} more rejected since the last warning)" if suppressed else ""
            self.get_logger().warning(f"rejected command on {source}: {reason}{more}")
            self._reject_warned[source] = (now, 0)
        else:
            self._reject_warned[source] = (last, suppressed + 1)

    # ------------------------------------------------------------------ callbacks

    def torque_callback(self, msg: Any, source: str) -> None:
        assert self.sim is not None
        received_ns = time.time_ns()
        torque, force, frame_id, stamp = conversions.torque_command_from_msg(msg)
        try:
            self.sim.receive_torque(source, torque, frame_id, stamp, force)
        except CommandRejected as exc:
            self._reject(self.resolve_topic_name(source), exc.reason, frame_id, torque)
        except Exception as exc:  # never out of a callback: rejected with the reason
            self._reject(self.resolve_topic_name(source), f"internal error: {exc!r}", frame_id, torque)
        if self.recorder is not None:
            self.recorder.record_command(self.resolve_topic_name(source), msg, received_ns)

    def set_state_callback(self, request, response):
        return self._serve(response, "~/set_state", lambda: self._set_state(request))

    def _set_state(self, request) -> str:
        sim = self.sim
        sim.set_state(conversions.quaternion_to_array(request.orientation), conversions.vector3_to_array(request.angular_velocity))
        self._publish_due(force=True)
        return f"state set at t = {sim.t:.9g} s; {self._run_state()}"

    def _set_initial_state(self) -> str:
        """The scene's initial attitude and ω at the current time (a reset of the state only)."""
        initial = self.scene.initial
        request = SetState.Request(
            orientation=conversions.array_to_quaternion(initial.orientation),
            angular_velocity=conversions.array_to_vector3(initial.angular_velocity),
        )
        return self._set_state(request)

    def reset_callback(self, request, response):
        return self._serve(response, "~/reset", self._reset)

    def _reset(self) -> str:
        self.sim.reset()
        self.finished = False
        self._anchor()
        self._publish_due(force=True)
        return f"reset to the scene's initial state at t = 0; {self._run_state()}"

    def _run_state(self) -> str:
        """What the run does after a reset or set_state (a failure's pause is lifted, a requested one stays)."""
        if not self.sim.paused:
            return "running"
        return "still paused as requested before (~/pause data=false resumes)"

    def pause_callback(self, request, response):
        return self._serve(response, "~/pause", lambda: self._pause(bool(request.data)))

    def _pause(self, paused: bool) -> str:
        sim = self.sim
        if not paused and sim.failure is not None:
            raise ValueError(f"cannot resume after a failure ({sim.failure}); reset or set_state first")
        sim.pause(paused)
        if not paused:
            self._anchor()
        return f"{'paused' if paused else 'running'} at t = {sim.t:.9g} s"

    def step_callback(self, request, response):
        def step() -> str:
            try:
                return self._step(int(request.steps))
            finally:
                conversions.fill_rigid_body_state(response.state, self.sim.snapshot(), self.frames.world, self.frames.body)

        return self._serve(response, "~/step", step)

    def _step(self, steps: int) -> str:
        """Advance a paused run by ``steps`` steps (~/step and ~/step_simulation); ValueError if refused.

        At most ``limits.MAX_STEPS_PER_REQUEST`` steps, run here in the service callback for
        at most ``STEP_REQUEST_WALL`` s of wall time, so the executor is never held for long.
        """
        sim = self.sim
        if not sim.paused:
            raise ValueError("not paused: call ~/pause with data=true first")
        if steps < 1:
            raise ValueError("steps must be >= 1")
        if steps > limits.MAX_STEPS_PER_REQUEST:
            raise ValueError(
                f"steps = {steps} exceeds the limit of {limits.MAX_STEPS_PER_REQUEST} per request "
                "(call ~/step again, or resume with ~/pause data=false)"
            )
        start = sim.step_index
        # the steps run here, in the callback, for at most STEP_REQUEST_WALL s of wall time
        self._run(start + steps, time.monotonic() + STEP_REQUEST_WALL)
        done = sim.step_index - start
        if sim.failure is not None:
            raise ValueError(f"stopped after {done} steps: {sim.failure}")
        if done < steps:
            raise ValueError(
                f"only {done} of {steps} steps done within the {STEP_REQUEST_WALL:g} s budget of a request "
                f"(t = {sim.t:.9g} s): call ~/step again for the rest"
            )
        return f"{done} steps done, t = {sim.t:.9g} s"

    def apply_torque_callback(self, request, response):
        def apply() -> str:
            torque = conversions.vector3_to_array(request.torque)
            duration = conversions.time_to_seconds(request.duration)
            try:
                command = self.sim.apply_torque(torque, request.frame_id, duration)
            except CommandRejected as exc:
                self._reject(self.resolve_service_name("~/apply_torque"), exc.reason, request.frame_id, torque)
                raise ValueError(exc.reason) from None
            return (
                f"torque {list(command.torque)} N*m ({command.frame} frame) from t = {command.effective_time:.9g} s "
                f"for {duration:g} s"
            )

        return self._serve(response, "~/apply_torque", apply)

    def _serve(self, response, name: str, action) -> Any:
        """Run a service action: success with its message, or success=false with the reason."""
        if self.sim is None:
            response.success = False
            response.message = "no scene loaded"
            return response
        try:
            response.message = action()
            response.success = True
        except ValueError as exc:
            response.success = False
            response.message = str(exc)
            self.get_logger().warning(f"{name} refused: {exc}")
        except Exception as exc:  # a callback must never raise: the node keeps serving
            response.success = False
            response.message = f"internal error: {exc!r}"
            self.get_logger().error(f"{name} failed: {exc!r}")
        return response

    def compute_inertia_callback(self, request, response):
        count = max(len(request.masses), len(request.positions))
        if count > limits.MAX_POINT_MASSES:  # refused before converting anything
            return self._reject_inertia(response, f"invalid request: {count} masses, more than the limit of {limits.MAX_POINT_MASSES}")
        if len(request.frame_id) > limits.MAX_NAME_LENGTH:
            return self._reject_inertia(
                response, f"invalid request: frame_id of {len(request.frame_id)} characters exceeds the limit of {limits.MAX_NAME_LENGTH}"
            )
        try:
            masses, positions, origin = conversions.compute_inertia_request_to_arrays(request)
            props = mass_properties(masses, positions, origin)
            conversions.fill_compute_inertia_response(response, props)
        except ValueError as exc:
            return self._reject_inertia(response, f"invalid request: {exc}")
        except Exception as exc:  # a callback must never raise: the node keeps serving
            self.get_logger().error(f"compute_inertia failed: {exc!r}")
            return self._reject_inertia(response, f"internal error: {exc!r}")
        response.success = True
        response.message = f"{len(masses)} masses, {props.total_mass:.6g} kg, {props.symmetry}"
        return response

    def _reject_inertia(self, response, message: str):
        self.get_logger().warning(message, throttle_duration_sec=REJECT_WARN_PERIOD)
        response.success = False
        response.message = message
        return response

    def destroy_node(self) -> None:
        if self.recorder is not None:
            self.recorder.close()  # summary and indexes: the file is complete (also on SIGINT / SIGTERM)
        super().destroy_node()

    # ------------------------------------------------------------------ parameters

    def validate_parameters_callback(self, parameters: list[Parameter]) -> SetParametersResult:
        """Refuse bad values with a reason; nothing changes then (applied after, if all are valid)."""
        values = {p.name: p.value for p in parameters}
        sim = self.sim
        try:
            if values.get("use_sim_time") is True:
                raise ValueError(USE_SIM_TIME_REFUSAL)
            if sim is None:
                return SetParametersResult(successful=True)
            if "integrator" in values or "dt" in values:
                method = values.get("integrator", self.get_parameter("integrator").value)
                dt = values.get("dt", sim.dt)
                if not isinstance(dt, float) or not (math.isfinite(dt) and dt > 0.0):
                    raise ValueError(f"dt must be a finite number > 0 s, got {dt!r}")
                sim.check_integrator(method, dt)
            for name, value in values.items():
                if name.startswith("rates."):
                    output = name[len("rates."):]
                    if value > 0.0 and output not in self.output_periods:
                        raise ValueError(f"{self._output_topic(output)} was not built at start-up; restart with {name} > 0")
                    if value <= 0.0 and output in self.output_periods:
                        raise ValueError(f"{name} must be > 0 for a built output (publishers are not destroyed at run time)")
        except ValueError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def apply_parameters_callback(self, parameters: list[Parameter]) -> None:
        values = {p.name: p.value for p in parameters}
        sim = self.sim
        if "integrator" in values or "dt" in values:
            try:
                sim.set_integrator(
                    method=values.get("integrator", self.get_parameter("integrator").value), dt=values.get("dt", sim.dt)
                )
            except ValueError as exc:  # e.g. a method that cannot take this scene's torque
                self.get_logger().error(f"integrator unchanged ({sim.method}, dt {sim.dt:g} s): {exc}")
            else:
                self.get_logger().info(f"integrator {sim.method}, dt {sim.dt:g} s from t = {sim.t:.9g} s")
                for warning in sim.warnings():
                    self.get_logger().warning(warning)
        if "real_time_factor" in values:
            self.real_time_factor = float(values["real_time_factor"])
            self._anchor()
        if "duration" in values:
            self.duration = values["duration"] if values["duration"] > 0.0 else None
        if "commands.max_torque" in values:
            sim.max_torque = float(values["commands.max_torque"])
        if {"integrator", "dt", "real_time_factor"} & values.keys():
            self.timer.timer_period_ns = int(self._tick_period() * 1e9)
        if {"integrator", "dt"} & values.keys() or any(name.startswith("rates.") for name in values):
            # periods in steps depend on dt; get_parameter already returns the new values here
            for output in self.output_periods:
                self.output_periods[output] = self._period_steps(self.get_parameter(f"rates.{output}").value)


#: What a bad scene, parameter or name raises while the node starts: exit code 2, one line.
STARTUP_ERRORS = (ValueError, ParameterException, NameValidationException)


def startup_error_line(exc: BaseException) -> str:
    """The one line (at most ``limits.MAX_ERROR_CHARS``) that reports a start-up error."""
    return limits.one_line(f"{NODE_NAME}: error: {exc}")


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


def main(args: list[str] | None = None) -> int:
    """Run the node until shut down or until the scene's duration is reached (exit code 0).

    A bad scene, parameter or ROS argument: one line on stderr, exit code 2.
    """
    ensure_ament_prefix_path()  # the console script works without activating the venv
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except _rclpy.RCLError as exc:  # e.g. an unparsable --ros-args rule
        print(startup_error_line(f"bad ROS arguments: {exc}"), file=sys.stderr, flush=True)
        return 2
    # while the node starts (the scene loads), Ctrl-C / SIGTERM stop it at once
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _interrupt)
    stop = threading.Event()
    node = None
    try:
        node = RigidRotSimNode()
        # from here SIGINT and SIGTERM only ask the loop below to stop: the node (and its
        # recording) then closes in `finally`, never interrupted in a callback or a file write
        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, lambda *_: stop.set())
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        while rclpy.ok() and not node.finished and not stop.is_set():
            executor.spin_once(timeout_sec=0.1)
        if node.finished:
            node.flush_publishers()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except STARTUP_ERRORS as exc:  # SceneError, a scene the integrator cannot run, a bad parameter
        print(startup_error_line(exc), file=sys.stderr, flush=True)
        return 2
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
