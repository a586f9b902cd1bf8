"""A Foxglove WebSocket server for the body: the node's messages as published, the body as a scene entity.

Foxglove (the app, or app.foxglove.dev in a browser) connects to ``ws://HOST:PORT`` (Open
connection -> Foxglove WebSocket) and shows what this server streams, without any ROS:

* every message the node publishes (or the recording holds), as the same CDR bytes, on a
  channel of its topic with the complete ``ros2msg`` definition as schema (Foxglove decodes
  ROS 2 messages from their definitions: /tf, ~/state, ~/imu ... look as they do over ROS);
* ``<namespace>/body_scene``: a ``foxglove.SceneUpdate`` (JSON) with one entity, the body's
  inertia box and its omega arrow in the body frame and, in a second entity, the L arrow in the
  world frame, drawn as :mod:`rigid_rot_sim.run.body_view` says (the same drawing as ``~/markers``);
* the server's time (the Time capability) is the sim time of the latest state, so Foxglove's
  timeline follows the simulation, not the wall clock.

``foxglove-sdk`` (PyPI, MIT, no dependencies) is an optional extra of the package
(``pip install rigid_rot_sim[viewer]``; ``make setup`` installs it): :func:`available` tells
whether it is importable, and nothing here imports it before a server is started.
"""

from __future__ import annotations

import importlib.util
import json
from dataclasses import dataclass
from typing import Any

import numpy as np

from rigid_rot_sim.recording.definitions import complete_definition
from rigid_rot_sim.run.body_view import BOX_COLOR, MOMENTUM_COLOR, OMEGA_COLOR, BodyView

__all__ = [
    "DEFAULT_HOST",
    "DEFAULT_PORT",
    "BodyScene",
    "FoxgloveServer",
    "available",
    "parse_address",
    "server_listener",
]

DEFAULT_HOST = "127.0.0.1"  # loopback: a viewer on another machine needs HOST given explicitly
DEFAULT_PORT = 8765  # Foxglove's default WebSocket port
SCENE_SCHEMA_NAME = "foxglove.SceneUpdate"
#: Foxglove recognises its own schemas by name; the JSON schema only has to admit the message.
_SCENE_JSON_SCHEMA = {"title": SCENE_SCHEMA_NAME, "type": "object"}


def available() -> bool:
    """True when foxglove-sdk is installed (the viewer extra)."""
    return importlib.util.find_spec("foxglove") is not None


def parse_address(text: str, what: str = "foxglove") -> tuple[str, int]:
    """``[HOST:]PORT`` -> (host, port); the host defaults to loopback. ValueError names ``what`` is wrong."""
    host, _, port_text = text.strip().rpartition(":")
    host = host.strip("[]") or DEFAULT_HOST
    try:
        port = int(port_text)
    except ValueError:
        raise ValueError(f"{what} address {text!r}: expected [HOST:]PORT, e.g. 8765 or 127.0.0.1:8765") from None
    if not 0 <= port <= 65535:
        raise ValueError(f"{what} address {text!r}: port must be 0..65535 (0: any free port)")
    return host, port


def _time(t_ns: int) -> dict[str, int]:
    sec, nsec = divmod(int(t_ns), 1_000_000_000)
    return {"sec": sec, "nsec": nsec}


def _color(rgba: tuple[float, float, float, float]) -> dict[str, float]:
    return dict(zip("rgba", (float(c) for c in rgba), strict=True))


def _vector(v: Any) -> dict[str, float]:
    return dict(zip("xyz", (float(c) for c in v), strict=True))


def _quaternion(q: Any) -> dict[str, float]:
    return dict(zip("xyzw", (float(c) for c in q), strict=True))


def _x_to(direction: np.ndarray) -> np.ndarray:
    """Unit quaternion (x, y, z, w) turning +x onto ``direction`` (identity for a zero vector)."""
    norm = float(np.linalg.norm(direction))
    if norm == 0.0:
        return np.array([0.0, 0.0, 0.0, 1.0])
    d = direction / norm
    axis = np.cross([1.0, 0.0, 0.0], d)
    w = 1.0 + d[0]
    if w < 1e-12:  # opposite to +x: half a turn about z
        return np.array([0.0, 0.0, 1.0, 0.0])
    q = np.array([axis[0], axis[1], axis[2], w])
    return q / np.linalg.norm(q)


@dataclass(frozen=True)
class BodyScene:
    """The body's scene entities for Foxglove's 3D panel, from a :class:`BodyView`."""

    view: BodyView
    world_frame: str
    body_frame: str

    def _arrow(self, tail: np.ndarray, tip: np.ndarray, color: tuple[float, float, float, float]) -> dict[str, Any]:
        length = float(np.linalg.norm(tip - tail))
        head = min(self.view.head_size, 0.5 * length)
        return {
            "pose": {"position": _vector(tail), "orientation": _quaternion(_x_to(tip - tail))},
            "shaft_length": length - head,
            "shaft_diameter": self.view.shaft_diameter,
            "head_length": head,
            "head_diameter": 2.0 * self.view.shaft_diameter,
            "color": _color(color),
        }

    def update(self, t_ns: int, omega_body: np.ndarray, momentum_world: np.ndarray) -> dict[str, Any]:
        """A ``foxglove.SceneUpdate`` (as JSON-ready dict) at sim time ``t_ns``."""
        view = self.view
        body = {
            "timestamp": _time(t_ns),
            "frame_id": self.body_frame,
            "id": "body",
            "frame_locked": True,
            "lifetime": {"sec": 0, "nsec": 0},
            "cubes": [
                {
                    "pose": {"position": _vector(view.box_center), "orientation": _quaternion(view.box_orientation)},
                    "size": _vector([max(side, 1e-3) for side in view.box_sides]),
                    "color": _color(BOX_COLOR),
                }
            ],
            "arrows": [self._arrow(*view.omega_arrow(omega_body), OMEGA_COLOR)],
        }
        momentum = {
            "timestamp": _time(t_ns),
            "frame_id": self.world_frame,
            "id": "angular_momentum",
            "frame_locked": False,
            "lifetime": {"sec": 0, "nsec": 0},
            "arrows": [self._arrow(*view.momentum_arrow(momentum_world), MOMENTUM_COLOR)],
        }
        return {"deletions": [], "entities": [body, momentum]}


def server_listener(
    on_subscribe: Any = None, on_playback_control_request: Any = None, on_unsubscribe: Any = None
) -> Any:
    """A foxglove-sdk ``ServerListener`` calling the given functions (the others answer as the SDK's defaults).

    The SDK calls every method of the listener it is given: an object that is not a
    ``ServerListener`` fails with AttributeError for each one it lacks.
    """
    from foxglove.websocket import ServerListener

    class _Listener(ServerListener):
        def on_subscribe(self, client: Any, channel: Any) -> None:
            if on_subscribe is not None:
                on_subscribe(client, channel)

        def on_unsubscribe(self, client: Any, channel: Any) -> None:
            if on_unsubscribe is not None:
                on_unsubscribe(client, channel)

        def on_playback_control_request(self, request: Any) -> Any:
            return None if on_playback_control_request is None else on_playback_control_request(request)

    return _Listener()


class FoxgloveServer:
    """A running foxglove-sdk WebSocket server with one channel per topic, and the body scene.

    ``playback_range`` (ns, ns): serving a recording; the app's play/pause/seek controls then reach
    ``listener.on_playback_control_request`` (foxglove-sdk's PlaybackControl capability).
    """

    def __init__(
        self,
        host: str,
        port: int,
        scene: BodyScene,
        *,
        name: str = "rigid_rot_sim",
        scene_topic: str = "/rigid_rot_sim/body_scene",
        listener: Any = None,
        playback_range: tuple[int, int] | None = None,
    ) -> None:
        import foxglove
        from foxglove import Schema
        from foxglove.websocket import Capability

        self._foxglove = foxglove
        self._schema = Schema
        self.context = foxglove.Context()
        self.scene = scene
        self.channels: dict[str, Any] = {}
        self.server: Any = foxglove.start_server(
            name=name,
            host=host,
            port=port,
            capabilities=[Capability.Time],
            server_listener=listener,
            context=self.context,
            playback_time_range=playback_range,
        )
        self.scene_channel = foxglove.Channel(
            scene_topic,
            message_encoding="json",
            context=self.context,
            schema=Schema(name=SCENE_SCHEMA_NAME, encoding="jsonschema", data=json.dumps(_SCENE_JSON_SCHEMA).encode()),
        )

    @property
    def port(self) -> int:
        """The port it listens on (the one chosen by the system when 0 was asked)."""
        return int(self.server.port)

    def channel(self, topic: str, type_name: str, definition: str | None = None) -> Any:
        """The channel of ``topic`` (created with its ros2msg schema on first use)."""
        channel = self.channels.get(topic)
        if channel is None:
            text = complete_definition(type_name) if definition is None else definition
            schema = self._schema(name=type_name, encoding="ros2msg", data=text.encode("utf-8"))
            channel = self._foxglove.Channel(topic, schema=schema, message_encoding="cdr", context=self.context)
            self.channels[topic] = channel
        return channel

    def log(self, topic: str, type_name: str, data: bytes, t_ns: int, definition: str | None = None) -> None:
        """Stream ``data`` (CDR) on ``topic`` stamped with sim time ``t_ns``."""
        self.channel(topic, type_name, definition).log(data, log_time=int(t_ns))

    def log_state(self, t_ns: int, omega_body: np.ndarray, momentum_world: np.ndarray) -> None:
        """The body scene at sim time ``t_ns``, and the server's time moved to it."""
        update = self.scene.update(t_ns, omega_body, momentum_world)
        self.scene_channel.log(json.dumps(update).encode("utf-8"), log_time=int(t_ns))
        self.server.broadcast_time(int(t_ns))

    def broadcast_playback_state(self, state: Any) -> None:
        self.server.broadcast_playback_state(state)

    def close(self) -> None:
        """Stop serving (idempotent)."""
        server, self.server = self.server, None
        if server is not None:
            server.stop()
