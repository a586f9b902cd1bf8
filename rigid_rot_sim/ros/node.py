"""The rigid_rot_sim ROS 2 node: a scene simulated by :class:`~rigid_rot_sim.run.simulator.Simulator`.

The node wires: parameters (:mod:`.parameters`), outputs (:mod:`.outputs`), torque inputs
(:mod:`.inputs`), services (:mod:`.services`, :mod:`.simulation_services`) and the
recording (:mod:`rigid_rot_sim.ros.recording`) around the simulator and the
run driver that paces it (:mod:`rigid_rot_sim.run.pacing`). It builds only what the scene
needs (a :class:`SceneRun`) and logs one start-up line saying what was built and what was
left out. Without a ``scene`` parameter it serves ``~/compute_inertia`` only (``node.run``
is None). :func:`run_until_finished` is the one loop that runs it, for :func:`main` and for
``rigid-rot run --echo``.

Topics (names relative to the node; QoS in the README, section "The simulation node")
-----------------------------------------------------------------------------------
~/state (rigid_rot_msgs/RigidBodyState), ~/orientation (geometry_msgs/QuaternionStamped),
~/angular_velocity (Vector3Stamped, body frame), ~/angular_momentum (Vector3Stamped,
world frame), ~/mass_properties (geometry_msgs/InertiaStamped, transient local, once),
~/top_state (rigid_rot_msgs/HeavyTopState, gravity scenes), ~/rejected
(rigid_rot_msgs/RejectedCommand), ~/imu (sensor_msgs/Imu; the gyro's readings when the scene
has ``sensors.gyro``) and ~/odom (nav_msgs/Odometry) when the scene asks for them,
~/star_tracker (geometry_msgs/PoseWithCovarianceStamped) with ``sensors.star_tracker``
(docs/sensors.md), /tf (world -> body) and /tf_static (body -> principal frame, where it
differs from the body frame), /clock (sim time; the frozen time while paused: :mod:`.paused_clock`),
~/sim_events (live, the recent history latched: :mod:`.sim_events`), and for a scene with wheels
the JointState door of ros2_control's topic hardware interface (:mod:`.joint_state_door`). QoS:
rigid_rot_sim.ros.qos.
Every header stamp is sim time. Frame names: the ``world_frame`` / ``body_frame``
parameters (default: the scene's ``frames``, REP 105 ``odom`` / ``base_link``), used by
every output, /tf and the recording. Torque inputs: the scene's topics (WrenchStamped or
Vector3Stamped).

Services
--------
~/compute_inertia, ~/set_state, ~/reset (std_srvs/Trigger), ~/pause (std_srvs/SetBool),
~/step (rigid_rot_msgs/Step, while paused; at most ``limits.MAX_STEPS_PER_REQUEST`` steps,
run in the service callback for at most ``services.STEP_REQUEST_WALL`` s: the reply says how many
were done), ~/apply_torque, ~/step_with_torque (a torque over the next N steps, then the state, in
one callback). A bad request gets ``success = false`` and the reason; nothing
raises out of a callback. Where simulation_interfaces is installed, also the standard
simulator services (:mod:`.simulation_services`), through the same actions
(``~/step_simulation`` runs ``~/step``'s code, limits included) and the SimulateSteps action
(``~/simulate_steps``, stepped by a timer of its own: :mod:`.simulate_steps`).
The node loop (:mod:`.run_loop`, docs/architecture.md "The node loop"): the run's turns on the main
thread, which also takes every command in arrival order (:mod:`.intake`); the services, parameters
and actions on an executor thread, each holding the run lock (the node's default group), so a
huge request is deserialised beside the stepping and the commands.
Every limit is in :mod:`rigid_rot_sim.core.limits` (README, "Limits and failure behaviour").

Pacing
------
``real_time_factor`` r > 0: each turn of the run loop advances the simulation to
``r * (wall time since the anchor)`` (at most ``run_loop.SLICE_WALL`` of work per turn, so
commands are taken in between), and the next turn comes when the next output is due; r = 0: as
fast as possible, in turns of at most ``SLICE_WALL``. The states do not depend on r
or on the publish rates (see the Simulator's determinism notes). The turns are timed on the
steady clock: the node is the source of sim time (/clock), so ``use_sim_time`` true (a
launch-wide setting) is accepted with a warning that says so: nothing here reads the ROS clock.

Lockstep (the scene's ``lockstep`` section or the read-only ``lockstep.*`` parameters): the
run waits at every turn for the controllers' commands stamped with the turn's time
(:mod:`rigid_rot_sim.run.lockstep` has the contract, :mod:`.lockstep` the wiring, docs/lockstep.md
the user's view); the turn that takes a lockstep turn's last answer steps on at once, and the
next turn is otherwise timed by the turn's timeout. ``dt`` is fixed in lockstep.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import rclpy
from rclpy.duration import Duration
from rclpy.exceptions import NameValidationException, ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions
from rclpy.subscription import Subscription
from rclpy.time_source import CLOCK_TOPIC

from rigid_rot_sim.core import limits
from rigid_rot_sim.ros import live_views, paused_clock, sim_events, simulation_services
from rigid_rot_sim.ros import parameters as params
from rigid_rot_sim.ros.inputs import Rejections, TorqueInputs
from rigid_rot_sim.ros.intake import TAKEN_BY_THE_RUN_LOOP, CommandIntake
from rigid_rot_sim.ros.joint_state_door import JointStateDoor
from rigid_rot_sim.ros.lockstep import NodeLockstep, declare_lockstep_parameters, lockstep_from_parameters
from rigid_rot_sim.ros.outputs import Outputs
from rigid_rot_sim.ros.parameters import RunParameters, declare_parameters, declare_scene_parameter, read_settings
from rigid_rot_sim.ros.qos import output_qos
from rigid_rot_sim.ros.run_loop import POLL_WALL, SLICE_WALL, RunCallbackGroup, RunLock, RunLoop
from rigid_rot_sim.ros.services import InertiaService, RunServices
from rigid_rot_sim.ros.topic_types import WrongTypeWatch
from rigid_rot_sim.ros.wheel_inputs import WheelTorqueInput
from rigid_rot_sim.run.pacing import OutputSchedule, Pacer, Progress, RunDriver
from rigid_rot_sim.run.sensors import SensorSuite
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import OutputQos, Scene, load_scene
from rigid_rot_sim.share import ensure_ament_prefix_path, resolve_scene

if TYPE_CHECKING:  # imported when recording only: the mcap packages are optional at run time
    from rigid_rot_sim.ros.foxglove_live import FoxgloveLive
    from rigid_rot_sim.ros.recording import NodeRecording
    from rigid_rot_sim.ros.web_live import WebLive

NODE_NAME = "rigid_rot_sim"
#: Most wall time (s) to wait at shutdown for a service in flight (a ~/step request is at most 0.25 s).
EXECUTOR_SHUTDOWN_WAIT = 2.0


class SceneRun:
    """A scene being simulated by ``node``: the simulator, its run driver and the ROS parts around them.

    Built only when the node has a scene; declares the node's parameters (:mod:`.parameters`)
    with the scene's values as defaults.
    """

    def __init__(self, node: Node, scene: Scene) -> None:
        self.logger = node.get_logger()
        declare_parameters(node, scene)
        declare_lockstep_parameters(node, scene)
        settings = read_settings(node, scene)
        self.scene = scene = settings.scene  # with the frame parameters' names
        self.sim = sim = Simulator(scene, method=settings[params.INTEGRATOR], dt=settings[params.DT])
        sim.commands.max_torque = float(settings[params.MAX_TORQUE])
        state_qos = output_qos(OutputQos(settings[params.QOS_RELIABILITY], settings[params.QOS_DEPTH]))
        models = (scene.sensors.gyro, scene.sensors.star_tracker, scene.sensors.magnetometer)
        has_sensors = any(model is not None for model in models)
        self.sensors = SensorSuite(scene.sensors, field=scene.orbit_field()) if has_sensors else None
        self.outputs = Outputs(
            node, scene, settings.rates(), state_qos, settings[params.GROUND_TRUTH_VARIANCE], self.sensors
        )
        schedule = OutputSchedule.from_rates(self.outputs.rates, sim.clock.dt)
        pacer = Pacer(settings[params.REAL_TIME_FACTOR])
        self.driver = RunDriver(sim, schedule, pacer, settings[params.DURATION] or None, observers=[self.outputs])
        rejections = Rejections(node, sim, self.outputs)
        # every command topic is taken by the run loop, in arrival order (never by the executor)
        self.intake = CommandIntake(node, lost=rejections.lost)
        self.driver.between_chunks = self.intake.drain  # also while a service steps the run
        self.inputs = TorqueInputs(self.intake, sim, scene, settings[params.COMMAND_DEPTH], rejections)
        self.wheel_input = WheelTorqueInput(self.intake, sim, scene, settings[params.COMMAND_DEPTH], rejections)
        self.joint_state_door = JointStateDoor(
            self.intake,
            sim,
            scene,
            (settings[params.JOINT_STATE_COMMANDS], settings[params.JOINT_STATE_STATES]),
            self.outputs.rates.get("wheels", 0.0),
            settings[params.COMMAND_DEPTH],
            rejections,
        )
        self.driver.observers.append(self.joint_state_door)  # the states, at ~/wheels' steps
        self.type_watch = WrongTypeWatch(
            node,
            self.inputs.subscriptions + self.wheel_input.subscriptions + self.joint_state_door.subscriptions,
        )
        self.lockstep: NodeLockstep | None = None
        lockstep = lockstep_from_parameters(node, scene, sim.clock.dt)
        if lockstep is not None:
            self.lockstep = NodeLockstep(node, lockstep, self.driver)
        self.services = RunServices(node, self.driver, scene, rejections, self.report_progress)
        self._action_destroyed = False
        self.simulation_services = (
            simulation_services.SimulationServices(
                node, self.services, settings[params.SIMULATION_INTERFACES_NAMESPACE]
            )
            if simulation_services.AVAILABLE
            else None
        )
        self.sim_events = sim_events.start(node, sim)  # ~/sim_events, live (latched recent history)
        self.paused_clock = paused_clock.start(node, sim, self.outputs.publishers, self.outputs.rates)
        self.recording: NodeRecording | None = None
        if settings[params.RECORD_PATH]:
            self.recording = self._start_recording(node, settings[params.RECORD_PATH], settings[params.RECORD_LOG_TIME])
        self.foxglove: FoxgloveLive | None = None
        self.foxglove_words = ""
        self.web: WebLive | None = None
        self.web_words = ""
        try:
            self.foxglove, self.foxglove_words = live_views.start_foxglove(
                node, settings[params.FOXGLOVE], sim, self.outputs, scene
            )
            self.web, self.web_words = live_views.start_web(
                node, settings[params.WEB], sim, self.outputs, self.driver, scene
            )
            sim.pause(settings[params.START_PAUSED])
            self.driver.pacer.anchor(sim.clock.t)
            # the run loop's turns (run_loop): paced on the steady clock, never on /clock, which this node publishes
            self.loop = RunLoop(node, self.intake, self.turn)
            if isinstance(node.default_callback_group, RunCallbackGroup):
                node.default_callback_group.wake = self.intake.wake
            self.parameters = RunParameters(node, self.driver, self.intake.wake)
            self.logger.info(
                self._startup_line(
                    settings[params.INTEGRATOR] == "auto",
                    settings[params.RECORD_PATH],
                    settings[params.RECORD_LOG_TIME],
                )
            )
            for warning in sim.warnings():
                self.logger.warning(warning)
            self.outputs.publish_latched(sim.clock.t)
            self.driver.publish_due(force=True)
            self.intake.wake()  # the first turn
        except BaseException:  # e.g. Ctrl-C / SIGTERM while starting (main's start-up handler)
            self.close()  # the recording started above ends as a complete file
            raise

    def _start_recording(self, node: Node, path: str, log_time: str) -> NodeRecording | None:
        """The recording, an observer of the simulator and a listener of the outputs and inputs;
        None (error logged) when it cannot start: the run goes on."""
        try:
            from rigid_rot_sim.ros.recording import NodeRecording  # imported only when recording
        except ImportError as exc:  # the mcap packages are optional at run time
            missing = (exc.name or "").split(".")[0] or str(exc)
            self.logger.error(f"recording disabled: {missing} is not installed (pip install mcap mcap-ros2-support)")
            return None
        subscriptions = self.inputs.subscriptions + self.wheel_input.subscriptions + self.joint_state_door.subscriptions
        recording = NodeRecording.start(node, self.sim, self.outputs, subscriptions, path, log_time)
        if recording is not None:
            self.sim.add_observer(recording)  # events: commands accepted, torques applied, set_state, ...
            self.outputs.listeners.append(recording)  # every message published, as the bytes published
            self.inputs.listeners.append(recording)  # every torque command as received
            self.wheel_input.listeners.append(recording)  # every wheel command as received
            self.joint_state_door.listeners.append(recording)  # every JointState command as received
        return recording

    def _startup_line(self, auto: bool, record_path: str, log_time: str) -> str:
        """What was built and what was left out (and why), in one line."""
        sim, scene, pacer, duration = self.sim, self.scene, self.driver.pacer, self.driver.duration
        built = [f"integrator {sim.stepper.method} (dt {sim.clock.dt:g} s{', auto' if auto else ''})"]
        left_out: list[str] = []
        if self.lockstep is not None:
            built.insert(0, self.lockstep.describe())
        else:
            left_out.append("lockstep (commands act when they arrive)")
        parts = (self.outputs.describe(), self.inputs.describe(), self.wheel_input.describe())
        for part_built, part_left_out in (*parts, self.joint_state_door.describe()):
            built += part_built
            left_out += part_left_out
        if self.sensors is None:
            left_out.append("sensor models (~/imu, if asked for, is ideal; no ~/star_tracker)")
        else:
            drawn = "" if scene.sensors.seed is not None else ", drawn"
            built.append(f"sensors {', '.join(self.sensors.names)} (seed {self.sensors.seed}{drawn})")
        if scene.schedules:
            built.append(f"{len(scene.schedules)} torque schedule(s)")
        if scene.gravity is None:
            left_out.append("gravity (no potential energy, no ~/top_state)")
        else:
            built.append(f"gravity {scene.gravity.acceleration:g} m/s^2 about the pivot")
        if self.simulation_services is not None:
            built.append(self.simulation_services.describe())
        else:
            left_out.append("simulation_interfaces services (package not installed)")
        if record_path:
            built.append(
                f"recording to {record_path} (log time: {log_time})"
                if self.recording
                else "no recording (see the error above)"
            )
        else:
            left_out.append("recorder (nothing recorded)")
        if self.foxglove_words:
            (built if self.foxglove is not None else left_out).append(self.foxglove_words)
        if self.web_words:
            (built if self.web is not None else left_out).append(self.web_words)
        return (
            f"scene {scene.name!r} ({scene.source}), rtf {pacer.real_time_factor:g}, {'paused, ' if sim.paused else ''}"
            f"duration {'unbounded' if duration is None else f'{duration:g} s'}; "
            f"built: {'; '.join(built)}; left out: {'; '.join(left_out) or 'nothing'}"
        )

    @property
    def finished(self) -> bool:
        """The run reached its duration."""
        return self.driver.finished

    def turn(self) -> float | None:
        """One turn of the run loop (:mod:`.run_loop`): step to the step due now (none while a lockstep turn
        waits for its answers), take every command in arrival order (they act from the step due now), and in
        lockstep decide the turn the run stands on (answered: it goes on at once, so a turn costs one round
        trip).

        Returns the wall time (s) until the run needs the next turn (None: only when woken).
        """
        try:
            turns = self.lockstep.turns if self.lockstep is not None else None
            self._paused_clock_follows()
            if turns is None or not turns.waiting:  # a waiting lockstep turn has nothing to step before its answers
                self.tick()
            self.intake.drain()
            if turns is not None and turns.waiting:
                # decide the open turn now, whoever took its answers: answered, the run goes on at once (a turn
                # costs one round trip); else its resend or timeout, or it waits
                self.tick()
                if turns.waiting:
                    return turns.next_decision()
            return self.driver.next_wait()
        except Exception as exc:  # never out of the loop: the run pauses with the reason, the node serves on
            self.logger.error(f"simulation paused: internal error {exc!r} (reset or set_state to continue)")
            self.sim.fail(f"internal error: {exc!r}")
            return None

    def _paused_clock_follows(self) -> None:
        """The paused /clock's timer runs only while the run is paused: while it plays, its ticks (on the
        executor's thread, at up to 50 Hz) would publish nothing and cost a share of a core at every one. Its
        first tick while playing cancels it (:meth:`.paused_clock.PausedClock.tick`, on the executor's thread);
        every change of pause is followed by a turn (a service or parameter wakes the loop; a paused loop
        looks every POLL_WALL), which re-arms it here."""
        clock = self.paused_clock
        if clock is not None and self.sim.paused and clock.timer.is_canceled():
            clock.timer.reset()

    def tick(self) -> None:
        """Advance the run by one slice (at most ``SLICE_WALL`` of wall time) and publish what is due."""
        if self.lockstep is None:
            self.report_progress(self.driver.tick(SLICE_WALL))
        else:
            self.report_progress(self.lockstep.turns.tick(self.driver, SLICE_WALL))

    def report_progress(self, progress: Progress) -> None:
        """Log what a slice of the run came to: falling behind, a failure, the duration reached."""
        if progress.falling_behind is not None:
            self.logger.warning(progress.falling_behind, throttle_duration_sec=5.0)
        if progress.lockstep_timeout is not None:
            self.logger.warning(progress.lockstep_timeout)
        if progress.failure is not None:
            self.logger.error(f"simulation paused: {progress.failure} (reset or set_state to continue)")
        if progress.finished:
            self.logger.info(f"duration reached: t = {self.sim.clock.t:.9g} s after {self.sim.clock.k} steps; stopping")
            if self.lockstep is not None:
                self.logger.info(self.lockstep.turns.summary())

    def close(self) -> None:
        """Close the recording (summary and indexes: the file is complete) and the live server; idempotent."""
        self.report_lost()
        if self.recording is not None:
            self.recording.close()
        if self.foxglove is not None:
            self.foxglove.close()
        if self.web is not None:
            self.web.close()
        action = self.simulation_services.simulate_steps if self.simulation_services is not None else None
        if action is not None and not self._action_destroyed:
            # rclpy's destroy_node leaves action servers alone; one left holds the node, which then
            # stays on the graph after destroy_node
            action.destroy()
            self._action_destroyed = True

    def report_lost(self) -> None:
        """At the end: how many commands each topic took, and how many it lost (0 unless a bound was hit)."""
        lost = [
            f"{door.topic}: {door.lost} lost of {door.taken + door.lost}" for door in self.intake.doors if door.lost
        ]
        if lost:
            self.logger.warning(f"commands lost before the node could take them: {'; '.join(lost)}")


class RigidRotSimNode(Node):
    """Node ``rigid_rot_sim``; keyword arguments go to :class:`rclpy.node.Node`.

    ``run``: the :class:`SceneRun` of the ``scene`` parameter; None without one (the node then
    serves ``~/compute_inertia`` only).
    """

    def __init__(self, **kwargs: Any) -> None:
        # the default group (services, parameters, actions) holds the run lock: the run loop steps beside it
        self.run_lock = RunLock()
        self._run_group = RunCallbackGroup(self.run_lock)
        self._clock_subscriptions: list[tuple[Subscription, Callable[[Any], None]]] = []
        super().__init__(NODE_NAME, **kwargs)
        params.accept_integers_for_doubles(self)  # `ros2 param set ... real_time_factor 2` stores 2.0
        params.explain_use_sim_time(self)  # with or without a scene
        self.inertia_service = InertiaService(self)
        self.run: SceneRun | None = None
        scene_path = declare_scene_parameter(self)
        if not scene_path:
            for subscription, _ in self._clock_subscriptions:  # no run loop: the executor takes /clock
                subscription.callback_group = self.default_callback_group
                self.default_callback_group.add_entity(subscription)
            self.get_logger().info(
                "no scene parameter: serving ~/compute_inertia only (rigid-rot run SCENE starts a simulation)"
            )
            return
        try:
            self.run = SceneRun(self, load_scene(resolve_scene(scene_path)))  # SceneError names the file, key, problem
        except BaseException:
            super().destroy_node()  # a node that could not start leaves the graph at once
            raise
        for subscription, callback in self._clock_subscriptions:
            self.run.intake.adopt(subscription, _message_only(callback))

    def create_subscription(
        self, msg_type: Any, topic: str, callback: Callable[[Any], None], qos_profile: Any, **kwargs: Any
    ) -> Subscription:
        """As rclpy's, but rclpy's own ``/clock`` subscription (``use_sim_time`` true) is taken by the run
        loop between its turns: its messages (this node's own /clock, at its rate) never wake the executor.
        The node reads no ROS time (module docstring); the ROS clock still follows /clock."""
        if topic != CLOCK_TOPIC or kwargs.get("callback_group") is not None:
            return super().create_subscription(msg_type, topic, callback, qos_profile, **kwargs)
        subscription = super().create_subscription(
            msg_type, topic, callback, qos_profile, callback_group=TAKEN_BY_THE_RUN_LOOP, **kwargs
        )
        self._clock_subscriptions.append((subscription, callback))
        run = getattr(self, "run", None)  # None while rclpy's Node.__init__ subscribes (the scene comes later)
        if run is not None:
            run.intake.adopt(subscription, _message_only(callback))
        return subscription

    @property
    def default_callback_group(self) -> RunCallbackGroup:
        """Every callback the node creates without a group: one at a time, each holding the run lock."""
        return self._run_group

    @property
    def finished(self) -> bool:
        """The run reached its duration."""
        return self.run is not None and self.run.finished

    def spin_run(self, keep_going: Callable[[], bool]) -> None:
        """The run loop on this thread until ``keep_going()`` is False or the run finished (no scene: just wait)."""
        if self.run is None:
            while keep_going():
                time.sleep(POLL_WALL)
            return
        self.run.loop.spin(self.run_lock, lambda: keep_going() and not self.finished)

    def flush_publishers(self, timeout: float = 1.0) -> None:
        """Wait (at most ``timeout`` s each) until reliable subscribers acknowledged what was published."""
        for publisher in self.publishers:
            publisher.wait_for_all_acked(Duration(seconds=timeout))

    def destroy_node(self) -> None:
        if self.run is not None:
            self.run.close()  # the recording's file is complete (also on SIGINT / SIGTERM)
            self.run.loop.destroy()
        super().destroy_node()


def _message_only(callback: Callable[[Any], None]) -> Callable[[Any, int], None]:
    """An intake handler ``(msg, received_ns)`` calling a subscription callback ``(msg)``."""
    return lambda msg, received_ns: callback(msg)


#: What a bad scene, parameter or name raises while the node starts: exit code 2, one line.
STARTUP_ERRORS = (ValueError, ParameterException, NameValidationException)


def startup_error_line(exc: BaseException) -> str:
    """The one line (at most ``limits.MAX_ERROR_CHARS``) that reports a start-up error."""
    return limits.one_line(f"{NODE_NAME}: error: {exc}")


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


def init_ros(args: list[str] | None) -> None:
    """``rclpy.init`` without rclpy's signal handlers: while nodes start, Ctrl-C / SIGTERM stop them at once.

    RuntimeError (rclpy's RCLError) for ROS arguments rcl cannot parse.
    """
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _interrupt)


def run_until_finished(start: Callable[[list[Node]], RigidRotSimNode], drain: float = 0.0) -> None:
    """Start the nodes and run them until the run finishes, Ctrl-C, SIGTERM or shutdown.

    ``start`` creates the nodes, adding each to the list it is given as soon as it exists,
    and returns the simulation node. The run loop (:mod:`.run_loop`) runs on this thread;
    an executor on a thread of its own serves every node's services, parameters and actions
    (and the other nodes' callbacks). Once they are started, SIGINT and SIGTERM only ask the
    loop to stop: the nodes (and the recording) then close here, never interrupted in a
    callback or a file write. When the run reached its duration, reliable subscribers get
    what was published (at most 1 s per publisher) and the executor serves ``drain`` s more
    for them. Then the executor's thread ends, every node is destroyed (last started first)
    and rclpy shut down: nothing of rclpy runs while the nodes are destroyed, so nothing is
    left to fail on a destroyed entity. A start-up error (:data:`STARTUP_ERRORS`) is raised
    after that.
    """
    nodes: list[Node] = []
    stop = threading.Event()
    executor: SingleThreadedExecutor | None = None
    server: threading.Thread | None = None
    try:
        node = start(nodes)
        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, lambda *_: stop.set())
        if node.run is not None:
            node.run.loop.detach()  # the turns run on this thread, never on the executor's
        executor = SingleThreadedExecutor()
        for each in nodes:
            executor.add_node(each)
        server = threading.Thread(target=_serve, args=(executor, stop), name="rigid_rot_sim services", daemon=True)
        server.start()
        node.spin_run(lambda: rclpy.ok() and not stop.is_set())
        if node.finished and not stop.is_set():
            node.flush_publishers()
            stop.wait(drain)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        stop.set()
        if server is not None:
            server.join(EXECUTOR_SHUTDOWN_WAIT)  # a service in flight ends before the recording closes
        if executor is not None:
            executor.shutdown(timeout_sec=0)
        for each in reversed(nodes):
            each.destroy_node()
        rclpy.try_shutdown()


def _serve(executor: SingleThreadedExecutor, stop: threading.Event) -> None:
    """The services' thread: spin until asked to stop (each wait at most ``POLL_WALL``)."""
    try:
        while not stop.is_set() and executor.context.ok():
            executor.spin_once(timeout_sec=POLL_WALL)
    except ExternalShutdownException:
        pass


#: A diagnostic, off unless set: a directory where the node dumps tracemalloc snapshots (:func:`trace_memory`).
TRACE_MEMORY_ENV = "RIGID_ROT_TRACEMALLOC"


def trace_memory(directory: str) -> None:
    """Trace Python's allocations (tracemalloc, 8 frames) and dump a snapshot into ``directory`` on SIGUSR1
    and at exit (``snapshot_<n>.tracemalloc``, renamed into place once whole): what grew between two of them
    is what benchmarks/firehose_memory.py prints. Off by default; tracing slows the node down."""
    import atexit
    import itertools
    import tracemalloc

    tracemalloc.start(8)
    numbers = itertools.count(1)

    def dump(*_: object) -> None:
        path = os.path.join(directory, f"snapshot_{next(numbers)}.tracemalloc")
        tracemalloc.take_snapshot().dump(path + ".part")
        os.replace(path + ".part", path)

    signal.signal(signal.SIGUSR1, dump)
    atexit.register(dump)


def main(args: list[str] | None = None, overrides: Sequence[Parameter] = ()) -> int:
    """Run the node until shut down or until the scene's duration is reached (exit code 0).

    ``overrides``: start-up values that win over ``--ros-args`` (rclpy applies a Node's
    ``parameter_overrides`` after every ``-p`` and params file): ``rigid-rot run``'s own options.
    A bad scene, parameter or ROS argument: one line on stderr, exit code 2.
    """

    def start_node(nodes: list[Node]) -> RigidRotSimNode:
        node = RigidRotSimNode(parameter_overrides=list(overrides))
        nodes.append(node)
        return node

    ensure_ament_prefix_path()  # the console script works without activating the venv
    if os.environ.get(TRACE_MEMORY_ENV):
        trace_memory(os.environ[TRACE_MEMORY_ENV])
    try:
        init_ros(args)
    except RuntimeError as exc:  # rclpy's RCLError: e.g. an unparsable --ros-args rule
        print(startup_error_line(RuntimeError(f"bad ROS arguments: {exc}")), file=sys.stderr, flush=True)
        return 2
    try:
        run_until_finished(start_node)
    except STARTUP_ERRORS as exc:  # SceneError, a scene the integrator cannot run, a bad parameter
        print(startup_error_line(exc), file=sys.stderr, flush=True)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
