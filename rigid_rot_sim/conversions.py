"""Conversions between ROS 2 messages and the numpy values of the core: the only place for them.

Every function here is pure (no node, no I/O) and keeps units and frames unchanged: ROS
messages carry SI units (REP 103) and quaternions are (x, y, z, w) on both sides.
"""

from __future__ import annotations

import numpy as np
from geometry_msgs.msg import Inertia, Point, Quaternion
from rigid_rot_msgs.srv import ComputeInertia

from rigid_rot_sim.core.inertia import MassProperties, principal_orientation


def point_to_array(point: Point) -> np.ndarray:
    """geometry_msgs/Point -> ndarray (3,), m."""
    return np.array([point.x, point.y, point.z], dtype=float)


def array_to_point(vector: np.ndarray) -> Point:
    """ndarray (3,) -> geometry_msgs/Point, m."""
    x, y, z = (float(value) for value in np.asarray(vector, dtype=float).reshape(3))
    return Point(x=x, y=y, z=z)


def array_to_quaternion(quat_xyzw: np.ndarray) -> Quaternion:
    """ndarray (4,) scalar-last -> geometry_msgs/Quaternion (same order, no renormalisation)."""
    x, y, z, w = (float(value) for value in np.asarray(quat_xyzw, dtype=float).reshape(4))
    return Quaternion(x=x, y=y, z=z, w=w)


def matrix_to_row_major(matrix: np.ndarray) -> np.ndarray:
    """ndarray (3, 3) -> ndarray (9,) row-major, for the float64[9] fields."""
    return np.ascontiguousarray(matrix, dtype=np.float64).reshape(9)


def row_major_to_matrix(values) -> np.ndarray:
    """float64[9] field, row-major -> ndarray (3, 3)."""
    return np.asarray(values, dtype=float).reshape(3, 3)


def mass_properties_to_inertia_msg(props: MassProperties) -> Inertia:
    """The standard geometry_msgs/Inertia: mass, centre of mass and the tensor about it."""
    tensor = props.inertia_com
    com = props.center_of_mass
    msg = Inertia(m=float(props.total_mass))
    msg.com.x, msg.com.y, msg.com.z = (float(value) for value in com)
    msg.ixx, msg.ixy, msg.ixz = float(tensor[0, 0]), float(tensor[0, 1]), float(tensor[0, 2])
    msg.iyy, msg.iyz, msg.izz = float(tensor[1, 1]), float(tensor[1, 2]), float(tensor[2, 2])
    return msg


def compute_inertia_request_to_arrays(request: ComputeInertia.Request) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ComputeInertia request -> (masses (n,) kg, positions (n, 3) m, origin (3,) m).

    No validation here beyond the message types: mismatched lengths come out as arrays of
    different lengths, for the core's validation to name.
    """
    masses = np.asarray(request.masses, dtype=float).reshape(-1)
    positions = np.array([[p.x, p.y, p.z] for p in request.positions], dtype=float).reshape(-1, 3)
    return masses, positions, point_to_array(request.origin)


def fill_compute_inertia_response(
    response: ComputeInertia.Response, props: MassProperties
) -> ComputeInertia.Response:
    """Write every result field of a ComputeInertia response from ``props``; returns it.

    ``success`` and ``message`` are left to the caller.
    """
    response.total_mass = float(props.total_mass)
    response.center_of_mass = array_to_point(props.center_of_mass)
    response.inertia_origin = matrix_to_row_major(props.inertia_origin)
    response.inertia_com = matrix_to_row_major(props.inertia_com)
    response.principal_moments = np.asarray(props.principal_moments, dtype=np.float64).reshape(3)
    response.principal_axes = matrix_to_row_major(props.principal_axes)
    response.principal_orientation = array_to_quaternion(principal_orientation(props.principal_axes))
    response.symmetry = props.symmetry
    response.inertia = mass_properties_to_inertia_msg(props)
    return response


def arrays_to_compute_inertia_request(
    masses: np.ndarray, positions: np.ndarray, origin=(0.0, 0.0, 0.0), frame_id: str = ""
) -> ComputeInertia.Request:
    """(masses (n,) kg, positions (n, 3) m, origin (3,) m, frame_id) -> ComputeInertia request."""
    request = ComputeInertia.Request()
    request.masses = [float(m) for m in np.asarray(masses, dtype=float).reshape(-1)]
    request.positions = [array_to_point(p) for p in np.asarray(positions, dtype=float).reshape(-1, 3)]
    request.origin = array_to_point(origin)
    request.frame_id = frame_id
    return request


def compute_inertia_response_to_mass_properties(
    response: ComputeInertia.Response, origin
) -> MassProperties:
    """A successful ComputeInertia response -> MassProperties (``origin`` as in the request, m)."""
    return MassProperties(
        total_mass=float(response.total_mass),
        center_of_mass=point_to_array(response.center_of_mass),
        origin=np.asarray(origin, dtype=float).reshape(3),
        inertia_origin=row_major_to_matrix(response.inertia_origin),
        inertia_com=row_major_to_matrix(response.inertia_com),
        principal_moments=np.asarray(response.principal_moments, dtype=float).reshape(3),
        principal_axes=row_major_to_matrix(response.principal_axes),
        symmetry=str(response.symmetry),
    )
