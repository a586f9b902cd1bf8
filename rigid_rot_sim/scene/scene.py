"""Scene files: the YAML description of one simulation run, validated into frozen dataclasses.

A scene says what a run needs, and the simulator and the node build only that. Its format
is one JSON Schema, :data:`rigid_rot_sim.scene.scene_schema.SCENE_SCHEMA` (exported as
``config/schema/scene.schema.json``, with a description of every key); a short scene::

    name: free_tumble                  # optional, defaults to the file stem
    body: {principal_moments: [0.8, 1.2, 1.5]}   # kg*m^2; or inertia_tensor, or point_masses
    initial: {angular_velocity: [0.05, 0.0, 4.0]} # rad/s, body frame
    integrator: {method: auto, dt: 0.001}
    duration: 20.0                     # s of sim time, or null for unbounded

:func:`load_scene` validates the file against the schema (keys, types, required keys,
choices, bounds: :mod:`rigid_rot_sim.core.limits`, the ranges of the node's parameters),
then checks what a schema cannot express, one small function each: a physical inertia
(positive definite, triangle inequality), the integrator's name in the registry, topic
and frame names ROS accepts (:mod:`names`), the rules across sections (gravity needs a
mass and centre of mass unless point masses give them; no torque inputs with gravity), and
what rates and durations imply: every output or sensor rate has a period of a finite whole
number of steps (:func:`~rigid_rot_sim.core.limits.check_rate`), a duration and a hold timeout
are at least one step, an orbit's mean motion is a rate within the limits.
Every error is a :class:`SceneError` (a ValueError) naming the file, the key and what is
wrong, in one line, e.g. ``free_tumble.yaml: body.principal_moments[2] must be > 0 kg*m^2, got -1.0``.
The file itself is read within limits, without YAML aliases (:mod:`bounded_yaml`).

With ``gravity`` the body frame's origin is the pivot, and the inertia (principal
moments or tensor) is about the pivot; point masses give the inertia about the origin
of their coordinates (the pivot) and their centre of mass. Without gravity the body
turns about its centre of mass: principal moments or a tensor are about it, and point
masses give their inertia about their centre of mass.
"""

from __future__ import annotations

import datetime
import math
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rigid_rot_sim.core import limits, validation
from rigid_rot_sim.core.geomagnetic import OrbitField, orbit_field
from rigid_rot_sim.core.inertia import inertia_about_center_of_mass, mass_properties
from rigid_rot_sim.core.integrators import get_method
from rigid_rot_sim.core.integrators.gyrostat import get_gyrostat_method
from rigid_rot_sim.core.orbit import KeplerOrbit
from rigid_rot_sim.core.quaternion import zxz_to_quaternion
from rigid_rot_sim.core.sensors import GyroModel, MagnetometerModel, StarTrackerModel
from rigid_rot_sim.core.steps import step_at_or_after, whole_steps
from rigid_rot_sim.scene import names
from rigid_rot_sim.scene.bounded_yaml import load_input, read_input
from rigid_rot_sim.scene.orbit import (
    MagneticField,
    epoch_datetime,
    parse_magnetic_field,
    parse_magnetometer,
    parse_orbit,
)
from rigid_rot_sim.scene.scene_schema import (
    DEFAULT_BODY_FRAME,
    DEFAULT_EPOCH,
    DEFAULT_GRAVITY,
    DEFAULT_WORLD_FRAME,
    OUTPUTS,
    QOS_RELIABILITIES,
    SCENE_SCHEMA,
    TORQUE_FRAMES,
    TORQUE_MESSAGE_TYPES,
)
from rigid_rot_sim.scene.schema import validated
from rigid_rot_sim.scene.spacecraft import ROD_COMMAND_TOPIC, GravityGradient, Spacecraft, parse_spacecraft

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
    "OutputRates",
    "OutputQos",
    "CommandSettings",
    "LockstepSpec",
    "Sensors",
    "Scene",
    "load_scene",
    "parse_scene",
    "parse_scene_text",
    "TORQUE_MESSAGE_TYPES",
    "TORQUE_FRAMES",
    "QOS_RELIABILITIES",
    "MAX_QOS_DEPTH",
    "OUTPUT_NAMES",
    "DEFAULT_OUTPUT_RATES",
]

#: The outputs' names, in publishing order, and their default rates (Hz): from the one table, OUTPUTS.
OUTPUT_NAMES = tuple(OUTPUTS)
DEFAULT_OUTPUT_RATES = {name: output.rate for name, output in OUTPUTS.items()}
#: Largest keep-last depth of an output (a bound on the memory a slow subscriber can pin).
MAX_QOS_DEPTH = limits.QOS_DEPTH_RANGE[1]

Vector3 = tuple[float, float, float]


class SceneError(ValueError):
    """A scene file is invalid; the message names the file, the key and what is wrong."""


@dataclass(frozen=True)
class JointStateTopics:
    """The JointState door of the reaction wheels (ros2_control's topic hardware interface; docs/ros2_control.md).

    ``commands``: sensor_msgs/JointState in, the motor torque (``effort``, N*m) per named wheel;
    ``states``: sensor_msgs/JointState out, position (rad), velocity (rad/s) and effort (N*m) per wheel.
    Topic names as ROS resolves them (absolute, relative to the node's namespace, or ``~/...``).
    """

    commands: str
    states: str


#: ``simulation_interfaces_namespace``: the node's private names (``~/step_simulation``), the default.
PRIVATE_NAMESPACE = "~"


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

    def checked(self) -> Frames:
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
    """Piecewise-constant torque written in the scene, expressed in ``frame`` (body or world).

    On a grid of fixed steps ``dt`` (s) from t = 0, a segment takes effect on the first
    step boundary at or after its start (:func:`rigid_rot_sim.core.steps.step_at_or_after`,
    the run engine's rule) and acts until the next segment takes over; of segments landing
    on the same boundary the last one acts.
    """

    frame: str
    segments: tuple[ScheduleSegment, ...]

    def change_steps(self, dt: float) -> tuple[int, ...]:
        """The step boundary where each segment takes effect at step ``dt`` (s), in segment order."""
        return tuple(step_at_or_after(segment.start, dt) for segment in self.segments)

    def torque_at_step(self, k: int, dt: float) -> Vector3:
        """The scheduled torque (N*m) acting over step k (from boundary k to k + 1) at step ``dt`` (s).

        Zero before the first segment takes effect.
        """
        value: Vector3 = (0.0, 0.0, 0.0)
        for segment, step in zip(self.segments, self.change_steps(dt), strict=True):
            if step <= k:
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


class OutputRates(Mapping[str, float]):
    """Publication rates in Hz of sim time (0 = not published), one per output, in publishing order.

    A frozen mapping over :data:`OUTPUT_NAMES` (the outputs of
    :data:`~rigid_rot_sim.scene.scene_schema.OUTPUTS`); an output not given keeps its default
    rate there. ``OutputRates(imu=5.0)["imu"] == 5.0``; an unknown name is a ``KeyError``.
    """

    __slots__ = ("_rates",)
    _rates: dict[str, float]

    def __init__(self, rates: Mapping[str, float] | None = None, **by_name: float) -> None:
        given = {**(rates or {}), **by_name}
        unknown = sorted(set(given) - set(OUTPUT_NAMES))
        if unknown:
            raise KeyError(f"unknown output(s) {', '.join(unknown)}; known: {', '.join(OUTPUT_NAMES)}")
        rates_by_name = {name: float(given.get(name, DEFAULT_OUTPUT_RATES[name])) for name in OUTPUT_NAMES}
        object.__setattr__(self, "_rates", rates_by_name)

    def __getitem__(self, name: str) -> float:
        return self._rates[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._rates)

    def __len__(self) -> int:
        return len(self._rates)

    def __hash__(self) -> int:
        return hash(tuple(self._rates.items()))

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"{type(self).__name__} is frozen")

    def __reduce__(self) -> tuple[type[OutputRates], tuple[dict[str, float]]]:
        return (type(self), (self._rates,))  # pickled by value (scenes travel to sweep workers)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._rates!r})"


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
class LockstepSpec:
    """Lockstep with controllers (:mod:`rigid_rot_sim.run.lockstep` has the contract).

    ``period``: s of sim time between turns (a whole number of steps); ``inputs``: the topic
    inputs waited for at every turn; ``timeout``: s of wall time to wait for a turn's
    commands; ``on_timeout``: ``pause`` or ``hold``.
    """

    period: float
    inputs: tuple[str, ...]
    timeout: float = 5.0
    on_timeout: str = "pause"


@dataclass(frozen=True)
class Sensors:
    """The scene's sensor models (:mod:`rigid_rot_sim.core.sensors`) and the seed of their noise.

    ``seed`` None: the run draws one at start and records it. ``gyro``: ~/imu carries its
    readings (at ``gyro.rate``); ``star_tracker``: ~/star_tracker at its rate.
    """

    seed: int | None = None
    gyro: GyroModel | None = None
    star_tracker: StarTrackerModel | None = None
    #: ~/magnetometer at its rate (a scene with environment.magnetic_field).
    magnetometer: MagnetometerModel | None = None


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
    outputs: OutputRates = OutputRates()
    qos: OutputQos = OutputQos()
    recording: str | None = None
    foxglove: str | None = None  # [HOST:]PORT of a Foxglove live server (a node setting; see ros/foxglove_live)
    web: str | None = None  # [HOST:]PORT of the body's web page (a node setting; see ros/web_live)
    commands: CommandSettings = CommandSettings()
    lockstep: LockstepSpec | None = None
    spacecraft: Spacecraft = Spacecraft()
    sensors: Sensors = Sensors()
    #: The wheels' JointState door (None: not built).
    joint_state_topics: JointStateTopics | None = None
    #: Where the simulation_interfaces services and the SimulateSteps action are served: ``~`` or a namespace.
    simulation_interfaces_namespace: str = PRIVATE_NAMESPACE
    description: str = ""
    #: UTC date and time of sim time 0 (ISO 8601; see :data:`scene_schema.DEFAULT_EPOCH`).
    epoch: str = DEFAULT_EPOCH
    #: The orbit of the centre of mass (``orbit:``; :mod:`.orbit`): the world frame is then ECI.
    orbit: KeplerOrbit | None = None
    #: ``environment.magnetic_field`` along :attr:`orbit` from :attr:`epoch`.
    magnetic_field: MagneticField | None = None
    source: str = "<string>"
    text: str = ""

    @property
    def is_top(self) -> bool:
        """True for gravity (heavy top) scenes."""
        return self.gravity is not None

    @property
    def torque_kind(self) -> str:
        """What drives the body besides its inertia: none, gravity, spacecraft (wheels or gravity gradient,
        besides any torque inputs), topic or schedule."""
        if self.gravity is not None:
            return "gravity"
        if self.spacecraft:
            return "spacecraft"
        if self.topic_inputs:
            return "topic"
        if self.schedules:
            return "schedule"
        return "none"

    def orbit_field(self) -> OrbitField | None:
        """The field along the orbit (:class:`rigid_rot_sim.core.geomagnetic.OrbitField`), None without one."""
        if self.magnetic_field is None or self.orbit is None:
            return None
        return orbit_field(self.magnetic_field.model, self.orbit, epoch_datetime(self.epoch), None)

    def mass_properties_about_com(self) -> tuple[float, Vector3, np.ndarray]:
        """Mass (kg; 0 when the scene gives none), centre of mass (m, body frame) and the
        inertia tensor (kg*m^2, body axes) about the centre of mass.

        A gravity scene's tensor is about the pivot; the others' about the centre of mass.
        """
        mass = self.body.mass or 0.0
        com = self.body.center_of_mass or (0.0, 0.0, 0.0)
        tensor = self.body.inertia_array
        if self.gravity is not None:
            tensor = inertia_about_center_of_mass(tensor, mass, com)
        return mass, com, tensor


# ----------------------------------------------------------------------------- loading


def load_scene(path: str | os.PathLike[str]) -> Scene:
    """Read and validate the scene file at ``path``."""
    path = os.fspath(path)
    return parse_scene_text(read_input(path, "scene file", SceneError), source=path)


def parse_scene_text(text: str, source: str = "<string>") -> Scene:
    """Validate a scene given as YAML text (e.g. from a recording's metadata)."""
    return parse_scene(load_input(text, source, SceneError), source=source, text=text)


def parse_scene(data: Any, source: str = "<string>", text: str = "") -> Scene:
    """Validate a scene given as parsed YAML (a mapping); ``source`` names it in errors."""
    # numpy overflows (a tensor near the magnitude limit) are checked as results, never warned
    with np.errstate(all="ignore"):
        return validated(data, SCENE_SCHEMA, source, SceneError, lambda spec: _scene(spec, source, text))


def parse_body(spec: Mapping[str, Any], source: str) -> Body:
    """A body section alone (``principal_moments``, ``inertia_tensor`` or ``point_masses``), checked as a
    scene's body is (inertia about the centre of mass); ValueError naming ``source``."""
    if not any(key in spec for key in ("principal_moments", "inertia_tensor", "point_masses")):
        raise ValueError(f"{source}: no inertia_tensor, principal_moments or point_masses")
    try:
        with np.errstate(all="ignore"):
            return _body(spec, under_gravity=False)
    except (ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"{source}: {exc}") from None


# ------------------------------------------- what the schema cannot say (the data passed it)


def _at(key: str, check: Callable[..., Any], *args: Any) -> Any:
    """``check(*args)``, its ValueError prefixed by the key it is about."""
    try:
        return check(*args)
    except ValueError as exc:
        raise ValueError(f"{key}: {exc}") from None


def _floats(values: Any) -> tuple[float, ...]:
    return tuple(float(v) for v in values)


def _scene(spec: Mapping[str, Any], source: str, text: str) -> Scene:
    default_name = os.path.splitext(os.path.basename(source))[0] if source != "<string>" else "scene"
    frames = _frames(spec.get("frames") or {})
    under_gravity = spec.get("gravity") not in (None, "none")
    point_masses = "point_masses" in spec["body"]
    gravity, mass, com = _gravity(spec["gravity"], point_masses) if under_gravity else (None, None, None)
    body = _body(spec["body"], under_gravity)
    if gravity is not None:
        if point_masses:
            if body.center_of_mass is None or math.hypot(*body.center_of_mass) == 0.0:
                raise ValueError(
                    "body.point_masses: centre of mass is at the pivot (body origin): gravity exerts no torque"
                )
        else:
            body = Body(inertia=body.inertia, given_as=body.given_as, mass=mass, center_of_mass=com)
    topics, schedules = _torque_inputs(spec.get("torque_inputs") or [])
    if gravity is not None and (topics or schedules):
        # the integrators expand gravity or a piecewise-constant torque exactly, not their sum
        raise ValueError("torque_inputs: not supported in a gravity (heavy top) scene; drop gravity or the inputs")
    kepler = parse_orbit(spec.get("orbit"))
    spacecraft = parse_spacecraft(spec.get("actuators"), spec.get("environment"), body.inertia_array, kepler)
    epoch = _at("epoch", _epoch, spec.get("epoch") or DEFAULT_EPOCH)
    magnetic_field = parse_magnetic_field(
        (spec.get("environment") or {}).get("magnetic_field"), kepler, epoch, spec.get("duration")
    )
    if gravity is not None and spacecraft:
        raise ValueError("actuators / environment: not supported in a gravity (heavy top) scene; drop gravity")
    duration = spec.get("duration")
    dt = float((spec.get("integrator") or {}).get("dt", IntegratorSpec.dt))
    if duration is not None:
        _at("duration", _whole_steps, float(duration), dt, "the run would end before it began; null runs unbounded")
    for index, topic in enumerate(topics):
        if topic.timeout is not None:  # counted from the boundary where a command takes effect
            _at(
                f"torque_inputs[{index}].hold.timeout",
                _whole_steps,
                topic.timeout,
                dt,
                "a command would act for no step",
            )
    if spacecraft.gravity_gradient is not None:
        _at("environment.gravity_gradient.orbit", _orbit_rate, spacecraft.gravity_gradient)
    qos = spec.get("qos") or {}
    commands = spec.get("commands") or {}
    recording = spec.get("recording")
    foxglove = spec.get("foxglove")
    web = spec.get("web")
    sensors = _sensors(spec.get("sensors") or {}, magnetic_field)
    outputs = spec.get("outputs") or {}
    joint_state_topics = spec.get("joint_state_topics")
    if spacecraft.rods and magnetic_field is None:
        raise ValueError(
            "actuators.magnetorquers: the rods act on the Earth's field: the scene needs environment.magnetic_field "
            "(on its orbit)"
        )
    if joint_state_topics is not None and not spacecraft.wheels:
        raise ValueError("joint_state_topics: the scene has no reaction wheels (actuators.reaction_wheels)")
    namespace = spec.get("simulation_interfaces_namespace")
    return Scene(
        name=spec.get("name", default_name).strip(),
        description=(spec.get("description") or "").strip(),
        epoch=epoch,
        orbit=kepler,
        magnetic_field=magnetic_field,
        frames=frames,
        body=body,
        initial=_initial(spec.get("initial") or {}),
        topic_inputs=topics,
        schedules=schedules,
        gravity=gravity,
        integrator=_integrator(spec.get("integrator") or {}, bool(spacecraft)),
        spacecraft=spacecraft,
        duration=None if duration is None else float(duration),
        real_time_factor=_at(
            "real_time_factor", limits.check_real_time_factor, float(spec.get("real_time_factor", 1.0))
        ),
        outputs=OutputRates(_sensor_rates(sensors, _output_rates(outputs))),
        sensors=sensors,
        qos=OutputQos(
            reliability=qos.get("reliability", OutputQos.reliability), depth=qos.get("depth", OutputQos.depth)
        ),
        recording=None if recording is None else recording.strip(),
        foxglove=None if foxglove is None else str(foxglove).strip(),
        web=None if web is None else str(web).strip(),
        commands=CommandSettings(
            max_torque=float(commands.get("max_torque", 0.0)),
            qos_depth=commands.get("qos_depth", limits.DEFAULT_COMMAND_DEPTH),
        ),
        lockstep=lockstep_spec(
            spec.get("lockstep"),
            topics,
            dt,
            (() if joint_state_topics is None else (joint_state_topics["commands"].strip(),))
            + ((ROD_COMMAND_TOPIC,) if spacecraft.rods else ()),
        ),
        joint_state_topics=None
        if joint_state_topics is None
        else JointStateTopics(joint_state_topics["commands"].strip(), joint_state_topics["states"].strip()),
        simulation_interfaces_namespace=PRIVATE_NAMESPACE if namespace is None else namespace.strip(),
        source=source,
        text=text,
    )


def lockstep_spec(
    spec: Mapping[str, Any] | None, topics: tuple[TopicInput, ...], dt: float, wheel_inputs: tuple[str, ...] = ()
) -> LockstepSpec | None:
    """The lockstep section: its inputs are topic inputs of the scene (or the actuators' command topics,
    ``wheel_inputs``: the wheels' JointState commands, the rods' ``~/magnetorquer_command``), its period whole
    steps of dt."""
    if spec is None:
        return None
    known = [t.topic for t in topics] + list(wheel_inputs)
    inputs = []
    for index, name in enumerate(spec["inputs"]):
        name = name.strip()
        if name not in known:
            raise ValueError(f"lockstep.inputs[{index}]: {name!r} is not a topic of torque_inputs ({known or 'none'})")
        if name in inputs:
            raise ValueError(f"lockstep.inputs[{index}]: {name!r} is listed twice")
        inputs.append(name)
    period = float(spec["period"])
    if whole_steps(period, dt) is None:
        raise ValueError(f"lockstep.period: {period:g} s is not a whole number of steps of integrator.dt {dt:g} s")
    return LockstepSpec(
        period=period,
        inputs=tuple(inputs),
        timeout=float(spec.get("timeout", LockstepSpec.timeout)),
        on_timeout=spec.get("on_timeout", LockstepSpec.on_timeout),
    )


def _epoch(text: str) -> str:
    """A real UTC date and time (the schema's pattern also passes 2026-02-30T25:00:00)."""
    try:
        datetime.datetime.fromisoformat(text.rstrip("Z")[:26])
    except ValueError:
        raise ValueError(f"not a valid date and time: {text!r}") from None
    return text


def _frames(spec: Mapping[str, Any]) -> Frames:
    """Frame names ROS accepts (no whitespace or control characters), world and body different."""
    given = {
        role: spec.get(role, default).strip()
        for role, default in (("world", DEFAULT_WORLD_FRAME), ("body", DEFAULT_BODY_FRAME))
    }
    for role, name in given.items():
        _at(f"frames.{role}", names.check_frame_id, name, "frame name")
    frames: Frames = _at("frames", Frames(**given).checked)
    return frames


def _body(spec: Mapping[str, Any], under_gravity: bool) -> Body:
    """A physical inertia: positive definite, triangle inequality (from point masses: not collinear)."""
    if "principal_moments" in spec:
        moments = validation.principal_moments("body.principal_moments", _floats(spec["principal_moments"]))
        return Body(inertia=_rows(np.diag(moments)), given_as="principal_moments")
    if "inertia_tensor" in spec:
        key = "body.inertia_tensor"
        tensor = validation.inertia_tensor(key, [_floats(row) for row in spec["inertia_tensor"]])
        validation.principal_moments(f"{key} eigenvalues", np.linalg.eigvalsh(tensor))
        return Body(inertia=_rows(tensor), given_as="inertia_tensor")
    key = "body.point_masses"
    masses = _floats(spec["point_masses"]["masses"])
    positions = tuple(_floats(p) for p in spec["point_masses"]["positions"])
    properties = _at(key, mass_properties, masses, positions)
    # about the pivot (body origin) under gravity, else about the centre of mass
    tensor = np.asarray(properties.inertia_origin if under_gravity else properties.inertia_com, dtype=float)
    eigenvalues = np.linalg.eigvalsh(tensor)
    if eigenvalues[0] <= validation.TRIANGLE_RTOL * float(eigenvalues[-1]):
        raise ValueError(
            f"{key}: the masses are collinear or a single point (principal moments {eigenvalues.tolist()}): "
            "a rotating rigid body needs three non-zero moments"
        )
    return Body(
        inertia=_rows(tensor),
        given_as="point_masses",
        mass=float(properties.total_mass),
        center_of_mass=_floats(properties.center_of_mass),  # type: ignore[arg-type]
        masses=masses,
        positions=positions,  # type: ignore[arg-type]
    )


def _rows(tensor: np.ndarray) -> tuple[Vector3, Vector3, Vector3]:
    return tuple(_floats(row) for row in tensor)  # type: ignore[return-value]


def _gravity(spec: Mapping[str, Any], point_masses: bool) -> tuple[Gravity, float | None, Vector3 | None]:
    """Gravity, and the mass and centre of mass (m, body frame) it acts on unless point masses give them."""
    gravity = Gravity(acceleration=float(spec.get("acceleration", DEFAULT_GRAVITY)))
    if point_masses:
        for name in ("mass", "center_of_mass"):
            if name in spec:
                raise ValueError(
                    f"gravity.{name}: unknown key (allowed: acceleration; the point masses give the {name})"
                )
        return gravity, None, None
    for name, what in (("mass", "kg"), ("center_of_mass", "m, body frame")):
        if name not in spec:
            raise ValueError(f"gravity: needs {name} (the body's, {what})")
    com = _floats(spec["center_of_mass"])
    if math.hypot(*com) == 0.0:
        raise ValueError(
            "gravity.center_of_mass: must not be at the pivot (then gravity exerts no torque; drop gravity)"
        )
    return gravity, float(spec["mass"]), com  # type: ignore[return-value]


def _initial(spec: Mapping[str, Any]) -> InitialState:
    """A non-zero quaternion, normalised (or the attitude from Euler angles)."""
    orientation: tuple[float, ...] = InitialState.orientation
    if "orientation" in spec:
        orientation = _floats(validation.quaternion("initial.orientation", _floats(spec["orientation"])))
    elif "euler_zxz" in spec:
        orientation = _floats(zxz_to_quaternion(*_floats(spec["euler_zxz"])))
    omega = _floats(spec.get("angular_velocity", InitialState.angular_velocity))
    return InitialState(orientation=orientation, angular_velocity=omega)  # type: ignore[arg-type]


def _torque_inputs(items: Sequence[Mapping[str, Any]]) -> tuple[tuple[TopicInput, ...], tuple[TorqueSchedule, ...]]:
    """Topic names ROS accepts, each listed once; schedule segments in order of their start."""
    topics: list[TopicInput] = []
    schedules: list[TorqueSchedule] = []
    for index, item in enumerate(items):
        key = f"torque_inputs[{index}]"
        if "schedule" in item:
            schedules.append(_schedule(item["schedule"], f"{key}.schedule"))
            continue
        topic = _at(f"{key}.topic", names.check_topic_name, item["topic"].strip())
        if any(t.topic == topic for t in topics):
            raise ValueError(f"{key}.topic: topic {topic!r} is listed twice")
        hold = item.get("hold", "hold")
        topics.append(
            TopicInput(
                topic=topic,
                message_type=item.get("type", TopicInput.message_type),
                frame=item.get("frame", TopicInput.frame),
                timeout=float(hold["timeout"]) if isinstance(hold, Mapping) else None,
            )
        )
    return tuple(topics), tuple(schedules)


def _schedule(spec: Mapping[str, Any], key: str) -> TorqueSchedule:
    segments: list[ScheduleSegment] = []
    for i, segment in enumerate(spec["segments"]):
        start = float(segment["start"])
        if segments and start <= segments[-1].start:
            raise ValueError(
                f"{key}.segments[{i}].start: must be later than the previous segment's start "
                f"{segments[-1].start:g}, got {start:g}"
            )
        segments.append(ScheduleSegment(start=start, torque=_floats(segment["torque"])))  # type: ignore[arg-type]
    return TorqueSchedule(frame=spec.get("frame", "body"), segments=tuple(segments))


def _integrator(spec: Mapping[str, Any], spacecraft: bool = False) -> IntegratorSpec:
    """A method name from the integrator registry (the gyrostat methods' for wheels or gravity gradient), or auto."""
    method = spec.get("method", IntegratorSpec.method).strip()
    if method != "auto":
        _at("integrator.method", get_gyrostat_method if spacecraft else get_method, method)
    options = spec.get("options") or {}
    return IntegratorSpec(
        method=method,
        dt=float(spec.get("dt", IntegratorSpec.dt)),
        options=tuple(sorted((str(name), value) for name, value in options.items())),
    )


def _gyro_fields(gyro: Mapping[str, Any]) -> dict[str, Any]:
    """The gyro section's keys as GyroModel's fields (lists become tuples of floats)."""
    return {name: _floats(value) if isinstance(value, list) else float(value) for name, value in gyro.items()}


def _sensors(spec: Mapping[str, Any], field: MagneticField | None) -> Sensors:
    gyro = spec.get("gyro")
    star_tracker = spec.get("star_tracker")
    return Sensors(
        magnetometer=parse_magnetometer(spec.get("magnetometer"), field),
        seed=spec.get("seed"),
        gyro=None if gyro is None else GyroModel(**_gyro_fields(gyro)),
        star_tracker=None
        if star_tracker is None
        else StarTrackerModel(
            rate=float(star_tracker.get("rate", StarTrackerModel.rate)),
            noise_equivalent_angle=_floats(star_tracker["noise_equivalent_angle"]),  # type: ignore[arg-type]
        ),
    )


def _whole_steps(seconds: float, dt: float, else_: str) -> int:
    """The steps a span (s) implies at ``dt`` (s), ``step_at_or_after`` (the run's rule): at least one,
    else ValueError saying what would happen (``else_``)."""
    steps = step_at_or_after(seconds, dt)
    if steps < 1:
        raise ValueError(f"{seconds!r} s is not one step of integrator.dt {dt:g} s ({else_})")
    return steps


def _orbit_rate(gravity_gradient: GravityGradient) -> float:
    """The orbit's frequency (Hz, n / 2 pi) within the rate limits: its square scales the torque."""
    try:
        n = gravity_gradient.model().mean_motion
    except (ZeroDivisionError, OverflowError):  # radius**3 underflowed to 0
        n = math.inf
    if not (math.isfinite(n) and n / (2.0 * math.pi) <= limits.RATE_RANGE[1]):
        raise ValueError(
            f"radius {gravity_gradient.radius!r} m and mu {gravity_gradient.mu!r} m^3/s^2 imply a mean motion of "
            f"{n:g} rad/s, more than {limits.RATE_RANGE[1]:g} orbits per second"
        )
    return n / (2.0 * math.pi)


def _output_rates(outputs: Mapping[str, Any]) -> dict[str, float]:
    """Each rate 0 or within the limits (:func:`limits.check_rate`: a period of whole steps)."""
    return {name: _at(f"outputs.{name}", limits.check_rate, float(rate)) for name, rate in outputs.items()}


def _sensor_rates(sensors: Sensors, rates: dict[str, float]) -> dict[str, float]:
    """The output rates with ~/imu at the gyro's rate and ~/star_tracker at the star tracker's."""
    for output, sensor, key in (
        ("imu", sensors.gyro, "sensors.gyro.rate"),
        ("star_tracker", sensors.star_tracker, "sensors.star_tracker.rate"),
        ("magnetometer", sensors.magnetometer, "sensors.magnetometer.rate"),
    ):
        if sensor is None:
            if output in ("star_tracker", "magnetometer") and rates.get(output, 0.0) > 0.0:
                raise ValueError(f"outputs.{output}: needs a sensors.{output} section (its noise)")
            continue
        _at(key, limits.check_rate, sensor.rate)
        if output in rates and rates[output] != sensor.rate:
            raise ValueError(
                f"outputs.{output}: {rates[output]:g} Hz differs from {key} {sensor.rate:g} Hz "
                f"(give the rate once, in {key})"
            )
        rates[output] = sensor.rate
    return rates
