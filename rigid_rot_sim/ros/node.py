"""The rigid_rot_sim ROS 2 node: a scene simulated by :class:`~rigid_rot_sim.run.simulator.Simulator`.

:class:`SceneRun` wires the parts of a run (:mod:`.parts`: outputs, command doors, lockstep, services,
live views, recording; each built from the scene) around the simulator and the run driver that paces
it (:mod:`rigid_rot_sim.run.pacing`), and logs one start-up line saying what was built and what was left
out. Without a ``scene`` parameter the node serves ``~/compute_inertia`` only (``node.run`` is None).
:func:`main` runs it (:mod:`.node_process`: ``rclpy.init``, the run until it finishes).

Topics (names relative to the node; QoS in the README, section "The simulation node")
-----------------------------------------------------------------------------------
~/state (rigid_rot_msgs/RigidBodyState), ~/orientation (geometry_msgs/QuaternionStamped), ~/angular_velocity
(Vector3Stamped, body frame), ~/angular_momentum (Vector3Stamped, world frame), ~/mass_properties
(geometry_msgs/InertiaStamped, transient local, once), ~/top_state (rigid_rot_msgs/HeavyTopState, gravity scenes),
~/rejected (rigid_rot_msgs/RejectedCommand), ~/imu (sensor_msgs/Imu; the gyro's readings when the scene has
``sensors.gyro``) and ~/odom (nav_msgs/Odometry) when the scene asks for them, ~/star_tracker
(geometry_msgs/PoseWithCovarianceStamped) with ``sensors.star_tracker`` (docs/sensors.md), /tf (world -> body) and
/tf_static (body -> principal frame, where it differs from the body frame), /clock (sim time; the frozen time while
paused: :mod:`.paused_clock`), ~/sim_events (live, the recent history latched: :mod:`.sim_events`), and for a scene
with wheels the JointState door of ros2_control's topic hardware interface (:mod:`.joint_state_door`). QoS:
rigid_rot_sim.ros.qos. Every header stamp is sim time. Frame names: the ``world_frame`` / ``body_frame`` parameters
(default: the scene's ``frames``, REP 105 ``odom`` / ``base_link``), used by every output, /tf and the recording.
Torque inputs: the scene's topics (WrenchStamped or Vector3Stamped).

Services
--------
~/compute_inertia, ~/set_state, ~/reset (std_srvs/Trigger), ~/pause (std_srvs/SetBool), ~/step (rigid_rot_msgs/Step,
while paused; at most ``limits.MAX_STEPS_PER_REQUEST`` steps, run in the service callback for at most
``services.STEP_REQUEST_WALL`` s: the reply says how many were done), ~/apply_torque, ~/step_with_torque (a torque
over the next N steps, then the state, in one callback). A bad request gets ``success = false`` and the reason;
nothing raises out of a callback. Where simulation_interfaces is installed, also the standard simulator services
(:mod:`.simulation_services`), through the same actions (``~/step_simulation`` runs ``~/step``'s code, limits
included) and the SimulateSteps action (``~/simulate_steps``, stepped by a timer of its own:
:mod:`.simulate_steps`). The node loop (:mod:`.run_loop`, docs/architecture.md "The node loop"): the run's turns on
the main thread, which also takes every command in arrival order (:mod:`.intake`); the services, parameters and
actions on an executor thread, each holding the run lock (the node's default group), so a huge request is
deserialised beside the stepping and the commands. Every limit is in :mod:`rigid_rot_sim.core.limits` (README,
"Limits and failure behaviour").

Pacing
------
``real_time_factor`` r > 0: each turn of the run loop advances the simulation to ``r * (wall time since the
anchor)`` (at most ``run_loop.SLICE_WALL`` of work per turn, so commands are taken in between), and the next turn
comes when the next output is due; r = 0: as fast as possible, in turns of at most ``SLICE_WALL``. The states do not
depend on r or on the publish rates (see the Simulator's determinism notes). The turns are timed on the steady
clock: the node is the source of sim time (/clock), so ``use_sim_time`` true (a launch-wide setting) is accepted
with a warning that says so: nothing here reads the ROS clock.

Lockstep (the scene's ``lockstep`` section or the read-only ``lockstep.*`` parameters): the run waits at every turn
for the controllers' commands stamped with the turn's time (:mod:`rigid_rot_sim.run.lockstep` has the contract,
:mod:`.lockstep` the wiring, docs/lockstep.md the user's view); the turn that takes a lockstep turn's last answer
steps on at once, and the next turn is otherwise timed by the turn's timeout. ``dt`` is fixed in lockstep.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.parameter import Parameter

from rigid_rot_sim.ros import live_views, node_process, parts, paused_clock, sim_events
from rigid_rot_sim.ros import parameters as params
from rigid_rot_sim.ros.inputs import Rejections
from rigid_rot_sim.ros.intake import CommandIntake
from rigid_rot_sim.ros.parameters import RunParameters, declare_scene_parameter
from rigid_rot_sim.ros.parts import Closing, Part
from rigid_rot_sim.ros.rclpy_internals import ClockTakenByTheRunLoop
from rigid_rot_sim.ros.run_loop import POLL_WALL, SLICE_WALL, RunCallbackGroup, RunLock, RunLoop
from rigid_rot_sim.ros.services import InertiaService, RunServices
from rigid_rot_sim.ros.topic_types import WrongTypeWatch
from rigid_rot_sim.run.pacing import Progress
from rigid_rot_sim.scene.scene import Scene, load_scene
from rigid_rot_sim.share import resolve_scene

NODE_NAME = node_process.NODE_NAME


class SceneRun:
    """A scene being simulated by ``node``: the simulator, its run driver and the parts around them (:mod:`.parts`).

    Built only when the node has a scene; declares the node's parameters (:mod:`.parameters`)
    with the scene's values as defaults.
    """

    def __init__(self, node: Node, scene: Scene) -> None:
        self.logger = node.get_logger()
        settings = parts.settings(node, scene)
        self.scene = scene = settings.scene  # with the frame parameters' names
        self.sim = sim = parts.simulator(settings)
        self.outputs = parts.outputs(node, settings, sim)
        self.driver = parts.driver(settings, sim, self.outputs)
        rejections = Rejections(node, sim, self.outputs)
        # every command topic is taken by the run loop, in arrival order (never by the executor)
        self.intake = CommandIntake(node, lost=rejections.lost)
        self.driver.between_chunks = self.intake.drain  # also while a service steps the run
        self.doors = parts.command_doors(self.intake, settings, self.driver, self.outputs, rejections)
        self.inputs = self.doors[0]
        self.type_watch = WrongTypeWatch(node, parts.subscriptions(self.doors))
        self.clock_watch = parts.clock_watch(node, self.outputs)  # another node on /clock, named in the log
        self.lockstep = parts.lockstep(node, settings, self.driver)
        self.services = RunServices(node, self.driver, scene, rejections, self.report_progress)
        self.simulation_services = parts.simulation_services(node, settings, self.services)
        self.sim_events = sim_events.start(node, sim)  # ~/sim_events, live (latched recent history)
        self.paused_clock = paused_clock.start(node, sim, self.outputs.publishers, self.outputs.rates)
        self.recording = parts.recording(node, settings, sim, self.outputs, self.doors)
        self.parts: list[Part] = [
            parts.lockstep_part(self.lockstep),
            parts.integrator_part(settings, sim),
            parts.OutputsPart(self.outputs, sim),
            *self.doors,
            parts.physics_part(scene, self.outputs.sensors),
            parts.simulation_services_part(self.simulation_services),
            parts.recording_part(settings, self.recording),
        ]
        try:
            self._start(node, settings)
        except BaseException:  # e.g. Ctrl-C / SIGTERM while starting (main's start-up handler)
            self.close()  # the recording started above ends as a complete file
            raise

    def _start(self, node: Node, settings: params.NodeSettings) -> None:
        """The live views, the run loop and the parameters' callbacks; the start-up line; the first outputs."""
        self.parts += live_views.start(
            node, settings[params.FOXGLOVE], settings[params.WEB], self.sim, self.outputs, self.driver, self.scene
        )
        self.sim.pause(settings[params.START_PAUSED])
        self.driver.pacer.anchor(self.sim.clock.t)
        # the run loop's turns (run_loop): paced on the steady clock, never on /clock, which this node publishes
        self.loop = RunLoop(node, self.intake, self.turn)
        if isinstance(node.default_callback_group, RunCallbackGroup):
            node.default_callback_group.wake = self.intake.wake
        self.parameters = RunParameters(node, self.driver, self.intake.wake)
        self.logger.info(parts.startup_line(self._headline(), self.parts))
        for warning in self.sim.warnings():
            self.logger.warning(warning)
        self.outputs.publish_latched(self.sim.clock.t)
        self.driver.publish_due(force=True)
        self.intake.wake()  # the first turn

    def _headline(self) -> str:
        """The start-up line's head: the scene, the pacing, the duration."""
        pacer, duration = self.driver.pacer, self.driver.duration
        return (
            f"scene {self.scene.name!r} ({self.scene.source}), rtf {pacer.real_time_factor:g}, "
            f"{'paused, ' if self.sim.paused else ''}duration {'unbounded' if duration is None else f'{duration:g} s'}"
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
        """Close the parts that hold something (the recording's file complete, the live servers, the
        action server); idempotent."""
        if lost := self.intake.losses():
            self.logger.warning(f"commands lost before the node could take them: {lost}")
        for part in self.parts:
            if isinstance(part, Closing):
                part.close()


class RigidRotSimNode(ClockTakenByTheRunLoop):
    """Node ``rigid_rot_sim``; keyword arguments go to :class:`rclpy.node.Node`.

    ``run``: the :class:`SceneRun` of the ``scene`` parameter; None without one (the node then
    serves ``~/compute_inertia`` only).
    """

    def __init__(self, **kwargs: Any) -> None:
        # the default group (services, parameters, actions) holds the run lock: the run loop steps beside it
        self.run_lock = RunLock()
        self._run_group = RunCallbackGroup(self.run_lock)
        super().__init__(NODE_NAME, **kwargs)
        params.accept_integers_for_doubles(self)  # `ros2 param set ... real_time_factor 2` stores 2.0
        params.explain_use_sim_time(self)  # with or without a scene
        self.inertia_service = InertiaService(self)
        self.run: SceneRun | None = None
        scene_path = declare_scene_parameter(self)
        if not scene_path:
            self.hand_clock_to(None)  # no run loop: the executor takes /clock
            self.get_logger().info(
                "no scene parameter: serving ~/compute_inertia only (rigid-rot run SCENE starts a simulation)"
            )
            return
        try:
            self.run = SceneRun(self, load_scene(resolve_scene(scene_path)))  # SceneError names the file, key, problem
        except BaseException:
            super().destroy_node()  # a node that could not start leaves the graph at once
            raise
        self.hand_clock_to(self.run.intake)  # rclpy's /clock (use_sim_time) taken between the turns

    @property
    def default_callback_group(self) -> RunCallbackGroup:
        """Every callback the node creates without a group: one at a time, each holding the run lock."""
        return self._run_group

    @property
    def finished(self) -> bool:
        """The run reached its duration."""
        return self.run is not None and self.run.finished

    def detach_run_loop(self) -> None:
        """From now on the turns run on :meth:`spin_run`'s thread only, never on an executor's."""
        if self.run is not None:
            self.run.loop.detach()

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


def main(args: list[str] | None = None, overrides: Sequence[Parameter] = ()) -> int:
    """Run the node until shut down or until the scene's duration is reached (exit code 0); a bad scene, parameter
    or ROS argument: one line on stderr, exit code 2 (:func:`.node_process.run_process`). ``overrides``: start-up
    values that win over ``--ros-args`` (the Node's ``parameter_overrides``): ``rigid-rot run``'s own options."""
    return node_process.run_process(lambda: RigidRotSimNode(parameter_overrides=list(overrides)), args)


if __name__ == "__main__":
    raise SystemExit(main())
