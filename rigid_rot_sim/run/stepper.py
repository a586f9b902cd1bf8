"""The integrator of a run, stepped under the commanded torque within the run's limits.

:class:`Stepper` holds the integrator chosen from the registry (in the principal frame),
gives it the torque of the :class:`~rigid_rot_sim.run.commands.CommandSchedule` for
each stretch of steps (a world-frame torque re-expressed in the body frame at every
boundary) and advances it on the :class:`~rigid_rot_sim.run.clock.StepClock`. A stretch
stops early, with a reason and the last good state kept, when

* ω, with the torque acting, would turn the body more than
  :data:`~rigid_rot_sim.core.limits.MAX_ROTATION_PER_STEP` rad in a step;
* the integrator fails (:class:`NonFiniteStateError`, or a math error on the way to it);
* the state's kinetic energy, |L| or |ω| would overflow a snapshot.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rigid_rot_sim.core import frames, limits, validation
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.dynamics import RigidBody
from rigid_rot_sim.core.integrators import get_method
from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError
from rigid_rot_sim.core.torque import ConstantTorque
from rigid_rot_sim.run import advice
from rigid_rot_sim.run.clock import StepClock
from rigid_rot_sim.run.commands import CommandSchedule
from rigid_rot_sim.run.digest import DIGEST_SEED, fold_steps
from rigid_rot_sim.run.observables import Observables, StateSnapshot
from rigid_rot_sim.run.rod_torque import RodTorque
from rigid_rot_sim.run.timeline import world_in_body
from rigid_rot_sim.scene.scene import Scene

__all__ = ["Stepper"]

_ZERO3 = (0.0, 0.0, 0.0)

#: Largest kinetic energy (J), |L| (kg*m^2/s) and |omega| (rad/s) a state may have: the snapshot's
#: rotations and drifts of such values stay finite (a NaN compares false: refused too).
_DERIVED_CEILING = 1e300


def command_torques(commands: CommandSchedule, orientation: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """The commanded torques acting now, by source (N*m, user body frame; world ones rotated at ``orientation``)."""
    q = tuple(float(v) for v in orientation)
    return [
        (name, np.array(quat.rotate_inverse(q, torque) if frame == "world" else torque, dtype=float))
        for name, torque, frame in commands.named_torques
    ]


class Stepper:
    """Steps ``body`` (of ``scene``) with ``method`` at the clock's dt under ``commands``' torque.

    ``method`` is a registry name or ``auto``; ``options`` the method's keyword options. The
    initial state is the scene's orientation at rest until :meth:`set_state`.
    :attr:`step_torque_body` is the commanded torque (N*m, user body frame) of the current step.
    """

    def __init__(
        self,
        scene: Scene,
        body: RigidBody,
        observables: Observables,
        clock: StepClock,
        commands: CommandSchedule,
        method: str,
        options: dict[str, Any],
    ) -> None:
        self.scene = scene
        self.body = body
        self.observables = observables
        self.gravity = observables.gravity
        self.clock = clock
        self.commands = commands
        self.integrator: Integrator | None = None
        self.method = ""
        self.options: dict[str, Any] = {}
        self.step_torque_body: tuple[float, float, float] = _ZERO3
        #: The run digest (:mod:`~rigid_rot_sim.run.digest`) of every step taken so far.
        self.digest = DIGEST_SEED
        self._i_min = float(np.min(body.principal_moments))
        #: The torque rods' torque (:mod:`~rigid_rot_sim.run.rod_torque`) in the scene's field along its orbit.
        self.rods = RodTorque.of(scene, observables.principal_from_body)
        self.configure(method, clock.dt, options, first=True)

    # ------------------------------------------------------------------ the integrator

    def configure(
        self, method: str, dt: float, options: dict[str, Any], *, first: bool = False, dry_run: bool = False
    ) -> None:
        """Switch to ``method`` (or ``auto``) at step ``dt`` (s); ValueError, nothing changed, if invalid.

        The state carries over; the clock starts a new epoch and pending commands move to
        the new step grid. ``dry_run``: only check that the method can run this scene at
        ``dt`` (no options).
        """
        dt = validation.positive_scalar("dt", dt)
        if method == "auto":
            omega_bound = advice.omega_bound(self.scene, self.body)
            method = advice.choose_integrator(self.body.principal_moments, omega_bound, dt, self.scene.torque_kind)
        cls = get_method(method)  # ValueError listing the valid names
        commanded = bool(self.scene.topic_inputs or self.scene.schedules or self.rods.present)
        if commanded or dry_run:
            # commands give the method a ConstantTorque between boundaries: refuse now, not mid-run,
            # a method that cannot take one (the exact flow is torque-free)
            try:
                cls(
                    self.body.principal_moments,
                    dt,
                    ConstantTorque(np.ones(3)) if commanded else self.gravity,
                    **options,
                )
            except ValueError as exc:
                what = "this scene" if dry_run else "this scene's torque inputs"
                raise ValueError(f"integrator {method!r} cannot run {what}: {exc}") from None
        if dry_run:
            return
        if first:
            state = (0.0, self.body.attitude_to_principal(np.array(self.scene.initial.orientation)), np.zeros(3))
        else:
            assert self.integrator is not None
            state = (self.integrator.t, self.integrator.q, self.integrator.omega)
        integrator = cls(
            self.body.principal_moments,
            dt,
            self.integrator.torque if self.integrator else self.gravity,
            t0=state[0],
            q0=state[1],
            omega0=state[2],
            **options,
        )
        self.integrator = integrator
        self.method = method
        self.options = dict(options)
        if not first:
            self.clock.change_dt(dt)  # keeps t = t_epoch + (k - k_epoch) dt exact from here on
            self.commands.reschedule()

    def reconfigure(self, method: str | None, dt: float | None, options: dict[str, Any] | None) -> None:
        """:meth:`configure` with what is None kept (options too, unless the method changes)."""
        self.configure(
            self.method if method is None else method,
            self.clock.dt if dt is None else dt,
            self.options if options is None and method in (None, self.method) else dict(options or {}),
        )

    def set_state(self, t: float, q_principal: np.ndarray, omega_principal: np.ndarray) -> None:
        """Put the integrator at time ``t`` (s) in the principal-frame state (q, ω); the drifts restart here."""
        assert self.integrator is not None
        self.integrator.set_state(t, q_principal, omega_principal)
        self.observables.set_reference(self.snapshot())

    def restart(self) -> None:
        """Back to the scene's initial state at t = 0 under the commands' torque (after they were cleared)."""
        self.step_torque_body = _ZERO3
        self.set_state(
            0.0,
            self.body.attitude_to_principal(np.array(self.scene.initial.orientation)),
            self.body.vector_to_principal(np.array(self.scene.initial.angular_velocity)),
        )
        self.set_command_torque()

    def set_body_state(self, q: np.ndarray, omega: np.ndarray) -> None:
        """Replace the state at the clock's time: ``q`` body -> world, ``omega`` (rad/s) in the user body frame.

        ValueError (nothing changed) if ``omega`` breaks the rotation limit (:meth:`check_spin`).
        """
        self.check_spin(omega)
        self.set_state(self.clock.t, self.body.attitude_to_principal(q), self.body.vector_to_principal(omega))
        if self.commands.world_sum is not None or self.rods.active:
            self.set_command_torque()  # the world-frame torque, the rods' torque, in the new body frame

    def snapshot(self) -> StateSnapshot:
        """The integrator's state at the clock's step, as the user sees it (:meth:`Observables.snapshot`)."""
        integrator = self.integrator
        assert integrator is not None
        snapshot = self.observables.snapshot(
            self.clock.t, self.clock.k, integrator.q, integrator.omega, self.step_torque_body, self.digest
        )
        sources = command_torques(self.commands, snapshot.orientation) + self.rods.named(
            integrator.t, integrator.q, self.commands.rod_dipoles
        )
        if self.gravity is not None:
            gravity = self.body.vector_from_principal(self.gravity(0.0, integrator.q, integrator.omega))
            sources.append(("gravity", np.asarray(gravity, dtype=float)))
        return dataclasses.replace(snapshot, torque_sources=tuple(sources))

    def set_command_torque(self) -> None:
        """Give the integrator the commanded torque for the next step (principal frame)."""
        if self.gravity is not None:
            return  # gravity scenes have no command inputs (scene validation)
        integrator = self.integrator
        assert integrator is not None
        principal_from_body = self.observables.principal_from_body
        body = self.commands.body_sum
        world = self.commands.world_sum
        if world is not None:
            in_body = world_in_body(tuple(integrator.q), principal_from_body, world)
            body = (body[0] + in_body[0], body[1] + in_body[1], body[2] + in_body[2])
        body = self.rods.add(body, integrator.t, integrator.q, self.commands.rod_dipoles)
        self.step_torque_body = body
        if not any(body):
            torque = None
        else:
            torque = ConstantTorque(np.array(frames.vector_to_principal(principal_from_body, body)))
        integrator.torque = torque

    # ------------------------------------------------------------------ stepping

    def advance(self, n: int) -> tuple[int, str | None]:
        """Advance up to ``n`` steps: (steps done, None) or, when a step fails, (steps done, reason).

        After a failure the integrator is at its last good state (never a non-finite one).
        """
        integrator = self.integrator
        assert integrator is not None
        clock = self.clock
        commands = self.commands
        end = clock.k + int(n)
        done = 0
        while clock.k < end:
            due = commands.next_event is not None and clock.k >= commands.next_event
            if due:
                commands.process_due()
            if due or commands.world_sum is not None or self.rods.active:  # re-expressed at every boundary
                self.set_command_torque()
            if commands.world_sum is not None or self.rods.active:
                stop = clock.k + 1
            else:
                stop = end if commands.next_event is None else min(end, commands.next_event)
            chunk = stop - clock.k
            reason = self.rotation_failure(clock.dt)
            if reason is not None:
                return done, f"rotation limit: {reason}"
            chunk = min(chunk, self._steps_within_rotation_limit())
            start = self._saved_state()
            try:
                q_steps, omega_steps = integrator.advance_saving(chunk, 1)  # = advance(chunk), each step kept
            except (ArithmeticError, ValueError) as exc:
                # NonFiniteStateError, or a math error on the way to it (sin(inf), overflow)
                good = integrator.n_steps - start[3]
                kept = good < chunk and np.all(np.isfinite(integrator.q)) and np.all(np.isfinite(integrator.omega))
                if kept and self._derived_failure() is None:
                    clock.k += good  # the method stopped at its last good step (energy and momentum finite)
                    done += good
                    self.digest = fold_steps(self.digest, [clock.t], [integrator.q], [integrator.omega])  # once
                else:
                    self._restore(start)
                name = "NonFiniteStateError" if isinstance(exc, NonFiniteStateError) else type(exc).__name__
                return done, f"{name}: {exc}"
            reason = self._derived_failure()
            if reason is not None:  # a finite state whose energy or momentum overflows
                self._restore(start)
                return done, f"NonFiniteStateError: {reason}"
            self.digest = fold_steps(self.digest, clock.times_of_next_steps(chunk), q_steps, omega_steps)
            clock.k += chunk
            done += chunk
        return done, None

    def _saved_state(self) -> tuple[Any, ...]:
        """What :meth:`_restore` puts back: (t, q, omega, steps taken)."""
        integrator = self.integrator
        assert integrator is not None
        return (integrator.t, integrator.q, integrator.omega, integrator.n_steps)

    def _restore(self, saved: tuple[Any, ...]) -> None:
        assert self.integrator is not None
        self.integrator.set_state(*saved[:3])
        self.integrator.n_steps = saved[3]

    # ------------------------------------------------------------------ limits

    def check_spin(self, omega: np.ndarray) -> None:
        """ValueError if ``omega`` (rad/s) turns the body more than the rotation limit per step."""
        rotation = math.hypot(*omega.tolist()) * self.clock.dt
        if rotation > limits.MAX_ROTATION_PER_STEP:
            raise ValueError(
                f"angular_velocity of norm {rotation / self.clock.dt:.3g} rad/s "
                f"turns the body {rotation:.3g} rad per step of "
                f"{self.clock.dt:g} s (limit {limits.MAX_ROTATION_PER_STEP:g} rad per step)"
            )

    def _torque_bound(self) -> float:
        """A bound (N*m) on the torque norm over the next steps."""
        if self.gravity is not None:
            return self.observables.gravity_torque_bound()
        return self.commands.norm_bound() + self.rods.bound(self.clock.t)

    def rotation_failure(self, dt_ahead: float) -> str | None:
        """Why the state violates the rotation limit after ``dt_ahead`` s under the current torque.

        None: it does not.
        """
        dt = self.clock.dt
        omega = math.hypot(*self.integrator.omega.tolist())  # type: ignore[union-attr]
        reach = omega + dt_ahead * self._torque_bound() / self._i_min
        rotation = reach * dt
        if rotation <= limits.MAX_ROTATION_PER_STEP:
            return None
        return (
            f"|omega| {'would reach' if dt_ahead else 'is'} {reach:.3g} rad/s, {rotation:.3g} rad per step of {dt:g} s "
            f"(limit {limits.MAX_ROTATION_PER_STEP:g} rad per step): lower the torque or dt, then reset or set_state"
        )

    def _steps_within_rotation_limit(self) -> int:
        """How many steps the current torque may act before |ω| dt could pass the rotation limit."""
        torque = self._torque_bound()
        if torque == 0.0:
            return 1 << 62
        dt = self.clock.dt
        omega = math.hypot(*self.integrator.omega.tolist())  # type: ignore[union-attr]
        gain_per_step = dt * torque / self._i_min
        if not gain_per_step > 0.0:  # a torque so small that its effect underflows
            return 1 << 62
        return max(1, int(min((limits.MAX_ROTATION_PER_STEP / dt - omega) / gain_per_step, 1 << 62)))

    def _derived_failure(self) -> str | None:
        """Why a snapshot of the current state would hold a non-finite number (None: it would not)."""
        i1, i2, i3 = (float(v) for v in self.body.principal_moments)
        w1, w2, w3 = self.integrator.omega.tolist()  # type: ignore[union-attr]
        kinetic = 0.5 * (i1 * w1 * w1 + i2 * w2 * w2 + i3 * w3 * w3)
        momentum = math.hypot(i1 * w1, i2 * w2, i3 * w3)
        # a margin below the float range: the snapshot rotates these vectors and forms drifts
        if max(kinetic, momentum, math.hypot(w1, w2, w3)) <= _DERIVED_CEILING:
            return None
        return f"kinetic energy {kinetic} J or |L| {momentum} kg*m^2/s overflows at t = {self.clock.t:.9g} s"
