"""Measurements from a bag: an MCAP file or a rosbag2 directory, ours or anyone's.

Messages are decoded from the definitions stored in the file (``ros2msg`` schemas, read by
:class:`rigid_rot_sim.recording.reader.Bag`: a file or a rosbag2 directory; mcap-ros2-support), so no
ROS installation is needed. Times are header stamps (the log time when a stamp is zero), in s from the first
sample of the rate source.

Inputs (:class:`BagInputs`): the rate from ``sensor_msgs/Imu`` (``angular_velocity``; its
``orientation`` too unless ``orientation_covariance[0] == -1``), ``geometry_msgs/Vector3Stamped``
or our ``RigidBodyState``; torque from ``geometry_msgs/WrenchStamped`` topics (summed), each
command held until the next on its topic, its ``header.frame_id`` naming the body frame or the
world frame. A recording of this package needs no options: the gyro (``~/imu``) when the scene
had one, else the state's rate; the state's ``torque_body`` (the torque applied over the step
before each state, so held backwards) and its attitude.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from rigid_rot_sim.identify.data import Measurements, PiecewiseTorque, world_torque_in_body
from rigid_rot_sim.recording.reader import Bag, RecordedMessage
from rigid_rot_sim.scene.scene import parse_scene_text

IMU = "sensor_msgs/msg/Imu"
VECTOR3_STAMPED = "geometry_msgs/msg/Vector3Stamped"
STATE = "rigid_rot_msgs/msg/RigidBodyState"
WRENCH = "geometry_msgs/msg/WrenchStamped"
#: frame_id values taken as the body frame / the world frame besides the ones the user names.
BODY_FRAMES = ("base_link", "body")
WORLD_FRAMES = ("odom", "world", "map")


@dataclass(frozen=True)
class BagInputs:
    """Which topics to read; all None: a recording of this package, understood without options."""

    imu: str | None = None
    angular_velocity: str | None = None
    state: str | None = None
    torque: tuple[str, ...] = ()
    body_frames: tuple[str, ...] = BODY_FRAMES
    world_frames: tuple[str, ...] = WORLD_FRAMES


@dataclass(frozen=True)
class BagData:
    """What a bag held: the measurements (whole bag), where they came from, the recorded scene if any."""

    measurements: Measurements
    sources: dict[str, str]
    scene_text: str | None = None
    topics: dict[str, str] = field(default_factory=dict)


def _stamp_ns(message: RecordedMessage, decoded: Any) -> int:
    header = getattr(decoded, "header", None)
    if header is not None:
        ns = int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)
        if ns > 0:
            return ns
    return message.log_time_ns


def _vector(v: Any) -> list[float]:
    return [float(v.x), float(v.y), float(v.z)]


def _rate_samples(bag: Bag, topic: str, kind: str) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, str, np.ndarray]:
    """(stamps ns, omega (n, 3), orientation (n, 4) or None, frame_id, torque_body (n, 3) of a state)."""
    stamps, omega, orientation, torque = [], [], [], []
    has_orientation = kind in ("imu", "state")
    frame = ""
    for message, msg in bag.decoded(topic):
        stamps.append(_stamp_ns(message, msg))
        if kind == "imu":
            omega.append(_vector(msg.angular_velocity))
            has_orientation = has_orientation and float(msg.orientation_covariance[0]) != -1.0
            q = msg.orientation
        elif kind == "state":
            omega.append(_vector(msg.angular_velocity_body))
            torque.append(_vector(msg.torque_body))
            q = msg.orientation
        else:
            omega.append(_vector(msg.vector))
        if has_orientation:
            orientation.append([float(q.x), float(q.y), float(q.z), float(q.w)])
        frame = frame or (msg.child_frame_id if kind == "state" else msg.header.frame_id)
    if not stamps:
        raise ValueError(f"{topic}: no messages")
    order = np.argsort(np.asarray(stamps), kind="stable")
    t = np.asarray(stamps, dtype=np.int64)[order]
    keep = np.append(True, np.diff(t) > 0)  # a repeated stamp (a forced publish) adds nothing
    q_array = np.asarray(orientation, dtype=float)[order][keep] if has_orientation and orientation else None
    torque_array = np.asarray(torque, dtype=float).reshape(-1, 3)[order][keep] if torque else np.zeros((0, 3))
    return t[keep], np.asarray(omega, dtype=float)[order][keep], q_array, frame, torque_array


def _commands(
    bag: Bag, topic: str, body: Sequence[str], world: Sequence[str]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(stamps ns, torque (m, 3), is_world (m,)) of a WrenchStamped topic."""
    stamps, values, is_world = [], [], []
    for message, msg in bag.decoded(topic):
        frame = msg.header.frame_id.lstrip("/")
        if frame in body:
            is_world.append(False)
        elif frame in world:
            is_world.append(True)
        else:
            raise ValueError(
                f"--torque {topic}: unknown frame {frame!r} (body frame: {', '.join(body)}; "
                f"world frame: {', '.join(world)}; name others with --body-frame/--world-frame)"
            )
        stamps.append(_stamp_ns(message, msg))
        values.append(_vector(msg.wrench.torque))
    order = np.argsort(np.asarray(stamps, dtype=np.int64), kind="stable")
    return (
        np.asarray(stamps, dtype=np.int64)[order],
        np.asarray(values, dtype=float).reshape(-1, 3)[order],
        np.asarray(is_world, dtype=bool)[order],
    )


def read_bag(path: str | os.PathLike[str], inputs: BagInputs = BagInputs()) -> BagData:
    """The whole bag's measurements (cut a window with :meth:`Measurements.window`).

    :raises ValueError: a missing topic (the message lists the bag's topics and types), a topic of
        the wrong type, an unknown torque frame, world-frame torque without an attitude source.
    """
    bag = Bag(path)
    ours = inputs.imu is None and inputs.angular_velocity is None and inputs.state is None and not inputs.torque
    scene = bag.metadata.get("scene", {}).get("text")
    if ours:
        return _read_ours(bag, scene)
    named = [(o, t) for o, t in (("--imu", inputs.imu), ("--angular-velocity", inputs.angular_velocity),
                                  ("--state", inputs.state)) if t]  # fmt: skip
    if len(named) != 1:
        raise ValueError("name exactly one rate source: --imu, --angular-velocity or --state")
    option, topic = named[0]
    kind = {"--imu": "imu", "--angular-velocity": "vector", "--state": "state"}[option]
    bag.require(topic, {"imu": [IMU], "vector": [VECTOR3_STAMPED], "state": [STATE]}[kind], option)
    stamps, omega, orientation, frame, _ = _rate_samples(bag, topic, kind)
    t0 = stamps[0]
    t = (stamps - t0) * 1e-9
    body = tuple(inputs.body_frames) + ((frame,) if frame else ())
    schedules = []
    for torque_topic in inputs.torque:
        bag.require(torque_topic, [WRENCH], "--torque")
        c_stamps, values, is_world = _commands(bag, torque_topic, body, inputs.world_frames)
        times = (c_stamps - t0) * 1e-9
        body_part = PiecewiseTorque(times, np.where(is_world[:, None], 0.0, values))
        schedules.append(body_part)
        if np.any(is_world):
            if orientation is None:
                raise ValueError(
                    f"--torque {torque_topic}: torque in the world frame needs an attitude; {topic} has none "
                    "(use an Imu with orientation or --state)"
                )
            world_values = np.where(is_world[:, None], values, 0.0)
            schedules.append(world_torque_in_body(times, world_values, t, orientation, t[-1]))
    sources = {"rate": topic, "torque": ", ".join(inputs.torque) or "none"}
    return BagData(
        Measurements(t, omega, _sum(schedules), orientation),
        sources,
        scene,
        {n: x.type_name for n, x in bag.topics.items()},
    )


def _read_ours(bag: Bag, scene: str | None) -> BagData:
    state_topic = bag.find_topic("state", STATE)
    if state_topic is None or "rigid_rot_sim" not in bag.metadata and scene is None:
        raise ValueError(
            f"{bag.path} is not a rigid_rot_sim recording: name the inputs (--imu, --angular-velocity or "
            f"--state, and --torque); it has {bag.listing()}"
        )
    s_stamps, s_omega, s_q, _, torque = _rate_samples(bag, state_topic, "state")
    imu_topic = bag.find_topic("imu", IMU)
    gyro = scene is not None and parse_scene_text(scene, source="<recorded scene>").sensors.gyro is not None
    if imu_topic is not None and gyro:
        stamps, omega, _, _, _ = _rate_samples(bag, imu_topic, "imu")
        sources = {"rate": imu_topic, "torque": f"{state_topic} torque_body", "orientation": state_topic}
    else:
        stamps, omega = s_stamps, s_omega
        sources = {"rate": state_topic, "torque": f"{state_topic} torque_body", "orientation": state_topic}
    t0 = stamps[0]
    t = (stamps - t0) * 1e-9
    ts = (s_stamps - t0) * 1e-9
    # torque_body of the state at t_k is the torque over the step before t_k: from the previous state on
    starts = np.concatenate([[ts[0] - (ts[1] - ts[0]) if ts.shape[0] > 1 else ts[0]], ts[:-1]])
    schedule = PiecewiseTorque(starts, torque)
    # the attitude at the rate samples (the state's, interpolated where the streams differ)
    orientation = None
    if s_q is not None and ts.shape[0] > 1:
        orientation = Slerp(ts, Rotation.from_quat(s_q))(np.clip(t, ts[0], ts[-1])).as_quat()
    return BagData(
        Measurements(t, omega, schedule, orientation), sources, scene, {n: x.type_name for n, x in bag.topics.items()}
    )


def _sum(schedules: list[PiecewiseTorque]) -> PiecewiseTorque:
    if not schedules:
        return PiecewiseTorque.none()
    if len(schedules) == 1:
        return schedules[0]
    times = np.unique(np.concatenate([s.times for s in schedules]))
    return PiecewiseTorque(times, sum((s.at(times) for s in schedules), np.zeros((times.shape[0], 3))))
