"""Random hostile inputs for the fuzz tests (test/fuzz) and the long campaign (benchmarks/fuzz_node.py).

Every generator takes a ``random.Random`` so a run is reproduced from its seed. The classes
follow issue 9: mutated scene files (deep nesting, alias bombs, huge numbers, bad topic
names, out-of-range settings, long lists, byte damage), torque commands (non-finite, huge,
tiny, bad or long frame ids, wall-clock stamps), service requests and parameter values.
"""

from __future__ import annotations

import math
import random
from pathlib import Path

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"

NUMBERS = [
    0.0,
    -0.0,
    1e-300,
    5e-324,
    1e-3,
    1.0,
    -1.0,
    3.5,
    1e6,
    -1e6,
    1e12,
    1e13,
    1e30,
    1e200,
    1e308,
    -1e308,
    math.inf,
    -math.inf,
    math.nan,
]
FRAMES = [
    "",
    "base_link",
    "odom",
    "body",
    "world",
    "map",
    "Body",
    " body",
    "body\n",
    "ünïcode",
    "x" * 300,
    "f" * 100_000,
]


def number(rng: random.Random) -> float:
    return rng.choice(NUMBERS) if rng.random() < 0.7 else rng.uniform(-10.0, 10.0)


def torque_command(rng: random.Random) -> dict:
    """Fields of a WrenchStamped torque command: torque, force, frame_id, stamp (s)."""
    small = rng.random() < 0.3
    return {
        "torque": tuple(rng.uniform(-0.5, 0.5) if small else number(rng) for _ in range(3)),
        "force": tuple(0.0 if rng.random() < 0.7 else number(rng) for _ in range(3)),
        "frame_id": rng.choice(FRAMES),
        "stamp": rng.choice([0.0, 0.0, 1e-9, 0.5, 1e3, 1.7e9, 2.0e9]),
    }


def inertia_request(rng: random.Random) -> dict:
    """masses, positions, origin and frame_id of a ComputeInertia request (possibly mismatched)."""
    n = rng.choice([0, 1, 2, 3, 10, 1000, 10_001])
    masses = [number(rng) if rng.random() < 0.2 else rng.uniform(0.1, 5.0) for _ in range(n)]
    m = n if rng.random() < 0.8 else max(0, n + rng.choice([-1, 1]))
    positions = [tuple(number(rng) if rng.random() < 0.1 else rng.uniform(-1, 1) for _ in range(3)) for _ in range(m)]
    origin = tuple(number(rng) if rng.random() < 0.3 else 0.0 for _ in range(3))
    return {"masses": masses, "positions": positions, "origin": origin, "frame_id": rng.choice(FRAMES)}


def set_state_request(rng: random.Random) -> dict:
    q = tuple(number(rng) if rng.random() < 0.3 else rng.uniform(-1, 1) for _ in range(4))
    omega = tuple(number(rng) if rng.random() < 0.5 else rng.uniform(-5, 5) for _ in range(3))
    return {"orientation": q, "angular_velocity": omega}


def step_count(rng: random.Random) -> int:
    return rng.choice([0, 1, 7, 100, 9_999, 10_000, 10_001, 100_000, 1_000_000_000, 2**32 - 1])


def parameter(rng: random.Random) -> tuple[str, object]:
    """A (name, value) to set at run time: wrong types, out-of-range values, read-only names."""
    return rng.choice(
        [
            ("dt", rng.choice([0.0, -1.0, 1e-8, 20.0, 0.002, 0.0005, math.nan, math.inf, "x", 3])),
            ("real_time_factor", rng.choice([-1.0, 0.0, 1.0, 5.0, 5000.0, math.nan])),
            ("integrator", rng.choice(["rk4", "taylor", "exact", "magic", "", "x" * 1000, "euler", 5])),
            ("duration", rng.choice([-1.0, 0.0, 1e10, math.inf])),
            ("rates.state", rng.choice([0.0, 50.0, 2e6, -3.0])),
            ("rates.top_state", rng.choice([0.0, 10.0])),
            ("use_sim_time", rng.choice([True, False, "yes"])),
            ("commands.max_torque", rng.choice([0.0, 0.5, 1e6, -1.0, 1e13])),
            ("commands.qos_depth", rng.choice([1, 100, 0])),
            ("scene", "/etc/passwd"),
            ("record_path", "/tmp/x.mcap"),
        ]
    )


# ------------------------------------------------------------------------------ scene files


def _base_scene(rng: random.Random) -> str:
    return rng.choice(sorted(SCENES.glob("*.yaml"))).read_text()


def _deep(rng: random.Random, text: str) -> str:
    depth = rng.choice([20, 200, 5000, 50_000])
    return text + "description: " + "[" * depth + "]" * depth + "\n"


def _alias_bomb(rng: random.Random, text: str) -> str:
    if rng.random() < 0.5:
        lines = ['l0: &l0 "' + "lol" * 10 + '"']
    else:
        lines = ["l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for i in range(1, 10):
        refs = ", ".join([f"*l{i - 1}"] * 9)
        lines.append(f"l{i}: &l{i} [{refs}]")
    return text + "\n".join(lines) + "\n"


def _replace_value(rng: random.Random, text: str) -> str:
    lines = text.splitlines()
    candidates = [i for i, line in enumerate(lines) if ":" in line and not line.strip().startswith("#")]
    if not candidates:
        return text
    i = rng.choice(candidates)
    key, _, _ = lines[i].partition(":")
    value = rng.choice(
        [
            "9" * rng.choice([20, 310, 400]),
            "1.0e+300",
            "-1.0e+300",
            ".nan",
            ".inf",
            "-5",
            "0",
            "1.0e-8",
            "20",
            "5000",
            "2.0e+6",
            "[]",
            "{}",
            "null",
            "~",
            "true",
            "'x'",
            "[1, 2]",
            "!!python/object:os.system {}",
            "&a 1",
            "~/tor-que",
            "9torque",
            "/a//b",
            "'" + "z" * 5000 + "'",
        ]
    )
    lines[i] = f"{key}: {value}"
    return "\n".join(lines) + "\n"


def _point_masses(rng: random.Random, text: str) -> str:
    n = rng.choice([2, 3, 9_999, 10_001, 100_000])
    masses = ", ".join("1" for _ in range(n))
    positions = ", ".join(f"[{i % 7}, {i % 5}, {i % 3}]" for i in range(n))
    return f"body:\n  point_masses:\n    masses: [{masses}]\n    positions: [{positions}]\n"


def _damage(rng: random.Random, text: str) -> str:
    data = bytearray(text.encode())
    for _ in range(rng.randint(1, 8)):
        if not data:
            break
        i = rng.randrange(len(data))
        action = rng.random()
        if action < 0.4:
            data[i] = rng.randrange(256)
        elif action < 0.7:
            del data[i : i + rng.randint(1, 20)]
        else:
            data[i:i] = rng.choice([b"{", b"[", b"\t", b": ", b"\n  ", b"&a ", b"*a", b"\x00", b"- "])
    return data.decode("utf-8", errors="replace")


def _topic(rng: random.Random, text: str) -> str:
    name = rng.choice(["~/tor-que", "9torque", "/a//b", "a/", "~torque", "{node}/t", "t" * 300, "~/ok_topic"])
    return text.split("torque_inputs:")[0] + f"torque_inputs:\n  - topic: '{name}'\n"


MUTATIONS = [_deep, _alias_bomb, _replace_value, _replace_value, _point_masses, _damage, _damage, _topic]


def mutated_scene(rng: random.Random) -> str:
    """A shipped scene after one or two random mutations."""
    text = _base_scene(rng)
    for _ in range(rng.randint(1, 2)):
        text = rng.choice(MUTATIONS)(rng, text)
    return text
