"""Scene files: the YAML description of one simulation run, validated into frozen dataclasses.

A scene says what a run needs, and the simulator and the node build only that. Every
error is a :class:`SceneError` (a ValueError) naming the file, the key and what is wrong,
e.g. ``free_tumble.yaml: body.principal_moments[2]: must be finite and > 0, got -1.0``.

Schema (SI units; frames REP 103; quaternions scalar-last, body -> world)::

    name: free_tumble                  # optional, defaults to the file stem
    description: "..."                 # optional
    frames: {world: odom, body: base_link}  # optional, these are the defaults (REP 105)
    body:                              # exactly one of the three inertia forms
      principal_moments: [I1, I2, I3]  # kg*m^2, along the body frame's axes
      inertia_tensor: [[..], [..], [..]]   # kg*m^2, symmetric positive definite, body axes
      point_masses:                    # inertia computed by core.inertia
        masses: [m, ...]               # kg
        positions: [[x, y, z], ...]    # m, body frame
    initial:                           # optional, defaults to identity attitude and rest
      orientation: [x, y, z, w]        # body -> world, normalised on load
      euler_zxz: [phi, theta, psi]     # rad, intrinsic z-x'-z'' (instead of orientation)
      angular_velocity: [wx, wy, wz]   # rad/s, body frame
    torque_inputs:                     # optional list; each item is a topic or a schedule
      - topic: ~/torque                # a topic input
        type: WrenchStamped            # or Vector3Stamped
        frame: body                    # body | world | header (header.frame_id names one)
        hold: hold                     # hold until replaced, or {timeout: seconds} then zero
      - schedule:                      # piecewise-constant torque written in the file
          frame: body                  # body | world
          segments:                    # each holds from its start to the next start
            - {start: 0.0, torque: [0, 0, 0.1]}
            - {start: 2.0, torque: [0, 0, 0]}
    gravity:                           # optional (heavy top); omit or null for none
      acceleration: 9.81               # m/s^2 along -z of the world frame
      mass: 1.0                        # kg (not with point_masses: their total is used)
      center_of_mass: [0, 0, 0.1]      # m, body frame (not with point_masses)
    integrator:
      method: auto                     # a name from the integrator registry, or auto
      dt: 0.001                        # s, the fixed physics step (> 0)
      options: {tol: 1.0e-12}          # optional keyword options of the method (e.g. taylor's tol)
    duration: 10.0                     # s of sim time, or null for unbounded
    real_time_factor: 1.0              # 1 = wall-clock pace, 0 = as fast as possible
    outputs:                           # Hz of sim time; 0 = not published
      state: 100
      orientation: 100
      angular_velocity: 100
      angular_momentum: 100
      top_state: 100                   # gravity scenes only
      tf: 50                           # only where tf2_msgs is installed
      clock: 100
      imu: 0                           # sensor_msgs/Imu on ~/imu (0: not built, the default)
      odom: 0                          # nav_msgs/Odometry on ~/odom (0: not built, the default)
    qos:                               # QoS of the state-like outputs (~/state ... ~/top_state)
      reliability: reliable            # reliable | best_effort
      depth: 10                        # keep-last history depth, 1..MAX_QOS_DEPTH
    recording: null                    # or a path to an .mcap file
    commands:                          # optional, for the torque inputs
      max_torque: 0                    # N*m; a command whose |torque| exceeds it is rejected (0 = no limit)
      qos_depth: 10                    # keep-last depth of the torque subscriptions

Limits (:mod:`rigid_rot_sim.core.limits`, README "Limits and failure behaviour"): the
file size, YAML nesting depth and list lengths are bounded and YAML aliases are refused
(:mod:`bounded_yaml`); physical numbers have at most ``MAX_MAGNITUDE`` in magnitude; dt,
real-time factor, duration and rates lie in the ranges of the node's parameters; topic
names follow the ROS 2 rules (:mod:`names`).

With ``gravity`` the body frame's origin is the pivot, and the inertia (principal
moments or tensor) is about the pivot; point masses give the inertia about the origin
of their coordinates (the pivot) and their centre of mass. Without gravity the body
turns about its centre of mass: principal moments or a tensor are about it, and point
masses give their inertia about their centre of mass.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
from rigid_rot_sim.core import limits, names, validation
from rigid_rot_sim.core.bounded_yaml import BoundedYAMLError, load_bounded, read_bounded
from rigid_rot_sim.core.quaternion import zxz_to_quaternion

__all__ = [
    "SceneError",
    "Frames",
    "Body",
    "InitialState",
    "TopicInput",
    "ScheduleSegment",
    "TorqueSchedule",
    "Gravity",
    "IntegratorSpec",
    "Outputs",
    "OutputQos",
    "CommandSettings",
    "Scene",
    "load_scene",
    "parse_scene",
    "parse_scene_text",
    "TORQUE_MESSAGE_TYPES",
    "TORQUE_FRAMES",
]

TORQUE_MESSAGE_TYPES = ("WrenchStamped", "Vector3Stamped")
TORQUE_FRAMES = ("body", "world", "header")
OUTPUT_NAMES = ("state", "orientation", "angular_velocity", "angular_momentum", "top_state", "tf", "clock", "imu", "odom")
DEFAULT_OUTPUT_RATES = {
    "state": 100.0,
    "orientation": 100.0,
    "angular_velocity": 100.0,
    "angular_momentum": 100.0,
    "top_state": 100.0,
    "tf": 50.0,
    "clock": 100.0,
    "imu": 0.0,  # sensor_msgs/Imu and nav_msgs/Odometry: built only when the scene asks
    "odom": 0.0,
}

QOS_RELIABILITIES = ("reliable", "best_effort")
#: Largest keep-last depth of an output (a bound on the memory a slow subscriber can pin).
MAX_QOS_DEPTH = 100_000

Vector3 = tuple[float, float, float]


class SceneError(ValueError):
    """A scene file is invalid; the message names the file, the key and what is wrong."""


#: Default frame names, REP 105: the fixed frame the attitude is given in, and the body.
DEFAULT_WORLD_FRAME = "odom"
DEFAULT_BODY_FRAME = "base_link"


@dataclass(frozen=True)
class Frames:
    """Names of the world frame and of the body frame (REP 103 axes, REP 105 names).

    ``world`` is the fixed frame the attitude is expressed in (``odom`` by default: a
    continuous, non-jumping frame, as REP 105 defines it), ``body`` the frame rigidly
    attached to the body at its centre of mass, or at the pivot for gravity scenes
    (``base_link``). Every output, ``/tf`` and the recorder use these names.
    """

    world: str = DEFAULT_WORLD_FRAME
    body: str = DEFAULT_BODY_FRAME

    def checked(self) -> "Frames":
        """These frames, or ValueError when a name is empty or unusable (:func:`names.check_frame_id`)
        or both are equal."""
        for role, name in (("world", self.world), ("body", self.body)):
            if not isinstance(name, str) or not name:
                raise ValueError(f"{role} frame name must be a non-empty string, got {name!r}")
            names.check_frame_id(name, f"{role} frame name")
        if self.world == self.body:
            raise ValueError(f"world and body frames must differ, both are {self.world!r}")
        return self

    @property
    def principal(self) -> str:
        """Name of the principal-axes frame (child of the body frame on /tf_static)."""
        return f"{self.body}_principal"


@dataclass(frozen=True)
class Body:
    """Mass properties of the body, in the body frame, about the point it turns about.

    ``inertia`` (kg*m^2) is a symmetric positive-definite 3x3 tensor, row-major tuples,
    about the centre of mass (free body) or about the pivot (gravity scenes).
    ``given_as`` is ``principal_moments``, ``inertia_tensor`` or ``point_masses``.
    ``mass`` (kg) and ``center_of_mass`` (m, body frame, from the body origin) are known
    for point masses and for gravity scenes, else None.
    """

    inertia: tuple[Vector3, Vector3, Vector3]
    given_as: str
    mass: float | None = None
    center_of_mass: Vector3 | None = None
    masses: tuple[float, ...] | None = None
    positions: tuple[Vector3, ...] | None = None

    @property
    def inertia_array(self) -> np.ndarray:
        """The inertia tensor as a (3, 3) array, kg*m^2."""
        return np.array(self.inertia, dtype=float)


@dataclass(frozen=True)
class InitialState:
    """Initial attitude (unit quaternion x, y, z, w; body -> world) and ω (rad/s, body frame)."""

    orientation: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    angular_velocity: Vector3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class TopicInput:
    """A torque command topic.

    ``frame`` is ``body`` or ``world`` (the vector is expressed there; a non-empty
    header.frame_id must then name that frame) or ``header`` (header.frame_id must name
    the body or the world frame). ``timeout`` is None for "hold until replaced", else the
    sim time (s) after which the command falls back to zero.
    """

    topic: str
    message_type: str = "WrenchStamped"
    frame: str = "body"
    timeout: float | None = None


@dataclass(frozen=True)
class ScheduleSegment:
    """A torque (N*m) that acts from ``start`` (s, sim time) until the next segment's start."""

    start: float
    torque: Vector3


@dataclass(frozen=True)
class TorqueSchedule:
    """Piecewise-constant torque written in the scene, expressed in ``frame`` (body or world)."""

    frame: str
    segments: tuple[ScheduleSegment, ...]

    def torque_at(self, t: float) -> Vector3:
        """The scheduled torque (N*m) at sim time t (s); zero before the first segment."""
        value: Vector3 = (0.0, 0.0, 0.0)
        for segment in self.segments:
            if segment.start <= t:
                value = segment.torque
        return value


@dataclass(frozen=True)
class Gravity:
    """Uniform gravity of ``acceleration`` (m/s^2) along -z of the world frame, body pivoted at its origin."""

    acceleration: float


@dataclass(frozen=True)
class IntegratorSpec:
    """Integrator name (or ``auto``), fixed physics step ``dt`` (s) and the method's options.

    ``options`` are (name, value) pairs passed as keyword arguments to the method (its
    tolerances, e.g. taylor's ``tol``); the method itself rejects unknown ones.
    """

    method: str = "auto"
    dt: float = 0.001
    options: tuple[tuple[str, Any], ...] = ()


@dataclass(frozen=True)
class Outputs:
    """Publication rates in Hz of sim time (0 = not published)."""

    state: float = DEFAULT_OUTPUT_RATES["state"]
    orientation: float = DEFAULT_OUTPUT_RATES["orientation"]
    angular_velocity: float = DEFAULT_OUTPUT_RATES["angular_velocity"]
    angular_momentum: float = DEFAULT_OUTPUT_RATES["angular_momentum"]
    top_state: float = DEFAULT_OUTPUT_RATES["top_state"]
    tf: float = DEFAULT_OUTPUT_RATES["tf"]
    clock: float = DEFAULT_OUTPUT_RATES["clock"]
    imu: float = DEFAULT_OUTPUT_RATES["imu"]
    odom: float = DEFAULT_OUTPUT_RATES["odom"]

    def as_dict(self) -> dict[str, float]:
        return {name: getattr(self, name) for name in OUTPUT_NAMES}


@dataclass(frozen=True)
class OutputQos:
    """QoS of the state-like outputs: ``reliability`` (reliable | best_effort), keep-last ``depth``.

    Defaults, reliable with depth 10: every subscriber matches (reliable or best effort), a
    reliable one gets every message unless it falls 10 behind, and memory stays bounded.
    A depth sized to a run (rate x duration) makes a reliable subscriber that keeps up
    within it receive every message of the run.
    """

    reliability: str = "reliable"
    depth: int = 10


@dataclass(frozen=True)
class CommandSettings:
    """Settings of the torque command inputs.

    ``max_torque`` (N*m): a command (topic or ``~/apply_torque``) whose torque norm exceeds it
    is rejected with the reason; 0 = no limit. ``qos_depth``: keep-last depth of the torque
    subscriptions (a burst larger than this between two executor turns loses its oldest
    commands before the node sees them).
    """

    max_torque: float = 0.0
    qos_depth: int = limits.DEFAULT_COMMAND_DEPTH


@dataclass(frozen=True)
class Scene:
    """A validated scene. ``source`` is the file it came from, ``text`` the YAML as given."""

    name: str
    body: Body
    frames: Frames = Frames()
    initial: InitialState = InitialState()
    topic_inputs: tuple[TopicInput, ...] = ()
    schedules: tuple[TorqueSchedule, ...] = ()
    gravity: Gravity | None = None
    integrator: IntegratorSpec = IntegratorSpec()
    duration: float | None = None
    real_time_factor: float = 1.0
    outputs: Outputs = Outputs()
    qos: OutputQos = OutputQos()
    recording: str | None = None
    commands: CommandSettings = CommandSettings()
    description: str = ""
    source: str = "<string>"
    text: str = ""

    @property
    def is_top(self) -> bool:
        """True for gravity (heavy top) scenes."""
        return self.gravity is not None

    @property
    def torque_kind(self) -> str:
        """What drives the body besides its inertia: none, gravity, topic or schedule."""
        if self.gravity is not None:
            return "gravity"
        if self.topic_inputs:
            return "topic"
        if self.schedules:
            return "schedule"
        return "none"


# ----------------------------------------------------------------------------- parsing


class _Ctx:
    """Error factory that prefixes the file name and the key path.

    ``error_class`` is SceneError here; other YAML specs built on scenes (sweep specs)
    reuse these helpers with their own error class, so every file error reads the same.
    """

    def __init__(self, source: str, error_class: type[ValueError] = SceneError) -> None:
        self.label = os.path.basename(source) if source else "<string>"
        self.error_class = error_class

    def error(self, key: str, what: str) -> ValueError:
        return self.error_class(f"{self.label}: {key}: {what}")

    def checked(self, check: Any, key: str, value: Any) -> Any:
        """Run a core.validation check named ``key``; its ValueError becomes a SceneError."""
        try:
            return check(key, value)
        except ValueError as exc:
            raise self.error_class(f"{self.label}: {exc}") from None


def _mapping(ctx: _Ctx, value: Any, key: str, allowed: tuple[str, ...]) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise ctx.error(key, f"must be a mapping, got {type(value).__name__}")
    for name in value:
        if name not in allowed:
            shown = limits.clip_text(str(name), 60)
            raise ctx.error(f"{key}.{shown}" if key else shown, f"unknown key (allowed: {', '.join(allowed)})")
    return value


def _show(value: Any) -> str:
    """A value as echoed in an error message: its repr, cut to a readable length."""
    return limits.clip_text(repr(value), 60)


def _number(
    ctx: _Ctx,
    value: Any,
    key: str,
    *,
    minimum: float | None = None,
    strict: bool = False,
    maximum: float = limits.MAX_MAGNITUDE,
) -> float:
    """A finite number; ``minimum`` (exclusive when ``strict``) and ``maximum`` on its value,
    which by default bounds its magnitude by MAX_MAGNITUDE."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ctx.error(key, f"must be a number, got {_show(value)}")
    try:
        number = float(value)
    except OverflowError:  # a YAML integer too large for a float
        raise ctx.error(key, f"must be a number of magnitude <= {maximum:g}, got an integer of {len(str(abs(value)))} digits") from None
    if not math.isfinite(number):
        raise ctx.error(key, f"must be finite, got {number}")
    if minimum is not None and (number < minimum or (strict and number == minimum)):
        raise ctx.error(key, f"must be {'>' if strict else '>='} {minimum:g}, got {number:g}")
    if number > maximum or (minimum is None and -number > maximum):
        raise ctx.error(key, f"must be {'<=' if minimum is not None else 'of magnitude <='} {maximum:g}, got {number:g}")
    return number


def _in_range(ctx: _Ctx, value: Any, key: str, bounds: tuple[float, float], *, strict: bool = False) -> float:
    """A number within a parameter's range (the node's descriptor range)."""
    return _number(ctx, value, key, minimum=bounds[0], strict=strict, maximum=bounds[1])


def _vector(ctx: _Ctx, value: Any, key: str, length: int) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)) or len(value) != length:
        raise ctx.error(key, f"must be a list of {length} numbers, got {_show(value)}")
    return tuple(_number(ctx, v, f"{key}[{i}]") for i, v in enumerate(value))


def _string(ctx: _Ctx, value: Any, key: str, max_length: int = limits.MAX_NAME_LENGTH) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ctx.error(key, f"must be a non-empty string, got {_show(value)}")
    if len(value) > max_length:
        raise ctx.error(key, f"longer than {max_length} characters (limit)")
    return value.strip()


def _frame(ctx: _Ctx, value: Any, key: str) -> str:
    name = _string(ctx, value, key)
    try:
        return names.check_frame_id(name, "frame name")
    except ValueError as exc:
        raise ctx.error(key, str(exc)) from None


def _parse_body(ctx: _Ctx, raw: Any, gravity_raw: Any) -> Body:
    forms = ("principal_moments", "inertia_tensor", "point_masses")
    body = _mapping(ctx, raw, "body", forms)
    given = [name for name in forms if name in body]
    if len(given) != 1:
        raise ctx.error("body", f"must give exactly one of {', '.join(forms)}, got {given or 'none'}")
    form = given[0]
    key = f"body.{form}"
    mass = com = masses = positions = None
    if form == "principal_moments":
        tensor = np.diag(ctx.checked(validation.principal_moments, key, _vector(ctx, body[form], key, 3)))
    elif form == "inertia_tensor":
        rows = body[form]
        if not isinstance(rows, (list, tuple)) or len(rows) != 3:
            raise ctx.error(key, f"must be a 3x3 list of lists, got {_show(rows)}")
        rows = [_vector(ctx, row, f"{key}[{i}]", 3) for i, row in enumerate(rows)]
        tensor = ctx.checked(validation.inertia_tensor, key, rows)
        ctx.checked(validation.principal_moments, f"{key} eigenvalues", np.linalg.eigvalsh(tensor))
    else:
        from rigid_rot_sim.core.inertia import mass_properties

        spec = _mapping(ctx, body[form], key, ("masses", "positions"))
        if "masses" not in spec or "positions" not in spec:
            raise ctx.error(key, "needs both masses and positions")
        raw_masses = spec["masses"]
        raw_positions = spec["positions"]
        if not isinstance(raw_masses, (list, tuple)) or not isinstance(raw_positions, (list, tuple)):
            raise ctx.error(key, "masses and positions must be lists")
        if max(len(raw_masses), len(raw_positions)) > limits.MAX_POINT_MASSES:
            raise ctx.error(key, f"more than {limits.MAX_POINT_MASSES} point masses (limit)")
        masses = tuple(_number(ctx, m, f"{key}.masses[{i}]") for i, m in enumerate(raw_masses))
        positions = tuple(_vector(ctx, p, f"{key}.positions[{i}]", 3) for i, p in enumerate(raw_positions))
        try:
            properties = mass_properties(masses, positions)
        except ValueError as exc:
            raise ctx.error(key, str(exc)) from None
        mass = float(properties.total_mass)
        com = tuple(float(c) for c in properties.center_of_mass)
        # about the pivot (body origin) under gravity, else about the centre of mass
        tensor = np.asarray(properties.inertia_origin if gravity_raw else properties.inertia_com, dtype=float)
        eigenvalues = np.linalg.eigvalsh(tensor)
        if eigenvalues[0] <= validation.TRIANGLE_RTOL * float(eigenvalues[-1]):
            raise ctx.error(
                key,
                f"the masses are collinear or a single point (principal moments {eigenvalues.tolist()}): "
                "a rotating rigid body needs three non-zero moments",
            )
    tensor_tuple = tuple(tuple(float(v) for v in row) for row in tensor)
    return Body(
        inertia=tensor_tuple,  # type: ignore[arg-type]
        given_as=form,
        mass=mass,
        center_of_mass=com,  # type: ignore[arg-type]
        masses=masses,
        positions=positions,  # type: ignore[arg-type]
    )


def _parse_initial(ctx: _Ctx, raw: Any) -> InitialState:
    if raw is None:
        return InitialState()
    initial = _mapping(ctx, raw, "initial", ("orientation", "euler_zxz", "angular_velocity"))
    if "orientation" in initial and "euler_zxz" in initial:
        raise ctx.error("initial", "give orientation or euler_zxz, not both")
    orientation = (0.0, 0.0, 0.0, 1.0)
    if "orientation" in initial:
        q = ctx.checked(validation.quaternion, "initial.orientation", _vector(ctx, initial["orientation"], "initial.orientation", 4))
        orientation = tuple(float(v) for v in q)
    elif "euler_zxz" in initial:
        angles = _vector(ctx, initial["euler_zxz"], "initial.euler_zxz", 3)
        orientation = tuple(float(v) for v in zxz_to_quaternion(*angles))
    omega = (0.0, 0.0, 0.0)
    if "angular_velocity" in initial:
        omega = _vector(ctx, initial["angular_velocity"], "initial.angular_velocity", 3)
    return InitialState(orientation=orientation, angular_velocity=omega)  # type: ignore[arg-type]


def _parse_torque_inputs(ctx: _Ctx, raw: Any) -> tuple[tuple[TopicInput, ...], tuple[TorqueSchedule, ...]]:
    if raw is None:
        return (), ()
    if not isinstance(raw, (list, tuple)):
        raise ctx.error("torque_inputs", f"must be a list, got {type(raw).__name__}")
    if len(raw) > limits.MAX_TORQUE_INPUTS:
        raise ctx.error("torque_inputs", f"more than {limits.MAX_TORQUE_INPUTS} inputs (limit)")
    topics: list[TopicInput] = []
    schedules: list[TorqueSchedule] = []
    for index, item in enumerate(raw):
        key = f"torque_inputs[{index}]"
        if isinstance(item, Mapping) and "schedule" in item:
            spec = _mapping(ctx, item, key, ("schedule",))
            schedules.append(_parse_schedule(ctx, spec["schedule"], f"{key}.schedule"))
            continue
        spec = _mapping(ctx, item, key, ("topic", "type", "frame", "hold"))
        if "topic" not in spec:
            raise ctx.error(key, "needs a topic (or a schedule)")
        topic = _string(ctx, spec["topic"], f"{key}.topic")
        try:
            names.check_topic_name(topic)
        except ValueError as exc:
            raise ctx.error(f"{key}.topic", str(exc)) from None
        message_type = spec.get("type", "WrenchStamped")
        if message_type not in TORQUE_MESSAGE_TYPES:
            raise ctx.error(f"{key}.type", f"must be one of {', '.join(TORQUE_MESSAGE_TYPES)}, got {_show(message_type)}")
        frame = spec.get("frame", "body")
        if frame not in TORQUE_FRAMES:
            raise ctx.error(f"{key}.frame", f"must be one of {', '.join(TORQUE_FRAMES)}, got {_show(frame)}")
        hold = spec.get("hold", "hold")
        timeout = None
        if isinstance(hold, Mapping):
            hold = _mapping(ctx, hold, f"{key}.hold", ("timeout",))
            if "timeout" not in hold:
                raise ctx.error(f"{key}.hold", "must be 'hold' or {timeout: seconds}")
            timeout = _in_range(ctx, hold["timeout"], f"{key}.hold.timeout", limits.DURATION_RANGE, strict=True)
        elif hold != "hold":
            raise ctx.error(f"{key}.hold", f"must be 'hold' or {{timeout: seconds}}, got {_show(hold)}")
        if any(t.topic == topic for t in topics):
            raise ctx.error(f"{key}.topic", f"topic {topic!r} is listed twice")
        topics.append(TopicInput(topic=topic, message_type=message_type, frame=frame, timeout=timeout))
    return tuple(topics), tuple(schedules)


def _parse_schedule(ctx: _Ctx, raw: Any, key: str) -> TorqueSchedule:
    spec = _mapping(ctx, raw, key, ("frame", "segments"))
    frame = spec.get("frame", "body")
    if frame not in ("body", "world"):
        raise ctx.error(f"{key}.frame", f"must be body or world, got {_show(frame)}")
    raw_segments = spec.get("segments")
    if not isinstance(raw_segments, (list, tuple)) or not raw_segments:
        raise ctx.error(f"{key}.segments", "must be a non-empty list of {start, torque}")
    segments = []
    previous = -math.inf
    for i, item in enumerate(raw_segments):
        item_key = f"{key}.segments[{i}]"
        segment = _mapping(ctx, item, item_key, ("start", "torque"))
        if "start" not in segment or "torque" not in segment:
            raise ctx.error(item_key, "needs start (s) and torque [x, y, z] (N*m)")
        start = _in_range(ctx, segment["start"], f"{item_key}.start", limits.DURATION_RANGE)
        if start <= previous:
            raise ctx.error(f"{item_key}.start", f"must be later than the previous segment's start {previous:g}, got {start:g}")
        previous = start
        segments.append(ScheduleSegment(start=start, torque=_vector(ctx, segment["torque"], f"{item_key}.torque", 3)))  # type: ignore[arg-type]
    return TorqueSchedule(frame=frame, segments=tuple(segments))


def _parse_gravity(ctx: _Ctx, raw: Any, body_raw: Any) -> tuple[Gravity | None, float | None, Vector3 | None]:
    if raw is None or raw == "none":
        return None, None, None
    point_masses = isinstance(body_raw, Mapping) and "point_masses" in body_raw
    allowed = ("acceleration",) if point_masses else ("acceleration", "mass", "center_of_mass")
    spec = _mapping(ctx, raw, "gravity", allowed)
    acceleration = _number(ctx, spec.get("acceleration", 9.80665), "gravity.acceleration", minimum=0.0, strict=True)
    if point_masses:
        return Gravity(acceleration=acceleration), None, None
    for name in ("mass", "center_of_mass"):
        if name not in spec:
            raise ctx.error("gravity", f"needs {name} (the body's {'kg' if name == 'mass' else 'm, body frame'})")
    mass = _number(ctx, spec["mass"], "gravity.mass", minimum=0.0, strict=True)
    com = _vector(ctx, spec["center_of_mass"], "gravity.center_of_mass", 3)
    if math.hypot(*com) == 0.0:
        raise ctx.error("gravity.center_of_mass", "must not be at the pivot (then gravity exerts no torque; drop gravity)")
    return Gravity(acceleration=acceleration), mass, com  # type: ignore[return-value]


def _parse_integrator(ctx: _Ctx, raw: Any) -> IntegratorSpec:
    if raw is None:
        return IntegratorSpec()
    spec = _mapping(ctx, raw, "integrator", ("method", "dt", "options"))
    method = _string(ctx, spec.get("method", "auto"), "integrator.method")
    if method != "auto":
        from rigid_rot_sim.core.integrators import get_method

        try:
            get_method(method)
        except ValueError as exc:
            raise ctx.error("integrator.method", str(exc)) from None
    dt = _in_range(ctx, spec.get("dt", 0.001), "integrator.dt", limits.DT_RANGE)
    options = spec.get("options") or {}
    if not isinstance(options, Mapping):
        raise ctx.error("integrator.options", f"must be a mapping of option names to values, got {_show(options)}")
    for name, value in options.items():
        if isinstance(value, (Mapping, list)):
            raise ctx.error(f"integrator.options.{name}", f"must be a number, string or null, got {_show(value)}")
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            _number(ctx, value, f"integrator.options.{name}")
        elif isinstance(value, str):
            _string(ctx, value, f"integrator.options.{name}")
    return IntegratorSpec(method=method, dt=dt, options=tuple(sorted((str(k), v) for k, v in options.items())))


def _parse_outputs(ctx: _Ctx, raw: Any) -> Outputs:
    if raw is None:
        return Outputs()
    spec = _mapping(ctx, raw, "outputs", OUTPUT_NAMES)
    rates = {name: _in_range(ctx, value, f"outputs.{name}", limits.RATE_RANGE) for name, value in spec.items()}
    return Outputs(**rates)


def _parse_qos(ctx: _Ctx, raw: Any) -> OutputQos:
    if raw is None:
        return OutputQos()
    spec = _mapping(ctx, raw, "qos", ("reliability", "depth"))
    reliability = spec.get("reliability", OutputQos.reliability)
    if reliability not in QOS_RELIABILITIES:
        raise ctx.error("qos.reliability", f"must be one of {', '.join(QOS_RELIABILITIES)}, got {reliability!r}")
    depth = spec.get("depth", OutputQos.depth)
    if isinstance(depth, bool) or not isinstance(depth, int) or not 1 <= depth <= MAX_QOS_DEPTH:
        raise ctx.error("qos.depth", f"must be an integer from 1 to {MAX_QOS_DEPTH}, got {depth!r}")
    return OutputQos(reliability=reliability, depth=depth)


def _parse_commands(ctx: _Ctx, raw: Any) -> CommandSettings:
    if raw is None:
        return CommandSettings()
    spec = _mapping(ctx, raw, "commands", ("max_torque", "qos_depth"))
    max_torque = _in_range(ctx, spec.get("max_torque", 0.0), "commands.max_torque", limits.MAX_TORQUE_RANGE)
    depth = spec.get("qos_depth", limits.DEFAULT_COMMAND_DEPTH)
    low, high = limits.COMMAND_DEPTH_RANGE
    if isinstance(depth, bool) or not isinstance(depth, int) or not low <= depth <= high:
        raise ctx.error("commands.qos_depth", f"must be an integer from {low} to {high}, got {_show(depth)}")
    return CommandSettings(max_torque=max_torque, qos_depth=depth)


def parse_scene(data: Any, source: str = "<string>", text: str = "") -> Scene:
    """Validate a scene given as parsed YAML (a mapping); ``source`` names it in errors."""
    # numpy overflows (a tensor near the magnitude limit) are checked as results, never warned
    with np.errstate(all="ignore"):
        return _parse_scene(data, source, text)


def _parse_scene(data: Any, source: str, text: str) -> Scene:
    ctx = _Ctx(source)
    top_keys = (
        "name",
        "description",
        "frames",
        "body",
        "initial",
        "torque_inputs",
        "gravity",
        "integrator",
        "duration",
        "real_time_factor",
        "outputs",
        "qos",
        "recording",
        "commands",
    )
    spec = _mapping(ctx, data, "", top_keys)
    if "body" not in spec:
        raise ctx.error("body", "missing (a scene needs the body's inertia)")
    default_name = os.path.splitext(os.path.basename(source))[0] if source != "<string>" else "scene"
    name = _string(ctx, spec.get("name", default_name), "name")
    description = spec.get("description", "") or ""
    if not isinstance(description, str):
        raise ctx.error("description", "must be a string")
    if len(description) > limits.MAX_TEXT_LENGTH:
        raise ctx.error("description", f"longer than {limits.MAX_TEXT_LENGTH} characters (limit)")

    frames_raw = _mapping(ctx, spec.get("frames") or {}, "frames", ("world", "body"))
    frames = Frames(
        world=_frame(ctx, frames_raw.get("world", DEFAULT_WORLD_FRAME), "frames.world"),
        body=_frame(ctx, frames_raw.get("body", DEFAULT_BODY_FRAME), "frames.body"),
    )
    try:
        frames.checked()
    except ValueError as exc:
        raise ctx.error("frames", str(exc)) from None

    gravity, mass, com = _parse_gravity(ctx, spec.get("gravity"), spec["body"])
    body = _parse_body(ctx, spec["body"], spec.get("gravity") not in (None, "none"))
    if gravity is not None:
        if body.given_as == "point_masses":
            if body.center_of_mass is None or math.hypot(*body.center_of_mass) == 0.0:
                raise ctx.error("body.point_masses", "centre of mass is at the pivot (body origin): gravity exerts no torque")
        else:
            body = Body(inertia=body.inertia, given_as=body.given_as, mass=mass, center_of_mass=com)
    initial = _parse_initial(ctx, spec.get("initial"))
    topics, schedules = _parse_torque_inputs(ctx, spec.get("torque_inputs"))
    if gravity is not None and (topics or schedules):
        # the integrators expand gravity or a piecewise-constant torque exactly, not their sum
        raise ctx.error("torque_inputs", "not supported in a gravity (heavy top) scene; drop gravity or the inputs")
    integrator = _parse_integrator(ctx, spec.get("integrator"))

    duration = spec.get("duration")
    if duration is not None:
        duration = _in_range(ctx, duration, "duration", limits.DURATION_RANGE, strict=True)
    rtf = _in_range(ctx, spec.get("real_time_factor", 1.0), "real_time_factor", limits.REAL_TIME_FACTOR_RANGE)
    outputs = _parse_outputs(ctx, spec.get("outputs"))
    qos = _parse_qos(ctx, spec.get("qos"))
    recording = spec.get("recording")
    if recording is not None:
        recording = _string(ctx, recording, "recording", limits.MAX_TEXT_LENGTH)
    commands = _parse_commands(ctx, spec.get("commands"))
    return Scene(
        name=name,
        description=description.strip(),
        frames=frames,
        body=body,
        initial=initial,
        topic_inputs=topics,
        schedules=schedules,
        gravity=gravity,
        integrator=integrator,
        duration=duration,
        real_time_factor=rtf,
        outputs=outputs,
        qos=qos,
        recording=recording,
        commands=commands,
        source=source,
        text=text,
    )


def parse_scene_text(text: str, source: str = "<string>") -> Scene:
    """Validate a scene given as YAML text (e.g. from a recording's metadata)."""
    try:
        data = load_bounded(text)
    except BoundedYAMLError as exc:
        raise SceneError(f"{os.path.basename(source)}: {exc}") from None
    return parse_scene(data, source=source, text=text)


def load_scene(path: str | os.PathLike[str]) -> Scene:
    """Read and validate the scene file at ``path``."""
    path = os.fspath(path)
    try:
        text = read_bounded(path)
    except OSError as exc:
        raise SceneError(f"{path}: cannot read scene file: {exc.strerror}") from None
    except BoundedYAMLError as exc:
        raise SceneError(f"{path}: {exc}") from None
    return parse_scene_text(text, source=path)
