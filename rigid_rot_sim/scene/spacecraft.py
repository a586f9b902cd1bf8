"""A scene's spacecraft parts, validated: reaction wheels, their torque schedule, the gravity gradient,
torque rods.

The schema is :mod:`rigid_rot_sim.scene.spacecraft_schema`; the equations are in
:mod:`rigid_rot_sim.core.wheels` and :mod:`rigid_rot_sim.core.magnetorquer`. A scene with wheels or
gravity gradient is run by the gyrostat integrators (:mod:`rigid_rot_sim.core.integrators.gyrostat`);
the rods need the Earth's field, and every path refuses them until one runs it
(:mod:`rigid_rot_sim.scene.features`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rigid_rot_sim.core.magnetorquer import Magnetorquers
from rigid_rot_sim.core.orbit import KeplerOrbit
from rigid_rot_sim.core.wheels import (
    DEFAULT_STICTION_SPEED,
    OrbitModel,
    WheelModel,
    kepler_orbit_model,
    orbit_model,
    wheel_model,
)

__all__ = [
    "ReactionWheel",
    "WheelSegment",
    "WheelTorqueSchedule",
    "GravityGradient",
    "TorqueRod",
    "ROD_COMMAND_TOPIC",
    "Spacecraft",
    "parse_spacecraft",
]

Vector3 = tuple[float, float, float]

#: The node's topic of the rods' commands (sensor_msgs/JointState), as ``lockstep.inputs`` may list it.
ROD_COMMAND_TOPIC = "~/magnetorquer_command"


@dataclass(frozen=True)
class ReactionWheel:
    """One wheel: ``axis`` (unit, body frame), spin ``inertia`` (kg*m^2), ``max_torque`` (N*m),
    ``max_speed`` and ``initial_speed`` (rad/s, relative to the body), friction ``coulomb`` (N*m),
    ``viscous`` (N*m*s/rad) and ``stiction_speed`` (rad/s)."""

    name: str
    axis: Vector3
    inertia: float
    max_torque: float
    max_speed: float
    initial_speed: float = 0.0
    coulomb: float = 0.0
    viscous: float = 0.0
    stiction_speed: float = DEFAULT_STICTION_SPEED


@dataclass(frozen=True)
class WheelSegment:
    """Motor torques (N*m, one per wheel, scene order) acting from ``start`` (s) until the next segment."""

    start: float
    torques: tuple[float, ...]


@dataclass(frozen=True)
class WheelTorqueSchedule:
    segments: tuple[WheelSegment, ...]


@dataclass(frozen=True)
class GravityGradient:
    """Gravity gradient of a planet of parameter ``mu`` (m^3/s^2) on a circular orbit (``radius`` m,
    ``inclination`` rad) in the world frame (:mod:`rigid_rot_sim.core.wheels` defines its geometry), or on the
    scene's orbit (``kepler``; ``radius`` its semi-major axis, ``inclination`` its inclination)."""

    mu: float
    radius: float
    inclination: float = 0.0
    kepler: KeplerOrbit | None = None

    def model(self) -> OrbitModel:
        if self.kepler is not None:
            return kepler_orbit_model(self.kepler)
        return orbit_model(self.mu, self.radius, self.inclination)


@dataclass(frozen=True)
class TorqueRod:
    """One magnetorquer: ``axis`` (unit, body frame), ``max_dipole`` (A*m^2), and its field at the
    magnetometer per unit dipole, ``magnetometer_coupling`` (T/(A*m^2), body frame)."""

    name: str
    axis: Vector3
    max_dipole: float
    magnetometer_coupling: Vector3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Spacecraft:
    """The spacecraft parts of a scene (all empty for a plain rigid body).

    ``rods`` and ``residual_dipole`` (A*m^2, body frame) are ``actuators.magnetorquers``.
    """

    wheels: tuple[ReactionWheel, ...] = ()
    wheel_schedule: WheelTorqueSchedule | None = None
    gravity_gradient: GravityGradient | None = None
    rods: tuple[TorqueRod, ...] = ()
    residual_dipole: Vector3 = (0.0, 0.0, 0.0)

    def __bool__(self) -> bool:
        return bool(self.wheels) or self.gravity_gradient is not None

    @property
    def wheel_names(self) -> tuple[str, ...]:
        return tuple(w.name for w in self.wheels)

    @property
    def rod_names(self) -> tuple[str, ...]:
        return tuple(r.name for r in self.rods)

    def magnetorquers(self) -> Magnetorquers | None:
        """The rods as a :class:`Magnetorquers` (G_t, limits, residual, coupling), None without rods."""
        if not self.rods:
            return None
        return Magnetorquers(
            axes=np.array([r.axis for r in self.rods]).T,
            max_dipoles=np.array([r.max_dipole for r in self.rods]),
            names=self.rod_names,
            residual=np.array(self.residual_dipole),
            coupling=np.array([r.magnetometer_coupling for r in self.rods]).T,
        )

    def wheel_model(self, inertia: Any) -> WheelModel | None:
        """The wheels as a :class:`WheelModel` in the user body frame (None without wheels)."""
        if not self.wheels:
            return None
        return wheel_model(
            inertia,
            self.wheel_names,
            [w.axis for w in self.wheels],
            [w.inertia for w in self.wheels],
            [w.max_torque for w in self.wheels],
            [w.max_speed for w in self.wheels],
            [w.coulomb for w in self.wheels],
            [w.viscous for w in self.wheels],
            [w.stiction_speed for w in self.wheels],
        )

    def summary(self) -> str:
        """What the scene's spacecraft has, for the node's start-up line ('' for none)."""
        parts = []
        if self.wheels:
            parts.append(f"{len(self.wheels)} reaction wheel(s) [{', '.join(self.wheel_names)}]")
        if self.wheel_schedule is not None:
            parts.append(f"a wheel-torque schedule of {len(self.wheel_schedule.segments)} segment(s)")
        if self.gravity_gradient is not None:
            parts.append(f"gravity gradient (orbit radius {self.gravity_gradient.radius:g} m)")
        if self.rods:
            parts.append(f"{len(self.rods)} torque rod(s) [{', '.join(self.rod_names)}]")
        return ", ".join(parts)


def parse_spacecraft(
    actuators: Mapping[str, Any] | None,
    environment: Mapping[str, Any] | None,
    inertia: Any,
    kepler: KeplerOrbit | None = None,
) -> Spacecraft:
    """The validated spacecraft parts of a scene whose data passed the schema; ValueError naming the key.

    ``kepler``: the scene's orbit (``orbit:``), which a gravity gradient without an orbit of its own follows.
    """
    actuators = actuators or {}
    environment = environment or {}
    wheels = []
    seen: set[str] = set()
    for i, spec in enumerate(actuators.get("reaction_wheels") or ()):
        key = f"actuators.reaction_wheels[{i}]"
        name = spec["name"].strip()
        if name in seen:
            raise ValueError(f"{key}.name: {name!r} is listed twice")
        seen.add(name)
        axis = np.array(spec["axis"], dtype=float)
        norm = float(np.linalg.norm(axis))
        if not (math.isfinite(norm) and norm > 0.0):
            raise ValueError(f"{key}.axis: must be a non-zero vector, got {spec['axis']}")
        friction = spec.get("friction") or {}
        wheel = ReactionWheel(
            name=name,
            axis=(float(axis[0] / norm), float(axis[1] / norm), float(axis[2] / norm)),
            inertia=float(spec["inertia"]),
            max_torque=float(spec["max_torque"]),
            max_speed=float(spec["max_speed"]),
            initial_speed=float(spec.get("initial_speed", 0.0)),
            coulomb=float(friction.get("coulomb", 0.0)),
            viscous=float(friction.get("viscous", 0.0)),
            stiction_speed=float(friction.get("stiction_speed", DEFAULT_STICTION_SPEED)),
        )
        if abs(wheel.initial_speed) > wheel.max_speed:
            raise ValueError(
                f"{key}.initial_speed: |{wheel.initial_speed:g}| rad/s exceeds max_speed {wheel.max_speed:g} rad/s"
            )
        wheels.append(wheel)
    schedule = None
    schedule_spec = actuators.get("wheel_torque_schedule")
    if schedule_spec:
        if not wheels:
            raise ValueError("actuators.wheel_torque_schedule: the scene has no reaction_wheels")
        segments: list[WheelSegment] = []
        for i, segment in enumerate(schedule_spec["segments"]):
            key = f"actuators.wheel_torque_schedule.segments[{i}]"
            torques = tuple(float(v) for v in segment["torques"])
            if len(torques) != len(wheels):
                raise ValueError(f"{key}.torques: {len(torques)} values for {len(wheels)} wheel(s)")
            start = float(segment["start"])
            if segments and start <= segments[-1].start:
                raise ValueError(
                    f"{key}.start: {start:g} s must be later than the previous segment's {segments[-1].start:g} s"
                )
            segments.append(WheelSegment(start, torques))
        schedule = WheelTorqueSchedule(tuple(segments))
    gravity_gradient = None
    gg = environment.get("gravity_gradient")
    if gg is not None and "orbit" in gg:
        if kepler is not None:
            raise ValueError(
                "environment.gravity_gradient.orbit: the scene has an orbit: section; give no orbit here "
                "(the gradient follows the scene's orbit)"
            )
        gravity_gradient = GravityGradient(
            float(gg.get("mu", 3.986004418e14)),
            float(gg["orbit"]["radius"]),
            float(gg["orbit"].get("inclination", 0.0)),
        )
    elif gg is not None:
        if kepler is None:
            raise ValueError(
                "environment.gravity_gradient: needs an orbit: a circular orbit {radius, inclination} here, "
                "or the scene's orbit: section"
            )
        if "mu" in gg:
            raise ValueError("environment.gravity_gradient.mu: the scene's orbit is the Earth's (mu is its own)")
        gravity_gradient = GravityGradient(kepler.mu, kepler.a, kepler.i, kepler)
    rods, residual = _parse_rods(actuators.get("magnetorquers"))
    spacecraft = Spacecraft(tuple(wheels), schedule, gravity_gradient, rods, residual)
    try:
        spacecraft.wheel_model(inertia)
    except ValueError as exc:
        raise ValueError(f"actuators.reaction_wheels: {exc}") from None
    return spacecraft


def _parse_rods(spec: Mapping[str, Any] | None) -> tuple[tuple[TorqueRod, ...], Vector3]:
    """``actuators.magnetorquers`` (passed the schema): the rods and the residual dipole; ValueError naming the key."""
    if not spec:
        return (), (0.0, 0.0, 0.0)
    rods: list[TorqueRod] = []
    for i, rod in enumerate(spec["rods"]):
        key = f"actuators.magnetorquers.rods[{i}]"
        name = rod["name"].strip()
        if name in (r.name for r in rods):
            raise ValueError(f"{key}.name: {name!r} is listed twice")
        axis = np.array(rod["axis"], dtype=float)
        norm = float(np.linalg.norm(axis))
        if not (math.isfinite(norm) and norm > 0.0):
            raise ValueError(f"{key}.axis: must be a non-zero vector, got {rod['axis']}")
        ux, uy, uz = (axis / norm).tolist()
        cx, cy, cz = (float(v) for v in rod.get("magnetometer_coupling") or (0.0, 0.0, 0.0))
        rods.append(TorqueRod(name, (ux, uy, uz), float(rod["max_dipole"]), (cx, cy, cz)))
    rx, ry, rz = (float(v) for v in spec.get("residual_dipole") or (0.0, 0.0, 0.0))
    return tuple(rods), (rx, ry, rz)
