"""Recording the node's run: one observer of the simulator, one listener of the node's messages.

:meth:`NodeRecording.start` opens a :class:`~rigid_rot_sim.recording.session.RunRecorder`
and registers the node's topics; :meth:`NodeRecording.attach` (the node's recording part,
:func:`rigid_rot_sim.ros.parts.recording`) then attaches it in three visible lines:

* ``sim.add_observer(recording)``: the simulator reports every change made from outside
  the physics (:class:`~rigid_rot_sim.run.observer.SimulationObserver`), which is recorded
  on ``~/sim_events`` with the step index it happened at (what resim replays): torque
  commands with their effective time (``torque``), ``apply_torque``, ``set_state``,
  ``reset``, integrator / step changes (``integrator``);
* ``outputs.listeners.append(recording)``: every message the node publishes, as the CDR
  bytes it published (:meth:`published`);
* ``door.listeners.append(recording)`` for every command door (:class:`~rigid_rot_sim.ros.intake.CommandDoor`):
  every command as received, with its receive time (:meth:`received`).

The node closes the recording in ``destroy_node``. ``/tf`` and ``/tf_static`` are recorded as
published, like every other output.

A recording that cannot start or that fails (full disk) is logged as an error and the
simulation runs on unrecorded.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any, cast

from rclpy.node import Node
from rclpy.subscription import Subscription

from rigid_rot_sim.recording import LOG_TIME_BASES
from rigid_rot_sim.recording.session import RunRecorder
from rigid_rot_sim.recording.writer import QosProfile, RecorderError
from rigid_rot_sim.ros.intake import CommandDoor
from rigid_rot_sim.ros.outputs import Outputs
from rigid_rot_sim.ros.rclpy_internals import Logger
from rigid_rot_sim.run.commands import TorqueCommand
from rigid_rot_sim.run.digest import format_digest
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.run.simulator import Simulator

#: Topics registered after the scene's outputs, in this order.
_LATER = ("rejected", "mass_properties", "tf_static")
#: Outputs whose topic the ``rigid_rot_sim`` metadata names by role (for resim and plot).
_ROLES = (
    "state",
    "clock",
    "rejected",
    "mass_properties",
    "imu",
    "star_tracker",
    "wheels",
    "magnetometer",
    "magnetic_field",
    "orbit",
)


class NodeRecording(SimulationObserver):
    """The run's file, fed by the simulator's reports and the node's published and received messages."""

    def __init__(self, file: RunRecorder, sim: Simulator, logger: Logger) -> None:
        self.file = file
        self.sim = sim
        self.logger = logger
        #: For the start-up line: where it records (set by :meth:`attach`).
        self.words = "recording"

    @classmethod
    def attach(
        cls, node: Node, sim: Simulator, outputs: Outputs, doors: Sequence[CommandDoor], path: str, log_time: str
    ) -> NodeRecording | None:
        """:meth:`start`, then the recording hears the run: None (error logged) if it cannot start."""
        subscriptions = [subscription for door in doors for subscription in door.subscriptions]
        recording = cls.start(node, sim, outputs, subscriptions, path, log_time)
        if recording is not None:
            recording.words = f"recording to {path} (log time: {log_time})"
            sim.add_observer(recording)  # events: commands accepted, torques applied, set_state, ...
            outputs.listeners.append(recording)  # every message published, as the bytes published
            for door in doors:  # every command as received, on every command topic
                door.listeners.append(recording)
        return recording

    def describe(self) -> tuple[list[str], list[str]]:
        """For the start-up line (:class:`~rigid_rot_sim.ros.parts.Part`)."""
        return [self.words], []

    @classmethod
    def start(
        cls,
        node: Node,
        sim: Simulator,
        outputs: Outputs,
        subscriptions: Sequence[Subscription],
        path: str,
        log_time: str = "sim",
    ) -> NodeRecording | None:
        """Open ``path`` for ``node``'s run and register its topics; None (error logged) if it cannot.

        ``log_time`` is the time base of the MCAP log times: ``sim`` (the run's sim time) or
        ``wall`` (see :mod:`.session`). ``outputs``: the node's :class:`~rigid_rot_sim.ros.outputs.Outputs`;
        ``subscriptions``: its torque subscriptions.
        """
        log = node.get_logger()
        if log_time not in LOG_TIME_BASES:
            log.error(f"record_log_time must be one of {', '.join(LOG_TIME_BASES)}, got {log_time!r}; not recording")
            return None
        scene = outputs.scene
        try:
            scene_text = Path(scene.source).read_text(encoding="utf-8")
        except OSError:
            scene_text = getattr(scene, "text", "") or ""
        names = sorted(node.list_parameters([], 0).names)  # every parameter (depth 0: all levels)
        parameters = {p.name: _jsonable(p.value) for p in node.get_parameters(names)}

        def on_error(error: RecorderError) -> None:
            log.error(f"{error}; the simulation continues without recording")

        try:
            file = RunRecorder(
                path,
                scene_text=scene_text,
                scene_file=str(scene.source),
                parameters=parameters,
                integrator={"method": sim.stepper.method, "dt": sim.clock.dt, "options": sim.stepper.options},
                events_topic=node.resolve_topic_name("~/sim_events"),
                on_error=on_error,
                sim_seconds=(lambda: sim.clock.t) if log_time == "sim" else None,
                sensors=None if outputs.sensors is None else {"seed": outputs.sensors.seed},
            )
        except RecorderError as exc:
            log.error(f"{exc}; the simulation runs without recording")
            return None
        publishers = outputs.publishers
        for name in [n for n in publishers if n not in _LATER] + [n for n in _LATER if n in publishers]:
            publisher = publishers[name]
            file.add_topic(
                publisher.topic_name,
                cast(type, publisher.msg_type),
                publisher.qos_profile,
                role=name if name in _ROLES else None,
            )
        for subscription in subscriptions:
            file.add_topic(
                subscription.topic_name,
                cast(type, subscription.msg_type),
                _subscription_qos(subscription),
                role="torque",
            )
        return cls(file, sim, log)

    @property
    def active(self) -> bool:
        return self.file.active

    # ------------------------------------------------------------------ the node's messages

    def published(self, name: str, topic: str, data: bytes, msg: Any) -> None:
        """A message the node published on output ``name``: recorded as the bytes published."""
        if self.active:
            self.file.record_serialized(topic, data)
            if name == "state":  # the run digest of the last recorded state: the file's `digest` metadata
                self.last_state_digest = (msg.digest, msg.header.stamp.sec, msg.header.stamp.nanosec)

    def received(self, topic: str, msg: Any, received_ns: int) -> None:
        """A torque command message as received (log time: receive time in the run's time base)."""
        if self.active:
            self.file.record(topic, msg, self.file.receive_log_time(received_ns))

    # ------------------------------------------------------------------ the simulator's reports

    def _event(self, kind: str, step: int, summary: str, **values: Any) -> None:
        if self.active:
            self.file.record_event(kind, step, summary, **values)

    def command_accepted(self, step: int, command: TorqueCommand) -> None:
        self._event(
            "torque",
            step,
            f"{command.source}: {list(command.torque)} N*m ({command.frame}) from t = {command.effective_time:.9g} s",
            source=command.source,
            frame=command.frame,
            torque=tuple(float(v) for v in command.torque),
            effective_time=float(command.effective_time),
            receipt_time=command.receipt_time,
            stamp=command.stamp,
        )

    def wheel_command_accepted(
        self, step: int, source: str, torques: Sequence[float], effective_time: float, clamped: Sequence[int]
    ) -> None:
        said = f"; clamped to max_torque: wheel(s) {list(clamped)}" if clamped else ""
        self._event(
            "wheel_torque",
            step,
            f"{source}: wheel torques {list(torques)} N*m from t = {effective_time:.9g} s{said}",
            source=source,
            torques=tuple(float(v) for v in torques),
            effective_time=float(effective_time),
            clamped=list(clamped),
        )

    def rod_command_accepted(
        self, step: int, source: str, dipoles: Sequence[float], effective_time: float, clamped: Sequence[int]
    ) -> None:
        said = f"; clamped to max_dipole: rod(s) {list(clamped)}" if clamped else ""
        self._event(
            "rod_dipoles",
            step,
            f"{source}: rod dipoles {list(dipoles)} A*m^2 from t = {effective_time:.9g} s{said}",
            source=source,
            dipoles=tuple(float(v) for v in dipoles),
            effective_time=float(effective_time),
            clamped=list(clamped),
        )

    def torque_applied(self, step: int, command: TorqueCommand) -> None:
        self._event(
            "apply_torque",
            step,
            f"apply_torque: {list(command.torque)} N*m ({command.frame}) for {command.duration:g} s "
            f"from t = {command.effective_time:.9g} s",
            frame=command.frame,
            torque=tuple(float(v) for v in command.torque),
            duration=float(command.duration or 0.0),
            effective_time=float(command.effective_time),
        )

    def state_set(self, step: int, orientation: Sequence[float], angular_velocity: Sequence[float]) -> None:
        self._event(
            "set_state",
            step,
            f"set_state at t = {self.sim.clock.t:.9g} s",
            orientation=tuple(float(v) for v in orientation),
            angular_velocity=tuple(float(v) for v in angular_velocity),
        )

    def reset(self, step: int) -> None:
        self._event("reset", step, "reset to the scene's initial state")

    def integrator_changed(self, step: int, method: str, dt: float, options: dict[str, Any]) -> None:
        self._event(
            "integrator",
            step,
            f"integrator {method}, dt {dt:g} s from t = {self.sim.clock.t:.9g} s",
            method=method,
            dt=float(dt),
            options=dict(options),
        )

    def lockstep_timeout(self, step: int, reason: str, action: str) -> None:
        self._event("lockstep_timeout", step, f"{reason} ({action})", reason=reason, action=action)

    # ------------------------------------------------------------------ end

    def close(self) -> None:
        """Finish the file (idempotent); logs where it is and how to inspect it."""
        if self.file.error is None and self.file.active:
            digest = getattr(self, "last_state_digest", None)
            if digest is not None:
                self.file.add_metadata(
                    "digest",
                    {
                        "digest": format_digest(digest[0]),
                        "stamp": f"{digest[1]}.{digest[2]:09d}",
                        "definition": "rigid_rot_sim.run.digest "
                        "(FNV-1a 64 over the float64 words of every step's t, q, omega)",
                    },
                )
            self.file.close()
            path = self.file.path
            self.logger.info(
                f"recording finished: {path} ({self.file.message_count} messages); "
                f"inspect with `rigid-rot bag info {path}`, `rigid-rot plot {path}`, `rigid-rot resim {path}`"
            )
        else:
            self.file.close()


def _subscription_qos(subscription: Subscription) -> QosProfile:
    """What a commanding peer offers is unknown here; record the subscription's own profile."""
    profile = getattr(subscription, "qos_profile", None)
    return QosProfile.from_rclpy(profile) if profile is not None else QosProfile()


def _jsonable(value: Any) -> Any:
    try:
        json.dumps(value)
        return value
    except TypeError:
        return list(value) if hasattr(value, "__iter__") else str(value)
