"""The node on an orbit in the Earth's field: ~/magnetometer (seeded, faults by window), ~/magnetic_field (the
truth), ~/orbit and /tf (ECI), recorded and re-simulated bit for bit, readings included."""

import numpy as np
import pytest
import rclpy
from rclpy.parameter import Parameter

from rigid_rot_sim.message_fields import time_to_seconds, vector3_to_array
from rigid_rot_sim.recording.reader import BagReader
from rigid_rot_sim.recording.resim import resimulate
from rigid_rot_sim.ros.node import RigidRotSimNode
from rigid_rot_sim.scene.scene import parse_scene_text

SIGMA = 3e-9 * np.sqrt(10.0)  # noise density * sqrt(rate), T
SCENE = """
name: orbiting
epoch: "2026-06-21T00:00:00Z"
body: {principal_moments: [0.04, 0.05, 0.01]}
initial: {angular_velocity: [0.05, -0.03, 0.08]}
orbit:
  elements: {semi_major_axis: 6900000.0, eccentricity: 0.02, inclination_deg: 97.4, raan_deg: 30.0,
             argument_of_periapsis_deg: 45.0, true_anomaly_deg: 10.0}
  j2: true
environment: {gravity_gradient: {}, magnetic_field: {model: igrf14}}
sensors:
  magnetometer:
    rate: 10.0
    noise_density: 3.0e-9
    bias: [5.0e-8, -3.0e-8, 2.0e-8]
    faults:
      - {kind: stuck_value, start: 0.5, end: 1.0, axes: [1], value: 1.0e-6}
      - {kind: stuck_current, start: 1.5, end: 2.0, axes: [0]}
      - {kind: spiking, start: 2.2, end: 2.6, axes: [2], probability: 1.0, amount: -1.0}
integrator: {method: auto, dt: 0.01}
duration: 3.0
outputs: {state: 10, angular_velocity: 0, angular_momentum: 0, orientation: 0, tf: 10, clock: 0,
          torque_breakdown: 0, magnetic_field: 10, orbit: 10}
"""
MAGNETOMETER, TRUTH = "/rigid_rot_sim/magnetometer", "/rigid_rot_sim/magnetic_field"
ORBIT, STATE = "/rigid_rot_sim/orbit", "/rigid_rot_sim/state"


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    tmp_path = tmp_path_factory.mktemp("orbit")
    scene = tmp_path / "orbiting.yaml"
    scene.write_text(SCENE)
    bag = tmp_path / "orbiting.mcap"
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
        assert node.run.outputs.sensors.names == ["magnetometer"]
        assert set(node.run.outputs.publishers) >= {"magnetometer", "magnetic_field", "orbit", "tf"}
        while not node.finished:
            node.run.tick()
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    return bag


def _by_time(reader, topic):
    return {time_to_seconds(m.header.stamp): m for _, m in reader.decoded([topic])}


def test_the_run_resimulates_bit_exact_magnetometer_included(recorded):
    report = resimulate(recorded)
    assert report.identical, report.format()
    counts = BagReader(recorded).counts()
    assert counts[MAGNETOMETER] == 31 and report.sensor_readings == 31 and report.sensor_mismatches == 0


def test_readings_are_the_truth_plus_bias_and_noise_and_each_fault_shows(recorded):
    reader = BagReader(recorded)
    readings, truth = _by_time(reader, MAGNETOMETER), _by_time(reader, TRUTH)
    assert set(readings) == set(truth)
    bias = np.array([5e-8, -3e-8, 2e-8])
    held = None
    for t in sorted(readings):
        m, b = readings[t], truth[t]
        assert m.header.frame_id == b.header.frame_id == "base_link"
        reading, field = vector3_to_array(m.magnetic_field), vector3_to_array(b.magnetic_field)
        assert 2e-5 < np.linalg.norm(field) < 6e-5  # LEO: tens of microtesla
        np.testing.assert_allclose(np.array(m.magnetic_field_covariance).reshape(3, 3), np.eye(3) * SIGMA**2)
        expected = field + bias
        normal = np.ones(3, dtype=bool)
        if 0.5 <= t < 1.0:
            assert reading[1] == 1e-6
            normal[1] = False
        if 1.5 <= t < 2.0:
            held = reading[0] if held is None else held
            assert reading[0] == held  # stuck at the reading before the window
            normal[0] = False
        if 2.2 <= t < 2.6:
            assert abs(reading[2] + expected[2]) < 6 * SIGMA  # every sample spiked, times -1
            normal[2] = False
        assert np.all(np.abs(reading - expected)[normal] < 6 * SIGMA)
    assert held is not None


def test_orbit_and_tf_carry_the_centre_of_mass_in_eci(recorded):
    reader = BagReader(recorded)
    kepler = parse_scene_text(SCENE).orbit
    orbit = _by_time(reader, ORBIT)
    assert len(orbit) == 31
    for t, msg in orbit.items():
        r, v = kepler.state(t)
        p = msg.pose.pose.position
        np.testing.assert_allclose([p.x, p.y, p.z], r, rtol=0, atol=1e-6)
        assert msg.header.frame_id == "odom" and msg.child_frame_id == "base_link"
        assert np.linalg.norm(vector3_to_array(msg.twist.twist.linear)) == pytest.approx(np.linalg.norm(v))
    for _, tf in reader.decoded(["/tf"]):
        body, earth = tf.transforms
        t = time_to_seconds(body.header.stamp)
        np.testing.assert_allclose(vector3_to_array(body.transform.translation), kepler.state(t)[0], atol=1e-6)
        assert (earth.header.frame_id, earth.child_frame_id) == ("odom", "earth")
