"""The simulation event log recorded next to the topics: what re-simulation replays.

Every change the node makes to the simulation from outside the physics (a torque command
accepted, a torque applied through the service, set_state, reset, an integrator or step
change) is recorded as one ``diagnostic_msgs/msg/DiagnosticStatus`` on ``~/sim_events``:
``name`` is ``rigid_rot_sim/<kind>``, ``message`` a one-line summary a person reads in
Foxglove, ``values`` the exact arguments as key/value strings. Floats are written with
``repr`` (the shortest string that reads back to the same float64), so a re-simulation
fed these events is bit-exact. ``step`` is the simulator's step index when the event
happened: re-simulation advances to it, then applies the event, as the node did.

A standard message type keeps every tool (rosbag2 playback, Foxglove, rosbags) able to
read the channel; it is serialised from its definition, so no Python package is needed.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

EVENT_TYPE = "diagnostic_msgs/msg/DiagnosticStatus"
EVENT_PREFIX = "rigid_rot_sim/"
KINDS = (
    "torque",
    "apply_torque",
    "set_state",
    "reset",
    "integrator",
    "wheel_torque",
    "rod_dipoles",
    "lockstep_timeout",
)


@dataclass(frozen=True)
class SimEvent:
    """One recorded event: its kind, the step index it happened at, and its arguments."""

    kind: str
    step: int
    values: Mapping[str, str]

    def number(self, key: str) -> float:
        """A float argument, exactly as recorded."""
        return float(self.values[key])

    def vector(self, key: str, n: int = 3) -> tuple[float, ...]:
        """A vector argument stored as ``key_0 .. key_{n-1}``."""
        return tuple(float(self.values[f"{key}_{i}"]) for i in range(n))

    def optional_float(self, key: str) -> float | None:
        """A float argument that may be absent (``""``)."""
        text = self.values.get(key, "")
        return float(text) if text else None


def _text(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (dict, list, tuple)):
        return json.dumps(value, sort_keys=True)
    return str(value)


def event_fields(kind: str, step: int, summary: str, **values: Any) -> dict[str, Any]:
    """The DiagnosticStatus content (nested mappings) of one event.

    Sequences of floats are stored component-wise as ``key_0``, ``key_1``, ...
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    pairs = [("step", str(int(step)))]
    for key, value in values.items():
        if isinstance(value, (tuple, list)) and value and all(isinstance(v, float) for v in value):
            pairs.extend((f"{key}_{i}", repr(v)) for i, v in enumerate(value))
        else:
            pairs.append((key, _text(value)))
    return {
        "level": 0,
        "name": EVENT_PREFIX + kind,
        "message": summary,
        "hardware_id": "",
        "values": [{"key": k, "value": v} for k, v in pairs],
    }


def decode_event(status: Any) -> SimEvent:
    """A decoded DiagnosticStatus (object with ``name`` and ``values``) -> SimEvent."""
    name = str(status.name)
    if not name.startswith(EVENT_PREFIX):
        raise ValueError(f"not a rigid_rot_sim event: name {name!r}")
    values = {str(kv.key): str(kv.value) for kv in status.values}
    return SimEvent(kind=name[len(EVENT_PREFIX) :], step=int(values.pop("step")), values=values)
