"""Mass properties of point masses: hand-computed bodies, validation and invariants."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.inertia import (
    SYMMETRY_LABELS,
    mass_properties,
    parallel_axis_shift,
    principal_frame,
    principal_frame_pose,
    principal_orientation,
)


def assert_proper_principal_frame(props):
    axes = props.principal_axes
    np.testing.assert_allclose(axes.T @ axes, np.eye(3), atol=1e-12)
    assert np.linalg.det(axes) == pytest.approx(1.0, abs=1e-12)
    scale = max(float(props.principal_moments[-1]), 1e-300)
    np.testing.assert_allclose(axes @ np.diag(props.principal_moments) @ axes.T, props.inertia_com, atol=1e-12 * scale)
    assert np.all(np.diff(props.principal_moments) >= 0.0)
    assert np.all(props.principal_moments >= 0.0)


# --- hand-computed bodies -------------------------------------------------------------------


def test_cube_corners_are_spherical_with_16_m_a2():
    m, a = 0.25, 0.3  # kg, half edge in m
    corners = np.array([[x, y, z] for x in (-a, a) for y in (-a, a) for z in (-a, a)])
    centre = np.array([1.0, -2.0, 0.5])
    props = mass_properties(np.full(8, m), corners + centre)
    assert props.total_mass == pytest.approx(8 * m)
    np.testing.assert_allclose(props.center_of_mass, centre, atol=1e-15)
    # each corner is at distance a*sqrt(2) from every axis through the centre: 8 m (2 a^2)
    np.testing.assert_allclose(props.inertia_com, 16 * m * a**2 * np.eye(3), atol=1e-14)
    np.testing.assert_allclose(props.principal_moments, [16 * m * a**2] * 3, rtol=1e-13)
    assert props.symmetry == "spherical"
    assert_proper_principal_frame(props)


def test_cube_corners_about_one_corner_by_hand():
    # unit cube [0,1]^3, unit masses, about the corner at the origin:
    # Ixx = sum (y^2 + z^2) = 4 * (1 + 1) = 8; Ixy = -sum x y = -2
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    props = mass_properties(np.ones(8), corners)
    expected = np.array([[8.0, -2.0, -2.0], [-2.0, 8.0, -2.0], [-2.0, -2.0, 8.0]])
    np.testing.assert_allclose(props.inertia_origin, expected, atol=1e-14)
    np.testing.assert_allclose(props.inertia_com, 4.0 * np.eye(3), atol=1e-14)


def test_dumbbell_has_reduced_mass_moment_about_its_axis():
    m1, m2, length = 2.0, 3.0, 1.5
    direction = np.array([1.0, 2.0, -2.0]) / 3.0
    start = np.array([0.1, 0.2, 0.3])
    props = mass_properties([m1, m2], [start, start + length * direction])
    reduced = m1 * m2 / (m1 + m2)
    np.testing.assert_allclose(props.center_of_mass, start + m2 / (m1 + m2) * length * direction, atol=1e-15)
    np.testing.assert_allclose(props.principal_moments, [0.0, reduced * length**2, reduced * length**2], atol=1e-13)
    assert props.symmetry == "linear"
    # the zero moment belongs to the dumbbell's axis
    assert abs(props.principal_axes[:, 0] @ direction) == pytest.approx(1.0, abs=1e-12)
    assert_proper_principal_frame(props)


def test_planar_lamina_obeys_perpendicular_axis_theorem():
    # 4 masses at (+-a, +-b, 0): Ixx = 4 m b^2, Iyy = 4 m a^2, Izz = Ixx + Iyy
    m, a, b = 0.5, 0.4, 0.1
    points = [[sx * a, sy * b, 0.0] for sx in (-1, 1) for sy in (-1, 1)]
    props = mass_properties(np.full(4, m), points)
    np.testing.assert_allclose(
        props.inertia_com, np.diag([4 * m * b**2, 4 * m * a**2, 4 * m * (a**2 + b**2)]), atol=1e-15
    )
    i1, i2, i3 = props.principal_moments
    assert i3 == pytest.approx(i1 + i2, rel=1e-14)
    assert abs(props.principal_axes[2, 2]) == pytest.approx(1.0)  # I3 about the plane's normal
    assert props.symmetry == "asymmetric"
    assert_proper_principal_frame(props)


def test_general_lamina_in_a_tilted_plane_has_i3_equal_i1_plus_i2():
    rng = np.random.default_rng(7)
    in_plane = rng.normal(size=(6, 2))
    rotation = Rotation.from_rotvec([0.3, -1.1, 0.7])
    points = rotation.apply(np.column_stack([in_plane, np.zeros(6)]))
    props = mass_properties(rng.uniform(0.1, 2.0, 6), points)
    i1, i2, i3 = props.principal_moments
    assert i3 == pytest.approx(i1 + i2, rel=1e-12)
    normal = rotation.apply([0.0, 0.0, 1.0])
    assert abs(props.principal_axes[:, 2] @ normal) == pytest.approx(1.0, abs=1e-10)


def test_equilateral_triangle_is_symmetric_with_i3_twice_i1():
    angles = np.deg2rad([90.0, 210.0, 330.0])
    radius = 0.7
    points = np.column_stack([radius * np.cos(angles), radius * np.sin(angles), np.zeros(3)])
    props = mass_properties([1.0, 1.0, 1.0], points)
    # I about the normal = 3 m r^2; in-plane moments equal, each half of it
    np.testing.assert_allclose(props.principal_moments, [1.5 * radius**2, 1.5 * radius**2, 3 * radius**2], rtol=1e-13)
    assert props.symmetry == "symmetric"


@pytest.mark.parametrize("count", [2, 5, 50])
def test_rod_of_equal_masses_by_hand(count):
    # count equal masses equally spaced h apart on the x axis: sum x_k^2 = h^2 n (n^2 - 1) / 12
    m, h = 0.2, 0.05
    x = (np.arange(count) - (count - 1) / 2) * h
    props = mass_properties(np.full(count, m), np.column_stack([x + 3.0, np.zeros(count), np.zeros(count)]))
    transverse = m * h**2 * count * (count**2 - 1) / 12
    np.testing.assert_allclose(props.principal_moments, [0.0, transverse, transverse], atol=1e-14)
    assert props.symmetry == "linear"
    assert abs(props.principal_axes[0, 0]) == pytest.approx(1.0)


def test_fine_rod_approaches_m_l2_over_12():
    count, total_mass, length = 2001, 3.0, 2.0
    x = np.linspace(-length / 2, length / 2, count)
    props = mass_properties(np.full(count, total_mass / count), np.column_stack([x, 0 * x, 0 * x]))
    # discrete sum: M L^2 (n + 1) / (12 (n - 1)); the continuum limit is M L^2 / 12
    assert props.principal_moments[2] == pytest.approx(total_mass * length**2 / 12, rel=2e-3)
    assert props.principal_moments[2] == pytest.approx(
        total_mass * length**2 * (count + 1) / (12 * (count - 1)), rel=1e-12
    )


def test_single_point_mass():
    position = np.array([0.3, -0.4, 1.2])
    origin = np.array([0.1, 0.1, 0.1])
    props = mass_properties([2.5], [position], origin=origin)
    assert props.symmetry == "point"
    np.testing.assert_array_equal(props.principal_moments, np.zeros(3))
    np.testing.assert_array_equal(props.inertia_com, np.zeros((3, 3)))
    np.testing.assert_allclose(props.center_of_mass, position)
    d = position - origin
    np.testing.assert_allclose(props.inertia_origin, 2.5 * (d @ d * np.eye(3) - np.outer(d, d)), atol=1e-15)
    assert_proper_principal_frame(props)


def test_coincident_masses_are_a_point_despite_rounding():
    props = mass_properties([1.0, 3.0, 0.7], [[0.1, 0.7, 0.3]] * 3)
    assert props.symmetry == "point"
    assert np.all(props.principal_moments >= 0.0)


def test_symmetry_labels_do_not_depend_on_scale():
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    for mass_scale, length_scale, offset in [(1e-9, 1e-4, 0.0), (1e6, 1e3, 0.0), (1.0, 1.0, 1e4)]:
        props = mass_properties(np.full(8, mass_scale), corners * length_scale + offset)
        assert props.symmetry == "spherical", (mass_scale, length_scale, offset)
        rod = mass_properties([mass_scale] * 3, [[k * length_scale + offset, offset, offset] for k in range(3)])
        assert rod.symmetry == "linear", (mass_scale, length_scale, offset)


def test_labels_are_the_documented_ones():
    assert set(SYMMETRY_LABELS) == {"asymmetric", "symmetric", "spherical", "linear", "point"}


def test_result_is_frozen():
    props = mass_properties([1.0], [[0.0, 0.0, 0.0]])
    with pytest.raises(AttributeError):
        props.total_mass = 2.0


# --- principal orientation ------------------------------------------------------------------


def test_principal_orientation_is_the_rotation_of_the_axes():
    props = mass_properties([1.0, 2.0, 3.0, 0.5], [[0, 0, 0], [1, 0.2, 0], [0, 2, 0.1], [0.3, 0.3, 1]])
    quat = principal_orientation(props.principal_axes)
    assert quat[3] >= 0.0
    assert np.linalg.norm(quat) == pytest.approx(1.0)
    np.testing.assert_allclose(Rotation.from_quat(quat).as_matrix(), props.principal_axes, atol=1e-12)
    # scalar-last: the principal frame's x axis expressed in the input frame is the first column
    np.testing.assert_allclose(Rotation.from_quat(quat).apply([1, 0, 0]), props.principal_axes[:, 0], atol=1e-12)


def test_principal_orientation_rejects_a_reflection():
    with pytest.raises(ValueError, match="principal_axes"):
        principal_orientation(np.diag([1.0, 1.0, -1.0]))


def test_principal_frame_rejects_bad_tensor():
    with pytest.raises(ValueError, match="inertia_com"):
        principal_frame(np.eye(2))
    with pytest.raises(ValueError, match=r"inertia_com\[\[1, 1\]\] must be finite"):
        principal_frame(np.diag([1.0, np.nan, 1.0]))


# --- parallel-axis theorem ------------------------------------------------------------------


def test_parallel_axis_shift_by_hand():
    shifted = parallel_axis_shift(np.diag([1.0, 2.0, 3.0]), 2.0, [0.0, 0.0, 0.5])
    np.testing.assert_allclose(shifted, np.diag([1.5, 2.5, 3.0]))
    shifted = parallel_axis_shift(np.zeros((3, 3)), 1.0, [1.0, 1.0, 0.0])
    np.testing.assert_allclose(shifted, [[1.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 2.0]])


@pytest.mark.parametrize(
    "args, message",
    [
        ((np.eye(2), 1.0, [0, 0, 0]), "inertia_com must have shape"),
        ((np.eye(3), 0.0, [0, 0, 0]), r"mass must be > 0"),
        ((np.eye(3), math.nan, [0, 0, 0]), r"mass must be finite"),
        ((np.eye(3), 1.0, [0, 0]), r"offset must have shape"),
        ((np.eye(3), 1.0, [0, math.inf, 0]), r"offset\[1\] must be finite"),
    ],
)
def test_parallel_axis_shift_validation(args, message):
    with pytest.raises(ValueError, match=message):
        parallel_axis_shift(*args)


# --- validation -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "masses, positions, origin, message",
    [
        ([], np.zeros((0, 3)), (0, 0, 0), r"masses must contain at least one mass"),
        ([1.0, 2.0], [[0, 0, 0]], (0, 0, 0), r"positions has 1 points but masses has 2"),
        ([1.0, -2.0], [[0, 0, 0], [1, 0, 0]], (0, 0, 0), r"masses\[1\] must be > 0"),
        ([1.0, 0.0], [[0, 0, 0], [1, 0, 0]], (0, 0, 0), r"masses\[1\] must be > 0"),
        ([math.nan, 1.0], [[0, 0, 0], [1, 0, 0]], (0, 0, 0), r"masses\[0\] must be finite"),
        ([1.0, math.inf], [[0, 0, 0], [1, 0, 0]], (0, 0, 0), r"masses\[1\] must be finite"),
        ([1.0, 1.0, 1.0], [[0, 0, 0], [1, 0, 0], [0, math.nan, 0]], (0, 0, 0), r"positions\[2\] must be finite"),
        ([1.0], [[0, 0]], (0, 0, 0), r"positions must have shape \(n, 3\)"),
        ([[1.0]], [[0, 0, 0]], (0, 0, 0), r"masses must be one-dimensional"),
        (["a"], [[0, 0, 0]], (0, 0, 0), r"masses must be a sequence of numbers"),
        ([1.0], [[0, 0, 0]], (0, 0), r"origin must have shape \(3,\)"),
        ([1.0], [[0, 0, 0]], (0, math.inf, 0), r"origin\[1\] must be finite"),
    ],
)
def test_invalid_input_names_argument_and_index(masses, positions, origin, message):
    with pytest.raises(ValueError, match=message):
        mass_properties(masses, positions, origin)


# --- properties -----------------------------------------------------------------------------

coordinates = st.floats(min_value=-10.0, max_value=10.0, allow_nan=False)
bodies = st.integers(min_value=1, max_value=8).flatmap(
    lambda n: st.tuples(
        arrays(float, n, elements=st.floats(min_value=1e-3, max_value=100.0)),
        arrays(float, (n, 3), elements=coordinates),
    )
)
quaternions = arrays(float, 4, elements=st.floats(min_value=-1.0, max_value=1.0)).filter(
    lambda q: np.linalg.norm(q) > 0.1
)


def eigenspace_projectors(moments, axes, gap):
    """Projectors onto the eigenspaces of moments closer than ``gap`` (unique where axes are not)."""
    clusters, current = [], [0]
    for i in (1, 2):
        if moments[i] - moments[i - 1] <= gap:
            current.append(i)
        else:
            clusters.append(current)
            current = [i]
    clusters.append(current)
    return [(c, axes[:, c] @ axes[:, c].T) for c in clusters]


@settings(deadline=None, max_examples=150)
@given(body=bodies, quat=quaternions)
def test_rotating_the_body_rotates_axes_and_keeps_moments(body, quat):
    masses, positions = body
    rotation = Rotation.from_quat(quat)
    before = mass_properties(masses, positions)
    after = mass_properties(masses, rotation.apply(positions))
    matrix = rotation.as_matrix()
    scale = float(np.sum(masses) * (1.0 + np.max(np.sum(positions**2, axis=1))))
    np.testing.assert_allclose(after.principal_moments, before.principal_moments, atol=1e-11 * scale)
    np.testing.assert_allclose(after.inertia_com, matrix @ before.inertia_com @ matrix.T, atol=1e-11 * scale)
    assert_proper_principal_frame(after)
    # Eigenvectors are unique only up to sign, and only for distinct moments: compare the
    # projectors onto each group of (numerically) equal moments instead.
    gap = 1e-4 * scale
    for cluster, projector in eigenspace_projectors(before.principal_moments, before.principal_axes, gap):
        after_clusters = dict(
            (tuple(c), p) for c, p in eigenspace_projectors(after.principal_moments, after.principal_axes, gap)
        )
        assume(tuple(cluster) in after_clusters)  # a gap right at the threshold splits differently
        np.testing.assert_allclose(after_clusters[tuple(cluster)], matrix @ projector @ matrix.T, atol=1e-6)


@settings(deadline=None, max_examples=150)
@given(body=bodies, origin=arrays(float, 3, elements=coordinates))
def test_parallel_axis_theorem_between_origin_and_centre_of_mass(body, origin):
    masses, positions = body
    props = mass_properties(masses, positions, origin=origin)
    scale = float(np.sum(masses) * (1.0 + np.max(np.sum((positions - origin) ** 2, axis=1))))
    shifted = parallel_axis_shift(props.inertia_com, props.total_mass, props.center_of_mass - origin)
    np.testing.assert_allclose(shifted, props.inertia_origin, atol=1e-12 * scale)
    # and back: the tensor about the centre of mass is the smallest (Steiner: I_origin - I_com >= 0)
    assert np.all(np.linalg.eigvalsh(props.inertia_origin - props.inertia_com) >= -1e-12 * scale)


@settings(deadline=None, max_examples=100)
@given(body=bodies)
def test_moments_obey_the_triangle_inequality(body):
    masses, positions = body
    props = mass_properties(masses, positions)
    i1, i2, i3 = props.principal_moments
    assert i1 + i2 >= i3 - 1e-12 * max(i3, 1e-300)
    assert props.symmetry in SYMMETRY_LABELS
    assert_proper_principal_frame(props)


def test_principal_frame_pose_is_none_for_principal_body_axes_at_the_centre_of_mass():
    assert principal_frame_pose(np.diag([3.0, 1.0, 2.0])) is None  # unsorted moments: still the body axes


def test_principal_frame_pose_of_an_offset_diagonal_body_is_a_pure_translation():
    translation, rotation = principal_frame_pose(np.diag([1.0, 2.0, 3.0]), (0.0, 0.0, 0.1))
    assert translation.tolist() == [0.0, 0.0, 0.1] and rotation.tolist() == [0.0, 0.0, 0.0, 1.0]


def test_principal_frame_pose_rotates_the_tensor_to_ascending_diagonal_form():
    turn = Rotation.from_euler("zyx", [0.4, -0.3, 1.1]).as_matrix()
    tensor = turn @ np.diag([1.0, 2.0, 3.0]) @ turn.T
    translation, rotation = principal_frame_pose(tensor, (0.1, -0.2, 0.3))
    assert translation.tolist() == [0.1, -0.2, 0.3]
    axes = Rotation.from_quat(rotation).as_matrix()  # principal -> body: columns are the principal axes
    np.testing.assert_allclose(axes.T @ tensor @ axes, np.diag([1.0, 2.0, 3.0]), atol=1e-12)
