"""Trajectories from truth we choose: a known full inertia tensor under known piecewise-constant
torques, integrated by scipy's DOP853 at tight tolerances (not by the code under test), then
read by a gyro with known white noise and bias; and rosbags (an independent writer) to put them
in MCAP files as a foreign robot's bag would.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

#: A full, non-diagonal, physical tensor (kg*m^2): principal moments about 0.018, 0.030, 0.041.
INERTIA = np.array([[0.020, 0.0015, -0.0020], [0.0015, 0.030, 0.0025], [-0.0020, 0.0025, 0.040]])


@dataclass(frozen=True)
class Truth:
    t: np.ndarray  # (n,) s
    omega: np.ndarray  # (n, 3) true rate, body
    q: np.ndarray  # (n, 4) body -> world
    command_times: np.ndarray  # (m,) s
    commands: np.ndarray  # (m, 3) N*m, in ``frame``
    frame: str  # "body" or "world"


def excitation(duration: float, period: float, amplitude: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Random steps: a new torque every ``period`` s, each axis uniform in +-amplitude (N*m)."""
    rng = np.random.default_rng(seed)
    times = np.arange(0.0, duration, period)
    return times, rng.uniform(-amplitude, amplitude, size=(times.shape[0], 3))


def simulate(
    inertia: np.ndarray,
    omega0: np.ndarray,
    duration: float,
    rate: float,
    command_times: np.ndarray,
    commands: np.ndarray,
    frame: str = "body",
    torque_bias: np.ndarray | None = None,
) -> Truth:
    """Euler's equations and the attitude, torque held between commands, sampled at ``rate`` Hz."""
    inv = np.linalg.inv(inertia)
    bias = np.zeros(3) if torque_bias is None else torque_bias

    def rhs(t: float, y: np.ndarray, tau: np.ndarray) -> np.ndarray:
        w, q = y[:3], y[3:]
        if frame == "world":
            body_tau = Rotation.from_quat(q).inv().apply(tau)
        else:
            body_tau = tau
        dw = inv @ (body_tau + bias - np.cross(w, inertia @ w))
        x, y_, z, s = q
        dq = 0.5 * np.array(
            [s * w[0] + y_ * w[2] - z * w[1], s * w[1] + z * w[0] - x * w[2], s * w[2] + x * w[1] - y_ * w[0],
             -(x * w[0] + y_ * w[1] + z * w[2])]
        )  # fmt: skip
        return np.concatenate([dw, dq])

    t = np.arange(int(round(duration * rate)) + 1) / rate
    edges = np.append(command_times, np.inf)
    pieces = [(-np.inf, edges[0], np.zeros(3))] + [(edges[j], edges[j + 1], commands[j]) for j in range(len(commands))]
    y = np.concatenate([omega0, [0.0, 0.0, 0.0, 1.0]])
    out = np.empty((t.shape[0], 7))
    now = 0.0
    for _, b, tau in pieces:
        end = min(b, t[-1])
        if end <= now:
            continue
        inside = (t >= now) & (t < end) | ((t == end) & (end == t[-1]))
        sol = solve_ivp(rhs, (now, end), y, method="DOP853", rtol=1e-13, atol=1e-16, args=(tau,), dense_output=True)
        out[inside] = sol.sol(t[inside]).T
        y, now = sol.y[:, -1], end
    q = out[:, 3:] / np.linalg.norm(out[:, 3:], axis=1, keepdims=True)
    return Truth(t, out[:, :3], q, command_times, commands, frame)


def gyro(truth: Truth, sigma: float, bias: np.ndarray, seed: int) -> np.ndarray:
    """Readings: the true rate plus a constant bias plus white noise of ``sigma`` rad/s per axis."""
    rng = np.random.default_rng(seed)
    return truth.omega + bias + sigma * rng.standard_normal(truth.omega.shape)


def write_bag(
    path: Path,
    truth: Truth,
    readings: np.ndarray,
    *,
    with_orientation: bool = False,
    imu_topic: str = "/robot/imu",
    torque_topics: tuple[str, ...] = ("/robot/torque",),
    vector_topic: str | None = None,
    stamp0: int = 1_700_000_000_000_000_000,
    command_frame: str | None = None,
) -> Path:
    """A rosbag2 directory (metadata.yaml + MCAP) written by rosbags: Imu readings and WrenchStamped commands.

    With several torque topics each command is split evenly among them (the sum is the command).
    """
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    Imu = store.types["sensor_msgs/msg/Imu"]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    Vector3 = store.types["geometry_msgs/msg/Vector3"]
    Quaternion = store.types["geometry_msgs/msg/Quaternion"]
    Wrench = store.types["geometry_msgs/msg/Wrench"]
    WrenchStamped = store.types["geometry_msgs/msg/WrenchStamped"]
    Vector3Stamped = store.types["geometry_msgs/msg/Vector3Stamped"]

    def header(t: float, frame: str) -> object:
        ns = stamp0 + int(round(t * 1e9))
        return Header(stamp=Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000), frame_id=frame)

    def vec(v: np.ndarray) -> object:
        return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))

    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        imu = writer.add_connection(imu_topic, "sensor_msgs/msg/Imu", typestore=store)
        vector = (
            writer.add_connection(vector_topic, "geometry_msgs/msg/Vector3Stamped", typestore=store)
            if vector_topic
            else None
        )
        torques = [writer.add_connection(t, "geometry_msgs/msg/WrenchStamped", typestore=store) for t in torque_topics]
        events = []
        for i, t in enumerate(truth.t):
            q = truth.q[i] if with_orientation else np.array([0.0, 0.0, 0.0, 1.0])
            cov = np.zeros(9)
            cov[0] = 0.0 if with_orientation else -1.0
            msg = Imu(
                header=header(t, "imu_link"),
                orientation=Quaternion(x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3])),
                orientation_covariance=cov,
                angular_velocity=vec(readings[i]),
                angular_velocity_covariance=np.zeros(9),
                linear_acceleration=vec(np.zeros(3)),
                linear_acceleration_covariance=np.zeros(9),
            )
            events.append((t, imu, store.serialize_cdr(msg, "sensor_msgs/msg/Imu")))
            if vector is not None:
                v = Vector3Stamped(header=header(t, "imu_link"), vector=vec(readings[i]))
                events.append((t, vector, store.serialize_cdr(v, "geometry_msgs/msg/Vector3Stamped")))
        frame = command_frame or ("base_link" if truth.frame == "body" else "odom")
        for t, value in zip(truth.command_times, truth.commands, strict=True):
            for conn in torques:
                w = WrenchStamped(
                    header=header(t, frame), wrench=Wrench(force=vec(np.zeros(3)), torque=vec(value / len(torques)))
                )
                events.append((t, conn, store.serialize_cdr(w, "geometry_msgs/msg/WrenchStamped")))
        for t, conn, data in sorted(events, key=lambda e: e[0]):
            writer.write(conn, stamp0 + int(round(t * 1e9)), data)
    return path
