"""The node's Foxglove live server: a listener of every message the node publishes.

Attached like the recorder (``outputs.listeners``), so the server streams exactly the bytes
that go on the wire, stamped with the sim time they were published at; each ``state`` (or,
without it, ``orientation``/``angular_velocity`` are not enough: the body scene needs omega
and L, so it follows ``state``) also updates the body scene entity and the server's time. See
:mod:`rigid_rot_sim.viewer.foxglove` for what Foxglove shows.

The once-only messages (``~/mass_properties``, ``/tf_static``: transient local over DDS) are kept
and logged again whenever a client subscribes to their channel, so that a client that connects
after start-up gets them too, as a late DDS subscriber does (the clients already subscribed get
the same message once more).
"""

from __future__ import annotations

import threading
from typing import Any

from rigid_rot_sim.message_fields import vector3_to_array
from rigid_rot_sim.recording.session import type_name_of
from rigid_rot_sim.run.body_view import BodyView
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import Frames
from rigid_rot_sim.viewer.foxglove import BodyScene, FoxgloveServer, available, parse_address, server_listener

#: The outputs published once (latched over DDS): sent again to each new subscriber.
LATCHED = ("mass_properties", "tf_static")

__all__ = ["FoxgloveLive", "start"]


class FoxgloveLive:
    """Streams the node's published messages to a :class:`FoxgloveServer` (a ``PublishedListener``)."""

    def __init__(self, server: FoxgloveServer, sim: Simulator) -> None:
        self.server = server
        self.sim = sim
        self._types: dict[type, str] = {}
        self._latched: dict[str, tuple[str, bytes, int]] = {}  # topic -> (type, data, log time)

    def published(self, name: str, topic: str, data: bytes, msg: Any) -> None:
        t_ns = round(self.sim.clock.t * 1e9)
        kind = type(msg)
        type_name = self._types.get(kind) or self._types.setdefault(kind, type_name_of(kind))
        if name in LATCHED:
            self._latched[topic] = (type_name, data, t_ns)
        self.server.log(topic, type_name, data, t_ns)
        if name == "state":
            self.server.log_state(
                t_ns, vector3_to_array(msg.angular_velocity_body), vector3_to_array(msg.angular_momentum_world)
            )

    def subscribed(self, topic: str) -> None:
        """A client subscribed to ``topic`` (on the SDK's thread): a latched message goes out again,
        from a thread of its own (the SDK's callback returns at once)."""
        latched = self._latched.get(topic)
        if latched is not None:
            type_name, data, t_ns = latched
            threading.Thread(target=self.server.log, args=(topic, type_name, data, t_ns), daemon=True).start()

    def close(self) -> None:
        self.server.close()


def start(
    address: str, sim: Simulator, view: BodyView, frames: Frames, namespace: str
) -> tuple[FoxgloveLive | None, str]:
    """The live server on ``[HOST:]PORT`` and the start-up line's words; (None, why) without foxglove-sdk.

    ValueError for a malformed address; OSError when the port cannot be bound.
    """
    host, port = parse_address(address)
    if not available():
        return None, "Foxglove live server (foxglove-sdk not installed: pip install rigid_rot_sim[viewer])"
    scene_topic = f"{namespace.rstrip('/')}/body_scene"
    lives: list[FoxgloveLive] = []  # the listener exists before the server, the server before its FoxgloveLive

    def on_subscribe(client: Any, channel: Any) -> None:
        for live in lives:
            live.subscribed(channel.topic)

    listener = server_listener(on_subscribe=on_subscribe)
    server = FoxgloveServer(
        host, port, BodyScene(view, frames.world, frames.body), scene_topic=scene_topic, listener=listener
    )
    lives.append(FoxgloveLive(server, sim))
    return lives[0], f"Foxglove live server ws://{host}:{server.port} ({scene_topic})"
