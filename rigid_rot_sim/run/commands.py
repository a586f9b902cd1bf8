"""Torque commands of a run: their checks, their step boundaries, what each input holds.

:class:`CommandSchedule` turns what comes from outside (topic commands, ``~/apply_torque``
requests) and the scene's torque schedules into the torque that acts over each step:
the sum of what the topic inputs hold, the torques applied for a duration and the
schedules' current segments, split into a body-frame and a world-frame part (N*m, user
frames). Every change is an event on a heap keyed by the step boundary where it takes
effect (:class:`EventKind`); :meth:`CommandSchedule.process_due` applies those due at the
clock's current step.

Rules (pinned by ``test/run/test_commands.py``):

* an input holds its last command from the command's step until a newer command replaces
  it; an input with a hold ``timeout`` falls back to zero ``timeout`` s of sim time after
  the command took effect (on the first boundary at or after that time), unless a newer
  command took over meanwhile;
* an applied torque acts from its step for ``duration`` s (ending on the first boundary at
  or after its end); applied torques add up with each other and with the inputs;
* a schedule segment replaces the schedule's previous one at its start time;
* after a dt change (:meth:`CommandSchedule.reschedule`) every pending event moves to the
  first boundary at or after its time on the new grid.
"""

from __future__ import annotations

import enum
import heapq
import itertools
import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from rigid_rot_sim.core import limits, steps, validation
from rigid_rot_sim.run.clock import StepClock
from rigid_rot_sim.scene.scene import Scene, TopicInput

__all__ = [
    "APPLY_TORQUE_SOURCE",
    "STAMP_HORIZON",
    "CommandRejected",
    "CommandSchedule",
    "EventKind",
    "TorqueCommand",
]

Torque = tuple[float, float, float]

#: ``source`` of torques applied through ``apply_torque`` (:meth:`CommandSchedule.apply`).
APPLY_TORQUE_SOURCE = "apply_torque"
#: Source name of the scene's wheel-torque schedule (topic wheel commands carry their topic's name).
WHEEL_SCHEDULE_SOURCE = "wheel_torque_schedule"

#: A command stamped further ahead of sim time than this (s) is rejected: its publisher
#: almost certainly stamps with wall-clock time instead of the sim time on /clock, and
#: would otherwise wait for decades of sim time.
STAMP_HORIZON = 60.0

_ZERO3: Torque = (0.0, 0.0, 0.0)


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
    ``apply_torque`` torques, which end after it.
    """

    source: str
    torque: Torque
    frame: str
    effective_time: float
    step: int
    receipt_time: float | None = None
    stamp: float | None = None
    duration: float | None = None


class EventKind(enum.Enum):
    """What happens at an event's step boundary."""

    COMMAND = "command"  # a topic command starts being held (payload: TorqueCommand)
    EXPIRE = "expire"  # a held command's timeout ends (payload: end time, source, serial of the command)
    APPLY_START = "apply_start"  # an applied torque starts (payload: TorqueCommand)
    APPLY_END = "apply_end"  # an applied torque ends (payload: end time, serial of its start)
    SCHEDULE = "schedule"  # a schedule segment starts (payload: start time, schedule index, torque)
    WHEELS = "wheels"  # wheel motor torques start (payload: effective time, clamped torques, source)
    RODS = "rods"  # torque-rod dipoles start (payload: effective time, clamped dipoles, source)


@dataclass
class _Held:
    """The value an input currently holds (user frames)."""

    torque: Torque
    frame: str
    serial: int


def clamp_wheel_torques(wheels: Any, source: str, torques: Any) -> tuple[tuple[float, ...], tuple[int, ...]]:
    """Wheel motor torques (N*m, one per wheel of ``wheels``) clamped to each wheel's max_torque, and which were.

    CommandRejected for a scene without wheels, a wrong number of values or a non-finite one.
    """
    values = [float(v) for v in np.asarray(torques, dtype=float).reshape(-1)]
    if not wheels:
        raise CommandRejected(source, "this scene has no reaction wheels")
    if len(values) != len(wheels):
        raise CommandRejected(
            source, f"{len(values)} torque(s) for {len(wheels)} wheel(s) [{', '.join(w.name for w in wheels)}]"
        )
    clamped = []
    for value, wheel in zip(values, wheels, strict=True):
        if not math.isfinite(value):
            raise CommandRejected(source, f"non-finite torque for wheel {wheel.name!r}: {value}")
        clamped.append(min(max(value, -wheel.max_torque), wheel.max_torque))
    return tuple(clamped), tuple(i for i, (a, b) in enumerate(zip(values, clamped, strict=True)) if a != b)


def clamp_rod_dipoles(rods: Any, source: str, dipoles: Any) -> tuple[tuple[float, ...], tuple[int, ...]]:
    """Rod dipoles (A*m^2, one per rod of ``rods``) clamped to each rod's max_dipole, and which were.

    CommandRejected for a scene without rods, a wrong number of values or a non-finite one (the rule of
    :func:`clamp_wheel_torques`: a clamp is said, never a rejection).
    """
    values = [float(v) for v in np.asarray(dipoles, dtype=float).reshape(-1)]
    if not rods:
        raise CommandRejected(source, "this scene has no torque rods (actuators.magnetorquers)")
    if len(values) != len(rods):
        raise CommandRejected(
            source, f"{len(values)} dipole(s) for {len(rods)} rod(s) [{', '.join(r.name for r in rods)}]"
        )
    clamped = []
    for value, rod in zip(values, rods, strict=True):
        if not math.isfinite(value):
            raise CommandRejected(source, f"non-finite dipole for rod {rod.name!r}: {value}")
        clamped.append(min(max(value, -rod.max_dipole), rod.max_dipole))
    return tuple(clamped), tuple(i for i, (a, b) in enumerate(zip(values, clamped, strict=True)) if a != b)


class CommandSchedule:
    """The torque inputs of ``scene`` on the step grid of ``clock``; see the module docstring.

    ``max_torque`` (N*m): the largest accepted torque norm of a command or apply request
    (0 = no limit). :attr:`body_sum` and :attr:`world_sum` (None when zero) are the torque
    acting from the current step on, in the user body and world frames. :attr:`next_event`
    is the step of the earliest pending event (None when none is pending).
    """

    def __init__(self, scene: Scene, clock: StepClock) -> None:
        self.clock = clock
        self.frames = scene.frames
        self.inputs: dict[str, TopicInput] = {spec.topic: spec for spec in scene.topic_inputs}
        self.schedules = scene.schedules
        self.max_torque = float(scene.commands.max_torque)
        self.spacecraft = scene.spacecraft
        self._serial = itertools.count()
        self.clear()

    def clear(self) -> None:
        """Forget every command and applied torque; the schedules start again from their first segment."""
        self._events: list[tuple[int, int, EventKind, Any]] = []
        self.next_event: int | None = None
        self._held: dict[str, _Held] = {}
        self._applied: dict[int, TorqueCommand] = {}
        self._scheduled: dict[int, Torque] = {}
        self.body_sum: Torque = _ZERO3
        self.world_sum: Torque | None = None
        self.named_torques: tuple[tuple[str, Torque, str], ...] = ()
        #: The wheels' motor torques (N*m, clamped, scene order) acting from the current step on.
        self.wheel_torques: tuple[float, ...] = (0.0,) * len(self.spacecraft.wheels)
        #: The torque rods' dipoles (A*m^2, clamped, scene order) held from the current step on.
        self.rod_dipoles: tuple[float, ...] = (0.0,) * len(self.spacecraft.rods)
        if self.spacecraft.wheel_schedule is not None:
            for wheel_segment in self.spacecraft.wheel_schedule.segments:
                torques = clamp_wheel_torques(self.spacecraft.wheels, WHEEL_SCHEDULE_SOURCE, wheel_segment.torques)[0]
                self._push(
                    self.clock.step_at_or_after(wheel_segment.start),
                    EventKind.WHEELS,
                    (wheel_segment.start, torques, WHEEL_SCHEDULE_SOURCE),
                )
        for index, schedule in enumerate(self.schedules):
            for segment in schedule.segments:
                self._push(
                    self.clock.step_at_or_after(segment.start),
                    EventKind.SCHEDULE,
                    (segment.start, index, segment.torque),
                )

    # ------------------------------------------------------------------ checks

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
                source,
                f"frame {frame_id!r} is neither the body frame {self.frames.body!r} "
                f"nor the world frame {self.frames.world!r}",
            )
        if policy == "header":
            if not frame_id:
                raise CommandRejected(
                    source,
                    "empty header.frame_id: this input takes the frame from the header "
                    f"({self.frames.body!r} or {self.frames.world!r})",
                )
            return names[frame_id]
        if frame_id and names[frame_id] != policy:
            expected = self.frames.body if policy == "body" else self.frames.world
            raise CommandRejected(source, f"frame {frame_id!r} given, but this input is expressed in {expected!r}")
        return policy

    def finite_torque(self, source: str, torque: Any, what: str = "torque") -> Torque:
        """``torque`` (3 components) as floats, or CommandRejected: not finite, beyond the limits or max_torque."""
        values = tuple(float(v) for v in np.asarray(torque, dtype=float).reshape(3))
        for axis, value in zip("xyz", values, strict=True):
            if not math.isfinite(value):
                raise CommandRejected(source, f"non-finite {what}.{axis} = {value}")
            if abs(value) > limits.MAX_MAGNITUDE:
                raise CommandRejected(source, f"{what}.{axis} = {value:g} beyond the limit of {limits.MAX_MAGNITUDE:g}")
        if what == "torque" and self.max_torque > 0.0:
            norm = math.hypot(*values)
            if norm > self.max_torque:
                raise CommandRejected(source, f"|torque| = {norm:.6g} N*m exceeds max_torque = {self.max_torque:g} N*m")
        return values  # type: ignore[return-value]

    def submit_wheels(
        self, source: str, torques: Any, effective_time: float
    ) -> tuple[int, tuple[float, ...], tuple[int, ...]]:
        """Hold wheel motor torques (:func:`clamp_wheel_torques`) from ``effective_time`` (s).

        Returns (step, clamped torques, indexes of the wheels clamped)."""
        clamped, which = clamp_wheel_torques(self.spacecraft.wheels, source, torques)
        effective_time = validation.finite_scalar("effective_time", effective_time)
        step = self.clock.step_at_or_after(effective_time)
        self._push(step, EventKind.WHEELS, (effective_time, clamped, source))
        return step, clamped, which

    def submit_rods(
        self, source: str, dipoles: Any, effective_time: float
    ) -> tuple[int, tuple[float, ...], tuple[int, ...]]:
        """Hold rod dipoles (:func:`clamp_rod_dipoles`) from ``effective_time`` (s), until the next command: the
        wheels' hold rule. Returns (step, clamped dipoles, indexes of the rods clamped)."""
        clamped, which = clamp_rod_dipoles(self.spacecraft.rods, source, dipoles)
        effective_time = validation.finite_scalar("effective_time", effective_time)
        step = self.clock.step_at_or_after(effective_time)
        self._push(step, EventKind.RODS, (effective_time, clamped, source))
        return step, clamped, which

    def input_spec(self, source: str) -> TopicInput:
        """The topic input ``source`` (ValueError naming the inputs if there is none)."""
        spec = self.inputs.get(source)
        if spec is None:
            raise ValueError(f"source {source!r} is not a torque input of this scene (inputs: {sorted(self.inputs)})")
        return spec

    def admit(
        self, source: str, torque: Any, frame_id: str, stamp: float | None, force: Any
    ) -> tuple[Torque, str, float, float | None]:
        """Check a command that arrived now on input ``source``: (torque, frame, effective time, stamp).

        ``stamp`` comes back None when zero or not finite. Effective time: the stamp when
        there is one and it is not in the past, else now. CommandRejected for a refused
        command, ValueError for an unknown input.
        """
        spec = self.input_spec(source)
        values = self.finite_torque(source, torque)
        if force is not None:
            force_values = self.finite_torque(source, force, "force")
            if any(force_values):
                raise CommandRejected(
                    source, f"non-zero force {force_values} N: only torques act on the body (send force = 0)"
                )
        frame = self.resolve_frame(source, frame_id, spec.frame)
        now = self.clock.t
        if stamp is not None and (not math.isfinite(stamp) or stamp == 0.0):
            stamp = None
        if stamp is not None and stamp > now + STAMP_HORIZON:
            raise CommandRejected(
                source,
                f"header stamp {stamp:.9g} s is {stamp - now:.3g} s ahead of sim time {now:.9g} s "
                f"(limit {STAMP_HORIZON:g} s): stamp with sim time (/clock) or leave the stamp zero",
            )
        effective = stamp if stamp is not None and stamp >= now else now
        return values, frame, effective, stamp

    # ------------------------------------------------------------------ scheduling

    def submit(
        self,
        source: str,
        torque: Any,
        frame: str,
        effective_time: float,
        receipt_time: float | None = None,
        stamp: float | None = None,
    ) -> TorqueCommand:
        """Hold ``torque`` (N*m, ``frame`` body or world) on input ``source`` from ``effective_time`` (s)."""
        self.input_spec(source)
        if frame not in ("body", "world"):
            raise ValueError(f"frame must be 'body' or 'world', got {frame!r}")
        values = self.finite_torque(source, torque)
        effective_time = validation.finite_scalar("effective_time", effective_time)
        return self._schedule(
            EventKind.COMMAND, source, values, frame, effective_time, receipt_time=receipt_time, stamp=stamp
        )

    def apply(self, torque: Any, frame_id: str, duration: float, effective_time: float | None = None) -> TorqueCommand:
        """Add ``torque`` (N*m, in ``frame_id``; empty = body) for ``duration`` s from now (or ``effective_time``)."""
        source = APPLY_TORQUE_SOURCE
        values = self.finite_torque(source, torque)
        frame = self.resolve_frame(source, frame_id, "header" if frame_id else "body")
        if not (math.isfinite(duration) and duration > 0.0):
            raise CommandRejected(source, f"duration must be finite and > 0 s, got {duration}")
        if steps.step_at_or_after(duration, self.clock.dt) < 1:  # it would end on the boundary it starts on
            raise CommandRejected(
                source, f"duration {duration!r} s is not one step of dt {self.clock.dt:g} s: it would act for no step"
            )
        now = self.clock.t
        start = now if effective_time is None else validation.finite_scalar("effective_time", effective_time)
        receipt_time = now if effective_time is None else None
        return self._schedule(
            EventKind.APPLY_START, source, values, frame, start, receipt_time=receipt_time, duration=float(duration)
        )

    def _schedule(
        self, kind: EventKind, source: str, torque: Torque, frame: str, effective_time: float, **details: Any
    ) -> TorqueCommand:
        """The command of ``kind`` taking effect on the first boundary at or after ``effective_time``, queued."""
        step = self.clock.step_at_or_after(effective_time)
        command = TorqueCommand(source, torque, frame, effective_time, step, **details)
        self._push(step, kind, command)
        return command

    def reschedule(self) -> None:
        """Recompute the step of every pending event from its time (after a dt change)."""
        events, self._events = self._events, []
        self.next_event = None
        for _, _, kind, payload in events:
            if kind is EventKind.COMMAND or kind is EventKind.APPLY_START:
                step = self.clock.step_at_or_after(payload.effective_time)
                payload = replace(payload, step=step)
            else:
                step = self.clock.step_at_or_after(payload[0])
            self._push(step, kind, payload)

    def _push(self, step: int, kind: EventKind, payload: Any) -> None:
        heapq.heappush(self._events, (step, next(self._serial), kind, payload))
        if self.next_event is None or step < self.next_event:
            self.next_event = step

    # ------------------------------------------------------------------ taking effect

    def process_due(self) -> None:
        """Apply every event due at the clock's step; update :attr:`body_sum` and :attr:`world_sum`."""
        k = self.clock.k
        events = self._events
        while events and events[0][0] <= k:
            _, serial, kind, payload = heapq.heappop(events)
            if kind is EventKind.COMMAND:
                self._held[payload.source] = _Held(payload.torque, payload.frame, serial)
                timeout = self.inputs[payload.source].timeout
                if timeout is not None:
                    end = self.clock.t + timeout
                    self._push(self.clock.step_at_or_after(end), EventKind.EXPIRE, (end, payload.source, serial))
            elif kind is EventKind.EXPIRE:
                _, source, held_serial = payload
                held = self._held.get(source)
                if held is not None and held.serial == held_serial:
                    del self._held[source]
            elif kind is EventKind.APPLY_START:
                self._applied[serial] = payload
                end = self.clock.t + payload.duration
                self._push(self.clock.step_at_or_after(end), EventKind.APPLY_END, (end, serial))
            elif kind is EventKind.APPLY_END:
                self._applied.pop(payload[1], None)
            elif kind is EventKind.SCHEDULE:
                _, index, torque = payload
                self._scheduled[index] = torque
            elif kind is EventKind.WHEELS:
                self.wheel_torques = payload[1]
            elif kind is EventKind.RODS:
                self.rod_dipoles = payload[1]
        self.next_event = events[0][0] if events else None
        self._sum_torques()

    def _sum_torques(self) -> None:
        body = [0.0, 0.0, 0.0]
        world = [0.0, 0.0, 0.0]
        named = [(source, h.torque, h.frame) for source, h in self._held.items()]
        named += [(c.source, c.torque, c.frame) for c in self._applied.values()]
        named += [(f"schedule[{i}]", torque, self.schedules[i].frame) for i, torque in sorted(self._scheduled.items())]
        #: The torques acting from the current step on, by source: (name, torque N*m, frame body | world).
        self.named_torques = tuple(named)
        for _, torque, frame in named:
            target = body if frame == "body" else world
            for i in range(3):
                target[i] += torque[i]
        self.body_sum = tuple(body)  # type: ignore[assignment]
        self.world_sum = tuple(world) if any(world) else None  # type: ignore[assignment]

    def norm_bound(self) -> float:
        """A bound (N*m) on the norm of the torque acting from the current step on."""
        return math.hypot(*self.body_sum) + (math.hypot(*self.world_sum) if self.world_sum else 0.0)

    def held_torques(self) -> dict[str, tuple[Torque, str]]:
        """What each topic input holds now: {source: (torque N*m, frame)} (absent = zero)."""
        return {source: (h.torque, h.frame) for source, h in self._held.items()}
