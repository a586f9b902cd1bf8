"""Conversions to messages whose frame conventions a standard consumer relies on."""

import numpy as np
from scipy.spatial.transform import Rotation

from rigid_rot_sim.conversions import UNMEASURED_POSITION_VARIANCE, star_tracker_pose
from rigid_rot_sim.core.sensors import StarTrackerModel, star_tracker_sample

#: Boresight (body z) noise ten times the cross-boresight noise, as real trackers have.
NEA = (1e-5, 1e-5, 1e-4)


def test_star_tracker_covariance_is_about_the_fixed_axes_as_pose_with_covariance_defines():
    """The rotation block of geometry_msgs/PoseWithCovariance is about the fixed axes (robot_localization
    reads it so): the body covariance diag(NEA^2) rotated by the attitude, R C R^T (issue 29)."""
    model = StarTrackerModel(rate=10.0, noise_equivalent_angle=NEA)
    # body z (the boresight) along world x: the large variance belongs on world x, not world z
    attitude = Rotation.from_euler("y", 90, degrees=True) * Rotation.from_euler("z", 30, degrees=True)
    q = attitude.as_quat()  # scipy: (x, y, z, w), body -> world, as the node
    msg = star_tracker_pose(q, 1.5, "odom", model.covariance)
    covariance = np.array(msg.pose.covariance).reshape(6, 6)
    matrix = attitude.as_matrix()
    np.testing.assert_allclose(covariance[3:, 3:], matrix @ np.diag(np.square(NEA)) @ matrix.T, rtol=0, atol=1e-22)
    assert covariance[3, 3] > 50 * covariance[5, 5]  # the boresight's variance lies along world x
    np.testing.assert_array_equal(covariance[:3, :3], np.eye(3) * UNMEASURED_POSITION_VARIANCE)
    assert np.all(covariance[:3, 3:] == 0.0) and np.all(covariance[3:, :3] == 0.0)
    assert msg.header.frame_id == "odom" and msg.header.stamp.sec == 1 and msg.header.stamp.nanosec == 500_000_000


def test_star_tracker_covariance_is_the_spread_of_its_errors_about_the_fixed_axes():
    """Monte Carlo: the errors of 4000 readings, as rotation vectors about the world axes
    (q_m q^-1), have the published covariance (within sampling error), not the body one."""
    model = StarTrackerModel(rate=10.0, noise_equivalent_angle=NEA)
    truth = Rotation.from_rotvec([0.4, -1.1, 0.7])
    q = truth.as_quat()
    errors = np.array(
        [(Rotation.from_quat(star_tracker_sample(model, 7, k, q)) * truth.inv()).as_rotvec() for k in range(4000)]
    )
    sample = np.cov(errors.T)
    published = np.array(star_tracker_pose(q, 0.0, "odom", model.covariance).pose.covariance).reshape(6, 6)[3:, 3:]
    scale = max(NEA) ** 2
    # sampling error of a covariance entry from 4000 draws: about sqrt(2 / 4000) = 2 % of the largest variance
    np.testing.assert_allclose(sample, published, rtol=0, atol=0.08 * scale)
    assert np.abs(sample - np.diag(np.square(NEA))).max() > 0.3 * scale  # the body-axes covariance would fail
