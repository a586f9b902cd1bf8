"""A client of Foxglove's WebSocket protocol for the tests (what the Foxglove app does on connect).

ws-protocol (github.com/foxglove/ws-protocol, docs/spec.md): the server sends JSON text frames
``serverInfo`` and ``advertise`` (channels: id, topic, encoding, schemaName, schema,
schemaEncoding); the client sends ``subscribe`` with its own subscription ids; the server then
sends binary frames, opcode 0x01 *Message Data* (u32 subscription id, u64 log time ns, payload,
little endian) and 0x02 *Time* (u64 ns).
"""

from __future__ import annotations

import json
import struct
import time
from dataclasses import dataclass, field
from typing import Any

from websockets.sync.client import connect

SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
MESSAGE_DATA, TIME = 0x01, 0x02


@dataclass
class FoxgloveClient:
    url: str
    channels: dict[int, dict[str, Any]] = field(default_factory=dict)
    server_info: dict[str, Any] = field(default_factory=dict)
    messages: list[tuple[str, int, bytes]] = field(default_factory=list)  # (topic, log time ns, payload)
    times: list[int] = field(default_factory=list)
    json_ops: list[dict[str, Any]] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.ws = connect(self.url, subprotocols=SUBPROTOCOLS, open_timeout=30)
        self._subscriptions: dict[int, int] = {}  # subscription id -> channel id

    def close(self) -> None:
        self.ws.close()

    def _receive(self, timeout: float) -> None:
        try:
            frame = self.ws.recv(timeout=timeout)
        except TimeoutError:
            return
        if isinstance(frame, str):
            message = json.loads(frame)
            self.json_ops.append(message)
            if message["op"] == "serverInfo":
                self.server_info = message
            elif message["op"] == "advertise":
                for channel in message["channels"]:
                    self.channels[channel["id"]] = channel
            elif message["op"] == "unadvertise":
                for channel_id in message["channelIds"]:
                    self.channels.pop(channel_id, None)
            return
        opcode = frame[0]
        if opcode == MESSAGE_DATA:
            subscription, log_time = struct.unpack_from("<IQ", frame, 1)
            channel = self.channels[self._subscriptions[subscription]]
            self.messages.append((channel["topic"], log_time, bytes(frame[13:])))
        elif opcode == TIME:
            self.times.append(struct.unpack_from("<Q", frame, 1)[0])

    def until(self, condition, timeout: float, what: str, check=None) -> None:
        deadline = time.monotonic() + timeout
        while not condition():
            if check is not None:
                check()
            assert time.monotonic() < deadline, f"timed out after {timeout} s waiting for {what}"
            self._receive(0.1)

    def pump(self, seconds: float) -> None:
        """Receive whatever arrives for ``seconds``."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self._receive(0.05)

    def channel_of(self, topic: str) -> dict[str, Any] | None:
        return next((c for c in self.channels.values() if c["topic"] == topic), None)

    def subscribe(self, *topics: str) -> None:
        subscriptions = []
        for topic in topics:
            channel = self.channel_of(topic)
            assert channel is not None, f"{topic} not advertised: {[c['topic'] for c in self.channels.values()]}"
            subscription = len(self._subscriptions) + 1
            self._subscriptions[subscription] = channel["id"]
            subscriptions.append({"id": subscription, "channelId": channel["id"]})
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))

    def received(self, topic: str) -> list[tuple[int, bytes]]:
        return [(t, payload) for name, t, payload in self.messages if name == topic]
