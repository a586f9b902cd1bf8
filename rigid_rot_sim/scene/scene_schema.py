"""The scene file format: its one JSON Schema, and the names and defaults it is built from.

:data:`SCENE_SCHEMA` says which keys a scene file may hold, their types, required keys,
choices, bounds and defaults, with a description of each for editors. It is exported as
``config/schema/scene.schema.json`` (docs/scenes.md shows how editors use it)::

    python -m rigid_rot_sim.scene.scene_schema > config/schema/scene.schema.json

and :mod:`rigid_rot_sim.scene.scene` validates every scene against it before the checks a
schema cannot express. Bounds come from :mod:`rigid_rot_sim.core.limits`, the numbers the
node's parameter descriptors use, so a scene holds exactly what a ``-p`` override may hold.
"""

from __future__ import annotations

from typing import Any, NamedTuple

from rigid_rot_sim.core import limits
from rigid_rot_sim.scene.orbit import MAGNETOMETER, ORBIT
from rigid_rot_sim.scene.schema import (
    DIALECT,
    array,
    choice,
    dump,
    integer,
    magnitude,
    mapping,
    nullable,
    number,
    text,
    vector,
)
from rigid_rot_sim.scene.spacecraft_schema import ACTUATORS, ENVIRONMENT

__all__ = [
    "SCENE_SCHEMA",
    "OUTPUTS",
    "OutputSpec",
    "TORQUE_MESSAGE_TYPES",
    "TORQUE_FRAMES",
    "SCHEDULE_FRAMES",
    "QOS_RELIABILITIES",
    "INERTIA_FORMS",
    "DEFAULT_WORLD_FRAME",
    "DEFAULT_BODY_FRAME",
    "DEFAULT_GRAVITY",
    "LOCKSTEP_ON_TIMEOUT",
    "DEFAULT_EPOCH",
    "EPOCH_PATTERN",
]

TORQUE_MESSAGE_TYPES = ("WrenchStamped", "Vector3Stamped")
TORQUE_FRAMES = ("body", "world", "header")
SCHEDULE_FRAMES = ("body", "world")
QOS_RELIABILITIES = ("reliable", "best_effort")
INERTIA_FORMS = ("principal_moments", "inertia_tensor", "point_masses")
#: Default frame names, REP 105: the fixed frame the attitude is given in, and the body.
DEFAULT_WORLD_FRAME = "odom"
DEFAULT_BODY_FRAME = "base_link"
#: Standard gravity, m/s^2.
DEFAULT_GRAVITY = 9.80665
#: UTC date and time of sim time 0 when a scene names none (used by exports such as CCSDS AEM):
#: noon of 1 January 2000, UTC.
DEFAULT_EPOCH = "2000-01-01T12:00:00Z"
#: ISO 8601 UTC date and time, whole seconds or up to nanoseconds, 'Z' or no zone.
EPOCH_PATTERN = r"^[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}(\.[0-9]{1,9})?Z?$"


class OutputSpec(NamedTuple):
    """An output of the node: its default rate (Hz of sim time, 0 = not built) and what it is."""

    rate: float
    description: str


#: The outputs, in publishing order: the one list of their names and default rates.
OUTPUTS: dict[str, OutputSpec] = {
    "state": OutputSpec(100.0, "rigid_rot_msgs/RigidBodyState on ~/state"),
    "orientation": OutputSpec(100.0, "geometry_msgs/QuaternionStamped on ~/orientation (body -> world)"),
    "angular_velocity": OutputSpec(100.0, "geometry_msgs/Vector3Stamped on ~/angular_velocity (rad/s, body frame)"),
    "angular_momentum": OutputSpec(100.0, "geometry_msgs/Vector3Stamped on ~/angular_momentum (N*m*s, world frame)"),
    "top_state": OutputSpec(100.0, "rigid_rot_msgs/HeavyTopState on ~/top_state (gravity scenes only)"),
    "tf": OutputSpec(50.0, "world -> body transform on /tf (where tf2_msgs is installed)"),
    "clock": OutputSpec(100.0, "sim time on /clock"),
    # sensor_msgs/Imu and nav_msgs/Odometry: built only when the scene asks
    "imu": OutputSpec(
        0.0,
        "sensor_msgs/Imu on ~/imu: ideal, or the gyro's readings (set by sensors.gyro.rate); 0: not built, the default",
    ),
    "odom": OutputSpec(0.0, "nav_msgs/Odometry on ~/odom (0: not built, the default)"),
    "markers": OutputSpec(
        0.0,
        "visualization_msgs/MarkerArray on ~/markers: the inertia box (body frame), omega "
        "(body) and L (world) arrows (0: not built, the default)",
    ),
    "star_tracker": OutputSpec(
        0.0,
        "geometry_msgs/PoseWithCovarianceStamped on ~/star_tracker (set by sensors.star_tracker.rate; 0: not built)",
    ),
    "wheels": OutputSpec(100.0, "sensor_msgs/JointState on ~/wheels (scenes with reaction wheels only)"),
    "magnetometer": OutputSpec(
        0.0,
        "sensor_msgs/MagneticField on ~/magnetometer: the magnetometer's readings (set by sensors.magnetometer.rate)",
    ),
    "magnetic_field": OutputSpec(
        10.0, "sensor_msgs/MagneticField on ~/magnetic_field: the true field, T, body frame (scenes with a field only)"
    ),
    "orbit": OutputSpec(
        10.0, "nav_msgs/Odometry on ~/orbit: the centre of mass on its orbit, ECI (scenes with an orbit only)"
    ),
    "torque_breakdown": OutputSpec(
        100.0,
        "rigid_rot_msgs/TorqueBreakdown on ~/torque_breakdown "
        "(N*m, body frame; every torque by source: scenes where a torque acts)",
    ),
}

_DURATION_MAX = limits.DURATION_RANGE[1]


def _rate(description: str, default: float) -> dict[str, Any]:
    return number(
        f"{description}; Hz of sim time, 0 = not published.",
        minimum=limits.RATE_RANGE[0],
        maximum=limits.RATE_RANGE[1],
        default=default,
    )


_POINT_MASSES = mapping(
    "Point masses; the inertia is computed from them (about their centre of mass, or about the body origin "
    "(the pivot) in a gravity scene).",
    {
        "masses": array("Masses, kg (> 0).", magnitude("kg"), max_items=limits.MAX_POINT_MASSES),
        "positions": array(
            "Positions [x, y, z], m, body frame; one per mass.", vector("m", 3), max_items=limits.MAX_POINT_MASSES
        ),
    },
    required=["masses", "positions"],
)

_BODY = mapping(
    "The body's mass properties: principal_moments, inertia_tensor or point_masses.",
    {
        "principal_moments": vector(
            "Principal moments [I1, I2, I3], kg*m^2, along the body axes: > 0, and each "
            "at most the sum of the other two.",
            3,
        ),
        "inertia_tensor": vector(
            "Inertia tensor, kg*m^2, body axes: 3 rows of 3, symmetric positive definite.", 3, item=vector("row", 3)
        ),
        "point_masses": _POINT_MASSES,
    },
    oneOf=[{"required": [form]} for form in INERTIA_FORMS],
)

_INITIAL = nullable(
    mapping(
        "Initial state; defaults to the identity attitude and rest.",
        {
            "orientation": vector("Attitude quaternion [x, y, z, w], body -> world; normalised on load.", 4),
            "euler_zxz": vector(
                "Attitude as intrinsic z-x'-z'' Euler angles [phi, theta, psi], rad (instead of orientation).", 3
            ),
            "angular_velocity": vector("Angular velocity [wx, wy, wz], rad/s, body frame.", 3),
        },
        **{"not": {"type": "object", "required": ["orientation", "euler_zxz"]}},
    )
)

_TOPIC_INPUT = mapping(
    "A torque command topic.",
    {
        "topic": text("The ROS topic name, e.g. ~/torque or /cmd; or give a schedule instead."),
        "type": choice("Message type of the commands.", TORQUE_MESSAGE_TYPES, default=TORQUE_MESSAGE_TYPES[0]),
        "frame": choice(
            "Frame the torque is expressed in: body, world, or header (header.frame_id names "
            "the body or the world frame).",
            TORQUE_FRAMES,
            default=TORQUE_FRAMES[0],
        ),
        "hold": {
            "description": "hold: a command holds until replaced; {timeout: s}: falls back to zero that long "
            "(sim time) after the last command.",
            "default": "hold",
            "errorMessage": "must be 'hold' or {timeout: seconds}",
            "anyOf": [
                {"const": "hold"},
                mapping(
                    "Fall back to zero torque after a timeout.",
                    {"timeout": number("Seconds of sim time.", exclusive_minimum=0.0, maximum=_DURATION_MAX)},
                    required=["timeout"],
                ),
            ],
        },
    },
    required=["topic"],
)

_SEGMENT = mapping(
    "A torque that acts from its start until the next segment's start.",
    {
        "start": number(
            "Start, s of sim time (later than the previous segment's).", minimum=0.0, maximum=_DURATION_MAX
        ),
        "torque": vector("Torque [x, y, z], N*m.", 3),
    },
    required=["start", "torque"],
)

_SCHEDULE_INPUT = mapping(
    "A piecewise-constant torque written in the file.",
    {
        "schedule": mapping(
            "Torque segments, in order of their start.",
            {
                "frame": {
                    **choice("Frame the torque is expressed in.", SCHEDULE_FRAMES, default="body"),
                    "errorMessage": "must be body or world (a schedule has no header)",
                },
                "segments": array("The segments, each {start, torque}.", _SEGMENT, min_items=1),
            },
            required=["segments"],
        ),
    },
    required=["schedule"],
)

_TORQUE_INPUTS = {
    "description": "Torque inputs: topics the node subscribes to, or schedules written in the file.",
    "type": ["array", "null"],
    "maxItems": limits.MAX_TORQUE_INPUTS,
    "items": {
        "description": "A topic input {topic, type, frame, hold} or a schedule {schedule: {frame, segments}}.",
        "type": "object",
        "if": {"required": ["schedule"]},
        "then": _SCHEDULE_INPUT,
        "else": _TOPIC_INPUT,
    },
}

_GRAVITY = {
    "description": "Uniform gravity (a heavy top pivoted at the body frame's origin); omit, null or none for none.",
    "anyOf": [
        {"type": "null"},
        {"const": "none"},
        mapping(
            "Gravity along -z of the world frame.",
            {
                "acceleration": number("Acceleration, m/s^2.", exclusive_minimum=0.0, default=DEFAULT_GRAVITY),
                "mass": number(
                    "Mass of the body, kg (not with point_masses: their total is used).", exclusive_minimum=0.0
                ),
                "center_of_mass": vector("Centre of mass, m, body frame, from the pivot (not with point_masses).", 3),
            },
        ),
    ],
}

_INTEGRATOR = nullable(
    mapping(
        "The integrator.",
        {
            "method": text("A method of the integrator registry (rk4, taylor, exact, ...), or auto.", default="auto"),
            "dt": number(
                "The fixed physics step, s.", minimum=limits.DT_RANGE[0], maximum=limits.DT_RANGE[1], default=0.001
            ),
            "options": {
                "description": "Keyword options of the method (e.g. taylor's tol).",
                "type": ["object", "null"],
                "additionalProperties": {
                    "description": "An option's value.",
                    "anyOf": [magnitude("A number."), text("A string."), {"type": "boolean"}, {"type": "null"}],
                },
            },
        },
    )
)

LOCKSTEP_ON_TIMEOUT = ("pause", "hold")

_LOCKSTEP = nullable(
    mapping(
        "Lockstep with controllers: at every turn (t_k = k * period) the node publishes the state, then waits "
        "until each listed input has delivered one command stamped t_k; those act from t_k. Absent or null: "
        "free-running (commands act when they arrive).",
        {
            "period": number(
                "Sim time between two controller turns, s; a whole number of physics steps.",
                exclusive_minimum=0.0,
                maximum=_DURATION_MAX,
            ),
            "inputs": array(
                "The torque topic inputs (their topic, as in torque_inputs) the node waits for at every turn.",
                text("A topic of torque_inputs, e.g. ~/torque."),
                min_items=1,
                max_items=limits.MAX_TORQUE_INPUTS,
            ),
            "timeout": number(
                "Wall time to wait for a turn's commands, s.", exclusive_minimum=0.0, maximum=_DURATION_MAX, default=5.0
            ),
            "on_timeout": choice(
                "What a turn that timed out does: pause (the reason on ~/sim_events and the log) "
                "or hold (keep each input's last command and go on).",
                LOCKSTEP_ON_TIMEOUT,
                default="pause",
            ),
        },
        required=["period", "inputs"],
    )
)

#: Largest sensor noise seed + 1 (Philox's 64-bit key word).
SEED_LIMIT = 1 << 64

_GYRO = mapping(
    "A three-axis rate gyro along the body axes; ~/imu publishes its readings (docs/sensors.md).",
    {
        "rate": number(
            "Samples per second, Hz of sim time (the ~/imu rate).",
            exclusive_minimum=0.0,
            maximum=limits.RATE_RANGE[1],
            default=100.0,
        ),
        "angle_random_walk": number(
            "Angle random walk N, rad/sqrt(s) (white rate noise of density N).", minimum=0.0, default=0.0
        ),
        "bias_instability": number(
            "Bias instability B, rad/s: the Allan deviation floor is 0.664 B (a Gauss-Markov bias).",
            minimum=0.0,
            default=0.0,
        ),
        "bias_correlation_time": number(
            "Correlation time T_c of the Gauss-Markov bias, s (the Allan floor lies at 1.89 T_c).",
            exclusive_minimum=0.0,
            default=100.0,
        ),
        "turn_on_bias": vector("Constant bias [x, y, z], rad/s, body axes.", 3),
        "turn_on_bias_sigma": number(
            "1-sigma of a constant bias per axis drawn once from the seed, rad/s.", minimum=0.0, default=0.0
        ),
        "scale_factor": vector("Scale factor error [x, y, z], fraction (100 ppm = 1e-4).", 3),
        "saturation": number("Largest |reading| per axis, rad/s; 0 = none.", minimum=0.0, default=0.0),
        "quantization": number("Resolution, rad/s per LSB; 0 = none.", minimum=0.0, default=0.0),
    },
)

_STAR_TRACKER = mapping(
    "A star tracker along the body axes: ~/star_tracker (geometry_msgs/PoseWithCovarianceStamped).",
    {
        "rate": number(
            "Attitude solutions per second, Hz of sim time.",
            exclusive_minimum=0.0,
            maximum=limits.RATE_RANGE[1],
            default=10.0,
        ),
        "noise_equivalent_angle": vector(
            "Noise equivalent angle [x, y, z], rad (1 sigma) about each body axis.", 3, item=number("rad", minimum=0.0)
        ),
    },
    required=["noise_equivalent_angle"],
)

_SENSORS = nullable(
    mapping(
        "Sensor models with seeded noise; ground-truth topics stay exact (docs/sensors.md).",
        {
            "seed": integer(
                "Seed of every sensor noise; omitted: drawn at start and recorded.", minimum=0, maximum=SEED_LIMIT - 1
            ),
            "gyro": nullable(_GYRO),
            "star_tracker": nullable(_STAR_TRACKER),
            "magnetometer": MAGNETOMETER,
        },
    )
)

SCENE_SCHEMA: dict[str, Any] = {
    "$schema": DIALECT,
    "title": "rigid_rot_sim scene",
    **mapping(
        "One simulation run of rigid_rot_sim: the body, its start, what drives it and what is published. "
        "SI units, REP 103 frames, quaternions [x, y, z, w] body -> world.",
        {
            "name": text("Name of the scene; defaults to the file name without .yaml."),
            "description": nullable(
                {"description": "What the scene shows.", "type": "string", "maxLength": limits.MAX_TEXT_LENGTH}
            ),
            "frames": nullable(
                mapping(
                    "Frame names (REP 105 defaults).",
                    {
                        "world": text("The fixed frame the attitude is given in.", default=DEFAULT_WORLD_FRAME),
                        "body": text(
                            "The frame attached to the body (at its centre of mass, or at the pivot).",
                            default=DEFAULT_BODY_FRAME,
                        ),
                    },
                )
            ),
            "body": _BODY,
            "initial": _INITIAL,
            "torque_inputs": _TORQUE_INPUTS,
            "gravity": _GRAVITY,
            "actuators": ACTUATORS,
            "environment": ENVIRONMENT,
            "orbit": ORBIT,
            "integrator": _INTEGRATOR,
            "duration": nullable(
                number("Sim time to run, s; null runs unbounded.", exclusive_minimum=0.0, maximum=_DURATION_MAX)
            ),
            "epoch": nullable(
                {
                    "description": "UTC date and time of sim time 0, ISO 8601 (YYYY-MM-DDThh:mm:ss[.f...][Z]); "
                    f"used by exports (CCSDS AEM), the Earth's rotation and the field's date. Default {DEFAULT_EPOCH}.",
                    "type": "string",
                    "pattern": EPOCH_PATTERN,
                    "default": DEFAULT_EPOCH,
                }
            ),
            "real_time_factor": number(
                "Pace: 1 = wall clock, 0 = as fast as possible.",
                minimum=limits.REAL_TIME_FACTOR_RANGE[0],
                maximum=limits.REAL_TIME_FACTOR_RANGE[1],
                default=1.0,
            ),
            "outputs": nullable(
                mapping(
                    "Publication rates, Hz of sim time (0 = not published).",
                    {name: _rate(output.description, output.rate) for name, output in OUTPUTS.items()},
                )
            ),
            "qos": nullable(
                mapping(
                    "QoS of the state-like outputs (~/state ... ~/top_state).",
                    {
                        "reliability": choice("reliable or best_effort.", QOS_RELIABILITIES, default="reliable"),
                        "depth": integer(
                            "Keep-last history depth.",
                            minimum=limits.QOS_DEPTH_RANGE[0],
                            maximum=limits.QOS_DEPTH_RANGE[1],
                            default=10,
                        ),
                    },
                )
            ),
            "recording": nullable(text("Path of an .mcap file to record the run to.", limits.MAX_TEXT_LENGTH)),
            "foxglove": nullable(
                {
                    "description": "Serve the run live to Foxglove at [HOST:]PORT (WebSocket; host default 127.0.0.1, "
                    "loopback); needs foxglove-sdk (pip install rigid_rot_sim[viewer]).",
                    "type": ["string", "integer"],
                    "pattern": r"^(\S+:)?[0-9]{1,5}$",
                    "minimum": 0,
                    "maximum": 65535,
                }
            ),
            "web": nullable(
                {
                    "description": "Serve the body's web page at [HOST:]PORT (http; host default 127.0.0.1, "
                    "loopback): any browser, offline; needs viser (pip install rigid_rot_sim[web]).",
                    "type": ["string", "integer"],
                    "pattern": r"^(\S+:)?[0-9]{1,5}$",
                    "minimum": 0,
                    "maximum": 65535,
                }
            ),
            "sensors": _SENSORS,
            "joint_state_topics": nullable(
                mapping(
                    "The reaction wheels' JointState door for ros2_control's topic hardware interface "
                    "(docs/ros2_control.md); needs actuators.reaction_wheels.",
                    {
                        "commands": text(
                            "Topic of the sensor_msgs/JointState commands: effort (N*m) per named wheel, held "
                            "until the next command for that wheel."
                        ),
                        "states": text(
                            "Topic of the sensor_msgs/JointState states: position (rad, unwrapped), velocity "
                            "(rad/s), effort (N*m) per wheel, at outputs.wheels."
                        ),
                    },
                    required=["commands", "states"],
                )
            ),
            "simulation_interfaces_namespace": nullable(
                text(
                    "Where the simulation_interfaces services and the SimulateSteps action are served: '~' (the "
                    "node's private names, the default; quote it, a bare ~ is YAML's null), '/' (root names, "
                    "as generic clients look for them) or any namespace.",
                    default="~",
                )
            ),
            "commands": nullable(
                mapping(
                    "Settings of the torque command inputs.",
                    {
                        "max_torque": number(
                            "A command whose |torque| exceeds this (N*m) is rejected; 0 = no limit.",
                            minimum=limits.MAX_TORQUE_RANGE[0],
                            maximum=limits.MAX_TORQUE_RANGE[1],
                            default=0.0,
                        ),
                        "qos_depth": integer(
                            "Keep-last depth of the torque subscriptions.",
                            minimum=limits.COMMAND_DEPTH_RANGE[0],
                            maximum=limits.COMMAND_DEPTH_RANGE[1],
                            default=limits.DEFAULT_COMMAND_DEPTH,
                        ),
                    },
                )
            ),
            "lockstep": _LOCKSTEP,
        },
        required=["body"],
    ),
}


if __name__ == "__main__":
    print(dump(SCENE_SCHEMA), end="")
