"""Mass properties of a rigid body made of point masses.

Frames: every position, the origin and every result are expressed in one reference frame
(called "the body frame" below; any right-handed frame works). Units: kg, m, kg*m^2.

The inertia tensor of point masses m_i at r_i about a point p is

    I = sum_i m_i (|d_i|^2 E - d_i d_i^T),    d_i = r_i - p,

and the parallel-axis theorem relates the tensor about the centre of mass c to the one
about p:  I_p = I_c + M (|s|^2 E - s s^T)  with  s = c - p.

Example
-------
>>> props = mass_properties([1.0, 1.0], [[-0.5, 0, 0], [0.5, 0, 0]])
>>> props.principal_moments.round(6).tolist(), props.symmetry
([0.0, 0.5, 0.5], 'linear')
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core import limits, validation
from rigid_rot_sim.core.arrays import ArrayLike, FloatArray

#: Symmetry labels, from the most to the least degenerate.
SYMMETRY_LABELS = ("point", "linear", "spherical", "symmetric", "asymmetric")

#: Relative tolerance (to the largest principal moment) under which two moments count as
#: equal, or a moment as zero, for the symmetry label.
SYMMETRY_RTOL = 1e-9


@dataclass(frozen=True)
class MassProperties:
    """Mass properties of a body of point masses, all in the frame of the input positions.

    Attributes
    ----------
    total_mass : float
        kg.
    center_of_mass : ndarray, shape (3,)
        m.
    origin : ndarray, shape (3,)
        m, the point ``inertia_origin`` is taken about.
    inertia_origin : ndarray, shape (3, 3)
        kg*m^2, inertia tensor about ``origin``.
    inertia_com : ndarray, shape (3, 3)
        kg*m^2, inertia tensor about the centre of mass.
    principal_moments : ndarray, shape (3,)
        kg*m^2, eigenvalues of ``inertia_com`` in ascending order.
    principal_axes : ndarray, shape (3, 3)
        Columns are the unit principal axes matching ``principal_moments``; a proper
        rotation (det = +1), mapping principal-frame coordinates to the input frame:
        ``inertia_com == principal_axes @ diag(principal_moments) @ principal_axes.T``.
    symmetry : str
        ``point`` (all moments zero), ``linear`` (one zero moment, two equal: masses on a
        line), ``spherical`` (three equal), ``symmetric`` (two equal) or ``asymmetric``.
    """

    total_mass: float
    center_of_mass: np.ndarray
    origin: np.ndarray
    inertia_origin: np.ndarray
    inertia_com: np.ndarray
    principal_moments: np.ndarray
    principal_axes: np.ndarray
    symmetry: str


def validate_point_masses(masses: ArrayLike, positions: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Return ``masses`` (n,) and ``positions`` (n, 3) as float arrays, or raise ValueError.

    Rules: at least one mass and at most ``limits.MAX_POINT_MASSES``; as many positions as
    masses; every mass finite and > 0 (kg); every position finite (m). Errors name the
    argument and the first bad index.
    """
    try:
        mass_array = np.asarray(masses, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"masses must be a sequence of numbers, got {masses!r}") from exc
    if mass_array.ndim != 1:
        raise ValueError(f"masses must be one-dimensional, got shape {mass_array.shape}")
    if mass_array.size == 0:
        raise ValueError("masses must contain at least one mass")
    if mass_array.size > limits.MAX_POINT_MASSES:
        raise ValueError(f"{mass_array.size} masses, more than the limit of {limits.MAX_POINT_MASSES}")
    try:
        position_array = np.asarray(positions, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"positions must be a sequence of (x, y, z) points, got {positions!r}") from exc
    if position_array.ndim != 2 or position_array.shape[1] != 3:
        raise ValueError(f"positions must have shape (n, 3), got shape {position_array.shape}")
    if len(position_array) != len(mass_array):
        raise ValueError(
            f"positions has {len(position_array)} points but masses has {len(mass_array)}; they must match"
        )
    bad = np.flatnonzero(~np.isfinite(mass_array))
    if bad.size:
        raise ValueError(f"masses[{bad[0]}] must be finite, got {mass_array[bad[0]]}")
    bad = np.flatnonzero(mass_array <= 0.0)
    if bad.size:
        raise ValueError(f"masses[{bad[0]}] must be > 0 kg, got {mass_array[bad[0]]}")
    bad = np.flatnonzero(~np.all(np.isfinite(position_array), axis=1))
    if bad.size:
        raise ValueError(f"positions[{bad[0]}] must be finite, got {position_array[bad[0]].tolist()}")
    return mass_array, position_array


def _point_mass_inertia(masses: FloatArray, offsets: FloatArray) -> FloatArray:
    """Inertia tensor (kg*m^2) of point masses at ``offsets`` (n, 3) from the reference point."""
    weighted = offsets * masses[:, None]
    second_moment = offsets.T @ weighted  # sum_i m_i d_i d_i^T
    tensor: FloatArray = np.trace(second_moment) * np.eye(3) - second_moment
    return 0.5 * (tensor + tensor.T)


def parallel_axis_shift(inertia_com: ArrayLike, mass: float, offset: ArrayLike) -> FloatArray:
    """Inertia tensor about a point displaced by ``offset`` from the centre of mass.

    ``I_p = I_com + mass * (|s|^2 E - s s^T)`` with ``s = offset`` (m, from the centre of mass
    to the new point; the sign does not matter). ``inertia_com`` (3, 3) is in kg*m^2 and
    ``mass`` in kg (> 0). Returns a new (3, 3) array in the same axes.
    """
    tensor = validation.finite_array("inertia_com", inertia_com, (3, 3))
    mass = validation.positive_scalar("mass", mass)
    shift = validation.finite_vector("offset", offset)
    return tensor + mass * (float(shift @ shift) * np.eye(3) - np.outer(shift, shift))


def inertia_about_center_of_mass(inertia: ArrayLike, mass: float, offset: ArrayLike) -> FloatArray:
    """Inertia tensor about the centre of mass from the one about a point ``offset`` from it.

    The inverse of :func:`parallel_axis_shift`: ``I_com = I_p - mass * (|s|^2 E - s s^T)``
    (a gravity scene's tensor is about the pivot, its /tf_static and ~/mass_properties are
    about the centre of mass). Units and axes as there.

    >>> inertia_about_center_of_mass(parallel_axis_shift(np.eye(3), 2.0, (0.0, 0.0, 0.5)), 2.0, (0.0, 0.0, 0.5))
    array([[1., 0., 0.],
           [0., 1., 0.],
           [0., 0., 1.]])
    """
    tensor: FloatArray = np.asarray(inertia, dtype=float)
    return tensor - parallel_axis_shift(tensor * 0.0, mass, offset)


def _symmetry_label(moments: np.ndarray, point_scale: float) -> str:
    """Label of ascending principal moments.

    Moments are compared relative to the largest one. ``point_scale`` (kg*m^2) is the size
    rounding errors are relative to (total mass times the squared distance of the farthest
    mass from the frame origin): coincident masses leave moments of order eps * point_scale
    rather than exact zeros.
    """
    if moments[2] <= SYMMETRY_RTOL * point_scale:
        return "point"
    tol = SYMMETRY_RTOL * moments[2]
    low_equal = moments[1] - moments[0] <= tol
    high_equal = moments[2] - moments[1] <= tol
    if moments[0] <= tol and high_equal:
        return "linear"
    if low_equal and high_equal:
        return "spherical"
    if low_equal or high_equal:
        return "symmetric"
    return "asymmetric"


def principal_frame(inertia_com: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (ascending, kg*m^2) and axes (columns, det = +1) of an inertia tensor.

    Rounding can leave the zero moment of a linear or point body slightly negative; it is
    clamped to 0 so no negative moment leaves this function.
    """
    tensor = validation.finite_array("inertia_com", inertia_com, (3, 3))
    moments, axes = np.linalg.eigh(0.5 * (tensor + tensor.T))
    moments = np.clip(moments, 0.0, None)
    if np.linalg.det(axes) < 0.0:
        # eigh returns an orthonormal basis of either handedness; flipping one axis fixes that
        axes[:, 2] = -axes[:, 2]
    return moments, axes


def principal_orientation(principal_axes: ArrayLike) -> np.ndarray:
    """Quaternion (x, y, z, w), scalar-last, of the rotation principal frame -> input frame.

    ``principal_axes`` is the (3, 3) rotation matrix whose columns are the principal axes
    (as in :class:`MassProperties`). The sign is chosen with ``w >= 0``.
    """
    matrix = np.asarray(principal_axes, dtype=float)
    if matrix.shape != (3, 3):
        raise ValueError(f"principal_axes must have shape (3, 3), got shape {matrix.shape}")
    if np.linalg.det(matrix) <= 0.0:
        raise ValueError("principal_axes must be a proper rotation (det = +1)")
    quat = Rotation.from_matrix(matrix).as_quat()
    return -quat if quat[3] < 0.0 else quat


def principal_frame_pose(
    inertia_com: ArrayLike, center_of_mass: ArrayLike = (0.0, 0.0, 0.0)
) -> tuple[np.ndarray, np.ndarray] | None:
    """Pose of the principal-axes frame in the body frame, or None where the two coincide.

    The principal frame has its origin at the centre of mass (m, body frame) and its axes
    along the principal axes of ``inertia_com`` (kg*m^2, about the centre of mass, body
    axes), ascending moments. Returns (translation (3,) m, quaternion (4,) x y z w,
    principal -> body). A diagonal tensor (off-diagonal terms within ``SYMMETRY_RTOL`` of the
    largest moment) already has principal body axes: the rotation is then the identity,
    whatever the order of the moments. None when, in addition, the centre of mass is the
    body origin.
    """
    tensor = validation.finite_array("inertia_com", inertia_com, (3, 3))
    offset = validation.finite_vector("center_of_mass", center_of_mass)
    off_diagonal = np.abs(tensor - np.diag(np.diag(tensor))).max()
    if off_diagonal <= SYMMETRY_RTOL * np.abs(np.diag(tensor)).max():
        if not offset.any():
            return None
        return offset.copy(), np.array([0.0, 0.0, 0.0, 1.0])
    _, axes = principal_frame(tensor)
    return offset.copy(), principal_orientation(axes)


def mass_properties(masses: ArrayLike, positions: ArrayLike, origin: ArrayLike = (0.0, 0.0, 0.0)) -> MassProperties:
    """Mass properties of point masses.

    Parameters
    ----------
    masses : array_like, shape (n,)
        kg, each finite and > 0; n >= 1.
    positions : array_like, shape (n, 3)
        m, finite, in one right-handed frame.
    origin : array_like, shape (3,)
        m, the point (same frame) about which ``inertia_origin`` is computed.

    Returns
    -------
    MassProperties

    Raises
    ------
    ValueError
        Naming the argument and index of the first invalid entry, or the result that
        overflows (finite inputs can still give an infinite total mass or tensor: every
        result is finite or refused).
    """
    mass_array, position_array = validate_point_masses(masses, positions)
    origin_vector = validation.finite_vector("origin", origin)
    with np.errstate(all="ignore"):  # overflow is checked on the results below, never warned
        props = _mass_properties(mass_array, position_array, origin_vector)
    _check_finite(principal_moments=props.principal_moments, principal_axes=props.principal_axes)
    return props


def _check_finite(**results: Any) -> None:
    for name, value in results.items():
        if not np.all(np.isfinite(value)):
            raise ValueError(
                f"{name} overflows (not finite) for these masses and positions: "
                "scale the units (e.g. tonnes, km) so that sums of m * r^2 stay below 1e308"
            )


def _mass_properties(mass_array: np.ndarray, position_array: np.ndarray, origin_vector: np.ndarray) -> MassProperties:
    total_mass = float(np.sum(mass_array))
    center_of_mass = (mass_array @ position_array) / total_mass
    inertia_com = _point_mass_inertia(mass_array, position_array - center_of_mass)
    # Computed directly (not by the parallel-axis shift) so each tensor has its own rounding;
    # the tests check the theorem between the two.
    inertia_origin = _point_mass_inertia(mass_array, position_array - origin_vector)
    _check_finite(
        total_mass=total_mass, center_of_mass=center_of_mass, inertia_origin=inertia_origin, inertia_com=inertia_com
    )
    principal_moments, principal_axes = principal_frame(inertia_com)
    return MassProperties(
        total_mass=total_mass,
        center_of_mass=center_of_mass,
        origin=origin_vector,
        inertia_origin=inertia_origin,
        inertia_com=inertia_com,
        principal_moments=principal_moments,
        principal_axes=principal_axes,
        symmetry=_symmetry_label(principal_moments, total_mass * float(np.max(np.sum(position_array**2, axis=1)))),
    )


#: Longest side, m, of the box drawn for a body whose scene gives no mass (only its proportions are known).
NOMINAL_BOX_SIZE = 1.0


def equivalent_box(principal_moments: ArrayLike, mass: float | None = None) -> np.ndarray:
    """Sides (a, b, c), m, of the uniform box with these principal moments, along the principal axes.

    A uniform box of mass m and sides a, b, c has ``I1 = m (b^2 + c^2) / 12`` (cyclic), so
    ``a^2 = 6 (I2 + I3 - I1) / m``. Without a mass (None or 0) the proportions are the same and
    the box is scaled so that its longest side is :data:`NOMINAL_BOX_SIZE`. A side that the
    triangle inequality makes zero (a rod, a flat plate) stays zero.

    >>> [round(float(s), 12) for s in equivalent_box([5.0, 5.0, 2.0], mass=12.0)]
    [1.0, 1.0, 2.0]
    """
    moments = validation.finite_vector("principal_moments", principal_moments)
    i1, i2, i3 = moments
    squares = np.clip(6.0 * np.array([i2 + i3 - i1, i3 + i1 - i2, i1 + i2 - i3]), 0.0, None)
    if mass:
        return np.sqrt(squares / mass)
    sides = np.sqrt(squares)
    longest = sides.max()
    return sides * (NOMINAL_BOX_SIZE / longest) if longest > 0.0 else np.full(3, NOMINAL_BOX_SIZE)
