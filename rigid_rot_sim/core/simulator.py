"""The simulation of one scene, step by step, without ROS: what the node (and resim) drive.

:class:`Simulator` owns the rigid body, the integrator from the registry, the torque
inputs with their hold / timeout state, the scene's torque schedules, torques applied
for a duration (the ``~/apply_torque`` service), pause / step / reset / set_state and
the drift counters. It returns plain :class:`StateSnapshot` values (numpy, user body
frame, SI units).

Time and determinism
--------------------
Physics advances in fixed steps of ``dt``; the sim time of step k is computed from the
integer step counter (``t = t_epoch + (k - k_epoch) * dt``, with ``t_epoch = k_epoch = 0``
until dt is changed at run time), never accumulated. Every torque change takes effect at
a step boundary: the first boundary at or after its *effective time* (see
:meth:`Simulator.step_at_or_after`). A topic command's effective time is its header
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
components at most ``MAX_MAGNITUDE`` N*m (and a norm of at most :attr:`Simulator.max_torque`
when that is > 0), frame ids at most ``MAX_NAME_LENGTH`` characters, and a state whose ω
turns the body at most ``MAX_ROTATION_PER_STEP`` rad per step. A run stops (``paused``, the
reason in :attr:`Simulator.failure`, the last good state kept, every snapshot field finite)
when a step fails (:class:`NonFiniteStateError`, whatever the method) or when ω, with the
torque acting, would exceed the rotation limit before the next step. :meth:`Simulator.reset`
and :meth:`Simulator.set_state` clear the failure and resume a run that the failure paused.
"""

from __future__ import annotations

import heapq
import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core import advice, limits
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.dynamics import RigidBody
from rigid_rot_sim.core.exact import quaternion_to_zxz
from rigid_rot_sim.core.integrators import get_method
from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError
from rigid_rot_sim.core.observer import SimulationObserver
from rigid_rot_sim.core.scene import Scene, TopicInput
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque
from rigid_rot_sim.core import validation

__all__ = ["Simulator", "StateSnapshot", "TorqueCommand", "CommandRejected", "APPLY_TORQUE_SOURCE"]

#: ``source`` of torques applied through :meth:`Simulator.apply_torque`.
APPLY_TORQUE_SOURCE = "apply_torque"

# A time within this fraction of a step of a boundary counts as on it (t / dt is rarely an
# exact integer in floating point: 0.3 / 0.1 = 2.9999999999999996).
_BOUNDARY_SLACK = 1e-9

_ZERO3 = (0.0, 0.0, 0.0)

#: Methods whose ``advance(n)`` differs in the last bits from n single steps: dop853 lands
#: on ``t + n * dt`` (one rounding) instead of n additions. Stepped one at a time so that
#: states do not depend on how the node chunks the run (publish rates, wall clock).
_STEPWISE_METHODS = frozenset({"dop853"})

#: A command stamped further ahead of sim time than this (s) is rejected: its publisher
#: almost certainly stamps with wall-clock time instead of the sim time on /clock, and
#: would otherwise wait for decades of sim time.
STAMP_HORIZON = 60.0

#: A drift reference (J, kg*m^2/s) below this counts as zero (drift 0, as for a body at rest):
#: relative to it, any real change would overflow a float.
_TINY_REFERENCE = 1e-250

#: Largest kinetic energy (J), |L| (kg*m^2/s) and |omega| (rad/s) a state may have: the snapshot's
#: rotations and drifts of such values stay finite (a NaN compares false: refused too).
_DERIVED_CEILING = 1e300


class CommandRejected(ValueError):
    """A torque command or request that was refused; ``reason`` says why."""

    def __init__(self, source: str, reason: str) -> None:
        super().__init__(f"{source}: {reason}")
        self.source = source
        self.reason = reason


@dataclass(frozen=True)
class TorqueCommand:
    """An accepted torque command, as the simulator scheduled it.

    ``torque`` (N*m) is expressed in ``frame`` (``body`` or ``world``, resolved from the
    input's policy and the header). ``receipt_time`` is the sim time at receipt (None when
    fed with an explicit effective time), ``stamp`` the header stamp (s; None when zero or
    absent), ``effective_time`` the time it was scheduled for and ``step`` the first step
    boundary at or after it, where it takes effect. ``duration`` (s) is set for
    :meth:`Simulator.apply_torque` torques, which end after it.
    """

    source: str
    torque: tuple[float, float, float]
    frame: str
    effective_time: float
    step: int
    receipt_time: float | None = None
    stamp: float | None = None
    duration: float | None = None


@dataclass(frozen=True)
class StateSnapshot:
    """The state at one step boundary, in the scene's frames (user body frame, world frame).

    Units: s, rad/s, kg*m^2/s, N*m, J. ``orientation`` is the unit quaternion (x, y, z, w)
    rotating body -> world. ``torque_body`` is the total torque over the step that ended
    here (gravity at this state for a top). The drifts are ``(E - E_ref) / |E_ref|`` and
    ``(|L| - |L_ref|) / |L_ref|`` since the last reset or set_state (0 when the reference
    is 0, i.e. a body at rest). ``euler_zxz`` (rad: precession, nutation, spin of the
    symmetry axis pivot -> centre of mass), ``p_phi`` and ``p_psi`` (kg*m^2/s) are set for
    gravity scenes only.
    """

    t: float
    step: int
    orientation: np.ndarray
    angular_velocity_body: np.ndarray
    angular_velocity_world: np.ndarray
    angular_momentum_body: np.ndarray
    angular_momentum_world: np.ndarray
    torque_body: np.ndarray
    kinetic_energy: float
    potential_energy: float
    energy_drift: float
    angular_momentum_drift: float
    euler_zxz: np.ndarray | None = None
    p_phi: float | None = None
    p_psi: float | None = None

    @property
    def energy(self) -> float:
        """Total energy, J."""
        return self.kinetic_energy + self.potential_energy


@dataclass
class _Held:
    """The value an input currently holds (user frames)."""

    torque: tuple[float, float, float]
    frame: str
    serial: int


class Simulator:
    """Simulate ``scene``; ``method`` / ``dt`` / ``options`` override the scene's integrator.

    Parameters
    ----------
    scene : Scene
        A validated scene (:func:`rigid_rot_sim.core.scene.load_scene`).
    method : str, optional
        Integrator name from the registry, or ``auto`` (the scene's choice by default).
    dt : float, optional
        Physics step, s (> 0).
    options : dict, optional
        Keyword options of the method; default the scene's.
    """

    def __init__(
        self,
        scene: Scene,
        *,
        method: str | None = None,
        dt: float | None = None,
        options: dict[str, Any] | None = None,
    ) -> None:
        self.scene = scene
        self.body = RigidBody.from_inertia(scene.body.inertia_array, name="body.inertia")
        self.frames = scene.frames
        self.inputs: dict[str, TopicInput] = {spec.topic: spec for spec in scene.topic_inputs}
        self.gravity: GravityTorque | None = None
        self._com_body: np.ndarray | None = None
        self._weight = 0.0
        if scene.gravity is not None:
            assert scene.body.mass is not None and scene.body.center_of_mass is not None
            self._com_body = np.array(scene.body.center_of_mass, dtype=float)
            self._weight = scene.body.mass * scene.gravity.acceleration
            self.gravity = GravityTorque(self.body.vector_to_principal(self._com_body), self._weight)
            self._symmetry_axis = self._com_body / np.linalg.norm(self._com_body)
            # frame whose z is the symmetry axis, for the heavy top's Euler angles
            align, _ = Rotation.align_vectors([self._symmetry_axis], [[0.0, 0.0, 1.0]])
            self._body_from_top = tuple(float(v) for v in align.as_quat())
        self._body_from_principal = tuple(float(v) for v in self.body.body_from_principal)
        self._principal_from_body = quat.conjugate(self._body_from_principal)
        self._serial = itertools.count()
        #: Told what happens to the run, in order (:class:`SimulationObserver`); add with :meth:`add_observer`.
        self.observers: list[SimulationObserver] = []
        self._k = 0
        self.paused = False
        self.failure: str | None = None
        self._paused_by_failure = False
        #: Largest accepted torque norm (N*m) of a command or apply_torque request; 0 = no limit.
        self.max_torque = float(scene.commands.max_torque)
        self._i_min = float(np.min(self.body.principal_moments))
        self._integrator: Integrator | None = None
        self.method = ""
        self.dt = 0.0
        self.options: dict[str, Any] = {}
        self._configure_integrator(
            scene.integrator.method if method is None else method,
            scene.integrator.dt if dt is None else dt,
            dict(scene.integrator.options) if options is None else dict(options),
            first=True,
        )
        self.reset()
        reason = self._rotation_failure(0.0)
        if reason is not None:
            raise ValueError(f"initial angular velocity: {reason}")

    def add_observer(self, observer: SimulationObserver) -> None:
        """Report what happens to the run to ``observer`` from now on (after those added before)."""
        self.observers.append(observer)

    # ------------------------------------------------------------------ integrator

    def omega_bound(self) -> float:
        """A bound on |ω| (rad/s) over the run, for :mod:`advice` (exact where physics gives one).

        Free body: |L| / I_min (|L| is conserved). Gravity: energy conservation,
        ``T <= E - V_min`` so ``|ω| <= sqrt(2 (E + m g l) / I_min)``. Driven by
        torques: the initial |L| / I_min plus the schedules' total angular impulse /
        I_min; a topic-driven run has no a-priori bound (its commands are unknown).
        """
        i_min = float(np.min(self.body.principal_moments))
        omega0 = np.array(self.scene.initial.angular_velocity, dtype=float)
        l0 = float(np.linalg.norm(self.body.inertia_tensor @ omega0))
        if self.gravity is not None:
            q0 = self.scene.initial.orientation
            v0 = self._weight * quat.rotate(q0, self._com_body)[2]  # type: ignore[arg-type]
            t0 = 0.5 * float(omega0 @ self.body.inertia_tensor @ omega0)
            reach = self._weight * float(np.linalg.norm(self._com_body))
            return math.sqrt(2.0 * max(t0 + v0 + reach, 0.0) / i_min)
        impulse = 0.0
        for schedule in self.scene.schedules:
            segments = schedule.segments
            for this, following in zip(segments, segments[1:]):
                impulse += math.hypot(*this.torque) * (following.start - this.start)
            if math.hypot(*segments[-1].torque) > 0.0 and self.scene.duration is not None:
                impulse += math.hypot(*segments[-1].torque) * max(self.scene.duration - segments[-1].start, 0.0)
        return (l0 + impulse) / i_min

    def _configure_integrator(self, method: str, dt: float, options: dict[str, Any], first: bool = False) -> None:
        dt = validation.positive_scalar("dt", dt)
        if method == "auto":
            method = advice.choose_integrator(self.body.principal_moments, self.omega_bound(), dt, self.scene.torque_kind)
        cls = get_method(method)  # ValueError listing the valid names
        if self.scene.topic_inputs or self.scene.schedules:
            # commands give the method a ConstantTorque between boundaries: refuse now, not mid-run,
            # a method that cannot take one (the exact flow is torque-free)
            try:
                cls(self.body.principal_moments, dt, ConstantTorque(np.ones(3)), **options)
            except ValueError as exc:
                raise ValueError(f"integrator {method!r} cannot run this scene's torque inputs: {exc}") from None
        if first:
            state = (0.0, self.body.attitude_to_principal(np.array(self.scene.initial.orientation)), np.zeros(3))
        else:
            assert self._integrator is not None
            state = (self._integrator.t, self._integrator.q, self._integrator.omega)
        integrator = cls(
            self.body.principal_moments, dt, self._integrator.torque if self._integrator else self.gravity,
            t0=state[0], q0=state[1], omega0=state[2], **options,
        )
        if not first:
            # keep t = t_epoch + (k - k_epoch) dt exact from here on
            self._t_epoch = self.t
            self._k_epoch = self.step_index
        self._integrator = integrator
        self.method = method
        self.dt = float(dt)
        self.options = dict(options)
        if not first:
            self._reschedule()

    def set_integrator(self, method: str | None = None, dt: float | None = None, options: dict[str, Any] | None = None) -> None:
        """Switch method and/or step at the current state (ValueError, nothing changed, if invalid)."""
        step = self._k
        self._configure_integrator(
            self.method if method is None else method,
            self.dt if dt is None else dt,
            self.options if options is None and method in (None, self.method) else dict(options or {}),
        )
        for observer in self.observers:
            observer.integrator_changed(step, self.method, self.dt, dict(self.options))

    def check_integrator(self, method: str, dt: float) -> None:
        """ValueError (the reason) if :meth:`set_integrator` would refuse ``method`` at ``dt``; no change."""
        dt = validation.positive_scalar("dt", dt)
        if method == "auto":
            method = advice.choose_integrator(self.body.principal_moments, self.omega_bound(), dt, self.scene.torque_kind)
        cls = get_method(method)
        torque = ConstantTorque(np.ones(3)) if self.scene.topic_inputs or self.scene.schedules else self.gravity
        try:
            cls(self.body.principal_moments, dt, torque)
        except ValueError as exc:
            raise ValueError(f"integrator {method!r} cannot run this scene: {exc}") from None

    def warnings(self) -> list[str]:
        """Stability / accuracy warnings for the current method and step (:mod:`advice`)."""
        return advice.step_warnings(self.method, self.body.principal_moments, self.omega_bound(), self.dt)

    # ------------------------------------------------------------------ time

    @property
    def step_index(self) -> int:
        """Number of steps since the last reset."""
        return self._k

    @property
    def t(self) -> float:
        """Sim time of the current step boundary, s."""
        return self.time_of_step(self._k)

    def time_of_step(self, k: int) -> float:
        """Sim time (s) of step boundary k."""
        return self._t_epoch + (k - self._k_epoch) * self.dt

    def step_at_or_after(self, t: float) -> int:
        """The first step boundary at or after sim time t (s), never before the current one."""
        k = self._k_epoch + math.ceil((t - self._t_epoch) / self.dt - _BOUNDARY_SLACK)
        return max(k, self._k)

    def step_at_or_before(self, t: float) -> int:
        """The last step boundary at or before sim time t (s) (may be in the past)."""
        return self._k_epoch + math.floor((t - self._t_epoch) / self.dt + _BOUNDARY_SLACK)

    # ------------------------------------------------------------------ commands

    def resolve_frame(self, source: str, frame_id: str, policy: str) -> str:
        """``body`` or ``world`` for a command given in ``frame_id`` under an input's frame policy.

        Policies: ``body`` / ``world`` (an empty frame_id means that frame; a non-empty one
        must name it), ``header`` (frame_id must name the body or the world frame).
        CommandRejected otherwise.
        """
        names = {self.frames.body: "body", self.frames.world: "world"}
        if len(frame_id) > limits.MAX_NAME_LENGTH:
            raise CommandRejected(
                source, f"frame_id of {len(frame_id)} characters exceeds the limit of {limits.MAX_NAME_LENGTH}"
            )
        if frame_id and frame_id not in names:
            raise CommandRejected(
                source, f"frame {frame_id!r} is neither the body frame {self.frames.body!r} nor the world frame {self.frames.world!r}"
            )
        if policy == "header":
            if not frame_id:
                raise CommandRejected(
                    source, f"empty header.frame_id: this input takes the frame from the header ({self.frames.body!r} or {self.frames.world!r})"
                )
            return names[frame_id]
        if frame_id and names[frame_id] != policy:
            expected = self.frames.body if policy == "body" else self.frames.world
            raise CommandRejected(source, f"frame {frame_id!r} given, but this input is expressed in {expected!r}")
        return policy

    def _finite_torque(self, source: str, torque: Any, what: str = "torque") -> tuple[float, float, float]:
        values = tuple(float(v) for v in np.asarray(torque, dtype=float).reshape(3))
        for axis, value in zip("xyz", values):
            if not math.isfinite(value):
                raise CommandRejected(source, f"non-finite {what}.{axis} = {value}")
            if abs(value) > limits.MAX_MAGNITUDE:
                raise CommandRejected(source, f"{what}.{axis} = {value:g} beyond the limit of {limits.MAX_MAGNITUDE:g}")
        if what == "torque" and self.max_torque > 0.0:
            norm = math.hypot(*values)
            if norm > self.max_torque:
                raise CommandRejected(
                    source, f"|torque| = {norm:.6g} N*m exceeds max_torque = {self.max_torque:g} N*m"
                )
        return values  # type: ignore[return-value]

    def receive_torque(
        self,
        source: str,
        torque: Any,
        frame_id: str = "",
        stamp: float | None = None,
        force: Any = None,
    ) -> TorqueCommand:
        """Accept a command that arrived now on topic input ``source``, or raise CommandRejected.

        ``torque`` (N*m) in ``frame_id`` (resolved with the input's policy); ``stamp`` the
        header stamp (s; 0 or None = none); ``force`` (N) the force of a WrenchStamped:
        a rotation-only simulator cannot apply a force, so a non-zero one rejects the
        command. Effective time: the stamp when non-zero and not in the past, else now.
        """
        spec = self.inputs.get(source)
        if spec is None:
            raise ValueError(f"source {source!r} is not a torque input of this scene (inputs: {sorted(self.inputs)})")
        try:
            return self._receive_torque(spec, source, torque, frame_id, stamp, force)
        except CommandRejected as rejected:
            self._notify_rejected(rejected, frame_id, torque)
            raise

    def _receive_torque(
        self, spec: TopicInput, source: str, torque: Any, frame_id: str, stamp: float | None, force: Any
    ) -> TorqueCommand:
        values = self._finite_torque(source, torque)
        if force is not None:
            force_values = self._finite_torque(source, force, "force")
            if any(force_values):
                raise CommandRejected(
                    source, f"non-zero force {force_values} N: only torques act on the body (send force = 0)"
                )
        frame = self.resolve_frame(source, frame_id, spec.frame)
        now = self.t
        if stamp is not None and (not math.isfinite(stamp) or stamp == 0.0):
            stamp = None
        if stamp is not None and stamp > now + STAMP_HORIZON:
            raise CommandRejected(
                source,
                f"header stamp {stamp:.9g} s is {stamp - now:.3g} s ahead of sim time {now:.9g} s "
                f"(limit {STAMP_HORIZON:g} s): stamp with sim time (/clock) or leave the stamp zero",
            )
        effective = stamp if stamp is not None and stamp >= now else now
        return self.submit_torque(source, values, frame, effective, receipt_time=now, stamp=stamp)

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
        :meth:`step_at_or_after` ``(effective_time)``; replaces the input's previous value
        then, and falls back to zero after the input's timeout (sim time), if it has one.
        """
        if source not in self.inputs:
            raise ValueError(f"source {source!r} is not a torque input of this scene (inputs: {sorted(self.inputs)})")
        if frame not in ("body", "world"):
            raise ValueError(f"frame must be 'body' or 'world', got {frame!r}")
        values = self._finite_torque(source, torque)
        effective_time = validation.finite_scalar("effective_time", effective_time)
        step = self._k
        command = TorqueCommand(
            source=source,
            torque=values,
            frame=frame,
            effective_time=effective_time,
            step=self.step_at_or_after(effective_time),
            receipt_time=receipt_time,
            stamp=stamp,
        )
        self._push(command.step, "command", command)
        for observer in self.observers:
            observer.command_accepted(step, command)
        return command

    def apply_torque(self, torque: Any, frame_id: str, duration: float, effective_time: float | None = None) -> TorqueCommand:
        """Add ``torque`` (N*m, in ``frame_id``; empty = body frame) for ``duration`` s of sim time.

        Starts at the current step boundary (or at ``effective_time``, for resim) and acts
        on top of the topic commands; several such torques add up. CommandRejected for a
        non-finite torque, an unknown frame or a duration that is not finite and > 0.
        """
        source = APPLY_TORQUE_SOURCE
        try:
            values = self._finite_torque(source, torque)
            frame = self.resolve_frame(source, frame_id, "header" if frame_id else "body")
            if not (math.isfinite(duration) and duration > 0.0):
                raise CommandRejected(source, f"duration must be finite and > 0 s, got {duration}")
        except CommandRejected as rejected:
            self._notify_rejected(rejected, frame_id, torque)
            raise
        step = self._k
        start = self.t if effective_time is None else validation.finite_scalar("effective_time", effective_time)
        command = TorqueCommand(
            source=source,
            torque=values,
            frame=frame,
            effective_time=start,
            step=self.step_at_or_after(start),
            receipt_time=self.t if effective_time is None else None,
            duration=float(duration),
        )
        self._push(command.step, "apply_start", command)
        for observer in self.observers:
            observer.torque_applied(step, command)
        return command

    def _notify_rejected(self, rejected: CommandRejected, frame_id: str, torque: Any) -> None:
        for observer in self.observers:
            observer.command_rejected(self._k, rejected.source, rejected.reason, frame_id, torque)

    # ------------------------------------------------------------------ events

    def _push(self, step: int, kind: str, payload: Any) -> None:
        heapq.heappush(self._events, (step, next(self._serial), kind, payload))
        if step < self._next_event:
            self._next_event = step

    def _reschedule(self) -> None:
        """Recompute the step of every pending event from its time (after a dt change)."""
        events, self._events = self._events, []
        self._next_event = math.inf
        for _, _, kind, payload in events:
            if kind == "command" or kind == "apply_start":
                step = self.step_at_or_after(payload.effective_time)
                payload = TorqueCommand(**{**payload.__dict__, "step": step})
            else:
                step = self.step_at_or_after(payload[0])
            self._push(step, kind, payload)

    def _process_events(self) -> None:
        k = self._k
        events = self._events
        while events and events[0][0] <= k:
            _, serial, kind, payload = heapq.heappop(events)
            if kind == "command":
                self._held[payload.source] = _Held(payload.torque, payload.frame, serial)
                timeout = self.inputs[payload.source].timeout
                if timeout is not None:
                    end = self.t + timeout
                    self._push(self.step_at_or_after(end), "expire", (end, payload.source, serial))
            elif kind == "expire":
                _, source, held_serial = payload
                held = self._held.get(source)
                if held is not None and held.serial == held_serial:
                    del self._held[source]
            elif kind == "apply_start":
                self._applied[serial] = payload
                end = self.t + payload.duration
                self._push(self.step_at_or_after(end), "apply_end", (end, serial))
            elif kind == "apply_end":
                self._applied.pop(payload[1], None)
            elif kind == "schedule":
                _, index, torque = payload
                self._scheduled[index] = torque
        self._next_event = events[0][0] if events else math.inf
        self._update_torque_sums()

    def _update_torque_sums(self) -> None:
        body = [0.0, 0.0, 0.0]
        world = [0.0, 0.0, 0.0]
        contributions = [(h.torque, h.frame) for h in self._held.values()]
        contributions += [(c.torque, c.frame) for c in self._applied.values()]
        contributions += [(torque, self.scene.schedules[i].frame) for i, torque in self._scheduled.items()]
        for torque, frame in contributions:
            target = body if frame == "body" else world
            for i in range(3):
                target[i] += torque[i]
        self._torque_body_sum = tuple(body)
        self._torque_world_sum = tuple(world) if any(world) else None
        self._set_command_torque()

    def _set_command_torque(self) -> None:
        """Give the integrator the torque for the next step (principal frame)."""
        if self.gravity is not None:
            return  # gravity scenes have no command inputs (scene validation)
        body = self._torque_body_sum
        if self._torque_world_sum is not None:
            q_body = quat.multiply(self._integrator.q, self._principal_from_body)  # type: ignore[union-attr]
            world_in_body = quat.rotate_inverse(q_body, self._torque_world_sum)
            body = (body[0] + world_in_body[0], body[1] + world_in_body[1], body[2] + world_in_body[2])
        self._step_torque_body = body
        if not any(body):
            torque = None
        else:
            torque = ConstantTorque(np.array(quat.rotate(self._principal_from_body, body)))
        self._integrator.torque = torque  # type: ignore[union-attr]

    # ------------------------------------------------------------------ stepping

    def advance(self, n: int) -> int:
        """Advance up to ``n`` steps (fewer if a step fails); returns the number done.

        A non-finite state (an integrator diverging) pauses the simulation, restores the
        last good state and records the reason in :attr:`failure`.
        """
        integrator = self._integrator
        assert integrator is not None
        end = self._k + int(n)
        done = 0
        while self._k < end:
            if self._k >= self._next_event:
                self._process_events()
            if self._torque_world_sum is not None:
                self._set_command_torque()  # re-expressed in the body frame at every boundary
                stop = self._k + 1
            else:
                stop = min(end, self._next_event)
            chunk = stop - self._k
            reason = self._rotation_failure(self.dt)
            if reason is not None:
                self.fail(f"rotation limit: {reason}")
                return done
            chunk = min(chunk, self._steps_within_rotation_limit())
            start = (integrator.t, integrator.q, integrator.omega, integrator.n_steps)
            try:
                if integrator.name in _STEPWISE_METHODS:
                    for _ in range(chunk):
                        integrator.advance(1)
                else:
                    integrator.advance(chunk)
            except (ArithmeticError, ValueError) as exc:
                # NonFiniteStateError, or a math error on the way to it (sin(inf), overflow)
                good = integrator.n_steps - start[3]
                kept = good < chunk and np.all(np.isfinite(integrator.q)) and np.all(np.isfinite(integrator.omega))
                if kept and self._derived_failure() is None:
                    self._k += good  # the method stopped at its last good step (energy and momentum finite)
                    done += good
                else:
                    integrator.set_state(*start[:3])
                    integrator.n_steps = start[3]
                name = "NonFiniteStateError" if isinstance(exc, NonFiniteStateError) else type(exc).__name__
                self.fail(f"{name}: {exc}")
                return done
            reason = self._derived_failure()
            if reason is not None:  # a finite state whose energy or momentum overflows
                integrator.set_state(*start[:3])
                integrator.n_steps = start[3]
                self.fail(f"NonFiniteStateError: {reason}")
                return done
            self._k += chunk
            done += chunk
        return done

    def fail(self, reason: str) -> None:
        """Stop the run at the current (good) state with ``reason`` (cleared by reset / set_state)."""
        self.failure = reason
        self._paused_by_failure = self._paused_by_failure or not self.paused
        self.paused = True
        for observer in self.observers:
            observer.failed(self._k, reason)

    def _torque_bound(self) -> float:
        """A bound (N*m) on the torque norm over the next steps."""
        if self.gravity is not None:
            return self._weight * float(np.linalg.norm(self._com_body))
        return math.hypot(*self._torque_body_sum) + (math.hypot(*self._torque_world_sum) if self._torque_world_sum else 0.0)

    def _rotation_failure(self, dt_ahead: float) -> str | None:
        """Why the state violates the rotation limit after ``dt_ahead`` s under the current torque (None: it does not)."""
        omega = math.hypot(*self._integrator.omega.tolist())  # type: ignore[union-attr]
        reach = omega + dt_ahead * self._torque_bound() / self._i_min
        rotation = reach * self.dt
        if rotation <= limits.MAX_ROTATION_PER_STEP:
            return None
        return (
            f"|omega| {'would reach' if dt_ahead else 'is'} {reach:.3g} rad/s, {rotation:.3g} rad per step of {self.dt:g} s "
            f"(limit {limits.MAX_ROTATION_PER_STEP:g} rad per step): lower the torque or dt, then reset or set_state"
        )

    def _steps_within_rotation_limit(self) -> int:
        """How many steps the current torque may act before |ω| dt could pass the rotation limit."""
        torque = self._torque_bound()
        if torque == 0.0:
            return 1 << 62
        omega = math.hypot(*self._integrator.omega.tolist())  # type: ignore[union-attr]
        gain_per_step = self.dt * torque / self._i_min
        if not gain_per_step > 0.0:  # a torque so small that its effect underflows
            return 1 << 62
        return max(1, int(min((limits.MAX_ROTATION_PER_STEP / self.dt - omega) / gain_per_step, 1 << 62)))

    def _derived_failure(self) -> str | None:
        """Why a snapshot of the current state would hold a non-finite number (None: it would not)."""
        i1, i2, i3 = (float(v) for v in self.body.principal_moments)
        w1, w2, w3 = self._integrator.omega.tolist()  # type: ignore[union-attr]
        kinetic = 0.5 * (i1 * w1 * w1 + i2 * w2 * w2 + i3 * w3 * w3)
        momentum = math.hypot(i1 * w1, i2 * w2, i3 * w3)
        # a margin below the float range: the snapshot rotates these vectors and forms drifts
        if max(kinetic, momentum, math.hypot(w1, w2, w3)) <= _DERIVED_CEILING:
            return None
        return f"kinetic energy {kinetic} J or |L| {momentum} kg*m^2/s overflows at t = {self.t:.9g} s"

    def advance_to(self, k: int) -> int:
        """Advance to step boundary ``k`` (no-op when already there); returns steps done."""
        return self.advance(max(0, int(k) - self._k))

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
        step = self._k
        self._k = 0
        self._k_epoch = 0
        self._t_epoch = 0.0
        self._events: list[tuple[int, int, str, Any]] = []
        self._next_event: float = math.inf
        self._held: dict[str, _Held] = {}
        self._applied: dict[int, TorqueCommand] = {}
        self._scheduled: dict[int, tuple[float, float, float]] = {}
        self._torque_body_sum: tuple[float, float, float] = _ZERO3
        self._torque_world_sum: tuple[float, float, float] | None = None
        self._step_torque_body: tuple[float, float, float] = _ZERO3
        self._clear_failure()
        for index, schedule in enumerate(self.scene.schedules):
            for segment in schedule.segments:
                self._push(self.step_at_or_after(segment.start), "schedule", (segment.start, index, segment.torque))
        self._set_principal_state(
            0.0,
            self.body.attitude_to_principal(np.array(self.scene.initial.orientation)),
            self.body.vector_to_principal(np.array(self.scene.initial.angular_velocity)),
        )
        self._update_torque_sums()
        for observer in self.observers:
            observer.reset(step)

    def set_state(self, orientation: Any, angular_velocity: Any) -> None:
        """Replace attitude (x, y, z, w; body -> world) and ω (rad/s, body frame) at the current time.

        The quaternion is normalised; ValueError (state unchanged) for a zero or
        non-finite one or a non-finite ω. The drift references restart here.
        """
        step = self._k
        q = validation.quaternion("orientation", orientation)
        omega = validation.finite_vector("angular_velocity", angular_velocity)
        rotation = math.hypot(*omega.tolist()) * self.dt
        if rotation > limits.MAX_ROTATION_PER_STEP:
            raise ValueError(
                f"angular_velocity of norm {rotation / self.dt:.3g} rad/s turns the body {rotation:.3g} rad per step of "
                f"{self.dt:g} s (limit {limits.MAX_ROTATION_PER_STEP:g} rad per step)"
            )
        self._set_principal_state(self.t, self.body.attitude_to_principal(q), self.body.vector_to_principal(omega))
        self._clear_failure()
        if self._torque_world_sum is not None:
            self._set_command_torque()
        for observer in self.observers:
            observer.state_set(step, tuple(float(v) for v in orientation), tuple(float(v) for v in angular_velocity))

    def _clear_failure(self) -> None:
        """Forget a failure; a run the failure paused runs again (a pause asked for stays)."""
        if self.failure is not None and self._paused_by_failure:
            self.paused = False
        self.failure = None
        self._paused_by_failure = False

    def _set_principal_state(self, t: float, q_principal: np.ndarray, omega_principal: np.ndarray) -> None:
        assert self._integrator is not None
        self._integrator.set_state(t, q_principal, omega_principal)
        self._energy_ref = 0.0
        self._momentum_ref = 0.0
        reference = self.snapshot()
        self._energy_ref = reference.energy
        self._momentum_ref = math.hypot(*reference.angular_momentum_world)

    def snapshot(self) -> StateSnapshot:
        """The state at the current step boundary (user body frame; see :class:`StateSnapshot`)."""
        integrator = self._integrator
        assert integrator is not None
        # plain floats and the quaternion helpers: this runs at every publication
        i1, i2, i3 = (float(v) for v in self.body.principal_moments)
        q_principal = tuple(float(v) for v in integrator.q)
        w1, w2, w3 = (float(v) for v in integrator.omega)
        body_from_principal = self._body_from_principal
        q = quat.multiply(q_principal, self._principal_from_body)
        if q[3] < 0.0:
            q = (-q[0], -q[1], -q[2], -q[3])  # same rotation; w >= 0 keeps outputs continuous near identity
        omega_body = quat.rotate(body_from_principal, (w1, w2, w3))
        momentum_body = quat.rotate(body_from_principal, (i1 * w1, i2 * w2, i3 * w3))
        momentum_world = quat.rotate(q, momentum_body)
        kinetic = 0.5 * (i1 * w1 * w1 + i2 * w2 * w2 + i3 * w3 * w3)
        torque_body = self._step_torque_body
        potential = 0.0
        euler = p_phi = p_psi = None
        if self.gravity is not None:
            potential = self._weight * quat.rotate(q, self._com_body)[2]
            gravity = quat.rotate(body_from_principal, self.gravity(0.0, np.array(q_principal), np.array((w1, w2, w3))))
            torque_body = tuple(a + b for a, b in zip(torque_body, gravity))
            euler = np.array(quaternion_to_zxz(quat.multiply(q, self._body_from_top)))
            p_phi = momentum_world[2]
            p_psi = float(np.dot(momentum_body, self._symmetry_axis))
        energy = kinetic + potential
        momentum = math.hypot(*momentum_world)
        return StateSnapshot(
            t=self.t,
            step=self._k,
            orientation=np.array(q),
            angular_velocity_body=np.array(omega_body),
            angular_velocity_world=np.array(quat.rotate(q, omega_body)),
            angular_momentum_body=np.array(momentum_body),
            angular_momentum_world=np.array(momentum_world),
            torque_body=np.array(torque_body, dtype=float),
            kinetic_energy=kinetic,
            potential_energy=potential,
            energy_drift=_relative_change(energy, self._energy_ref),
            angular_momentum_drift=_relative_change(momentum, self._momentum_ref),
            euler_zxz=euler,
            p_phi=p_phi,
            p_psi=p_psi,
        )

    def held_torques(self) -> dict[str, tuple[tuple[float, float, float], str]]:
        """What each topic input holds now: {source: (torque N*m, frame)} (absent = zero)."""
        return {source: (h.torque, h.frame) for source, h in self._held.items()}


def _relative_change(value: float, reference: float) -> float:
    if abs(reference) < _TINY_REFERENCE:
        return 0.0
    return (value - reference) / abs(reference)
