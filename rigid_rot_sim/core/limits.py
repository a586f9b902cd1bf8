"""Documented limits of every input (docs/limits.md): the one place for them.

Scene files, service requests, torque commands and parameters are checked against these
numbers before anything else sees them; what is beyond a limit is refused with a message
saying which limit, never truncated silently. The parameter ranges below are also the
ranges of the node's parameter descriptors, so a scene can hold exactly the values a
``--ros-args -p`` override may hold.
"""

from __future__ import annotations

__all__ = [
    "MAX_SCENE_BYTES",
    "MAX_YAML_DEPTH",
    "MAX_YAML_ITEMS",
    "MAX_POINT_MASSES",
    "MAX_TORQUE_INPUTS",
    "MAX_NAME_LENGTH",
    "MAX_TEXT_LENGTH",
    "MAX_MAGNITUDE",
    "MAX_ROTATION_PER_STEP",
    "MAX_STEPS_PER_REQUEST",
    "MAX_ERROR_CHARS",
    "DT_RANGE",
    "REAL_TIME_FACTOR_RANGE",
    "MIN_REAL_TIME_FACTOR",
    "check_real_time_factor",
    "DURATION_RANGE",
    "RATE_RANGE",
    "MIN_RATE",
    "MAX_TORQUE_RANGE",
    "COMMAND_DEPTH_RANGE",
    "QOS_DEPTH_RANGE",
    "DEFAULT_COMMAND_DEPTH",
    "check_rate",
    "clip_text",
    "one_line",
]

#: Largest scene or body file read, bytes (a scene with MAX_POINT_MASSES masses is ~0.5 MB).
MAX_SCENE_BYTES = 1 << 20
#: Deepest nesting of YAML collections in a scene or body file (the schema needs 5).
MAX_YAML_DEPTH = 16
#: Most items in one YAML list or mapping.
MAX_YAML_ITEMS = 10_000
#: Most point masses in a scene, a body file or one ``~/compute_inertia`` request.
MAX_POINT_MASSES = 10_000
#: Most torque inputs (topics plus schedules) in one scene.
MAX_TORQUE_INPUTS = 32
#: Longest topic, frame or integrator name, and frame_id in a command or request (characters).
MAX_NAME_LENGTH = 256
#: Longest free text (a scene's description, a path), characters.
MAX_TEXT_LENGTH = 4096
#: Largest magnitude of a physical number in a scene (moments, masses, positions, ω, torques):
#: products of a few of them stay far from float overflow (1.8e308).
MAX_MAGNITUDE = 1e12
#: Most rotation (rad) a bound on |ω| allows in one physics step before the simulation is
#: stopped: beyond it the sampled states alias, and the adaptive methods' cost per step grows
#: with it (taylor at 25 000 rad per step: 0.2 s of wall time per step).
MAX_ROTATION_PER_STEP = 100.0
#: Most steps one ``~/step`` request may ask for.
MAX_STEPS_PER_REQUEST = 10_000
#: Longest error line printed by a command line tool (characters).
MAX_ERROR_CHARS = 300

# Parameter ranges (inclusive), shared by the scene schema (scene/scene_schema.py) and the node's descriptors.
DT_RANGE = (1e-7, 10.0)  # s
REAL_TIME_FACTOR_RANGE = (0.0, 1000.0)  # 0 = as fast as possible
#: Slowest pace other than 0 (as fast as possible): a second of sim time in at most about 11.6 days of
#: wall time. A slower one (a subnormal 5e-324) never reaches a step: the run would never advance.
MIN_REAL_TIME_FACTOR = 1e-6
DURATION_RANGE = (0.0, 1e9)  # s of sim time; 0 = unbounded (parameter)
RATE_RANGE = (0.0, 1e6)  # Hz of sim time; 0 = not published
#: Slowest rate (Hz of sim time) other than 0: a period of at most the longest duration. A slower
#: one (5e-324 Hz) implies a period no step count holds (1 / (rate * dt) overflows), and would
#: never be published within any run.
MIN_RATE = 1.0 / DURATION_RANGE[1]
MAX_TORQUE_RANGE = (0.0, MAX_MAGNITUDE)  # N*m; 0 = no limit
COMMAND_DEPTH_RANGE = (1, 10_000)  # keep-last depth of the torque subscriptions
DEFAULT_COMMAND_DEPTH = 10
#: Keep-last depth of the state-like outputs (the upper bound limits the memory a slow subscriber can pin).
QOS_DEPTH_RANGE = (1, 100_000)


def check_rate(rate: float) -> float:
    """``rate`` (Hz of sim time) when it is 0 (off) or from :data:`MIN_RATE` to ``RATE_RANGE[1]``, else
    ValueError saying the range: the one rule for output and sensor rates (scene files, parameters)."""
    if rate == 0.0 or MIN_RATE <= rate <= RATE_RANGE[1]:  # NaN fails both
        return rate
    raise ValueError(
        f"must be 0 (not published) or from {MIN_RATE:g} to {RATE_RANGE[1]:g} Hz "
        f"(a period of at most {DURATION_RANGE[1]:g} s), got {rate!r}"
    )


def check_real_time_factor(real_time_factor: float) -> float:
    """``real_time_factor`` when it is 0 (as fast as possible) or from :data:`MIN_REAL_TIME_FACTOR` to
    ``REAL_TIME_FACTOR_RANGE[1]``, else ValueError saying the range (scene files, parameters)."""
    if real_time_factor == 0.0 or MIN_REAL_TIME_FACTOR <= real_time_factor <= REAL_TIME_FACTOR_RANGE[1]:
        return real_time_factor
    raise ValueError(
        f"must be 0 (as fast as possible) or from {MIN_REAL_TIME_FACTOR:g} to {REAL_TIME_FACTOR_RANGE[1]:g} "
        f"(a slower pace never reaches a step), got {real_time_factor!r}"
    )


def clip_text(text: str, limit: int = MAX_NAME_LENGTH) -> str:
    """``text`` unchanged if it has at most ``limit`` characters, else its start, an ellipsis
    and the number of characters left out (for echoing user input in messages)."""
    if len(text) <= limit:
        return text
    return f"{text[:limit]}...({len(text) - limit} more characters)"


def one_line(text: str, limit: int = MAX_ERROR_CHARS) -> str:
    """Whitespace (newlines included) collapsed to single spaces, cut to ``limit`` characters."""
    line = " ".join(str(text).split())
    return line if len(line) <= limit else line[: limit - 3] + "..."
