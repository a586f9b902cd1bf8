"""Serve a recording to Foxglove: ``rigid-rot view BAG --foxglove PORT``.

Every recorded message goes out on its topic as recorded (CDR bytes, the file's own ``ros2msg``
definition as schema) at its log time, paced by the wall clock at the playback speed; each
recorded state also updates the body scene entity (:mod:`.foxglove`) and the server's time.
The app's playback controls (foxglove-sdk's PlaybackControl capability: play, pause, seek,
speed) drive the player; the app's timeline spans the recording's log times (sim time for a
recording made with the default ``record_log_time: sim``). Playback starts when the first
client subscribes to a channel, not when the server starts: a client that connects late misses
nothing, and with ``once`` none gets the end before the beginning.
"""

from __future__ import annotations

import bisect
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rigid_rot_sim.message_fields import vector3_to_array
from rigid_rot_sim.recording.definitions import dynamic_decoder
from rigid_rot_sim.recording.reader import BagReader, RecordedMessage
from rigid_rot_sim.run.body_view import body_view
from rigid_rot_sim.scene.scene import parse_scene_text
from rigid_rot_sim.viewer.foxglove import BodyScene, FoxgloveServer, server_listener

__all__ = ["RecordingPlayer"]

_STATE_TYPE = "rigid_rot_msgs/msg/RigidBodyState"
#: Longest wait between two checks of the controls and of a stop request, s.
_POLL = 0.05
#: With ``once``: how long the server stays up after the last message (foxglove-sdk has no flush; a
#: server stopped at once drops what is still queued for the clients), s.
END_DRAIN = 1.0


@dataclass
class _Controls:
    """What the app asked for; read by the player loop, written by the server's thread."""

    playing: bool = True
    speed: float = 1.0
    seek_to: int | None = None
    request_id: str | None = None


class RecordingPlayer:
    """One recording served to Foxglove; :meth:`play` runs until the end (``once``) or :meth:`stop`."""

    def __init__(self, path: str | Path, host: str, port: int, speed: float = 1.0) -> None:
        reader = BagReader(path)
        record = reader.metadata.get("scene", {})
        if "text" not in record:
            raise ValueError(f"{path}: no 'scene' metadata record: not recorded by rigid_rot_sim")
        scene = parse_scene_text(record["text"], source=record.get("file", "<recorded scene>"))
        self.messages: list[RecordedMessage] = list(reader.messages())
        if not self.messages:
            raise ValueError(f"{path}: the recording holds no messages")
        self.times = [m.log_time_ns for m in self.messages]
        self.topics = reader.topics
        self.state_topic = reader.find_topic("state", _STATE_TYPE)
        self._decode_state = (
            dynamic_decoder(_STATE_TYPE, self.topics[self.state_topic].definition) if self.state_topic else None
        )
        self._lock = threading.Lock()
        self._controls = _Controls(speed=speed)
        self._stop = threading.Event()
        self._subscribed = threading.Event()  # a client subscribed: playback may start
        self.server = FoxgloveServer(
            host,
            port,
            BodyScene(body_view(scene), scene.frames.world, scene.frames.body),
            scene_topic="/rigid_rot_sim/body_scene",
            listener=server_listener(
                on_subscribe=lambda client, channel: self._subscribed.set(),
                on_playback_control_request=self.on_playback_control_request,
            ),
            playback_range=(self.times[0], self.times[-1]),
        )
        for topic, info in self.topics.items():  # every channel advertised before playback: a client subscribes first
            self.server.channel(topic, info.type_name, info.definition)

    @property
    def port(self) -> int:
        return self.server.port

    # -- the server's listener (called on foxglove-sdk's thread) ---------------------------------
    def on_playback_control_request(self, request: Any) -> Any:
        from foxglove.websocket import PlaybackCommand

        with self._lock:
            self._controls.playing = request.playback_command == PlaybackCommand.Play
            self._controls.speed = float(request.playback_speed) or 1.0
            self._controls.seek_to = request.seek_time
            self._controls.request_id = request.request_id
        return None  # the player answers with the state it reaches (broadcast from its loop)

    # -- the player ------------------------------------------------------------------------------
    def _send(self, message: RecordedMessage) -> None:
        topic = self.topics[message.topic]
        self.server.log(message.topic, topic.type_name, message.data, message.log_time_ns, topic.definition)
        if message.topic == self.state_topic and self._decode_state is not None:
            state = self._decode_state(message.data)
            stamp = state.header.stamp
            self.server.log_state(
                int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec),
                vector3_to_array(state.angular_velocity_body),
                vector3_to_array(state.angular_momentum_world),
            )

    def _broadcast(self, status: str, t_ns: int, speed: float, did_seek: bool, request_id: str | None) -> None:
        from foxglove.websocket import PlaybackState, PlaybackStatus

        self.server.broadcast_playback_state(
            PlaybackState(
                status=getattr(PlaybackStatus, status),
                current_time=int(t_ns),
                playback_speed=speed,
                did_seek=did_seek,
                request_id=request_id,
            )
        )

    def stop(self) -> None:
        """Make :meth:`play` return (from any thread, e.g. a signal handler)."""
        self._stop.set()

    def play(self, once: bool = False) -> None:
        """Serve the messages at their log times, from the first subscription on, until stopped
        (or, with ``once``, the end is reached)."""
        while not self._subscribed.wait(_POLL):
            if self._stop.is_set():
                return
        index, position = 0, self.times[0]
        anchor_wall, anchor_position = time.monotonic(), position
        ended = False
        while not self._stop.is_set():
            with self._lock:
                controls, self._controls = (
                    self._controls,
                    _Controls(playing=self._controls.playing, speed=self._controls.speed),
                )
            if controls.seek_to is not None:
                position = min(max(int(controls.seek_to), self.times[0]), self.times[-1])
                index, ended = bisect.bisect_left(self.times, position), False
            if controls.seek_to is not None or controls.request_id is not None:
                anchor_wall, anchor_position = time.monotonic(), position
                status = "Playing" if controls.playing and not ended else ("Ended" if ended else "Paused")
                self._broadcast(status, position, controls.speed, controls.seek_to is not None, controls.request_id)
            if controls.playing and not ended:
                position = anchor_position + int((time.monotonic() - anchor_wall) * controls.speed * 1e9)
                while index < len(self.messages) and self.times[index] <= position:
                    self._send(self.messages[index])
                    index += 1
                if index == len(self.messages):
                    ended = True
                    self._broadcast("Ended", self.times[-1], controls.speed, False, None)
                    if once:
                        self._stop.wait(END_DRAIN)
                        return
            else:
                anchor_wall, anchor_position = time.monotonic(), position
            wait = _POLL
            if controls.playing and not ended and index < len(self.messages):
                wait = min(_POLL, max(0.0, (self.times[index] - position) / 1e9 / controls.speed))
            self._stop.wait(wait)

    def close(self) -> None:
        self.server.close()
