"""A scene's orbit (``orbit:``), the Earth's field (``environment.magnetic_field``) and the magnetometer
(``sensors.magnetometer``): their schemas and their parsing into the core's models.

``orbit:`` places the body's centre of mass on an orbit of the Earth (:mod:`rigid_rot_sim.core.orbit`): by
classical ``elements`` (semi-major axis m, eccentricity, angles in degrees) or by ``state`` (ECI position m
and velocity m/s at sim time 0), Keplerian or with J2's secular drift (``j2: true``). The scene's world frame
is then the orbit's inertial frame (ECI): the attitude, ``initial`` and the world-frame torques are in it.
The field (:mod:`rigid_rot_sim.core.geomagnetic`) follows that orbit from the scene's ``epoch`` (UTC).
"""

from __future__ import annotations

import datetime
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rigid_rot_sim.core import geomagnetic, limits
from rigid_rot_sim.core import orbit as core_orbit
from rigid_rot_sim.core.orbit import KeplerOrbit
from rigid_rot_sim.core.sensors import MAGNETOMETER_FAULTS, MagnetometerFault, MagnetometerModel
from rigid_rot_sim.scene.schema import array, choice, integer, mapping, nullable, number, vector

__all__ = [
    "ORBIT",
    "MAGNETIC_FIELD",
    "MAGNETOMETER",
    "MagneticField",
    "parse_orbit",
    "parse_magnetic_field",
    "parse_magnetometer",
    "epoch_datetime",
]


def _angle(description: str) -> dict[str, Any]:
    return number(description, minimum=-360.0, maximum=360.0, default=0.0)


ORBIT: dict[str, Any] = nullable(
    mapping(
        "The orbit of the body's centre of mass about the Earth; the world frame becomes the orbit's inertial "
        "frame (ECI). Give elements or state (docs/orbit_and_field.md).",
        {
            "elements": mapping(
                "Classical elements at sim time 0 (Basilisk's elem2rv conventions).",
                {
                    "semi_major_axis": number("Semi-major axis, m.", exclusive_minimum=0.0, maximum=1e10),
                    "eccentricity": {
                        **number("Eccentricity, in [0, 1).", minimum=0.0, maximum=1.0),
                        "exclusiveMaximum": 1.0,
                    },
                    "inclination_deg": number("Inclination, deg, in [0, 180].", minimum=0.0, maximum=180.0),
                    "raan_deg": _angle("Right ascension of the ascending node, deg."),
                    "argument_of_periapsis_deg": _angle("Argument of periapsis, deg."),
                    "true_anomaly_deg": _angle("True anomaly at sim time 0, deg."),
                },
                required=["semi_major_axis", "eccentricity", "inclination_deg"],
            ),
            "state": mapping(
                "Position and velocity of the centre of mass at sim time 0, ECI.",
                {"position": vector("Position [x, y, z], m, ECI.", 3), "velocity": vector("Velocity, m/s, ECI.", 3)},
                required=["position", "velocity"],
            ),
            "j2": {
                "description": "The Earth's J2: the secular drift of the node, periapsis and mean anomaly.",
                "type": "boolean",
                "default": False,
            },
        },
        oneOf=[{"required": ["elements"]}, {"required": ["state"]}],
    )
)

MAGNETIC_FIELD: dict[str, Any] = nullable(
    mapping(
        "The Earth's main field along the scene's orbit (needs orbit:), from the scene's epoch.",
        {
            "model": choice(
                "igrf14 (1900-2030), wmm2025 (2025-2030) or dipole (IGRF-14's degree 1).",
                geomagnetic.MODELS,
                default="igrf14",
            )
        },
    )
)

_FAULT = mapping(
    "A fault over a window of sim time (Basilisk's magnetometer faults).",
    {
        "kind": choice("stuck_current, stuck_value or spiking.", MAGNETOMETER_FAULTS),
        "start": number("Start of the window, s of sim time.", minimum=0.0, default=0.0),
        "end": number("End of the window (excluded), s of sim time; omitted: never.", minimum=0.0),
        "axes": array("Sensor axes it affects (0, 1, 2); omitted: all.", integer("axis", minimum=0, maximum=2)),
        "value": number("What a stuck_value axis reads, T.", default=0.0),
        "probability": number("Chance per sample and axis of a spike.", minimum=0.0, maximum=1.0, default=0.0),
        "amount": number("Factor of a spike.", default=1.0),
    },
    required=["kind"],
)

MAGNETOMETER: dict[str, Any] = nullable(
    mapping(
        "A three-axis magnetometer (needs environment.magnetic_field): ~/magnetometer, sensor_msgs/MagneticField.",
        {
            "rate": number(
                "Samples per second, Hz of sim time.", exclusive_minimum=0.0, maximum=limits.RATE_RANGE[1], default=10.0
            ),
            "noise_density": number("White noise density, T/sqrt(Hz).", minimum=0.0, default=0.0),
            "bias": vector("Bias [x, y, z], T, sensor axes.", 3),
            "scale_factor": vector("Scale factor error [x, y, z], fraction.", 3),
            "misalignment": vector("Rotation vector body -> sensor axes, rad (small).", 3),
            "saturation": number("Largest |reading| per axis, T; 0 = none.", minimum=0.0, default=0.0),
            "quantization": number("Resolution, T per LSB; 0 = none.", minimum=0.0, default=0.0),
            "faults": array("Faults by time window.", _FAULT, max_items=64),
        },
    )
)


@dataclass(frozen=True)
class MagneticField:
    """``environment.magnetic_field``: the model's name (:data:`rigid_rot_sim.core.geomagnetic.MODELS`)."""

    model: str = "igrf14"


def epoch_datetime(epoch: str) -> datetime.datetime:
    """The scene's epoch (ISO 8601, UTC) as an aware datetime (microseconds: the field needs no finer)."""
    return datetime.datetime.fromisoformat(epoch.rstrip("Z")[:26]).replace(tzinfo=datetime.timezone.utc)


def parse_orbit(spec: Mapping[str, Any] | None) -> KeplerOrbit | None:
    """The scene's orbit (its data passed the schema); ValueError naming the key."""
    if spec is None:
        return None
    j2 = core_orbit.EARTH_J2 if spec.get("j2", False) else 0.0
    mu = core_orbit.EARTH_MU
    if "elements" in spec:
        e = spec["elements"]
        angles = [math.radians(float(e.get(key, 0.0))) for key in ("raan_deg", "argument_of_periapsis_deg")]
        values = (float(e["semi_major_axis"]), float(e["eccentricity"]), math.radians(float(e["inclination_deg"])))
        nu = math.radians(float(e.get("true_anomaly_deg", 0.0)))
        key = "orbit.elements"
    else:
        s = spec["state"]
        try:
            el = core_orbit.rv_to_elements(mu, np.array(s["position"], float), np.array(s["velocity"], float))
        except (ValueError, ZeroDivisionError) as exc:
            raise ValueError(f"orbit.state: {exc}") from None
        values, angles, nu, key = (el.a, el.e, el.i), [el.raan, el.argp], el.nu, "orbit.state"
    try:
        kepler = core_orbit.kepler_orbit(values[0], values[1], values[2], angles[0], angles[1], nu, mu=mu, j2=j2)
    except ValueError as exc:
        raise ValueError(f"{key}: {exc}") from None
    periapsis = kepler.a * (1.0 - kepler.e)
    if periapsis <= core_orbit.EARTH_RADIUS * (1.0 - core_orbit.WGS84_FLATTENING):
        raise ValueError(f"{key}: the periapsis radius {periapsis:g} m is inside the Earth")
    if kepler.mean_anomaly_dot / (2.0 * math.pi) > limits.RATE_RANGE[1]:
        raise ValueError(f"{key}: more than {limits.RATE_RANGE[1]:g} orbits per second")
    return kepler


def parse_magnetic_field(
    spec: Mapping[str, Any] | None, kepler: KeplerOrbit | None, epoch: str, duration: float | None
) -> MagneticField | None:
    """``environment.magnetic_field``, checked against the orbit and the run's span of dates."""
    if spec is None:
        return None
    if kepler is None:
        raise ValueError("environment.magnetic_field: needs the scene's orbit: section (where the body is)")
    field = MagneticField(str(spec.get("model", MagneticField.model)))
    try:
        geomagnetic.orbit_field(field.model, kepler, epoch_datetime(epoch), duration)
    except ValueError as exc:
        raise ValueError(f"environment.magnetic_field: {exc} (the scene's epoch is {epoch})") from None
    return field


def parse_magnetometer(spec: Mapping[str, Any] | None, field: MagneticField | None) -> MagnetometerModel | None:
    """``sensors.magnetometer`` as the core's model; it needs the field."""
    if spec is None:
        return None
    if field is None:
        raise ValueError("sensors.magnetometer: needs environment.magnetic_field (what it measures)")
    faults = []
    for i, fault in enumerate(spec.get("faults") or []):
        start, end = float(fault.get("start", 0.0)), float(fault.get("end", math.inf))
        if not end > start:
            raise ValueError(f"sensors.magnetometer.faults[{i}]: end {end:g} s is not after start {start:g} s")
        faults.append(
            MagnetometerFault(
                kind=str(fault["kind"]),
                start=start,
                end=end,
                axes=tuple(int(a) for a in fault.get("axes", (0, 1, 2))),
                value=float(fault.get("value", 0.0)),
                probability=float(fault.get("probability", 0.0)),
                amount=float(fault.get("amount", 1.0)),
            )
        )

    def triple(name: str) -> tuple[float, float, float]:
        x, y, z = (float(v) for v in spec.get(name, (0.0, 0.0, 0.0)))
        return x, y, z

    return MagnetometerModel(
        rate=float(spec.get("rate", MagnetometerModel.rate)),
        noise_density=float(spec.get("noise_density", 0.0)),
        bias=triple("bias"),
        scale_factor=triple("scale_factor"),
        misalignment=triple("misalignment"),
        saturation=float(spec.get("saturation", 0.0)),
        quantization=float(spec.get("quantization", 0.0)),
        faults=tuple(faults),
    )
