"""The simulation of one scene, step by step, without ROS: what the node (and resim) drive.

:class:`Simulator` is the one entry point of a run: it owns the scene's rigid body, pause /
step / reset / set_state and the run's failure state, and reports every outside change to
its observers (:class:`~rigid_rot_sim.run.observer.SimulationObserver`: a command accepted
in :meth:`~Simulator.submit_torque`, where :meth:`~Simulator.receive_torque` leads too, or
rejected, an applied torque, set_state, reset, an integrator change, a failure). It
is made of four parts, each in its own module, read as the simulator's read-only attributes
(``sim.clock``, ``sim.commands``, ``sim.stepper``, ``sim.observables``): the step clock
(:mod:`~rigid_rot_sim.run.clock`),
the torque commands with their hold / timeout state, the scene's torque schedules and
the torques applied for a duration (:mod:`~rigid_rot_sim.run.commands`), the integrator
stepped within the run's limits (:mod:`~rigid_rot_sim.run.stepper`), and the user-frame
view of the state with its drifts (:mod:`~rigid_rot_sim.run.observables`).
It returns plain :class:`StateSnapshot` values (numpy, user body frame, SI units).

Time and determinism
--------------------
Physics advances in fixed steps of ``dt``; the sim time of step k is computed from the
integer step counter (``t = t_epoch + (k - k_epoch) * dt``, with ``t_epoch = k_epoch = 0``
until dt is changed at run time), never accumulated. Every torque change takes effect at
a step boundary: the first boundary at or after its *effective time* (see
:meth:`~rigid_rot_sim.run.clock.StepClock.step_at_or_after`). A topic command's effective time is its header
stamp when the stamp is non-zero and not in the past, else the sim time at receipt
(:meth:`Simulator.receive_torque`); :meth:`Simulator.submit_torque` takes an explicit
effective time, so that a re-simulation fed the recorded commands reproduces the run
bit for bit, whatever the publish rates and the real-time factor were.

Torque between boundaries is constant in the body frame. A command in the world frame
stays fixed in the world: it is re-expressed in the body frame at every step boundary
(a zero-order hold at the physics rate, like a controller running at that rate).
Hold-policy timeouts are in sim time and also end on a step boundary.

Failures and limits
-------------------
Every number that enters is finite and within :mod:`~rigid_rot_sim.core.limits`: torque
components at most ``MAX_MAGNITUDE`` N*m (and a norm of at most ``sim.commands.max_torque``
when that is > 0), frame ids at most ``MAX_NAME_LENGTH`` characters, and a state whose ω
turns the body at most ``MAX_ROTATION_PER_STEP`` rad per step. A run stops (``paused``, the
reason in :attr:`Simulator.failure`, the last good state kept, every snapshot field finite)
when a step fails (:class:`NonFiniteStateError`, whatever the method) or when ω, with the
torque acting, would exceed the rotation limit before the next step. :meth:`Simulator.reset`
and :meth:`Simulator.set_state` clear the failure and resume a run that the failure paused.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Final

from rigid_rot_sim.core import validation
from rigid_rot_sim.core.dynamics import RigidBody
from rigid_rot_sim.run import advice
from rigid_rot_sim.run.clock import StepClock
from rigid_rot_sim.run.commands import APPLY_TORQUE_SOURCE, CommandRejected, CommandSchedule, TorqueCommand
from rigid_rot_sim.run.gyrostat_stepper import make_stepper
from rigid_rot_sim.run.observables import Observables, StateSnapshot
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.scene.features import refuse_unhonoured
from rigid_rot_sim.scene.scene import Scene

# CommandRejected, TorqueCommand, APPLY_TORQUE_SOURCE and StateSnapshot are what the Simulator's
# methods raise, return and take: part of its API, importable from here.
__all__ = ["Simulator", "StateSnapshot", "TorqueCommand", "CommandRejected", "APPLY_TORQUE_SOURCE"]


class Simulator:
    """Simulate ``scene``; ``method`` / ``dt`` / ``options`` override the scene's integrator.

    Parameters
    ----------
    scene : Scene
        A validated scene (:func:`rigid_rot_sim.scene.scene.load_scene`).
    method : str, optional
        Integrator name from the registry, or ``auto`` (the scene's choice by default).
    dt : float, optional
        Physics step, s (> 0).
    options : dict, optional
        Keyword options of the method; default the scene's.
    """

    def __init__(
        self, scene: Scene, *, method: str | None = None, dt: float | None = None, options: dict[str, Any] | None = None
    ) -> None:
        refuse_unhonoured(scene, "engine")  # scene/features.py: what the engine runs
        self.scene = scene
        self.body = RigidBody.from_inertia(scene.body.inertia_array, name="body.inertia")
        self.frames = scene.frames
        self.observables: Final = Observables(scene, self.body)
        self.gravity = self.observables.gravity
        #: Told what happens to the run, in order (:class:`SimulationObserver`); add with :meth:`add_observer`.
        self.observers: list[SimulationObserver] = []
        self.paused = False
        #: ``gate(source, stamp)`` raises CommandRejected to refuse a checked topic command (lockstep).
        self.command_gate: Callable[[str, float | None], None] = lambda source, stamp: None
        self.failure: str | None = None
        self._paused_by_failure = False
        #: The run's parts, read through the simulator and never replaced: the step clock (``sim.clock.t``,
        #: ``.dt``, ``.k``, the boundary a time lands on), the torque commands (``sim.commands``: what each
        #: input holds, ``max_torque``, frame resolution) and the integrator (``sim.stepper.method``, ``.options``).
        #: Every change goes through the simulator's methods, which tell the observers.
        self.clock: Final = StepClock(validation.positive_scalar("dt", scene.integrator.dt if dt is None else dt))
        self.commands: Final = CommandSchedule(scene, self.clock)
        self.stepper: Final = make_stepper(
            scene,
            self.body,
            self.observables,
            self.clock,
            self.commands,
            scene.integrator.method if method is None else method,
            dict(scene.integrator.options) if options is None else dict(options),
        )
        self.reset()
        reason = self.stepper.rotation_failure(0.0)
        if reason is not None:
            raise ValueError(f"initial angular velocity: {reason}")

    def add_observer(self, observer: SimulationObserver) -> None:
        """Report what happens to the run to ``observer`` from now on (after those added before)."""
        self.observers.append(observer)

    # ------------------------------------------------------------------ integrator (the stepper)

    def set_integrator(
        self, method: str | None = None, dt: float | None = None, options: dict[str, Any] | None = None
    ) -> None:
        """Switch method and/or step at the current state (ValueError, nothing changed, if invalid)."""
        step = self.clock.k
        self.stepper.reconfigure(method, dt, options)
        for observer in self.observers:
            observer.integrator_changed(step, self.stepper.method, self.clock.dt, dict(self.stepper.options))

    def check_integrator(self, method: str, dt: float) -> None:
        """ValueError (the reason) if :meth:`set_integrator` would refuse ``method`` at ``dt``; no change."""
        self.stepper.configure(method, dt, {}, dry_run=True)

    def warnings(self) -> list[str]:
        """Stability / accuracy warnings for the current method and step (:mod:`advice`)."""
        return advice.step_warnings(
            self.stepper.method, self.body.principal_moments, advice.omega_bound(self.scene, self.body), self.clock.dt
        )

    # ------------------------------------------------------------------ commands (the schedule)

    def receive_torque(
        self, source: str, torque: Any, frame_id: str = "", stamp: float | None = None, force: Any = None
    ) -> TorqueCommand:
        """Accept a command that arrived now on topic input ``source``, or raise CommandRejected.

        ``torque`` (N*m) in ``frame_id`` (resolved with the input's policy); ``stamp`` the
        header stamp (s; 0 or None = none); ``force`` (N) the force of a WrenchStamped: a rotation-only
        simulator rejects a non-zero one. Effective time: the stamp when non-zero and not in the past, else now.
        The observers hear of a rejection (then it is raised) or of the accepted command.
        """
        try:
            values, frame, effective, stamp = self.commands.admit(source, torque, frame_id, stamp, force)
            self.command_gate(source, stamp)
        except CommandRejected as rejected:
            self._report_rejected(rejected, frame_id, torque)
            raise
        return self.submit_torque(source, values, frame, effective, receipt_time=self.clock.t, stamp=stamp)

    def submit_torque(
        self,
        source: str,
        torque: Any,
        frame: str,
        effective_time: float,
        *,
        receipt_time: float | None = None,
        stamp: float | None = None,
    ) -> TorqueCommand:
        """Schedule a command on input ``source`` for an explicit effective time (resim's entry).

        ``torque`` (N*m) in ``frame`` (``body`` or ``world``). Takes effect at
        ``sim.clock.step_at_or_after(effective_time)``; replaces the input's previous value
        then, and falls back to zero after the input's timeout (sim time), if it has one.
        """
        step = self.clock.k
        command = self.commands.submit(source, torque, frame, effective_time, receipt_time, stamp)
        for observer in self.observers:
            observer.command_accepted(step, command)
        return command

    def apply_torque(
        self, torque: Any, frame_id: str, duration: float, effective_time: float | None = None
    ) -> TorqueCommand:
        """Add ``torque`` (N*m, in ``frame_id``; empty = body frame) for ``duration`` s of sim time.

        Starts at the current step boundary (or at ``effective_time``, for resim) and acts
        on top of the topic commands; several such torques add up. CommandRejected for a
        non-finite torque, an unknown frame or a duration that is not finite and > 0.
        """
        step = self.clock.k
        try:
            command = self.commands.apply(torque, frame_id, duration, effective_time)
        except CommandRejected as rejected:
            self._report_rejected(rejected, frame_id, torque)
            raise
        for observer in self.observers:
            observer.torque_applied(step, command)
        return command

    def submit_wheel_torques(
        self, source: str, torques: Any, effective_time: float | None = None
    ) -> tuple[int, tuple[float, ...], tuple[int, ...]]:
        """Hold wheel motor torques (N*m, scene order) from now or ``effective_time`` (s, resim's entry).

        Returns (step it takes effect, torques as clamped to max_torque, indices of the wheels clamped);
        CommandRejected, the observers told, for a scene without wheels, a wrong number of values or a
        non-finite one (:meth:`CommandSchedule.submit_wheels`).
        """
        step, effective = self.clock.k, self.clock.t if effective_time is None else effective_time
        try:
            result = self.commands.submit_wheels(source, torques, effective)
        except CommandRejected as rejected:
            self._report_rejected(rejected, "", torques)
            raise
        for observer in self.observers:
            observer.wheel_command_accepted(step, source, result[1], effective, result[2])
        return result

    def submit_rod_dipoles(
        self, source: str, dipoles: Any, effective_time: float | None = None
    ) -> tuple[int, tuple[float, ...], tuple[int, ...]]:
        """Hold torque-rod dipoles (A*m^2, scene order) from now or ``effective_time`` (s), as wheel torques are
        held (:meth:`submit_wheel_torques`; :meth:`CommandSchedule.submit_rods`)."""
        step, effective = self.clock.k, self.clock.t if effective_time is None else effective_time
        try:
            result = self.commands.submit_rods(source, dipoles, effective)
        except CommandRejected as rejected:
            self._report_rejected(rejected, "", dipoles)
            raise
        for observer in self.observers:
            observer.rod_command_accepted(step, source, result[1], effective, result[2])
        return result

    def _report_rejected(self, rejected: CommandRejected, frame_id: str, torque: Any) -> None:
        for observer in self.observers:
            observer.command_rejected(self.clock.k, rejected.source, rejected.reason, frame_id, torque)

    # ------------------------------------------------------------------ stepping

    def advance(self, n: int) -> int:
        """Advance up to ``n`` steps (fewer if a step fails); returns the number done.

        A failing step (a non-finite state, the rotation limit) pauses the simulation,
        keeps the last good state and records the reason in :attr:`failure`.
        """
        done, reason = self.stepper.advance(n)
        if reason is not None:
            self.fail(reason)
        return done

    def fail(self, reason: str) -> None:
        """Stop the run at the current (good) state with ``reason`` (cleared by reset / set_state)."""
        self.failure = reason
        self._paused_by_failure = self._paused_by_failure or not self.paused
        self.paused = True
        for observer in self.observers:
            observer.failed(self.clock.k, reason)

    def advance_to(self, k: int) -> int:
        """Advance to step boundary ``k`` (no-op when already there); returns steps done."""
        return self.advance(max(0, int(k) - self.clock.k))

    def step(self, n: int) -> int:
        """``~/step``: advance ``n`` >= 1 steps while paused (ValueError if not paused or n < 1)."""
        if not self.paused:
            raise ValueError("not paused: pause the simulation before stepping it")
        if isinstance(n, bool) or int(n) != n or n < 1:
            raise ValueError(f"steps must be an integer >= 1, got {n}")
        return self.advance(int(n))

    def pause(self, paused: bool = True) -> None:
        """Pause (True) or resume (False) the free-running simulation."""
        self.paused = bool(paused)
        self._paused_by_failure = False

    # ------------------------------------------------------------------ state

    def reset(self) -> None:
        """Back to the scene's initial state at step 0, with no torque held or applied."""
        step = self.clock.k
        self.clock.reset()
        self.commands.clear()
        self._clear_failure()
        self.stepper.restart()
        for observer in self.observers:
            observer.reset(step)

    def set_state(self, orientation: Any, angular_velocity: Any) -> None:
        """Replace attitude (x, y, z, w; body -> world) and ω (rad/s, body frame) at the current time.

        The quaternion is normalised; ValueError (state unchanged) for a zero or
        non-finite one or a non-finite ω. The drift references restart here.
        """
        step = self.clock.k
        q = validation.quaternion("orientation", orientation)
        omega = validation.finite_vector("angular_velocity", angular_velocity)
        self.stepper.set_body_state(q, omega)
        self._clear_failure()
        for observer in self.observers:
            observer.state_set(step, tuple(float(v) for v in orientation), tuple(float(v) for v in angular_velocity))

    def _clear_failure(self) -> None:
        """Forget a failure; a run the failure paused runs again (a pause asked for stays)."""
        if self.failure is not None and self._paused_by_failure:
            self.paused = False
        self.failure = None
        self._paused_by_failure = False

    def snapshot(self) -> StateSnapshot:
        """The state at the current step boundary (user body frame; see :class:`StateSnapshot`)."""
        return self.stepper.snapshot()
