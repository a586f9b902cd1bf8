"""Conversions between ROS 2 messages and the numpy values of the core: the only place for them.

The readers (message -> numpy) need no ROS and live in :mod:`rigid_rot_sim.message_fields`,
so that code reading recordings without ROS (resim, plot) uses the same functions; they are
imported here, so the node finds every conversion in this one module.

Every function here is pure (no node, no I/O) and keeps units and frames unchanged: ROS
messages carry SI units (REP 103) and quaternions are (x, y, z, w) on both sides.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import (
    Inertia,
    InertiaStamped,
    Point,
    PoseWithCovarianceStamped,
    Quaternion,
    QuaternionStamped,
    TransformStamped,
    Vector3,
    Vector3Stamped,
)
from nav_msgs.msg import Odometry
from numpy.typing import ArrayLike
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu, JointState, MagneticField
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from rigid_rot_msgs.msg import (  # generated, untyped
    HeavyTopState,
    RejectedCommand,
    RigidBodyState,
    TorqueBreakdown,
    WheelTorques,
)
from rigid_rot_msgs.srv import ComputeInertia  # generated, untyped
from rigid_rot_sim.core import quaternion
from rigid_rot_sim.core.inertia import MassProperties, principal_orientation
from rigid_rot_sim.message_fields import (  # noqa: F401 (the readers are part of this module's API)
    quaternion_to_array,
    state_to_arrays,
    time_to_seconds,
    vector3_to_array,
)
from rigid_rot_sim.run.body_view import BOX_COLOR, MOMENTUM_COLOR, OMEGA_COLOR, BodyView

if TYPE_CHECKING:
    from rigid_rot_sim.run.simulator import StateSnapshot


def point_to_array(point: Point) -> np.ndarray:
    """geometry_msgs/Point -> ndarray (3,), m."""
    return np.array([point.x, point.y, point.z], dtype=float)


def array_to_point(vector: ArrayLike) -> Point:
    """ndarray (3,) -> geometry_msgs/Point, m."""
    x, y, z = (float(value) for value in np.asarray(vector, dtype=float).reshape(3))
    return Point(x=x, y=y, z=z)


def array_to_quaternion(quat_xyzw: ArrayLike) -> Quaternion:
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


def fill_compute_inertia_response(response: ComputeInertia.Response, props: MassProperties) -> ComputeInertia.Response:
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


def compute_inertia_response_to_mass_properties(response: ComputeInertia.Response, origin) -> MassProperties:
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


# --------------------------------------------------------------------- simulator (issue 4)
# Sim time is a float of seconds in the core and builtin_interfaces/Time on the wire; the
# conversion is exact to the nanosecond and deterministic (same float -> same stamp).


def seconds_to_time(seconds: float) -> Time:
    """Sim time (s, >= 0) -> builtin_interfaces/Time, rounded to the nanosecond."""
    return set_time(Time(), seconds)


def set_time(stamp: Time, seconds: float) -> Time:
    """Write sim time (s, >= 0) into a builtin_interfaces/Time in place, rounded to the nanosecond; returns it."""
    stamp.sec, stamp.nanosec = divmod(int(round(float(seconds) * 1e9)), 1_000_000_000)
    return stamp


def array_to_vector3(values) -> Vector3:
    """ndarray (3,) -> geometry_msgs/Vector3."""
    x, y, z = (float(value) for value in np.asarray(values, dtype=float).reshape(3))
    return Vector3(x=x, y=y, z=z)


def torque_command_from_msg(msg) -> tuple[np.ndarray, np.ndarray | None, str, float]:
    """WrenchStamped or Vector3Stamped -> (torque N*m, force N or None, frame_id, stamp s).

    A Vector3Stamped carries the torque itself; a WrenchStamped its ``wrench.torque`` and
    ``wrench.force`` (the simulator rejects a non-zero force). Values are passed through
    unvalidated: the simulator names what is wrong.
    """
    if hasattr(msg, "wrench"):
        torque = vector3_to_array(msg.wrench.torque)
        force = vector3_to_array(msg.wrench.force)
    else:
        torque = vector3_to_array(msg.vector)
        force = None
    return torque, force, msg.header.frame_id, time_to_seconds(msg.header.stamp)


def _set_vector3(vector, values) -> None:
    """Write a length-3 array into a geometry_msgs/Vector3 in place (cheaper than a new message)."""
    vector.x, vector.y, vector.z = values.tolist() if isinstance(values, np.ndarray) else (float(v) for v in values)


def fill_rigid_body_state(
    msg: RigidBodyState, snapshot: StateSnapshot, world_frame: str, body_frame: str
) -> RigidBodyState:
    """Write every field of a RigidBodyState from a snapshot (stamp: sim time); returns it."""
    set_time(msg.header.stamp, snapshot.t)
    msg.header.frame_id = world_frame
    msg.child_frame_id = body_frame
    q = msg.orientation
    q.x, q.y, q.z, q.w = snapshot.orientation.tolist()
    _set_vector3(msg.angular_velocity_body, snapshot.angular_velocity_body)
    _set_vector3(msg.angular_velocity_world, snapshot.angular_velocity_world)
    _set_vector3(msg.angular_momentum_body, snapshot.angular_momentum_body)
    _set_vector3(msg.angular_momentum_world, snapshot.angular_momentum_world)
    _set_vector3(msg.torque_body, snapshot.torque_body)
    msg.kinetic_energy = float(snapshot.kinetic_energy)
    msg.potential_energy = float(snapshot.potential_energy)
    msg.energy_drift = float(snapshot.energy_drift)
    msg.angular_momentum_drift = float(snapshot.angular_momentum_drift)
    msg.digest = snapshot.digest
    return msg


def snapshot_to_state(snapshot: StateSnapshot, world_frame: str, body_frame: str) -> RigidBodyState:
    """StateSnapshot -> rigid_rot_msgs/RigidBodyState."""
    return fill_rigid_body_state(RigidBodyState(), snapshot, world_frame, body_frame)


def snapshot_to_orientation(snapshot: StateSnapshot, world_frame: str) -> QuaternionStamped:
    """Attitude body -> world, header frame_id = world frame."""
    msg = QuaternionStamped()
    q = msg.quaternion
    q.x, q.y, q.z, q.w = snapshot.orientation.tolist()
    msg.header.stamp = seconds_to_time(snapshot.t)
    msg.header.frame_id = world_frame
    return msg


def vector_stamped(values, t: float, frame_id: str) -> Vector3Stamped:
    """ndarray (3,) at sim time t (s) in frame_id -> Vector3Stamped."""
    return fill_vector_stamped(Vector3Stamped(), values, t, frame_id)


def fill_vector_stamped(msg: Vector3Stamped, values, t: float, frame_id: str) -> Vector3Stamped:
    """Write every field of a Vector3Stamped: ndarray (3,) at sim time t (s) in frame_id; returns it."""
    _set_vector3(msg.vector, values)
    set_time(msg.header.stamp, t)
    msg.header.frame_id = frame_id
    return msg


def snapshot_to_top_state(snapshot: StateSnapshot, world_frame: str) -> HeavyTopState:
    """Heavy-top Euler angles (z-x-z, rad) and conserved momenta of a gravity scene's snapshot."""
    if snapshot.euler_zxz is None or snapshot.p_phi is None or snapshot.p_psi is None:
        raise ValueError("snapshot has no heavy-top quantities (not a gravity scene)")
    phi, theta, psi = (float(v) for v in snapshot.euler_zxz)
    msg = HeavyTopState(
        precession=phi,
        nutation=theta,
        spin=psi,
        p_phi=float(snapshot.p_phi or 0.0),
        p_psi=float(snapshot.p_psi or 0.0),
        energy=float(snapshot.energy),
    )
    msg.header.stamp = seconds_to_time(snapshot.t)
    msg.header.frame_id = world_frame
    return msg


def inertia_stamped(mass: float, center_of_mass, inertia_com, t: float, body_frame: str) -> InertiaStamped:
    """Mass (kg; 0 when the scene gives none), centre of mass (m, body frame) and tensor about it."""
    tensor = np.asarray(inertia_com, dtype=float)
    msg = InertiaStamped()
    msg.header.stamp = seconds_to_time(t)
    msg.header.frame_id = body_frame
    msg.inertia.m = float(mass)
    msg.inertia.com.x, msg.inertia.com.y, msg.inertia.com.z = (float(v) for v in np.asarray(center_of_mass).reshape(3))
    msg.inertia.ixx, msg.inertia.ixy, msg.inertia.ixz = float(tensor[0, 0]), float(tensor[0, 1]), float(tensor[0, 2])
    msg.inertia.iyy, msg.inertia.iyz, msg.inertia.izz = float(tensor[1, 1]), float(tensor[1, 2]), float(tensor[2, 2])
    return msg


def clock_message(t: float) -> Clock:
    """rosgraph_msgs/Clock at sim time t (s)."""
    return Clock(clock=seconds_to_time(t))


def transform_stamped(
    snapshot: StateSnapshot, world_frame: str, body_frame: str, position: ArrayLike | None = None
) -> TransformStamped:
    """world -> body transform of the attitude; translation ``position`` (m, world frame: the centre of mass on
    its orbit, ECI), else none (the body turns about a fixed point)."""
    msg = TransformStamped()
    msg.header.stamp = seconds_to_time(snapshot.t)
    msg.header.frame_id = world_frame
    msg.child_frame_id = body_frame
    if position is not None:
        msg.transform.translation = array_to_vector3(position)
    msg.transform.rotation = array_to_quaternion(snapshot.orientation)
    return msg


def earth_transform(t: float, world_frame: str, earth_frame: str, earth_rotation_angle: float) -> TransformStamped:
    """world (ECI) -> ``earth_frame`` (ECEF, REP 105's ``earth``): a turn by the Earth rotation angle (rad) about z."""
    msg = TransformStamped()
    msg.header.stamp = seconds_to_time(t)
    msg.header.frame_id = world_frame
    msg.child_frame_id = earth_frame
    msg.transform.rotation = array_to_quaternion(quaternion.exp_rotation_vector((0.0, 0.0, earth_rotation_angle)))
    return msg


def orbit_odometry(
    snapshot: StateSnapshot, position: ArrayLike, velocity: ArrayLike, world_frame: str, body_frame: str
) -> Odometry:
    """nav_msgs/Odometry of the body on its orbit: position (m) and attitude in the world frame (ECI); the twist
    in the body (child) frame, as Odometry defines it: the orbital velocity rotated into the body axes (m/s)
    and the angular velocity (rad/s). Covariances zero: the truth."""
    msg = Odometry()
    msg.header.stamp = seconds_to_time(snapshot.t)
    msg.header.frame_id = world_frame
    msg.child_frame_id = body_frame
    msg.pose.pose.position = array_to_point(position)
    q = msg.pose.pose.orientation
    q.x, q.y, q.z, q.w = snapshot.orientation.tolist()
    _set_vector3(msg.twist.twist.linear, quaternion.rotate_inverse(snapshot.orientation, np.asarray(velocity)))
    _set_vector3(msg.twist.twist.angular, snapshot.angular_velocity_body)
    return msg


def magnetic_field_message(field, t: float, frame_id: str, covariance: np.ndarray) -> MagneticField:
    """sensor_msgs/MagneticField of ``field`` (T, in ``frame_id``) at sim time t (s); ``covariance`` 3x3 (T^2)."""
    msg = MagneticField()
    msg.header.stamp = seconds_to_time(t)
    msg.header.frame_id = frame_id
    _set_vector3(msg.magnetic_field, field)
    msg.magnetic_field_covariance = np.asarray(covariance, dtype=float).reshape(9).tolist()
    return msg


def static_transform(translation, quaternion, parent_frame: str, child_frame: str) -> TransformStamped:
    """A fixed parent -> child transform (translation m, quaternion x y z w child -> parent), stamped t = 0.

    For /tf_static: tf2 ignores the stamp of a static transform.
    """
    msg = TransformStamped()
    msg.header.frame_id = parent_frame
    msg.child_frame_id = child_frame
    msg.transform.translation = array_to_vector3(translation)
    msg.transform.rotation = array_to_quaternion(quaternion)
    return msg


def rejected_command(source: str, reason: str, t: float, frame_id: str, torque) -> RejectedCommand:
    """RejectedCommand at sim time t (s); ``torque`` as received (non-finite values kept)."""
    msg = RejectedCommand(source=source, reason=reason)
    msg.header.stamp = seconds_to_time(t)
    msg.header.frame_id = frame_id
    values = np.asarray(torque, dtype=float).reshape(3)
    msg.torque = Vector3(x=float(values[0]), y=float(values[1]), z=float(values[2]))
    return msg


# --------------------------------------------------------------------- RViz / estimator outputs
# The simulated values are exact (ground truth): every covariance diagonal carries the same
# ``variance`` (the node's ``ground_truth_variance`` parameter, tiny by default, so that an
# estimator's matrices stay invertible); off-diagonal terms are 0. All-zero covariances would
# mean "unknown" to sensor_msgs consumers, and -1 in element 0 means "not provided".


def _diagonal(size: int, variances) -> list[float]:
    """Row-major size x size covariance with ``variances`` (one per axis) on the diagonal."""
    values = [0.0] * (size * size)
    for i, variance in enumerate(variances):
        values[i * size + i] = float(variance)
    return values


def snapshot_to_imu(snapshot: StateSnapshot, body_frame: str, variance: float) -> Imu:
    """sensor_msgs/Imu of an ideal IMU at the body frame's origin.

    ``orientation``: body -> world attitude (x, y, z, w); ``angular_velocity``: rad/s in
    the body frame (header.frame_id); both with ``variance`` on their covariance
    diagonals (rad^2, (rad/s)^2). No linear acceleration is simulated: the field is zero
    and ``linear_acceleration_covariance[0] = -1`` (the message's "not provided").
    """
    msg = Imu()
    msg.header.stamp = seconds_to_time(snapshot.t)
    msg.header.frame_id = body_frame
    q = msg.orientation
    q.x, q.y, q.z, q.w = snapshot.orientation.tolist()
    _set_vector3(msg.angular_velocity, snapshot.angular_velocity_body)
    msg.orientation_covariance = _diagonal(3, [variance] * 3)
    msg.angular_velocity_covariance = _diagonal(3, [variance] * 3)
    msg.linear_acceleration_covariance = [-1.0] + [0.0] * 8
    return msg


def snapshot_to_odometry(snapshot: StateSnapshot, world_frame: str, body_frame: str, variance: float) -> Odometry:
    """nav_msgs/Odometry: attitude in the world frame, angular velocity in the body (child) frame.

    The body turns about a fixed point, so position and linear velocity are exactly zero;
    every pose and twist covariance diagonal entry is ``variance``.
    """
    msg = Odometry()
    msg.header.stamp = seconds_to_time(snapshot.t)
    msg.header.frame_id = world_frame
    msg.child_frame_id = body_frame
    q = msg.pose.pose.orientation
    q.x, q.y, q.z, q.w = snapshot.orientation.tolist()
    _set_vector3(msg.twist.twist.angular, snapshot.angular_velocity_body)
    msg.pose.covariance = _diagonal(6, [variance] * 6)
    msg.twist.covariance = _diagonal(6, [variance] * 6)
    return msg


def wheel_torques_from_msg(msg: WheelTorques) -> tuple[list[float], float]:
    """rigid_rot_msgs/WheelTorques -> (motor torques N*m, unvalidated; header stamp s, 0 = none)."""
    return [float(v) for v in msg.torques], time_to_seconds(msg.header.stamp)


def joint_command_from_msg(msg: JointState) -> tuple[list[str], list[float], list[float], list[float], float]:
    """sensor_msgs/JointState -> (names, positions, velocities, efforts, unvalidated; header stamp s, 0 = none)."""
    return (
        [str(n) for n in msg.name],
        [float(v) for v in msg.position],
        [float(v) for v in msg.velocity],
        [float(v) for v in msg.effort],
        time_to_seconds(msg.header.stamp),
    )


def snapshot_to_joint_state(snapshot: StateSnapshot, body_frame: str) -> JointState:
    """The reaction wheels as sensor_msgs/JointState: name, position = angle relative to the body (rad,
    unwrapped: continuous, as a controller that differentiates it needs), velocity = speed relative to
    the body (rad/s), effort = the motor torque acting (N*m)."""
    msg = JointState()
    msg.header.stamp = seconds_to_time(snapshot.t)
    msg.header.frame_id = body_frame
    msg.name = list(snapshot.wheel_names or ())
    msg.position = [float(v) for v in (snapshot.wheel_angles if snapshot.wheel_angles is not None else ())]
    msg.velocity = [float(v) for v in (snapshot.wheel_speeds if snapshot.wheel_speeds is not None else ())]
    msg.effort = [float(v) for v in (snapshot.wheel_torques if snapshot.wheel_torques is not None else ())]
    return msg


def snapshot_to_torque_breakdown(snapshot: StateSnapshot, body_frame: str) -> TorqueBreakdown:
    """Every torque on the body by source and their total (N*m, body frame) as rigid_rot_msgs/TorqueBreakdown."""
    msg = TorqueBreakdown()
    msg.header.stamp = seconds_to_time(snapshot.t)
    msg.header.frame_id = body_frame
    sources = snapshot.torque_sources or ()
    msg.names = [name for name, _ in sources]
    msg.torques = [array_to_vector3(vector) for _, vector in sources]
    msg.total = array_to_vector3(np.sum([v for _, v in sources], axis=0) if sources else np.zeros(3))
    return msg


#: Marker namespace and ids of ``~/markers`` (replaced in place every message).
MARKER_NAMESPACE = "rigid_rot_sim"
BOX_MARKER, OMEGA_MARKER, MOMENTUM_MARKER = range(3)
#: Smallest drawn side, m: a rod's or plate's zero side still renders.
_MIN_SIDE = 1e-3


def _marker(kind: int, marker_id: int, t: float, frame_id: str, color) -> Marker:
    marker = Marker(type=kind, id=marker_id, ns=MARKER_NAMESPACE, action=Marker.ADD, frame_locked=True)
    marker.header.stamp = seconds_to_time(t)
    marker.header.frame_id = frame_id
    marker.color = ColorRGBA(r=float(color[0]), g=float(color[1]), b=float(color[2]), a=float(color[3]))
    marker.pose.orientation.w = 1.0
    return marker


def _arrow(marker: Marker, tail, tip, view: BodyView) -> Marker:
    marker.points = [array_to_point(tail), array_to_point(tip)]
    marker.scale = Vector3(x=view.shaft_diameter, y=2.0 * view.shaft_diameter, z=view.head_size)
    return marker


def body_markers(view: BodyView, snapshot: StateSnapshot, world_frame: str, body_frame: str) -> MarkerArray:
    """``~/markers``: the inertia box and omega (body frame), L (world frame); see :mod:`.run.body_view`."""
    box = _marker(Marker.CUBE, BOX_MARKER, snapshot.t, body_frame, BOX_COLOR)
    box.pose.position = array_to_point(view.box_center)
    box.pose.orientation = array_to_quaternion(view.box_orientation)
    box.scale = array_to_vector3([max(side, _MIN_SIDE) for side in view.box_sides])
    omega = _arrow(
        _marker(Marker.ARROW, OMEGA_MARKER, snapshot.t, body_frame, OMEGA_COLOR),
        *view.omega_arrow(snapshot.angular_velocity_body),
        view,
    )
    momentum = _arrow(
        _marker(Marker.ARROW, MOMENTUM_MARKER, snapshot.t, world_frame, MOMENTUM_COLOR),
        *view.momentum_arrow(snapshot.angular_momentum_world),
        view,
    )
    momentum.frame_locked = False
    return MarkerArray(markers=[box, omega, momentum])


# --------------------------------------------------------------------- sensor models (issue 20)
# Readings of the scene's sensors (rigid_rot_sim.run.sensors), not the ground truth: their
# covariances are the models' own. A quantity a sensor does not measure is marked as such.

#: Variance (m^2) of the position block of ~/star_tracker: a star tracker measures no position.
UNMEASURED_POSITION_VARIANCE = 1e6


def gyro_to_imu(reading, t: float, body_frame: str, variance: float) -> Imu:
    """sensor_msgs/Imu of a gyro reading (rad/s, body frame) at sim time t (s).

    ``angular_velocity_covariance``: ``variance`` ((rad/s)^2) on the diagonal, the model's
    per-sample noise. A gyro gives no orientation and no linear acceleration: both
    covariances have -1 in element 0 (the message's "not provided"), the orientation is the
    identity.
    """
    msg = Imu()
    msg.header.stamp = seconds_to_time(t)
    msg.header.frame_id = body_frame
    msg.orientation.w = 1.0
    _set_vector3(msg.angular_velocity, reading)
    msg.orientation_covariance = [-1.0] + [0.0] * 8
    msg.angular_velocity_covariance = _diagonal(3, [variance] * 3)
    msg.linear_acceleration_covariance = [-1.0] + [0.0] * 8
    return msg


def star_tracker_pose(
    orientation: np.ndarray | Sequence[float], t: float, world_frame: str, covariance_body: np.ndarray
) -> PoseWithCovarianceStamped:
    """geometry_msgs/PoseWithCovarianceStamped of a star tracker attitude (x, y, z, w; body -> world).

    Position (0, 0, 0), not measured (variance ``UNMEASURED_POSITION_VARIANCE``). The rotation
    block is about the fixed axes (those of ``world_frame``), as PoseWithCovariance defines it:
    ``covariance_body`` (3x3, rad^2, the attitude error's about the body axes) rotated by the
    published attitude, R C R^T. (The error vector about the fixed axes is R(q) δθ = R(q_m) δθ
    for q_m = q ⊗ exp(δθ), so the published attitude rotates it exactly as the true one would.)
    """
    msg = PoseWithCovarianceStamped()
    msg.header.stamp = seconds_to_time(t)
    msg.header.frame_id = world_frame
    attitude = tuple(float(v) for v in orientation)
    q = msg.pose.pose.orientation
    q.x, q.y, q.z, q.w = attitude
    rotation = np.array([quaternion.rotate(attitude, axis) for axis in np.eye(3)]).T  # columns: body axes in world
    block = np.zeros((6, 6))
    block[:3, :3] = np.eye(3) * UNMEASURED_POSITION_VARIANCE
    block[3:, 3:] = rotation @ np.asarray(covariance_body, dtype=float).reshape(3, 3) @ rotation.T
    msg.pose.covariance = block.reshape(36).tolist()
    return msg
