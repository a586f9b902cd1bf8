"""Recording wired into the simulation node, as decorators the node calls as before.

:func:`attach` is called by the node once its publishers and subscriptions exist, and
only when a recording was asked for (scene ``recording:`` or the ``record_path``
parameter). It opens a :class:`~rigid_rot_sim.recording.session.RunRecorder`, then

* replaces ``node.sim`` by a :class:`RecordedSimulator`, which forwards everything to the
  Simulator and records, on ``~/sim_events``, every call that changes the simulation from
  outside the physics (torque commands with their effective time, apply_torque,
  set_state, reset, integrator / step changes) with the step index it happened at: what
  resim replays;
* replaces the node's output, rejected and mass-properties publishers by
  :class:`RecordingPublisher` s, which publish and record the same serialised bytes;

and returns the :class:`NodeRecording` the node keeps as ``node.recorder``.

The node itself records the torque commands as received, with their receive time
(:meth:`NodeRecording.record_command`), and closes the recording in ``destroy_node``.
``/tf`` and ``/tf_static`` are recorded as published (``make setup`` installs tf2_msgs into
the venv). When ``tf2_msgs`` is not installed the node publishes no ``/tf``; the recording still
gets ``/tf`` (world -> body), built from the state messages at the ``rates.tf`` rate.

A recording that cannot start or that fails (full disk) is logged as an error and the
simulation runs on unrecorded.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from rclpy.serialization import serialize_message

from rigid_rot_sim.recording import LOG_TIME_BASES
from rigid_rot_sim.recording.session import RunRecorder
from rigid_rot_sim.recording.writer import QosProfile, RecorderError


class RecordingPublisher:
    """An rclpy publisher that also records what it publishes; other attributes pass through."""

    def __init__(self, publisher: Any, recording: "NodeRecording", after: Any = None) -> None:
        self._publisher = publisher
        self._recording = recording
        self._after = after
        self._topic = publisher.topic_name

    def publish(self, msg: Any) -> None:
        if not self._recording.active:
            self._publisher.publish(msg)
            return
        # serialise once: the same CDR bytes go on the wire (publish_raw) and into the file
        data = serialize_message(msg)
        self._publisher.publish(data)
        self._recording.run.record_serialized(self._topic, data)
        if self._after is not None:
            self._after(msg)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._publisher, name)


class RecordedSimulator:
    """The node's Simulator, recording every externally caused change as an event."""

    def __init__(self, sim: Any, recording: "NodeRecording") -> None:
        self._sim = sim
        self._recording = recording

    def __getattr__(self, name: str) -> Any:
        return getattr(self._sim, name)

    def _event(self, kind: str, step: int, summary: str, **values: Any) -> None:
        if self._recording.active:
            self._recording.run.record_event(kind, step, summary, **values)

    def receive_torque(self, source: str, torque: Any, frame_id: str = "", stamp: float | None = None, force: Any = None) -> Any:
        step = self._sim.step_index
        command = self._sim.receive_torque(source, torque, frame_id, stamp, force)
        self._torque_event(command, step)
        return command

    def submit_torque(self, source: str, torque: Any, frame: str, effective_time: float, **kwargs: Any) -> Any:
        step = self._sim.step_index
        command = self._sim.submit_torque(source, torque, frame, effective_time, **kwargs)
        self._torque_event(command, step)
        return command

    def _torque_event(self, command: Any, step: int) -> None:
        self._event(
            "torque", step,
            f"{command.source}: {list(command.torque)} N*m ({command.frame}) from t = {command.effective_time:.9g} s",
            source=command.source, frame=command.frame, torque=tuple(float(v) for v in command.torque),
            effective_time=float(command.effective_time), receipt_time=command.receipt_time, stamp=command.stamp,
        )

    def apply_torque(self, torque: Any, frame_id: str, duration: float, effective_time: float | None = None) -> Any:
        step = self._sim.step_index
        command = self._sim.apply_torque(torque, frame_id, duration, effective_time)
        self._event(
            "apply_torque", step,
            f"apply_torque: {list(command.torque)} N*m ({command.frame}) for {command.duration:g} s from t = {command.effective_time:.9g} s",
            frame=command.frame, torque=tuple(float(v) for v in command.torque),
            duration=float(command.duration), effective_time=float(command.effective_time),
        )
        return command

    def set_state(self, orientation: Any, angular_velocity: Any) -> None:
        step = self._sim.step_index
        self._sim.set_state(orientation, angular_velocity)
        self._event(
            "set_state", step, f"set_state at t = {self._sim.t:.9g} s",
            orientation=tuple(float(v) for v in orientation), angular_velocity=tuple(float(v) for v in angular_velocity),
        )

    def reset(self) -> None:
        step = self._sim.step_index
        self._sim.reset()
        self._event("reset", step, "reset to the scene's initial state")

    def set_integrator(self, method: str | None = None, dt: float | None = None, options: dict | None = None) -> None:
        step = self._sim.step_index
        self._sim.set_integrator(method, dt, options)
        sim = self._sim
        self._event(
            "integrator", step, f"integrator {sim.method}, dt {sim.dt:g} s from t = {sim.t:.9g} s",
            method=sim.method, dt=float(sim.dt), options=dict(sim.options),
        )


class NodeRecording:
    """What the node holds while recording: the run file and its decorators."""

    def __init__(self, node: Any, run: RunRecorder, sim: Any) -> None:
        self.node = node
        self.run = run
        self.sim = sim
        self._failed = False

    @property
    def active(self) -> bool:
        return self.run.active

    def record_command(self, topic: str, msg: Any, received_ns: int) -> None:
        """Record a torque command message as received (log time: receive time in the run's time base)."""
        if self.active:
            self.run.record(topic, msg, self.run.receive_log_time(received_ns))

    def close(self) -> None:
        """Finish the file (idempotent); logs where it is and how to inspect it."""
        if self.run.recorder.error is None and self.run.active:
            self.run.close()
            path = self.run.path
            self.node.get_logger().info(
                f"recording finished: {path} ({self.run.recorder.message_count} messages); "
                f"inspect with `rigid-rot bag info {path}`, `rigid-rot plot {path}`, `rigid-rot resim {path}`"
            )
        else:
            self.run.close()


def attach(node: Any, path: str, log_time: str = "sim") -> NodeRecording | None:
    """Start recording ``node``'s run to ``path``; None (error logged) if the file cannot be made.

    ``log_time`` is the time base of the MCAP log times: ``sim`` (the run's sim time) or
    ``wall`` (see :mod:`.session`). Replaces ``node.sim`` by a :class:`RecordedSimulator`
    and the node's publishers by :class:`RecordingPublisher` s.
    """
    log = node.get_logger()
    if log_time not in LOG_TIME_BASES:
        log.error(f"record_log_time must be one of {', '.join(LOG_TIME_BASES)}, got {log_time!r}; not recording")
        return None
    sim = node.sim
    scene = node.scene
    events_topic = node.resolve_topic_name("~/sim_events")
    try:
        scene_text = Path(scene.source).read_text(encoding="utf-8")
    except OSError:
        scene_text = getattr(scene, "text", "") or ""
    parameters = {name: _jsonable(p.value) for name, p in sorted(node.get_parameters_by_prefix("").items())}

    def on_error(error: RecorderError) -> None:
        log.error(f"{error}; the simulation continues without recording")

    try:
        run = RunRecorder(
            path, scene_text=scene_text, scene_file=str(scene.source), parameters=parameters,
            integrator={"method": sim.method, "dt": sim.dt, "options": sim.options},
            events_topic=events_topic, on_error=on_error,
            sim_seconds=(lambda: sim.t) if log_time == "sim" else None,
        )
    except RecorderError as exc:
        log.error(f"{exc}; the simulation runs without recording")
        return None
    recording = NodeRecording(node, run, sim)
    recorded_sim = RecordedSimulator(sim, recording)
    recording.sim = recorded_sim
    node.sim = recorded_sim

    tf_period = _tf_period(node)
    state_for_tf = "state" if "state" in node.publishers_by_output else (
        "orientation" if "orientation" in node.publishers_by_output else None)
    for name, publisher in list(node.publishers_by_output.items()):
        role = name if name in ("state", "clock") else None
        run.add_topic(publisher.topic_name, publisher.msg_type, publisher.qos_profile, role=role)
        after = None
        if name == state_for_tf and "tf" not in node.publishers_by_output and tf_period:
            after = _tf_from(node, recording, name, tf_period)
        node.publishers_by_output[name] = RecordingPublisher(publisher, recording, after)
    for attribute, role in (("rejected_publisher", "rejected"), ("mass_properties_publisher", "mass_properties"),
                            ("tf_static_publisher", None)):
        publisher = getattr(node, attribute, None)
        if publisher is None:  # no /tf_static: no fixed frame, or tf2_msgs not installed
            continue
        run.add_topic(publisher.topic_name, publisher.msg_type, publisher.qos_profile, role=role)
        setattr(node, attribute, RecordingPublisher(publisher, recording))
    for subscription in node.torque_subscriptions:
        run.add_topic(subscription.topic_name, subscription.msg_type, _subscription_qos(subscription), role="torque")
    return recording


def _tf_period(node: Any) -> int:
    """Steps between two /tf records (0: no /tf wanted)."""
    if not node.has_parameter("rates.tf"):
        return 0
    rate = float(node.get_parameter("rates.tf").value)
    return node._period_steps(rate) if rate > 0.0 else 0


def _tf_from(node: Any, recording: NodeRecording, output: str, period: int):
    body = node.frames.body

    def record_tf(msg: Any) -> None:
        if node.sim.step_index % period:
            return
        q = msg.orientation if output == "state" else msg.quaternion
        stamp = msg.header.stamp
        recording.run.record_tf(stamp.sec, stamp.nanosec, (q.x, q.y, q.z, q.w), msg.header.frame_id, body)

    return record_tf


def _subscription_qos(subscription: Any) -> QosProfile:
    """What a commanding peer offers is unknown here; record the subscription's own profile."""
    profile = getattr(subscription, "qos_profile", None)
    return QosProfile.from_rclpy(profile) if profile is not None else QosProfile()


def _jsonable(value: Any) -> Any:
    try:
        json.dumps(value)
        return value
    except TypeError:
        return list(value) if hasattr(value, "__iter__") else str(value)
