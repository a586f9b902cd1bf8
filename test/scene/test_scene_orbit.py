"""The scene's orbit:, environment.magnetic_field and sensors.magnetometer: parsed into the core's models, with
one-line refusals naming the key; the paths that do not run them refuse them by name."""

import math

import numpy as np
import pytest

from rigid_rot_sim.core import orbit
from rigid_rot_sim.scene.features import refuse_unhonoured
from rigid_rot_sim.scene.scene import SceneError, load_scene, parse_scene_text

BASE = """
name: orbiting
epoch: "2026-01-01T00:00:00Z"
body: {principal_moments: [1.0, 2.0, 3.0]}
"""
ELEMENTS = """
orbit:
  elements: {semi_major_axis: 7000000.0, eccentricity: 0.01, inclination_deg: 51.6, raan_deg: 20.0,
             argument_of_periapsis_deg: 30.0, true_anomaly_deg: 40.0}
  j2: true
"""

FAULT_BACKWARDS = "sensors: {magnetometer: {faults: [{kind: spiking, start: 5, end: 1}]}}\n"


def test_elements_and_state_give_the_same_orbit() -> None:
    by_elements = parse_scene_text(BASE + ELEMENTS).orbit
    assert by_elements is not None and by_elements.j2 == orbit.EARTH_J2
    r, v = by_elements.state(0.0)
    state = f"\norbit:\n  state: {{position: {r.tolist()}, velocity: {v.tolist()}}}\n  j2: true\n"
    by_state = parse_scene_text(BASE + state).orbit
    assert by_state is not None
    np.testing.assert_allclose(by_state.state(1000.0)[0], by_elements.state(1000.0)[0], rtol=1e-9)
    assert by_state.raan_dot == pytest.approx(by_elements.raan_dot, rel=1e-9)
    assert by_elements.i == pytest.approx(math.radians(51.6))


def test_the_gravity_gradient_follows_the_scene_orbit() -> None:
    scene = parse_scene_text(BASE + ELEMENTS + "environment: {gravity_gradient: {}}\n")
    gg = scene.spacecraft.gravity_gradient
    assert gg is not None and gg.kepler == scene.orbit
    np.testing.assert_allclose(gg.model().position_world(10.0), scene.orbit.state(10.0)[0] / 7e6, rtol=0.02)


@pytest.mark.parametrize(
    "extra, message",
    [
        ("environment: {magnetic_field: {model: igrf14}}\n", "environment.magnetic_field: needs the scene's orbit"),
        (ELEMENTS + "sensors: {magnetometer: {rate: 10}}\n", "sensors.magnetometer: needs environment.magnetic_field"),
        (ELEMENTS + "environment: {gravity_gradient: {orbit: {radius: 7.0e+6}}}\n", "give no orbit here"),
        ("environment: {gravity_gradient: {}}\n", "environment.gravity_gradient: needs an orbit"),
        (
            ELEMENTS.replace("7000000.0", "6000000.0"),
            "orbit.elements: the periapsis",
        ),
        (
            ELEMENTS + "environment: {magnetic_field: {model: wmm2025}}\nduration: 200000000.0\n",
            "the wmm2025 field is defined from 2025 to 2030",
        ),
        (
            ELEMENTS + "environment: {magnetic_field: {}}\n" + FAULT_BACKWARDS,
            r"sensors\.magnetometer\.faults\[0\]: end 1 s is not after start 5 s",
        ),
    ],
)
def test_refusals_name_the_key(extra: str, message: str) -> None:
    with pytest.raises(SceneError, match=message):
        parse_scene_text(BASE + extra)


def test_the_default_epoch_is_outside_wmm2025() -> None:
    with pytest.raises(SceneError, match=r"not at 2000\.0014 \(the scene's epoch is 2000-01-01T12:00:00Z\)"):
        parse_scene_text(
            BASE.replace('epoch: "2026-01-01T00:00:00Z"\n', "")
            + ELEMENTS
            + "environment: {magnetic_field: {model: wmm2025}}\n"
        )


def test_the_shipped_cubesat_scene() -> None:
    scene = load_scene("config/scenes/cubesat_orbit.yaml")
    assert scene.orbit is not None and scene.magnetic_field is not None and scene.sensors.magnetometer is not None
    assert scene.sensors.magnetometer.rate == 10.0 and scene.outputs["magnetometer"] == 10.0
    raan_dot_deg_per_day = math.degrees(scene.orbit.raan_dot) * 86400
    assert raan_dot_deg_per_day == pytest.approx(360 / 365.2422, rel=1e-3)  # sun-synchronous
    assert scene.orbit.a - orbit.EARTH_RADIUS == pytest.approx(500e3)


@pytest.mark.parametrize("path", ["engine", "resim", "sweep", "simulate"])
def test_every_path_runs_the_orbit_and_the_field(path: str) -> None:
    """The orbit acts through the gravity gradient (the engine per sample in the sweep, ``orbit=`` of simulate);
    the field acts on no state yet. test/conformance checks the shipped cubesat_orbit's end states on each path."""
    scene = parse_scene_text(BASE + ELEMENTS + "environment: {gravity_gradient: {}, magnetic_field: {}}\n")
    refuse_unhonoured(scene, path)
