"""The scene sections of a spacecraft: ``actuators`` (reaction wheels, a wheel-torque schedule, torque rods) and
``environment`` (gravity gradient), as JSON Schema pieces of :data:`~rigid_rot_sim.scene.scene_schema.SCENE_SCHEMA`.

The physics and its conventions (Basilisk's balanced wheels) are in :mod:`rigid_rot_sim.core.wheels`;
the torque rods' (Basilisk's ``MtbEffector``) in :mod:`rigid_rot_sim.core.magnetorquer`.
"""

from __future__ import annotations

from typing import Any

from rigid_rot_sim.core import limits
from rigid_rot_sim.scene.orbit import MAGNETIC_FIELD
from rigid_rot_sim.scene.schema import array, mapping, nullable, number, text, vector

__all__ = ["ACTUATORS", "ENVIRONMENT", "MAX_WHEELS", "MAX_RODS", "EARTH_MU"]

#: Most reaction wheels a scene may have.
MAX_WHEELS = 16
#: Most torque rods a scene may have.
MAX_RODS = 16
#: Earth's gravitational parameter, m^3/s^2 (WGS 84).
EARTH_MU = 3.986004418e14

_DURATION_MAX = limits.DURATION_RANGE[1]

_WHEEL = mapping(
    "A balanced reaction wheel (Basilisk's conventions: the body inertia includes the wheel).",
    {
        "name": text("The wheel's name (JointState name; unique)."),
        "axis": vector("Spin axis [x, y, z], body frame; normalised on load.", 3),
        "inertia": number("Spin inertia J about the axis, kg*m^2.", exclusive_minimum=0.0),
        "max_torque": number(
            "Largest motor torque, N*m: a larger command is clamped (and said on ~/sim_events).", exclusive_minimum=0.0
        ),
        "max_speed": number(
            "Largest wheel speed, rad/s: the motor never drives the wheel past it.", exclusive_minimum=0.0
        ),
        "initial_speed": number("Initial speed relative to the body, rad/s.", default=0.0),
        "friction": nullable(
            mapping(
                "Bearing friction, opposing the wheel's speed relative to the body.",
                {
                    "coulomb": number("Coulomb friction torque, N*m.", minimum=0.0, default=0.0),
                    "viscous": number("Viscous friction coefficient, N*m*s/rad.", minimum=0.0, default=0.0),
                    "stiction_speed": number(
                        "Below this speed (rad/s) the Coulomb torque is linear in the speed.",
                        exclusive_minimum=0.0,
                        default=1e-4,
                    ),
                },
            )
        ),
    },
    required=["name", "axis", "inertia", "max_torque", "max_speed"],
)

_WHEEL_SEGMENT = mapping(
    "Motor torques that act from their start until the next segment's start.",
    {
        "start": number(
            "Start, s of sim time (later than the previous segment's).", minimum=0.0, maximum=_DURATION_MAX
        ),
        "torques": array(
            "Motor torque of each wheel, N*m, in the order of reaction_wheels.",
            number("N*m."),
            min_items=1,
            max_items=MAX_WHEELS,
        ),
    },
    required=["start", "torques"],
)

_ROD = mapping(
    "A torque rod (magnetorquer): its dipole lies along its axis (a column of Basilisk's G_t).",
    {
        "name": text("The rod's name (the JointState name of its command; unique)."),
        "axis": vector("Dipole axis [x, y, z], body frame; normalised on load.", 3),
        "max_dipole": number(
            "Largest dipole, A*m^2: a larger command is clamped (and said on ~/sim_events).", exclusive_minimum=0.0
        ),
        "magnetometer_coupling": vector(
            "The rod's own field at the magnetometer per unit dipole, T/(A*m^2), body frame (a column of the "
            "3 x n coupling matrix; zero: no pollution).",
            3,
        ),
    },
    required=["name", "axis", "max_dipole"],
)

_MAGNETORQUERS = nullable(
    mapping(
        "Torque rods: tau = (G_t clamp(m) + residual) x b (rigid_rot_sim.core.magnetorquer).",
        {
            "rods": array("The rods, in the order of the dipole commands.", _ROD, min_items=1, max_items=MAX_RODS),
            "residual_dipole": vector("The spacecraft's residual dipole, A*m^2, body frame.", 3),
        },
        required=["rods"],
    )
)

ACTUATORS: dict[str, Any] = nullable(
    mapping(
        "Actuators of a spacecraft: reaction wheels and their motor-torque schedule, torque rods.",
        {
            "reaction_wheels": array(
                "The wheels, in the order of the wheel commands.", _WHEEL, min_items=1, max_items=MAX_WHEELS
            ),
            "wheel_torque_schedule": nullable(
                mapping(
                    "Piecewise-constant motor torques written in the file (runs without ROS).",
                    {"segments": array("The segments, each {start, torques}.", _WHEEL_SEGMENT, min_items=1)},
                    required=["segments"],
                )
            ),
            "magnetorquers": _MAGNETORQUERS,
        },
    )
)

ENVIRONMENT: dict[str, Any] = nullable(
    mapping(
        "The spacecraft's environment.",
        {
            "gravity_gradient": nullable(
                mapping(
                    "Gravity-gradient torque: on the scene's orbit: section (give no orbit here), or on a circular "
                    "orbit in the world frame (node line along world x, at the ascending node at t = 0).",
                    {
                        "mu": number(
                            "Gravitational parameter of the planet, m^3/s^2.",
                            exclusive_minimum=0.0,
                            maximum=1e22,
                            default=EARTH_MU,
                        ),
                        "orbit": mapping(
                            "The circular orbit (not with the scene's orbit: section).",
                            {
                                "radius": number("Orbit radius, m.", exclusive_minimum=0.0),
                                "inclination": number(
                                    "Inclination, rad, in [0, pi].", minimum=0.0, maximum=3.141592653589793, default=0.0
                                ),
                            },
                            required=["radius"],
                        ),
                    },
                )
            ),
            "magnetic_field": MAGNETIC_FIELD,
        },
    )
)
