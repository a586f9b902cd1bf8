"""``actuators.magnetorquers``: parsed into the core's Magnetorquers, bad rods refused naming the key, every
path but the engine and resim refusing the rods by name."""

from __future__ import annotations

import numpy as np
import pytest

from rigid_rot_sim.scene.features import PATHS, features_of, refuse_unhonoured
from rigid_rot_sim.scene.scene import SceneError, parse_scene_text

BASE = """
body: {principal_moments: [0.035, 0.035, 0.0065]}
initial: {angular_velocity: [0.17, 0.17, 0.17]}
integrator: {method: auto, dt: 0.1}
orbit:
  elements: {semi_major_axis: 6878137.0, eccentricity: 0.0, inclination_deg: 97.4, raan_deg: 0.0,
             argument_of_periapsis_deg: 0.0, true_anomaly_deg: 0.0}
environment:
  magnetic_field: {model: igrf14}
actuators:
  magnetorquers:
    residual_dipole: [0.001, 0.0, -0.002]
    rods:
      - {name: mtq_x, axis: [2.0, 0.0, 0.0], max_dipole: 0.2}
      - {name: mtq_y, axis: [0.0, 1.0, 0.0], max_dipole: 0.2, magnetometer_coupling: [0.0, 1.0e-6, 0.0]}
      - {name: mtq_z, axis: [0.0, 0.1, 1.0], max_dipole: 0.1}
"""


def test_rods_parse_into_the_cores_magnetorquers():
    scene = parse_scene_text(BASE)
    rods = scene.spacecraft.magnetorquers()
    assert rods is not None and rods.names == ("mtq_x", "mtq_y", "mtq_z")
    np.testing.assert_allclose(rods.axes[:, 0], [1.0, 0.0, 0.0])
    np.testing.assert_allclose(np.linalg.norm(rods.axes, axis=0), 1.0, rtol=1e-15)
    assert rods.max_dipoles.tolist() == [0.2, 0.2, 0.1]
    assert rods.residual.tolist() == [0.001, 0.0, -0.002]
    assert rods.coupling[:, 1].tolist() == [0.0, 1e-6, 0.0] and not rods.coupling[:, [0, 2]].any()
    assert "3 torque rod(s) [mtq_x, mtq_y, mtq_z]" in scene.spacecraft.summary()


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (("max_dipole: 0.1}", "max_dipole: 0.0}"), r"max_dipole"),
        (("name: mtq_y", "name: mtq_x"), r"actuators.magnetorquers.rods\[1\].name: 'mtq_x' is listed twice"),
        (("axis: [2.0, 0.0, 0.0]", "axis: [0.0, 0.0, 0.0]"), r"rods\[0\].axis: must be a non-zero vector"),
        (("axis: [2.0, 0.0, 0.0]", "axis: [1.0, 0.0]"), r"axis"),
    ],
)
def test_bad_rods_are_refused_naming_the_key(edit, message):
    with pytest.raises(SceneError, match=message):
        parse_scene_text(BASE.replace(*edit))


def test_the_engine_and_resim_run_rods_and_the_other_paths_refuse_them_by_name():
    scene = parse_scene_text(BASE.replace(", magnetometer_coupling: [0.0, 1.0e-6, 0.0]", ""))
    assert "spacecraft.magnetorquers" in features_of(scene)
    for path in PATHS:
        if path in ("engine", "resim"):
            refuse_unhonoured(scene, path)
            continue
        with pytest.raises(ValueError, match=r"^spacecraft.magnetorquers: not run by the"):
            refuse_unhonoured(scene, path)
    # a scene without rods does not use the feature
    plain = parse_scene_text(BASE.split("actuators:")[0])
    assert "spacecraft.magnetorquers" not in features_of(plain) and plain.spacecraft.magnetorquers() is None
