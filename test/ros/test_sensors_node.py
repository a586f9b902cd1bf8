"""The node with sensor models: ~/imu carries the gyro, ~/star_tracker the attitude with NEA^2, the
ground truth stays exact, and the recording (reset included) re-simulates bit for bit, readings too."""

import json

import numpy as np
import pytest
import rclpy
from rclpy.parameter import Parameter
from scipy.spatial.transform import Rotation
from std_srvs.srv import Trigger

from rigid_rot_sim.message_fields import quaternion_to_array, time_to_seconds, vector3_to_array
from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.recording.resim import resimulate
from rigid_rot_sim.ros.node import RigidRotSimNode

NEA = (2e-5, 2e-5, 1.5e-4)
SCENE = """
name: sensed
body: {principal_moments: [1.0, 1.5, 2.0]}
initial: {angular_velocity: [0.3, -0.2, 0.5]}
integrator: {method: rk4, dt: 0.001}
duration: 0.3
outputs: {state: 100, angular_velocity: 0, angular_momentum: 0, orientation: 0, tf: 0, clock: 0}
sensors:
  gyro: {rate: 200, angle_random_walk: 1.0e-3, bias_instability: 1.0e-4, bias_correlation_time: 5.0,
          turn_on_bias_sigma: 1.0e-3, scale_factor: [1.0e-4, -1.0e-4, 0.0], quantization: 1.0e-6, saturation: 8.0}
  star_tracker: {rate: 20, noise_equivalent_angle: [2.0e-5, 2.0e-5, 1.5e-4]}
"""
IMU, STAR_TRACKER, STATE = "/rigid_rot_sim/imu", "/rigid_rot_sim/star_tracker", "/rigid_rot_sim/state"


@pytest.fixture
def recorded(tmp_path):
    """A run of the scene (seed drawn at start), reset once at the end and run again, recorded."""
    scene = tmp_path / "sensed.yaml"
    scene.write_text(SCENE)
    bag = tmp_path / "sensed.mcap"
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = RigidRotSimNode(
            context=context,
            parameter_overrides=[
                Parameter("scene", value=str(scene)),
                Parameter("record_path", value=str(bag)),
                Parameter("real_time_factor", value=0.0),
            ],
        )
        sensors = node.run.outputs.sensors
        assert sensors.names == ["gyro", "star_tracker"] and set(node.run.outputs.publishers) >= {"imu", "star_tracker"}
        for _ in range(2):
            while not node.finished:
                node.run.tick()
            response = node.run.services.reset_callback(Trigger.Request(), Trigger.Response())  # as ~/reset
            assert response.success, response.message
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    return bag, sensors.seed


def test_a_run_with_noisy_sensors_resimulates_bit_exact_readings_included(recorded):
    bag, seed = recorded
    reader = BagReader(bag)
    assert json.loads(reader.metadata["sensors"]["seed"]) == seed
    counts = reader.counts()
    assert counts[IMU] >= 60 and counts[STAR_TRACKER] >= 6
    report = resimulate(bag)
    assert report.identical, report.format()
    assert report.sensor_readings == counts[IMU] + counts[STAR_TRACKER] and report.sensor_mismatches == 0


def test_resim_with_another_seed_finds_every_reading_different(recorded, monkeypatch):
    bag, seed = recorded
    from rigid_rot_sim.recording import resim

    real = resim.SensorSuite
    monkeypatch.setattr(resim, "SensorSuite", lambda models, seed, field=None: real(models, seed=seed + 1, field=field))
    report = resimulate(bag)
    assert not report.identical and report.sensor_mismatches == report.sensor_readings > 0
    assert "sensor readings differ" in report.verdict


def test_readings_are_noisy_ground_truth_exact_star_tracker_covariance_is_nea_squared_about_the_world_axes(recorded):
    bag, _ = recorded
    reader = BagReader(bag)
    truth = {}
    for _, decoded in reader.decoded([STATE]):
        truth[time_to_seconds(decoded.header.stamp)] = decoded
    errors = []
    for _, imu in reader.decoded([IMU]):
        state = truth.get(time_to_seconds(imu.header.stamp))
        if state is not None:
            errors.append(vector3_to_array(imu.angular_velocity) - vector3_to_array(state.angular_velocity_body))
        assert imu.orientation_covariance[0] == -1.0  # a gyro gives no attitude
        # one reading's noise: N^2 rate + sigma_b^2, sigma_b = 0.664 B / 0.61736 (docs/sensors.md)
        variance = (1e-3) ** 2 * 200 + (0.664 * 1e-4 / 0.61736) ** 2
        np.testing.assert_allclose(
            np.array(imu.angular_velocity_covariance).reshape(3, 3), np.eye(3) * variance, rtol=1e-4
        )
        assert imu.header.frame_id == "base_link"
    errors = np.array(errors)
    assert len(errors) > 20 and np.all(errors != 0.0)
    # the white part: ARW / sqrt(1/rate) = 1e-3 / sqrt(0.005 s) (the bias moves little in 0.3 s)
    assert np.std(errors - errors.mean(axis=0), axis=0) == pytest.approx([1e-3 / np.sqrt(0.005)] * 3, rel=0.3)
    attitude_errors = []
    for _, pose in reader.decoded([STAR_TRACKER]):
        covariance = np.array(pose.pose.covariance).reshape(6, 6)
        # about the fixed (world) axes, as PoseWithCovariance defines it: R diag(NEA^2) R^T
        matrix = Rotation.from_quat(quaternion_to_array(pose.pose.pose.orientation)).as_matrix()
        np.testing.assert_allclose(covariance[3:, 3:], matrix @ np.diag(np.square(NEA)) @ matrix.T, rtol=0, atol=1e-20)
        assert np.all(covariance[:3, 3:] == 0.0) and pose.header.frame_id == "odom"
        state = truth.get(time_to_seconds(pose.header.stamp))
        if state is not None:
            q_true, q_measured = quaternion_to_array(state.orientation), quaternion_to_array(pose.pose.pose.orientation)
            attitude_errors.append(2.0 * np.arccos(min(1.0, abs(float(np.dot(q_true, q_measured))))))
    assert attitude_errors and 0.0 < max(attitude_errors) < 10 * max(NEA)


def test_plot_shows_the_sensor_errors(recorded, tmp_path):
    import matplotlib.image

    from rigid_rot_sim.recording.plot import plot_run

    bag, _ = recorded
    written = plot_run(bag, tmp_path / "plots")
    assert [p.name for p in written] == ["omega.png", "drift.png", "torque.png", "polhode.png", "sensors.png"]
    image = matplotlib.image.imread(written[-1])
    assert image.shape[0] > 600 and np.std(image) > 0.01
