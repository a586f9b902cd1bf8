"""The scene's sensors: section: models with their units' defaults, rates given once, clear errors."""

import pytest

from rigid_rot_sim.core.sensors import GyroModel, StarTrackerModel
from rigid_rot_sim.scene.scene import SceneError, parse_scene_text

BODY = "body: {principal_moments: [1.0, 2.0, 2.5]}\n"


def test_no_sensors_section_builds_none_and_keeps_the_default_rates():
    scene = parse_scene_text(BODY)
    assert scene.sensors.gyro is None and scene.sensors.star_tracker is None and scene.sensors.seed is None
    assert scene.outputs["imu"] == 0.0 and scene.outputs["star_tracker"] == 0.0


def test_sensors_are_read_with_defaults_and_set_the_output_rates():
    scene = parse_scene_text(
        BODY
        + """
sensors:
  seed: 18446744073709551615
  gyro: {angle_random_walk: 1.0e-4, turn_on_bias: [1.0e-3, 0.0, -1.0e-3], scale_factor: [1.0e-4, 0.0, 0.0]}
  star_tracker: {rate: 4, noise_equivalent_angle: [1.0e-5, 1.0e-5, 5.0e-5]}
"""
    )
    assert scene.sensors.seed == 2**64 - 1
    assert scene.sensors.gyro == GyroModel(
        angle_random_walk=1e-4, turn_on_bias=(1e-3, 0.0, -1e-3), scale_factor=(1e-4, 0.0, 0.0)
    )
    assert scene.sensors.star_tracker == StarTrackerModel(rate=4.0, noise_equivalent_angle=(1e-5, 1e-5, 5e-5))
    assert scene.outputs["imu"] == 100.0 and scene.outputs["star_tracker"] == 4.0  # the gyro's default rate, 100 Hz


@pytest.mark.parametrize(
    "text, expected",
    [
        ("sensors: {seed: -1}", "sensors.seed: must be an integer from 0 to 18446744073709551615, got -1"),
        ("sensors: {seed: 18446744073709551616}", "sensors.seed: must be an integer from 0 to 18446744073709551615"),
        ("sensors: {seed: 1.5}", "sensors.seed: must be an integer"),
        ("sensors: {gyro: {rate: 0}}", "sensors.gyro.rate: must be > 0"),
        ("sensors: {gyro: {angle_random_walk: -1.0}}", "sensors.gyro.angle_random_walk: must be >= 0"),
        ("sensors: {gyro: {bias_correlation_time: 0}}", "sensors.gyro.bias_correlation_time: must be > 0"),
        ("sensors: {gyro: {arw: 1.0}}", "sensors.gyro.arw: unknown key (allowed: rate, angle_random_walk,"),
        ("sensors: {star_tracker: {rate: 5}}", "sensors.star_tracker: needs noise_equivalent_angle"),
        (
            "sensors: {star_tracker: {noise_equivalent_angle: [1.0, -1.0, 0.0]}}",
            "sensors.star_tracker.noise_equivalent_angle[1]: must be >= 0",
        ),
        ("outputs: {star_tracker: 5}", "outputs.star_tracker: needs a sensors.star_tracker section"),
        (
            "sensors: {gyro: {rate: 50}}\noutputs: {imu: 100}",
            "outputs.imu: 100 Hz differs from sensors.gyro.rate 50 Hz",
        ),
    ],
)
def test_errors_name_the_key(text, expected):
    with pytest.raises(SceneError) as error:
        parse_scene_text(BODY + text, source="bad.yaml")
    assert f"bad.yaml: {expected}" in str(error.value)


def test_the_same_rate_given_twice_is_accepted():
    scene = parse_scene_text(BODY + "sensors: {gyro: {rate: 50}}\noutputs: {imu: 50}")
    assert scene.outputs["imu"] == 50.0
