"""What viewers draw of the body: the box's moments are the body's, the arrows follow omega and L."""

from __future__ import annotations

import numpy as np
import pytest

from rigid_rot_sim import conversions
from rigid_rot_sim.core.inertia import NOMINAL_BOX_SIZE, equivalent_box, principal_frame
from rigid_rot_sim.run.body_view import body_view
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import parse_scene_text
from rigid_rot_sim.viewer import foxglove

TENSOR_SCENE = """
body:
  inertia_tensor: [[120.0, 2.0, -1.5], [2.0, 95.0, 3.0], [-1.5, 3.0, 140.0]]
initial: {angular_velocity: [0.1, -0.2, 0.3]}
"""
MASS_SCENE = """
body:
  point_masses: {masses: [1.0, 2.0, 3.0, 0.5], positions: [[0.3, 0, 0], [0, 0.2, 0], [0, 0, 0.1], [0.1, 0.1, 0.1]]}
initial: {angular_velocity: [0.0, 0.0, 2.0]}
"""


def _box_moments(sides, mass):
    a, b, c = sides
    return np.array([b * b + c * c, a * a + c * c, a * a + b * b]) * mass / 12.0


@pytest.mark.parametrize("moments", [(1.0, 2.0, 2.5), (3.0, 3.0, 3.0), (1.0, 1.0, 2.0), (0.5, 2.0, 2.5)])
def test_box_moments_equal_the_bodys(moments):
    for mass in (0.5, 7.0):
        np.testing.assert_allclose(_box_moments(equivalent_box(moments, mass), mass), moments, rtol=1e-12)


def test_without_a_mass_the_box_has_the_proportions_and_the_nominal_size():
    sides = equivalent_box((1.0, 2.0, 2.5))
    assert sides.max() == pytest.approx(NOMINAL_BOX_SIZE)
    np.testing.assert_allclose(
        sides / sides.max(),
        equivalent_box((1.0, 2.0, 2.5), 3.0) / equivalent_box((1.0, 2.0, 2.5), 3.0).max(),
        rtol=1e-12,
    )


def test_markers_box_is_the_bodys_inertia_in_the_principal_frame():
    scene = parse_scene_text(MASS_SCENE)
    mass, com, tensor = scene.mass_properties_about_com()
    view = body_view(scene)
    snapshot = Simulator(scene, method="rk4").snapshot()
    box, omega, momentum = conversions.body_markers(view, snapshot, "odom", "base_link").markers
    sides = np.array([box.scale.x, box.scale.y, box.scale.z])
    from scipy.spatial.transform import Rotation

    rotation = Rotation.from_quat(
        [box.pose.orientation.x, box.pose.orientation.y, box.pose.orientation.z, box.pose.orientation.w]
    ).as_matrix()
    # the box's inertia tensor, turned into the body frame, is the body's tensor about its centre of mass
    np.testing.assert_allclose(rotation @ np.diag(_box_moments(sides, mass)) @ rotation.T, tensor, atol=1e-12)
    np.testing.assert_allclose([box.pose.position.x, box.pose.position.y, box.pose.position.z], com, atol=1e-15)
    tip = np.array([omega.points[1].x, omega.points[1].y, omega.points[1].z])
    np.testing.assert_allclose(tip - com, view.omega_scale * snapshot.angular_velocity_body, atol=1e-12)
    assert view.omega_scale * np.linalg.norm(snapshot.angular_velocity_body) == pytest.approx(sides.max())
    L_tip = np.array([momentum.points[1].x, momentum.points[1].y, momentum.points[1].z])
    np.testing.assert_allclose(L_tip, view.momentum_scale * snapshot.angular_momentum_world, atol=1e-12)
    assert (box.header.frame_id, momentum.header.frame_id) == ("base_link", "odom")


def test_scene_entity_arrow_points_along_the_vector():
    scene = parse_scene_text(TENSOR_SCENE)
    view = body_view(scene)
    moments, _ = principal_frame(scene.mass_properties_about_com()[2])
    assert max(view.box_sides) == pytest.approx(NOMINAL_BOX_SIZE)  # no mass given
    update = foxglove.BodyScene(view, "odom", "base_link").update(
        1_500_000_000, np.array([0.0, -2.0, 0.0]), np.array([-1.0, 0.0, 0.0])
    )
    body, momentum = update["entities"]
    assert body["timestamp"] == {"sec": 1, "nsec": 500_000_000}
    arrow = momentum["arrows"][0]
    from scipy.spatial.transform import Rotation

    q = [arrow["pose"]["orientation"][k] for k in "xyzw"]
    direction = Rotation.from_quat(q).apply([1.0, 0.0, 0.0])
    np.testing.assert_allclose(direction, [-1.0, 0.0, 0.0], atol=1e-12)  # opposite to +x
    assert arrow["shaft_length"] + arrow["head_length"] == pytest.approx(view.momentum_scale)


@pytest.mark.parametrize(
    "text, expected",
    [
        ("8765", ("127.0.0.1", 8765)),
        ("0.0.0.0:9000", ("0.0.0.0", 9000)),
        ("localhost:0", ("localhost", 0)),
        ("[::1]:8765", ("::1", 8765)),
    ],
)
def test_addresses(text, expected):
    assert foxglove.parse_address(text) == expected


@pytest.mark.parametrize("text", ["", "host:", "host:port", "70000"])
def test_bad_addresses_are_refused(text):
    with pytest.raises(ValueError, match="foxglove address"):
        foxglove.parse_address(text)


def test_without_the_sdk_the_node_says_so(monkeypatch):
    from rigid_rot_sim.ros import foxglove_live

    monkeypatch.setattr(foxglove_live, "available", lambda: False)
    scene = parse_scene_text(TENSOR_SCENE)
    live, words = foxglove_live.start("8765", Simulator(scene, method="rk4"), body_view(scene), scene.frames, "/n")
    assert live is None and "foxglove-sdk not installed" in words
