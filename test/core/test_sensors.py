"""Sensor models: the gyro's Allan deviation from a long seeded run, each error term, seeded bits, star tracker."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.sensors import (
    FLICKER_FLOOR,
    GAUSS_MARKOV_PEAK_ADEV,
    GAUSS_MARKOV_PEAK_TAU,
    GyroModel,
    GyroState,
    StarTrackerModel,
    Stream,
    gauss_markov_allan_variance,
    gyro_batch,
    gyro_sample,
    gyro_turn_on_bias,
    standard_normals,
    star_tracker_sample,
)


def overlapping_allan_deviation(rates: np.ndarray, period: float, clusters: np.ndarray) -> np.ndarray:
    """Overlapping Allan deviation (IEEE Std 952) of rate samples (n,) every ``period`` s.

    With the angle θ_i = period * (y_0 + ... + y_{i-1}) and τ = m period:
    AVAR(τ) = Σ_i (θ_{i+2m} - 2 θ_{i+m} + θ_i)^2 / (2 τ^2 (n + 1 - 2m)).
    """
    theta = np.concatenate(([0.0], np.cumsum(rates) * period))
    result = []
    for m in clusters:
        second_difference = theta[2 * m :] - 2.0 * theta[m:-m] + theta[: len(theta) - 2 * m]
        result.append(math.sqrt(np.mean(second_difference**2) / (2.0 * (m * period) ** 2)))
    return np.array(result)


def test_peak_constants_are_the_maximum_of_the_gauss_markov_allan_variance():
    found = minimize_scalar(
        lambda x: -gauss_markov_allan_variance(x, 1.0, 1.0),
        bounds=(0.5, 5.0),
        method="bounded",
        options={"xatol": 1e-10},
    )
    assert found.x == pytest.approx(GAUSS_MARKOV_PEAK_TAU, rel=1e-6)
    assert math.sqrt(-found.fun) == pytest.approx(GAUSS_MARKOV_PEAK_ADEV, rel=1e-9)
    assert FLICKER_FLOOR == pytest.approx(0.664, abs=5e-4)  # sqrt(2 ln 2 / pi)
    # limits: rate random walk K^2 tau / 3 with K^2 = 2 sigma^2 / T_c, and white 2 sigma^2 T_c / tau
    assert gauss_markov_allan_variance(1e-4, 1.0, 1.0) == pytest.approx(2e-4 / 3, rel=1e-3)
    assert gauss_markov_allan_variance(1e4, 1.0, 1.0) == pytest.approx(2e-4, rel=1e-3)


ARW = 1e-4  # rad/sqrt(s)
BIAS_INSTABILITY = 3e-5  # rad/s
CORRELATION_TIME = 300.0  # s: the bias floor (568 s) far above 1 s, where the ARW dominates


@pytest.fixture(scope="module")
def long_run():
    """1e6 s of a gyro at rest sampled at 2 Hz (2e6 readings per axis), seeded."""
    model = GyroModel(
        rate=2.0, angle_random_walk=ARW, bias_instability=BIAS_INSTABILITY, bias_correlation_time=CORRELATION_TIME
    )
    readings = gyro_batch(model, seed=20, omega=np.zeros((2_000_000, 3)))
    return model, readings


def _pooled_adev(readings: np.ndarray, period: float, clusters: np.ndarray) -> np.ndarray:
    """Allan deviation pooled over the three independent axes (mean of the variances)."""
    variances = [overlapping_allan_deviation(readings[:, axis], period, clusters) ** 2 for axis in range(3)]
    return np.sqrt(np.mean(variances, axis=0))


def test_allan_deviation_has_the_arw_slope_and_value_at_one_second(long_run):
    model, readings = long_run
    clusters = np.array([1, 2, 4, 8])  # tau = 0.5, 1, 2, 4 s: the bias adds < 1 % of the variance here
    adev = _pooled_adev(readings, model.period, clusters)
    tau = clusters * model.period
    assert adev[1] == pytest.approx(ARW, rel=0.10)  # N is the Allan deviation at tau = 1 s
    slope = np.polyfit(np.log(tau), np.log(adev), 1)[0]
    assert slope == pytest.approx(-0.5, abs=0.05)


def test_allan_deviation_floor_is_the_bias_instability(long_run):
    """The bias is first-order Gauss-Markov, not flicker: its Allan deviation has a peak, not a flat
    floor. The model sets the bias's deviation so that the peak (at 1.89 T_c) equals the flicker floor
    0.664 B a datasheet quotes; there the ARW adds N^2 / tau, which is taken out (4 % of the variance here)."""
    model, readings = long_run
    tau_peak = GAUSS_MARKOV_PEAK_TAU * CORRELATION_TIME
    clusters = np.array([round(tau_peak / model.period)])
    adev = _pooled_adev(readings, model.period, clusters)[0]
    tau = clusters[0] * model.period
    bias_part = math.sqrt(adev**2 - ARW**2 / tau)
    assert bias_part == pytest.approx(0.664 * BIAS_INSTABILITY, rel=0.10)
    # and the whole curve follows the model: white ARW plus the Gauss-Markov variance
    clusters = np.array([20, 200, 2000, 6000])
    expected = np.sqrt(
        ARW**2 / (clusters * model.period)
        + gauss_markov_allan_variance(clusters * model.period, model.bias_sigma, CORRELATION_TIME)
    )
    np.testing.assert_allclose(_pooled_adev(readings, model.period, clusters), expected, rtol=0.10)


def _readings(model: GyroModel, seed: int, omega, samples: int = 5, period: float = 0.01) -> np.ndarray:
    state, out = GyroState(), []
    bias = gyro_turn_on_bias(model, seed)
    for k in range(samples):
        reading, state = gyro_sample(model, seed, bias, state, np.asarray(omega, dtype=float), k * period)
        out.append(reading)
    return np.array(out)


def test_turn_on_bias_given_is_added_and_drawn_is_constant_in_a_run_with_the_configured_spread():
    given = GyroModel(turn_on_bias=(1e-3, -2e-3, 5e-4))
    omega = np.array([0.1, 0.2, -0.3])
    np.testing.assert_array_equal(_readings(given, 1, omega), np.tile(omega + given.turn_on_bias, (5, 1)))
    drawn = GyroModel(turn_on_bias_sigma=1e-3)
    readings = _readings(drawn, 3, omega)
    assert np.all(readings == readings[0]) and not np.allclose(readings[0], omega)
    biases = np.array([gyro_turn_on_bias(drawn, seed) for seed in range(3000)])
    assert biases.std(axis=0) == pytest.approx([1e-3] * 3, rel=0.05)
    assert np.abs(biases.mean(axis=0)).max() < 1e-4


def test_scale_factor_multiplies_the_rate():
    model = GyroModel(scale_factor=(1e-4, -2e-3, 0.0))
    omega = np.array([2.0, -1.0, 0.5])
    np.testing.assert_array_equal(_readings(model, 1, omega)[0], (1.0 + np.array(model.scale_factor)) * omega)


def test_saturation_clips_each_axis():
    model = GyroModel(saturation=5.0, angle_random_walk=1e-3)
    readings = _readings(model, 4, [10.0, -10.0, 0.5], samples=50)
    np.testing.assert_array_equal(readings[:, :2], np.tile([5.0, -5.0], (50, 1)))
    assert np.all(np.abs(readings[:, 2] - 0.5) < 0.1) and len(set(readings[:, 2])) > 1  # unsaturated: noisy


def test_quantization_gives_whole_lsbs_within_half_an_lsb_of_the_rate():
    lsb = 1e-3
    model = GyroModel(quantization=lsb)
    omega = np.array([0.12345, -0.0004, 3.21071])
    reading = _readings(model, 1, omega)[0]
    counts = reading / lsb
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-9)
    assert np.all(np.abs(reading - omega) <= lsb / 2 + 1e-15)


NOISY = GyroModel(
    angle_random_walk=1e-3,
    bias_instability=1e-4,
    bias_correlation_time=10.0,
    turn_on_bias_sigma=1e-3,
    scale_factor=(1e-4, 1e-4, 1e-4),
    quantization=1e-7,
    saturation=10.0,
)


def test_same_seed_same_bits_different_seed_different_bits():
    omega = [0.3, -0.1, 0.05]
    first, again = _readings(NOISY, 11, omega, 200), _readings(NOISY, 11, omega, 200)
    assert first.tobytes() == again.tobytes()
    other = _readings(NOISY, 12, omega, 200)
    assert not np.any(first == other)


def test_the_noise_of_a_sample_depends_on_its_index_only():
    """Drawn alone or in a batch, sample k reads the same bits (counter-based Philox)."""
    batch = standard_normals(5, Stream.GYRO, 0, 100, 6)
    for k in (0, 1, 37, 99):
        np.testing.assert_array_equal(standard_normals(5, Stream.GYRO, k, 1, 6)[0], batch[k])
    assert not np.array_equal(standard_normals(5, Stream.STAR_TRACKER, 0, 1, 3)[0], batch[0, :3])
    normals = standard_normals(1, Stream.GYRO, 0, 50_000, 6).ravel()
    assert abs(normals.mean()) < 0.01 and normals.std() == pytest.approx(1.0, abs=0.01)


def test_sample_by_sample_agrees_with_the_batch():
    readings = _readings(NOISY, 9, np.zeros(3), 300, period=NOISY.period)
    np.testing.assert_allclose(gyro_batch(NOISY, 9, np.zeros((300, 3))), readings, rtol=0, atol=1e-7)


def test_a_sample_at_the_same_time_keeps_the_bias_and_uses_the_nominal_interval():
    model = GyroModel(angle_random_walk=1e-3, bias_instability=1e-3, bias_correlation_time=1.0)
    bias = gyro_turn_on_bias(model, 2)
    _, state = gyro_sample(model, 2, bias, GyroState(), np.zeros(3), 1.0)
    reading, repeated = gyro_sample(model, 2, bias, state, np.zeros(3), 1.0)
    assert repeated.bias == state.bias and np.all(np.isfinite(reading))
    _, reset = gyro_sample(model, 2, bias, repeated, np.zeros(3), 0.0)  # sim time went back (a reset)
    assert reset.bias == state.bias and reset.index == 3


def test_star_tracker_error_has_the_noise_equivalent_angle_per_body_axis():
    nea = np.array([2e-5, 3e-5, 2e-4])
    model = StarTrackerModel(rate=5.0, noise_equivalent_angle=tuple(nea))
    np.testing.assert_array_equal(model.covariance, np.diag(nea**2))
    truth = Rotation.from_rotvec([0.4, -1.1, 2.0])
    q = truth.as_quat()
    errors = np.array(
        [(truth.inv() * Rotation.from_quat(star_tracker_sample(model, 8, k, q))).as_rotvec() for k in range(20_000)]
    )  # body-frame error: q^-1 q_m
    assert errors.std(axis=0) == pytest.approx(nea, rel=0.03)
    assert np.abs(np.corrcoef(errors.T) - np.eye(3)).max() < 0.03
    sample = star_tracker_sample(model, 8, 5, q)
    assert np.linalg.norm(sample) == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_array_equal(sample, star_tracker_sample(model, 8, 5, q))
    assert not np.array_equal(sample, star_tracker_sample(model, 9, 5, q))


# ------------------------------------------------------------------ magnetometer


def _magnetometer_run(model, field, seed=7, samples=10_000, times=None):
    from rigid_rot_sim.core.sensors import MagnetometerState, magnetometer_sample

    state = MagnetometerState()
    readings = []
    times = np.arange(samples) / model.rate if times is None else times
    for t in times:
        reading, state = magnetometer_sample(model, seed, state, field, float(t))
        readings.append(reading)
    return np.array(readings), np.asarray(times)


def test_magnetometer_noise_statistics_over_ten_thousand_samples() -> None:
    from rigid_rot_sim.core.sensors import MagnetometerModel

    field = np.array([2.0e-5, -1.0e-5, 4.0e-5])
    model = MagnetometerModel(rate=10.0, noise_density=1e-8, bias=(1e-7, -2e-7, 0.0), quantization=5e-9)
    readings, _ = _magnetometer_run(model, field)
    n = len(readings)
    sigma = model.noise_sigma
    expected_std = math.sqrt(sigma**2 + model.quantization**2 / 12)
    assert np.all(np.abs(readings.mean(axis=0) - (field + model.bias)) < 3 * expected_std / math.sqrt(n))
    assert np.all(np.abs(readings.std(axis=0) - expected_std) < 3 * expected_std / math.sqrt(2 * n))
    steps = readings / model.quantization
    np.testing.assert_allclose(steps, np.round(steps), rtol=0, atol=1e-6)  # on the quantisation grid
    assert np.all(np.diff(np.unique(readings[:, 0])) >= model.quantization * (1 - 1e-9))  # no finer step
    np.testing.assert_allclose(np.diag(model.covariance), expected_std**2)


def test_magnetometer_scale_misalignment_saturation_are_deterministic() -> None:
    from rigid_rot_sim.core.sensors import MagnetometerModel

    field = np.array([3.0e-5, 0.0, 0.0])
    model = MagnetometerModel(scale_factor=(0.01, 0.0, 0.0), misalignment=(0.0, 0.0, math.pi / 2), saturation=2.9e-5)
    readings, _ = _magnetometer_run(model, field, samples=3)
    # the sensor frame turned +90 deg about z: the body's x field lies along the sensor's -y
    np.testing.assert_allclose(readings[0], [0.0, -2.9e-5, 0.0], atol=1e-20)  # clipped at the saturation
    model = MagnetometerModel(scale_factor=(0.0, 0.01, 0.0), misalignment=(0.0, 0.0, math.pi / 2))
    readings, _ = _magnetometer_run(model, field, samples=1)
    np.testing.assert_allclose(readings[0], [0.0, -3.03e-5, 0.0], rtol=1e-12, atol=1e-20)


def test_magnetometer_faults_each_visible_in_their_window() -> None:
    from rigid_rot_sim.core.sensors import MagnetometerFault, MagnetometerModel

    field = np.array([2.0e-5, -1.0e-5, 4.0e-5])
    faults = (
        MagnetometerFault("stuck_current", start=10.0, end=20.0, axes=(0,)),
        MagnetometerFault("stuck_value", start=30.0, end=40.0, axes=(1, 2), value=1e-6),
        MagnetometerFault("spiking", start=50.0, end=60.0, axes=(2,), probability=0.3, amount=10.0),
    )
    model = MagnetometerModel(rate=10.0, noise_density=1e-8, faults=faults)
    readings, t = _magnetometer_run(model, field, samples=800)
    clean, _ = _magnetometer_run(MagnetometerModel(rate=10.0, noise_density=1e-8), field, samples=800)
    stuck = (t >= 10.0) & (t < 20.0)
    assert np.all(readings[stuck, 0] == clean[np.argmax(stuck) - 1, 0])  # held at the last reading
    np.testing.assert_array_equal(readings[stuck, 1:], clean[stuck, 1:])  # the other axes unaffected
    value = (t >= 30.0) & (t < 40.0)
    assert np.all(readings[value, 1:] == 1e-6) and np.array_equal(readings[value, 0], clean[value, 0])
    window = (t >= 50.0) & (t < 60.0)
    spiked = readings[window, 2] != clean[window, 2]
    np.testing.assert_allclose(readings[window, 2][spiked], 10.0 * clean[window, 2][spiked])
    assert 0.3 - 3 * math.sqrt(0.21 / 100) < spiked.mean() < 0.3 + 3 * math.sqrt(0.21 / 100)
    outside = ~(stuck | value | window)
    np.testing.assert_array_equal(readings[outside], clean[outside])  # nothing outside the windows


def test_magnetometer_is_a_function_of_the_seed() -> None:
    from rigid_rot_sim.core.sensors import MagnetometerModel

    model = MagnetometerModel(noise_density=1e-8)
    a, _ = _magnetometer_run(model, np.ones(3) * 1e-5, seed=3, samples=50)
    b, _ = _magnetometer_run(model, np.ones(3) * 1e-5, seed=3, samples=50)
    c, _ = _magnetometer_run(model, np.ones(3) * 1e-5, seed=4, samples=50)
    assert a.tobytes() == b.tobytes() and not np.array_equal(a, c)
