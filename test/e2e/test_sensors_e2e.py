"""End to end: a node with a noisy gyro and a star tracker, seen over DDS from another process.

~/star_tracker carries PoseWithCovarianceStamped with the rotation covariance NEA^2, ~/imu the
gyro's readings; what arrives is what was recorded, and the recording (seed drawn by the node)
re-simulates bit for bit, sensor readings included.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from rigid_rot_sim.message_fields import quaternion_to_array, time_to_seconds, vector3_to_array
from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.recording.resim import resimulate

NEA = (1.0e-5, 1.0e-5, 8.0e-5)
SCENE = """
name: sensed_e2e
body: {principal_moments: [2.0, 3.0, 4.0]}
initial: {angular_velocity: [0.01, 0.02, 0.3]}
integrator: {method: rk4, dt: 0.002}
outputs: {state: 50, tf: 0, clock: 50}
sensors:
  gyro: {rate: 50, angle_random_walk: 5.0e-4, bias_instability: 2.0e-5, bias_correlation_time: 50.0,
         turn_on_bias_sigma: 1.0e-4, quantization: 1.0e-6}
  star_tracker: {rate: 10, noise_equivalent_angle: [1.0e-5, 1.0e-5, 8.0e-5]}
"""
IMU, STAR_TRACKER = "/rigid_rot_sim/imu", "/rigid_rot_sim/star_tracker"


def test_sensor_topics_over_dds_are_recorded_and_resimulate_bit_exact(tmp_path: Path, launch_node, ros_node, collector):
    from geometry_msgs.msg import PoseWithCovarianceStamped
    from sensor_msgs.msg import Imu

    from rigid_rot_sim.ros.qos import STATE_QOS

    scene = tmp_path / "sensed.yaml"
    scene.write_text(SCENE)
    bag = tmp_path / "sensed.mcap"
    node = launch_node("--ros-args", "-p", f"scene:={scene}", "-p", f"record_path:={bag}", name="sensed")
    poses = collector.subscribe(PoseWithCovarianceStamped, STAR_TRACKER, STATE_QOS)
    imus = collector.subscribe(Imu, IMU, STATE_QOS)
    collector.spin_until(lambda: len(poses) >= 3 and len(imus) >= 10, 60.0, node, "star tracker and imu messages")
    assert node.stop() == 0, node.log()

    for pose in poses:
        covariance = np.array(pose.pose.covariance).reshape(6, 6)
        # about the fixed (world) axes, as PoseWithCovariance defines it: R diag(NEA^2) R^T
        matrix = Rotation.from_quat(quaternion_to_array(pose.pose.pose.orientation)).as_matrix()
        np.testing.assert_allclose(covariance[3:, 3:], matrix @ np.diag(np.square(NEA)) @ matrix.T, rtol=0, atol=1e-20)
        assert pose.header.frame_id == "odom"
    assert all(imu.orientation_covariance[0] == -1.0 and imu.header.frame_id == "base_link" for imu in imus)

    reader = BagReader(bag)
    recorded = {time_to_seconds(m.header.stamp): vector3_to_array(m.angular_velocity) for _, m in reader.decoded([IMU])}
    for imu in imus:  # what arrived over DDS is what was recorded, bit for bit
        stamp = time_to_seconds(imu.header.stamp)
        np.testing.assert_array_equal(vector3_to_array(imu.angular_velocity), recorded[stamp])
    counts = reader.counts()
    report = resimulate(bag)
    assert report.identical, report.format()
    assert report.sensor_readings == counts[IMU] + counts[STAR_TRACKER] >= 13
    assert "sensor readings" in report.verdict and "seed" in reader.metadata["sensors"]
