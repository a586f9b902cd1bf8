"""The rigid_rot_sim ROS 2 node: a scene simulated by :class:`~rigid_rot_sim.run.simulator.Simulator`.

The node wires: parameters (:mod:`.parameters`), outputs (:mod:`.outputs`), torque inputs
(:mod:`.inputs`), services (:mod:`.services`, :mod:`.simulation_services`) and the
recording (:mod:`rigid_rot_sim.ros.recording`) around the simulator and the
run driver that paces it (:mod:`rigid_rot_sim.run.pacing`). It builds only what the scene
needs and logs one start-up line saying what was built and what was left out. Without a
``scene`` parameter it serves ``~/compute_inertia`` only.

Topics (names relative to the node; QoS in the README, section "The simulation node")
-----------------------------------------------------------------------------------
~/state (rigid_rot_msgs/RigidBodyState), ~/orientation (geometry_msgs/QuaternionStamped),
~/angular_velocity (Vector3Stamped, body frame), ~/angular_momentum (Vector3Stamped,
world frame), ~/mass_properties (geometry_msgs/InertiaStamped, transient local, once),
~/top_state (rigid_rot_msgs/HeavyTopState, gravity scenes), ~/rejected
(rigid_rot_msgs/RejectedCommand), ~/imu (sensor_msgs/Imu) and ~/odom (nav_msgs/Odometry)
when the scene asks for them, /tf (world -> body) and /tf_static (body -> principal
frame, where it differs from the body frame), both where tf2_msgs imports (``make setup``
builds it into the venv), /clock (sim time). QoS: rigid_rot_sim.ros.qos.
Every header stamp is sim time. Frame names: the ``world_frame`` / ``body_frame``
parameters (default: the scene's ``frames``, REP 105 ``odom`` / ``base_link``), used by
every output, /tf and the recording. Torque inputs: the scene's topics (WrenchStamped or
Vector3Stamped).

Services
--------
~/compute_inertia, ~/set_state, ~/reset (std_srvs/Trigger), ~/pause (std_srvs/SetBool),
~/step (rigid_rot_msgs/Step, while paused; at most ``limits.MAX_STEPS_PER_REQUEST`` steps,
run in the service callback for at most ``services.STEP_REQUEST_WALL`` s: the reply says how many
were done), ~/apply_torque. A bad request gets ``success = false`` and the reason; nothing
raises out of a callback. Where simulation_interfaces is installed, also the standard
simulator services (:mod:`.simulation_services`), through the same actions
(``~/step_simulation`` runs ``~/step``'s code, limits included).
Every limit is in :mod:`rigid_rot_sim.core.limits` (README, "Limits and failure behaviour").

Pacing
------
``real_time_factor`` r > 0: a wall-clock timer advances the simulation to
``r * (wall time since the anchor)`` each tick (at most ``run.pacing.MAX_TICK_WALL`` of work per
tick, so commands and services are served in between); r = 0: as fast as possible, in
batches of at most ``MAX_TICK_WALL`` wall time per tick. The states do not depend on r
or on the publish rates (see the Simulator's determinism notes). The timer runs on the
steady clock: the node is the source of sim time (/clock), so ``use_sim_time`` true is
refused (at start-up and at run time).

Lockstep (the scene's ``lockstep`` section or the read-only ``lockstep.*`` parameters): the
run waits at every turn for the controllers' commands stamped with the turn's time
(:mod:`rigid_rot_sim.run.lockstep` has the contract, :mod:`.lockstep` the wiring, docs/lockstep.md
the user's view); the timer then only decides timeouts and pacing, a guard condition wakes the
run the moment a turn is answered. ``dt`` is fixed in lockstep.
"""

from __future__ import annotations

import signal
import sys
import threading
from typing import Any

import rclpy
from rclpy.clock import Clock as SteadyClock
from rclpy.clock_type import ClockType
from rclpy.exceptions import NameValidationException, ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from rigid_rot_sim.core import limits
from rigid_rot_sim.run.pacing import OutputSchedule, Pacer, Progress, RunDriver
from rigid_rot_sim.scene.scene import load_scene
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.ros import simulation_services
from rigid_rot_sim.ros.inputs import Rejections, TorqueInputs
from rigid_rot_sim.ros.lockstep import NodeLockstep, declare_lockstep_parameters, lockstep_from_parameters, timer_period
from rigid_rot_sim.ros.outputs import Outputs
from rigid_rot_sim.ros.parameters import (
    USE_SIM_TIME_REFUSAL,
    ParameterCallbacks,
    accept_integers_for_doubles,
    declare_parameters,
    declare_scene_parameter,
    read_settings,
)
from rigid_rot_sim.ros.services import InertiaService, RunServices
from rigid_rot_sim.share import ensure_ament_prefix_path, resolve_scene

NODE_NAME = "rigid_rot_sim"


class RigidRotSimNode(Node):
    """Node ``rigid_rot_sim``; keyword arguments go to :class:`rclpy.node.Node`."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(NODE_NAME, **kwargs)
        log = self.get_logger()
        accept_integers_for_doubles(self)  # `ros2 param set ... real_time_factor 2` stores 2.0
        self.sim: Simulator | None = None
        self.run: RunDriver | None = None
        self.recording = None
        self.parameter_callbacks = ParameterCallbacks(self)  # refuses use_sim_time, with or without a scene
        self.inertia_service = InertiaService(self)
        scene_path = declare_scene_parameter(self)
        if not scene_path:
            log.info("no scene parameter: serving ~/compute_inertia only (rigid-rot run SCENE starts a simulation)")
            return
        if self.get_parameter("use_sim_time").value is True:
            raise ValueError(USE_SIM_TIME_REFUSAL)
        scene = load_scene(resolve_scene(scene_path))  # SceneError names the file, key and problem
        declare_parameters(self, scene)
        declare_lockstep_parameters(self, scene)
        settings = read_settings(self, scene)
        self.scene = scene = settings.scene
        self.sim = sim = Simulator(scene, method=settings.integrator, dt=settings.dt)
        sim.max_torque = settings.max_torque
        auto = ", auto" if settings.integrator == "auto" else ""
        built: list[str] = [f"integrator {sim.method} (dt {sim.dt:g} s{auto})"]
        left_out: list[str] = []

        self.outputs = Outputs(self, scene, settings.rates, settings.state_qos, settings.ground_truth_variance,
                               built, left_out)
        self.run = RunDriver(sim, OutputSchedule.from_rates(self.outputs.rates, sim.dt),
                             Pacer(settings.real_time_factor), settings.duration, observers=[self.outputs])
        rejections = Rejections(self, sim, self.outputs)
        self.inputs = TorqueInputs(self, sim, scene, settings.command_depth, rejections, built, left_out)
        self.lockstep: NodeLockstep | None = None
        lockstep = lockstep_from_parameters(self, scene, sim.dt)
        if lockstep is not None:
            self.lockstep = NodeLockstep(self, lockstep, self.run, self.timer_callback)
            self.inputs.listeners.append(self.lockstep)  # wakes the run when a turn is answered
            built.insert(0, self.lockstep.describe())
        else:
            left_out.append("lockstep (commands act when they arrive)")
        if scene.schedules:
            built.append(f"{len(scene.schedules)} torque schedule(s)")
        if scene.gravity is None:
            left_out.append("gravity (no potential energy, no ~/top_state)")
        else:
            built.append(f"gravity {scene.gravity.acceleration:g} m/s^2 about the pivot")
        self.run_services = RunServices(self, self.run, scene, rejections, self.report_progress)
        self.simulation_services = None
        if simulation_services.AVAILABLE:
            self.simulation_services = simulation_services.SimulationServices(self, self.run_services)
            built.append("simulation_interfaces services (~/step_simulation, ~/reset_simulation, ...)")
        else:
            left_out.append("simulation_interfaces services (package not installed)")
        if settings.record_path:
            self.recording = self._start_recording(settings.record_path, settings.record_log_time)
            built.append(f"recording to {settings.record_path} (log time: {settings.record_log_time})"
                         if self.recording else "no recording (see the error above)")
        else:
            left_out.append("recorder (nothing recorded)")

        try:
            sim.pause(settings.start_paused)
            self.run.pacer.anchor(sim.t)
            # steady clock: the pacing never depends on /clock, which this node itself publishes
            period = self.run.pacer.tick_period(sim.dt) if self.lockstep is None else timer_period(self.run, sim.dt)
            self.timer = self.create_timer(period, self.timer_callback,
                                           clock=SteadyClock(clock_type=ClockType.STEADY_TIME))
            self.parameter_callbacks.attach(self.run, self.timer)
            log.info(
                f"scene {scene.name!r} ({scene.source}), rtf {settings.real_time_factor:g}, "
                f"{'paused, ' if sim.paused else ''}"
                f"duration {'unbounded' if settings.duration is None else f'{settings.duration:g} s'}; "
                f"built: {'; '.join(built)}; left out: {'; '.join(left_out) or 'nothing'}"
            )
            for warning in sim.warnings():
                log.warning(warning)
            self.outputs.publish_latched(sim.t)
            self.run.publish_due(force=True)
        except BaseException:  # e.g. Ctrl-C / SIGTERM while starting (main's start-up handler)
            if self.recording is not None:
                self.recording.close()  # the recording started above ends as a complete file
            raise

    def _start_recording(self, path: str, log_time: str) -> Any:
        """The recording, an observer of the simulator and a listener of the outputs and inputs;
        None (error logged) when it cannot start: the run goes on."""
        try:
            from rigid_rot_sim.ros.recording import NodeRecording  # imported only when recording
        except ImportError as exc:  # the mcap packages are optional at run time
            missing = (exc.name or "").split(".")[0] or str(exc)
            self.get_logger().error(f"recording disabled: {missing} is not installed (pip install mcap mcap-ros2-support)")
            return None
        recording = NodeRecording.start(self, self.sim, self.outputs, self.inputs.subscriptions, path, log_time)
        if recording is not None:
            self.sim.add_observer(recording)  # events: commands accepted, torques applied, set_state, ...
            self.outputs.listeners.append(recording)  # every message published, as the bytes published
            self.inputs.listeners.append(recording)  # every torque command as received
        return recording

    @property
    def finished(self) -> bool:
        """The run reached its duration."""
        return self.run is not None and self.run.finished

    def timer_callback(self) -> None:
        try:
            if self.lockstep is None:
                self.report_progress(self.run.tick())
            else:
                self.report_progress(self.lockstep.turns.tick(self.run))
                self.lockstep.after_tick()
        except Exception as exc:  # never out of a callback: the run pauses with the reason, the node serves on
            self.get_logger().error(f"simulation paused: internal error {exc!r} (reset or set_state to continue)")
            self.sim.fail(f"internal error: {exc!r}")

    def report_progress(self, progress: Progress) -> None:
        """Log what a slice of the run came to: falling behind, a failure, the duration reached."""
        log = self.get_logger()
        if progress.falling_behind is not None:
            log.warning(progress.falling_behind, throttle_duration_sec=5.0)
        if progress.lockstep_timeout is not None:
            log.warning(progress.lockstep_timeout)
        if progress.failure is not None:
            log.error(f"simulation paused: {progress.failure} (reset or set_state to continue)")
        if progress.finished:
            log.info(f"duration reached: t = {self.sim.t:.9g} s after {self.sim.step_index} steps; stopping")
            if self.lockstep is not None:
                log.info(self.lockstep.turns.summary())

    def flush_publishers(self, timeout: float = 1.0) -> None:
        """Wait (at most ``timeout`` s each) until reliable subscribers acknowledged what was published."""
        for publisher in self.publishers:
            publisher.wait_for_all_acked(rclpy.duration.Duration(seconds=timeout))

    def destroy_node(self) -> None:
        if self.recording is not None:
            self.recording.close()  # summary and indexes: the file is complete (also on SIGINT / SIGTERM)
        super().destroy_node()


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
