"""One simulation run recorded to MCAP: the node's side of the recording.

:class:`RunRecorder` holds a :class:`~rigid_rot_sim.recording.writer.Recorder` (its
:attr:`~RunRecorder.writer`) and writes what a run of the simulator records:

* MCAP metadata records written first (so a crashed file keeps them): ``scene`` (the
  scene file as given: ``file``, ``text``), ``parameters`` (resolved node parameters,
  JSON values), ``integrator`` (``method`` after ``auto`` was resolved, ``dt``,
  ``options`` as JSON), ``sensors`` (``seed``: of the sensor noise, JSON; runs with
  sensor models), ``versions`` (packages and dependencies), ``rigid_rot_sim`` (the
  recorded topics by role, for resim and plot);
* the messages the node publishes and receives (rclpy objects, ``rclpy.serialization``);
* ``/tf`` (world -> body) encoded from the embedded TFMessage definition;
* the simulation event log (:mod:`.events`) on ``~/sim_events``.

Log times (MCAP ``log_time``, rosbag2's receive time) have one of two time bases, named in
the ``log_time`` metadata record:

* ``sim`` (the node's default): the sim time of the run in ns, as ``ros2 bag record
  --use-sim-time`` stores for a simulation. A state's log time equals its header stamp, a
  ``/clock`` message's its clock, so playback paces by sim time and a timeline (Foxglove)
  agrees with the stamps. Several messages of one step share a log time; readers keep
  file order among equal times, which is the order the node produced them in. After a
  reset (sim time back to 0) the log time goes on from where it was (:class:`SimLogTime`),
  so the file stays in one increasing order: there, log time = stamp + the sim time run
  before the reset(s).
* ``wall``: wall-clock ns, made strictly increasing within the run so that events and
  states keep the order in which the node produced them, even across a clock step.
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections.abc import Callable, Mapping
from typing import Any

from rigid_rot_sim.recording.events import EVENT_TYPE, event_fields
from rigid_rot_sim.recording.provenance import package_versions
from rigid_rot_sim.recording.writer import QosProfile, Recorder, RecorderError

TF_TOPIC = "/tf"
TF_TYPE = "tf2_msgs/msg/TFMessage"

__all__ = ["RunRecorder", "RecorderError", "SimLogTime", "type_name_of"]


def type_name_of(msg_type: type) -> str:
    """``pkg/msg/Type`` of a generated rclpy message class."""
    package = msg_type.__module__.split(".", 1)[0]
    return f"{package}/msg/{msg_type.__name__}"


class SimLogTime:
    """Log times (ns) from the sim time (s) that ``sim_seconds`` returns.

    Rounded to the nanosecond as header stamps are (:func:`rigid_rot_sim.conversions.seconds_to_time`),
    so without a reset log time == stamp. When the sim time goes back (a reset), an offset
    keeps the log times non-decreasing: they continue from the last one handed out.
    """

    def __init__(self, sim_seconds: Callable[[], float]) -> None:
        self._sim_seconds = sim_seconds
        self._offset = 0
        self._last = 0

    def __call__(self) -> int:
        sim_ns = int(round(float(self._sim_seconds()) * 1e9))
        if sim_ns < self._last:
            self._offset += self._last - sim_ns
        self._last = sim_ns
        return self._offset + sim_ns


def _qos(profile: Any) -> QosProfile:
    if profile is None:
        return QosProfile()
    if isinstance(profile, QosProfile):
        return profile
    return QosProfile.from_rclpy(profile)


class RunRecorder:
    """Record one run of the simulator.

    Parameters
    ----------
    path : str or PathLike
        Output .mcap file. RecorderError if it cannot be created.
    scene_text, scene_file : str
        The scene YAML as given and where it came from.
    parameters : mapping
        Resolved node parameters ({name: JSON-serialisable value}).
    integrator : mapping
        ``method`` (resolved), ``dt`` (s), ``options`` (dict).
    events_topic : str
        Fully qualified name of the event log topic (``/<node>/sim_events``).
    on_error : callable
        Called once with the RecorderError if recording stops (full disk, ...).
    flush_period : float
        Wall-clock seconds between chunk flushes. Half a second keeps the promise "a
        SIGKILL loses at most the last second" with room for a loaded machine.
    sim_seconds : callable, optional
        The run's sim time (s). Given: log times in sim time (time base ``sim``, see the
        module docstring); None: wall clock (``wall``).
    sensors : mapping, optional
        The run's sensor noise settings, recorded as the ``sensors`` metadata record (JSON
        values): ``seed``, the seed of every sensor's noise (resim draws the same bits).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        scene_text: str,
        scene_file: str,
        parameters: Mapping[str, Any],
        integrator: Mapping[str, Any],
        events_topic: str,
        on_error: Callable[[RecorderError], None] | None = None,
        flush_period: float = 0.5,
        sim_seconds: Callable[[], float] | None = None,
        sensors: Mapping[str, Any] | None = None,
    ) -> None:
        self.writer = Recorder(path, on_error=on_error, flush_period=flush_period)
        self.log_time_base = "wall" if sim_seconds is None else "sim"
        self._sim_log_time = None if sim_seconds is None else SimLogTime(sim_seconds)
        self.path = self.writer.path
        self.events_topic = events_topic
        self._roles: dict[str, str] = {"events": events_topic, "tf": TF_TOPIC}
        self._clock_lock = threading.Lock()
        self._last_ns = 0
        self.writer.add_metadata("scene", {"file": scene_file, "text": scene_text})
        self.writer.add_metadata("parameters", {name: json.dumps(value) for name, value in sorted(parameters.items())})
        self.writer.add_metadata(
            "integrator",
            {
                "method": str(integrator["method"]),
                "dt": repr(float(integrator["dt"])),
                "options": json.dumps(dict(integrator.get("options") or {}), sort_keys=True),
            },
        )
        self.writer.add_metadata("versions", package_versions())
        self.writer.add_metadata("log_time", {"base": self.log_time_base})
        if sensors is not None:
            self.writer.add_metadata("sensors", {name: json.dumps(value) for name, value in sorted(sensors.items())})
        self.writer.add_topic(events_topic, EVENT_TYPE, QosProfile(depth=100))
        self.writer.add_topic(TF_TOPIC, TF_TYPE, QosProfile(depth=100))

    # -- state -----------------------------------------------------------------------

    @property
    def active(self) -> bool:
        """True while recording (not closed, no error)."""
        return self.writer.active

    @property
    def message_count(self) -> int:
        """Messages written so far."""
        return self.writer.message_count

    @property
    def error(self) -> RecorderError | None:
        """Why recording stopped, or None."""
        return self.writer.error

    def log_time_ns(self) -> int:
        """Now, in the time base: sim time (ns, non-decreasing) or wall clock (ns, strictly
        after every log time handed out before)."""
        with self._clock_lock:
            if self._sim_log_time is not None:
                self._last_ns = max(self._sim_log_time(), self._last_ns)
            else:
                self._last_ns = max(time.time_ns(), self._last_ns + 1)
            return self._last_ns

    # -- topics ----------------------------------------------------------------------

    def add_topic(self, topic: str, msg_type: type | str, qos: Any = None, role: str | None = None) -> None:
        """Register a topic with its message class (or type name) and offered QoS profile.

        ``role`` (e.g. ``state``, ``torque``, ``rejected``) is written to the
        ``rigid_rot_sim`` metadata record when the run is closed and tells resim and
        plot which topic is which.
        """
        type_name = msg_type if isinstance(msg_type, str) else type_name_of(msg_type)
        self.writer.add_topic(topic, type_name, _qos(qos))
        if role is not None:
            key = role if role not in self._roles else f"{role}:{topic}"
            self._roles[key] = topic

    def record(self, topic: str, msg: Any, log_time_ns: int | None = None) -> None:
        """Record an rclpy message object published or received on ``topic``."""
        self.writer.write_message(topic, msg, self.log_time_ns() if log_time_ns is None else log_time_ns)

    def record_serialized(self, topic: str, data: bytes, log_time_ns: int | None = None) -> None:
        """Record already serialised CDR bytes (e.g. the bytes the node just published)."""
        self.writer.write(topic, data, self.log_time_ns() if log_time_ns is None else log_time_ns)

    def record_tf(
        self, stamp_sec: int, stamp_nanosec: int, orientation: Any, world_frame: str, body_frame: str
    ) -> None:
        """Record the world -> body transform (rotation only) on ``/tf``."""
        x, y, z, w = (float(v) for v in orientation)
        fields = {
            "transforms": [
                {
                    "header": {
                        "stamp": {"sec": int(stamp_sec), "nanosec": int(stamp_nanosec)},
                        "frame_id": world_frame,
                    },
                    "child_frame_id": body_frame,
                    "transform": {
                        "translation": {"x": 0.0, "y": 0.0, "z": 0.0},
                        "rotation": {"x": x, "y": y, "z": z, "w": w},
                    },
                }
            ]
        }
        self.writer.write_fields(TF_TOPIC, fields, self.log_time_ns())

    # -- events ----------------------------------------------------------------------

    def record_event(self, kind: str, step: int, summary: str, **values: Any) -> None:
        """Record one simulation event (see :mod:`.events`)."""
        self.writer.write_fields(self.events_topic, event_fields(kind, step, summary, **values), self.log_time_ns())

    def receive_log_time(self, wall_ns: int) -> int:
        """Log time of a message received at wall-clock ``wall_ns``: the sim time now (time
        base ``sim``), or ``wall_ns`` moved after every log time handed out before (``wall``)."""
        if self._sim_log_time is not None:
            return self.log_time_ns()
        with self._clock_lock:
            self._last_ns = max(int(wall_ns), self._last_ns + 1)
            return self._last_ns

    # -- end -------------------------------------------------------------------------

    def add_metadata(self, name: str, values: dict[str, str]) -> None:
        """One more MCAP metadata record (strings), e.g. the run digest at the end of the run."""
        if self.writer.active:
            self.writer.add_metadata(name, dict(values))

    def close(self) -> None:
        """Write the topic roles, the summary and close the file (idempotent)."""
        if self.writer.active:
            self.writer.add_metadata("rigid_rot_sim", dict(self._roles))
        self.writer.finish()

    finish = close

    def __enter__(self) -> RunRecorder:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
