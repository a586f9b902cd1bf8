"""Message fields -> numpy and seconds, without importing ROS (the readers of :mod:`rigid_rot_sim.conversions`).

Duck-typed: any object with the fields of the ROS message works, so the same functions read
live rclpy messages and messages decoded from a recording (mcap_ros2, rosbags) where
rclpy is not installed. Units and frames are unchanged (SI, quaternions (x, y, z, w)).
"""

from __future__ import annotations

from typing import Any

import numpy as np


def time_to_seconds(stamp: Any) -> float:
    """builtin_interfaces/Time (or Duration) -> seconds (float)."""
    return float(stamp.sec) + float(stamp.nanosec) * 1e-9


def vector3_to_array(vector: Any) -> np.ndarray:
    """geometry_msgs/Vector3 -> ndarray (3,)."""
    return np.array([vector.x, vector.y, vector.z], dtype=float)


def quaternion_to_array(q: Any) -> np.ndarray:
    """geometry_msgs/Quaternion -> ndarray (4,) scalar-last (no renormalisation)."""
    return np.array([q.x, q.y, q.z, q.w], dtype=float)


def state_to_arrays(msg: Any) -> dict[str, Any]:
    """RigidBodyState -> {t, orientation (4,), angular_velocity_body (3,), ...} (clients, tests)."""
    return {
        "t": time_to_seconds(msg.header.stamp),
        "orientation": quaternion_to_array(msg.orientation),
        "angular_velocity_body": vector3_to_array(msg.angular_velocity_body),
        "angular_velocity_world": vector3_to_array(msg.angular_velocity_world),
        "angular_momentum_body": vector3_to_array(msg.angular_momentum_body),
        "angular_momentum_world": vector3_to_array(msg.angular_momentum_world),
        "torque_body": vector3_to_array(msg.torque_body),
        "kinetic_energy": float(msg.kinetic_energy),
        "potential_energy": float(msg.potential_energy),
        "energy_drift": float(msg.energy_drift),
        "angular_momentum_drift": float(msg.angular_momentum_drift),
        "digest": int(getattr(msg, "digest", 0)),  # absent from recordings made before the digest
    }
