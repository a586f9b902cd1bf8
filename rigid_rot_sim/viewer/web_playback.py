"""Play a recording on the body's web page: ``rigid-rot view BAG --web [HOST:]PORT`` (no ROS).

The recorded states (``~/state``, decoded with the file's own definition) are the frames; the
page (:mod:`.web`) shows the one at the playback position, at most ``MAX_RATE`` times a second.
Play, pause, speed and a time slider over the recorded range are the page's controls; the
status panel shows the sim time, the speed and the digest of the state shown. Playback starts
when the first browser connects (so that nobody misses the beginning, nor, with ``once``, the end).
"""

from __future__ import annotations

import bisect
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from rigid_rot_sim.message_fields import quaternion_to_array, time_to_seconds, vector3_to_array
from rigid_rot_sim.recording.definitions import dynamic_decoder
from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.run.body_view import body_view
from rigid_rot_sim.run.digest import format_digest
from rigid_rot_sim.scene.scene import parse_scene_text
from rigid_rot_sim.viewer.web import MAX_RATE, PLOT_SAMPLES, BodyPage, Frame

__all__ = ["WebRecordingPlayer", "next_position", "recorded_frames"]

_STATE_TYPE = "rigid_rot_msgs/msg/RigidBodyState"
#: Speeds the slider offers (x real time).
SPEED_RANGE = (0.1, 10.0)


def recorded_frames(path: str | Path) -> tuple[Any, list[Frame]]:
    """The recorded scene and its states as frames, in log-time order. ValueError when there are none."""
    reader = BagReader(path)
    record = reader.metadata.get("scene", {})
    if "text" not in record:
        raise ValueError(f"{path}: no 'scene' metadata record: not recorded by rigid_rot_sim")
    scene = parse_scene_text(record["text"], source=record.get("file", "<recorded scene>"))
    topic = reader.find_topic("state", _STATE_TYPE)
    if topic is None:
        raise ValueError(f"{path}: no {_STATE_TYPE} topic: nothing to show")
    decode = dynamic_decoder(_STATE_TYPE, reader.topics[topic].definition)
    frames = []
    for message in reader.messages([topic]):
        state = decode(message.data)
        frames.append(
            Frame(
                time_to_seconds(state.header.stamp),
                quaternion_to_array(state.orientation),
                vector3_to_array(state.angular_velocity_body),
                vector3_to_array(state.angular_momentum_world),
                float(state.energy_drift),
                float(state.angular_momentum_drift),
                int(state.digest),
            )
        )
    if not frames:
        raise ValueError(f"{path}: the recording holds no states")
    return scene, frames


def next_position(
    position: float, elapsed: float, playing: bool, speed: float, seek: float | None, pressed: bool, end: float
) -> tuple[float, bool]:
    """The playback position (s of the playback clock) after ``elapsed`` s of wall time, and whether it jumped.

    A seek jumps; Play pressed at the end replays from the start (a media player's Play, not a no-op);
    playing advances by ``elapsed * speed``, up to ``end``.

    >>> next_position(10.0, 0.1, True, 1.0, None, True, 10.0)
    (0.0, True)
    >>> next_position(2.0, 0.5, True, 2.0, None, False, 10.0)
    (3.0, False)
    """
    if seek is not None:
        return seek, True
    if pressed and position >= end:
        return 0.0, True
    if playing:
        return min(position + elapsed * speed, end), False
    return position, False


class WebRecordingPlayer:
    """One recording on a :class:`BodyPage`; :meth:`play` runs until the end (``once``) or :meth:`stop`.

    The playback position is the index of the frame shown; it advances with wall time times the
    speed, through the frames' sim times (a reset in the recording shows as a jump back).
    """

    def __init__(self, path: str | Path, host: str, port: int, speed: float = 1.0) -> None:
        scene, self.frames = recorded_frames(path)
        # the playback clock: time since the first state, over the recorded order (monotonic even across resets)
        steps = np.diff([f.t for f in self.frames], prepend=self.frames[0].t)
        self.clock = np.cumsum(np.where(steps > 0.0, steps, 0.0)).tolist()
        self.page = BodyPage(host, port, body_view(scene), f"{scene.name}: {Path(path).name}")
        self._lock = threading.Lock()
        self.playing = True
        self.speed = min(max(speed, SPEED_RANGE[0]), SPEED_RANGE[1])
        self._seek: float | None = None
        #: Play was pressed (from the end of the recording it replays from the start).
        self._play_pressed = False
        self._stop = threading.Event()
        gui = self.page.server.gui
        with self.page.controls:
            gui.add_button("Play").on_click(lambda _: self._set(playing=True))
            gui.add_button("Pause").on_click(lambda _: self._set(playing=False))
            self.speed_slider = gui.add_slider(
                "speed", min=SPEED_RANGE[0], max=SPEED_RANGE[1], step=0.1, initial_value=self.speed
            )
            self.time_slider = gui.add_slider(
                "time (s)",
                min=0.0,
                max=max(self.clock[-1], 1e-9),
                step=max(self.clock[-1] / 1000, 1e-6),
                initial_value=0.0,
            )
        self.speed_slider.on_update(lambda event: self._set(speed=float(event.target.value)) if event.client else None)
        self.time_slider.on_update(lambda event: self._set(seek=float(event.target.value)) if event.client else None)

    @property
    def port(self) -> int:
        return self.page.port

    def _set(self, playing: bool | None = None, speed: float | None = None, seek: float | None = None) -> None:
        """A control from the page (viser's thread)."""
        with self._lock:
            if playing is not None:
                self.playing = playing
                self._play_pressed = self._play_pressed or playing
            if speed is not None:
                self.speed = speed
            if seek is not None:
                self._seek = seek

    def stop(self) -> None:
        """Make :meth:`play` return (from any thread, e.g. a signal handler)."""
        self._stop.set()

    def wait_for_browser(self) -> bool:
        """Block until a browser is connected (True) or :meth:`stop` (False)."""
        while not self._stop.is_set():
            if self.page.clients() > 0:
                return True
            self._stop.wait(0.05)
        return False

    def _history(self, index: int) -> list[Frame]:
        """The frames up to ``index``, thinned to at most ``PLOT_SAMPLES``."""
        stride = max(1, (index + 1) // PLOT_SAMPLES + 1)
        return self.frames[index % stride : index + 1 : stride]

    def play(self, once: bool = False) -> None:
        """Show the frames at their recorded pace until stopped (or, with ``once``, the end is shown)."""
        if not self.wait_for_browser():
            return
        position, shown = 0.0, -1
        last = time.monotonic()
        while not self._stop.wait(1.0 / MAX_RATE):
            now = time.monotonic()
            with self._lock:
                playing, speed, seek, self._seek = self.playing, self.speed, self._seek, None
                pressed, self._play_pressed = self._play_pressed, False
            position, jumped = next_position(position, now - last, playing, speed, seek, pressed, self.clock[-1])
            if jumped:
                self.page.clear_trail()
            last = now
            index = max(0, bisect.bisect_right(self.clock, position) - 1)
            if index != shown:
                frame = self.frames[index]
                self.page.show(frame, self._history(index))
                shown = index
            ended = index == len(self.frames) - 1
            frame = self.frames[index]
            self.page.status(
                f"**recording**  \nsim time: {frame.t:.3f} s ({index + 1} of {len(self.frames)} states)  \n"
                f"{'ended' if ended else 'playing' if playing else 'paused'} at {speed:g}x  \n"
                f"digest: {format_digest(frame.digest)}"
            )
            self.time_slider.value = round(position, 9)
            if ended and once:
                return

    def close(self) -> None:
        self.page.close()
