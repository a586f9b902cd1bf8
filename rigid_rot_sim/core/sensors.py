"""Sensor models: a rate gyro, a star tracker and a magnetometer, with noise drawn from a seed by sample index.

Pure numerics (no ROS): frozen dataclasses for the models and the gyro's state, plain
functions for one sample. Units SI; rates in rad/s in the body frame; quaternions
(x, y, z, w) rotating body -> world. The equations are in ``docs/sensors.md``.

Reproducible noise
------------------
Every normal deviate is a function of ``(seed, stream, sample index)`` only
(:func:`standard_normals`): a Philox4x64 counter-based generator keyed on the seed and the
sensor's stream, its counter placed at the sample index. Each sample uses a fixed number
of 64-bit words (:data:`WORDS_PER_SAMPLE`), turned into normals by Box-Muller, so sample
``k`` reads the same bits whether it is drawn alone or in a batch, whatever the pacing of
the run. The gyro's bias is a state (a first-order Gauss-Markov process): it evolves from
one sample to the next, deterministically given the sample index and the sim times of the
samples, which a run and its re-simulation share.

Gyro (per axis, sample k at sim time t_k, interval Δ_k = t_k - t_{k-1})
----------------------------------------------------------------------
::

    b_k  = a_k b_{k-1} + σ_b sqrt(1 - a_k^2) w_k,   a_k = exp(-Δ_k / T_c)   (b_0 ~ N(0, σ_b^2))
    n_k  = N / sqrt(Δ_k) v_k                                                 (angle random walk)
    ω_m  = clip(q round(((1 + s) ω + b_on + b_k + n_k) / q), -ω_max, ω_max)

with w_k, v_k independent standard normals. ``b_k`` is the exact discretisation of the
Gauss-Markov process db/dt = -b/T_c + sqrt(2 σ_b^2 / T_c) η(t) (42's discrete gyro bias,
``Bias = CorrCoef Bias + BiasStabCoef w``, with the exact coefficients for any Δ). Its
stationary deviation σ_b is set from the datasheet bias instability B so that the Allan
deviation of the bias peaks at 0.664 B (the flicker floor a datasheet quotes), which it
does at τ = 1.89 T_c (:data:`GAUSS_MARKOV_PEAK_TAU`, :func:`gauss_markov_allan_variance`).

Star tracker
------------
::

    q_m = q ⊗ exp(δθ),   δθ = NEA ⊙ w   (body frame, rad)

so the measured attitude's error is a rotation about the body axes with the noise
equivalent angle (1 sigma) per axis: its covariance is diag(NEA^2) in the body frame.

Magnetometer
------------
::

    m = clip(q round(((1 + s) ⊙ R_mis^T B + b + N sqrt(rate) w) / q), -sat, sat)   (T, sensor axes)

then its faults by time window (Basilisk's): an axis stuck at its last reading, stuck at a value, or
spiking (multiplied by a factor with a probability per sample). :func:`magnetometer_sample`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rigid_rot_sim.core import quaternion as quat

__all__ = [
    "FLICKER_FLOOR",
    "GAUSS_MARKOV_PEAK_ADEV",
    "GAUSS_MARKOV_PEAK_TAU",
    "GyroModel",
    "GyroState",
    "MAGNETOMETER_FAULTS",
    "MagnetometerFault",
    "MagnetometerModel",
    "MagnetometerState",
    "StarTrackerModel",
    "Stream",
    "WORDS_PER_SAMPLE",
    "gauss_markov_allan_variance",
    "gyro_batch",
    "gyro_sample",
    "gyro_turn_on_bias",
    "magnetometer_sample",
    "star_tracker_sample",
    "standard_normals",
]

#: Allan deviation floor of flicker (1/f) rate noise of bias instability B: 0.664 B (IEEE Std 952).
FLICKER_FLOOR = math.sqrt(2.0 * math.log(2.0) / math.pi)
#: τ / T_c where the Allan deviation of a first-order Gauss-Markov process peaks (maximum of
#: :func:`gauss_markov_allan_variance`; test/core/test_sensors.py checks both numbers).
GAUSS_MARKOV_PEAK_TAU = 1.8926177792691046
#: That peak Allan deviation over the process's stationary deviation σ_b.
GAUSS_MARKOV_PEAK_ADEV = 0.6173642831444414


class Stream:
    """The independent noise streams of a seed (one Philox key each)."""

    GYRO_TURN_ON = 1
    GYRO = 2
    STAR_TRACKER = 3
    MAGNETOMETER = 4


#: 64-bit words each sample of a stream consumes (a multiple of Philox's block of 4).
WORDS_PER_SAMPLE = {Stream.GYRO_TURN_ON: 4, Stream.GYRO: 8, Stream.STAR_TRACKER: 4, Stream.MAGNETOMETER: 8}

_TWO_POW_64 = 1 << 64


def standard_normals(seed: int, stream: int, first: int, samples: int, per_sample: int) -> np.ndarray:
    """Standard normal deviates of samples ``first`` .. ``first + samples - 1`` of ``stream``.

    Returns shape (samples, per_sample). A function of (seed, stream, sample index) only:
    sample k takes the 64-bit words [k W, (k + 1) W) (W = ``WORDS_PER_SAMPLE[stream]``) of
    Philox4x64 keyed on (seed, stream), and makes normals of them by Box-Muller
    (``per_sample`` <= W).
    """
    words = WORDS_PER_SAMPLE[stream]
    if not 0 < per_sample <= words:
        raise ValueError(f"per_sample must be in 1..{words}, got {per_sample}")
    if not 0 <= seed < _TWO_POW_64:
        raise ValueError(f"seed must be in [0, 2**64), got {seed}")
    generator = np.random.Philox(key=seed + stream * _TWO_POW_64, counter=first * (words // 4))
    raw = generator.random_raw(samples * words).reshape(samples, words // 2, 2)
    # 53-bit uniforms in (0, 1): never 0, so the logarithm is finite
    uniform = ((raw >> np.uint64(11)).astype(np.float64) + 0.5) * (1.0 / (1 << 53))
    radius = np.sqrt(-2.0 * np.log(uniform[..., 0]))
    angle = (2.0 * math.pi) * uniform[..., 1]
    normals = np.stack((radius * np.cos(angle), radius * np.sin(angle)), axis=-1).reshape(samples, words)
    return normals[:, :per_sample]


def gauss_markov_allan_variance(tau: np.ndarray | float, sigma: float, correlation_time: float) -> np.ndarray:
    """Allan variance ((rad/s)^2) at averaging time ``tau`` (s) of a first-order Gauss-Markov rate.

    The process has stationary deviation ``sigma`` (rad/s) and autocorrelation
    σ^2 exp(-|τ|/T_c); integrating the autocorrelation over two adjacent windows gives
    ``2 σ^2 T_c / τ [1 - T_c / (2τ) (3 - 4 exp(-τ/T_c) + exp(-2τ/T_c))]``: σ^2 2τ/(3 T_c)
    (a rate random walk) for τ << T_c, 2 σ^2 T_c / τ (white) for τ >> T_c.
    """
    x = np.asarray(tau, dtype=float) / correlation_time
    bracket = 1.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / (2.0 * x)
    return 2.0 * sigma**2 / x * bracket


@dataclass(frozen=True)
class GyroModel:
    """A three-axis rate gyro along the body axes.

    ``rate``: samples per second of sim time (Hz; the nominal interval 1/rate is used for the
    first sample). ``angle_random_walk`` N: rad/sqrt(s). ``bias_instability`` B: rad/s, the
    datasheet figure (the Allan deviation floor is 0.664 B), realised as a Gauss-Markov bias
    of correlation time ``bias_correlation_time`` T_c (s). ``turn_on_bias``: rad/s per axis,
    plus a draw of N(0, ``turn_on_bias_sigma``^2) (rad/s) per axis from the seed.
    ``scale_factor`` s: fraction per axis (100 ppm = 1e-4). ``saturation``: rad/s (0: none).
    ``quantization``: rad/s per LSB (0: none).
    """

    rate: float = 100.0
    angle_random_walk: float = 0.0
    bias_instability: float = 0.0
    bias_correlation_time: float = 100.0
    turn_on_bias: tuple[float, float, float] = (0.0, 0.0, 0.0)
    turn_on_bias_sigma: float = 0.0
    scale_factor: tuple[float, float, float] = (0.0, 0.0, 0.0)
    saturation: float = 0.0
    quantization: float = 0.0

    @property
    def bias_sigma(self) -> float:
        """Stationary deviation σ_b (rad/s) of the Gauss-Markov bias: its Allan peak is 0.664 B."""
        return FLICKER_FLOOR * self.bias_instability / GAUSS_MARKOV_PEAK_ADEV

    @property
    def period(self) -> float:
        """Nominal sample interval 1/rate (s)."""
        return 1.0 / self.rate

    @property
    def reading_variance(self) -> float:
        """Variance ((rad/s)^2) of one reading's noise beyond the constant biases: N^2 rate + σ_b^2."""
        return self.angle_random_walk**2 * self.rate + self.bias_sigma**2


@dataclass(frozen=True)
class GyroState:
    """The gyro between samples: the next sample's index, the last sample's sim time (s; None
    before the first) and the Gauss-Markov bias there (rad/s, body axes)."""

    index: int = 0
    t: float | None = None
    bias: tuple[float, float, float] = (0.0, 0.0, 0.0)


def gyro_turn_on_bias(model: GyroModel, seed: int) -> np.ndarray:
    """The constant bias (rad/s, body axes): the given one plus the seeded draw of sigma per axis."""
    draw = standard_normals(seed, Stream.GYRO_TURN_ON, 0, 1, 3)[0]
    bias: np.ndarray = np.asarray(model.turn_on_bias, dtype=float) + model.turn_on_bias_sigma * draw
    return bias


def _measure(model: GyroModel, omega: np.ndarray, error: np.ndarray) -> np.ndarray:
    """Scale factor, errors, then quantisation and saturation (what the converter outputs)."""
    measured: np.ndarray = (1.0 + np.asarray(model.scale_factor, dtype=float)) * omega + error
    if model.quantization > 0.0:
        measured = model.quantization * np.round(measured / model.quantization)
    if model.saturation > 0.0:
        measured = np.clip(measured, -model.saturation, model.saturation)
    return measured


def gyro_sample(
    model: GyroModel, seed: int, turn_on_bias: np.ndarray, state: GyroState, omega: np.ndarray, t: float
) -> tuple[np.ndarray, GyroState]:
    """One gyro reading (rad/s, body axes) of the true rate ``omega`` at sim time ``t`` (s).

    Returns the reading and the state after it. The interval Δ is the sim time since the
    previous sample; the nominal 1/rate for the first sample, and for the ARW of a sample
    taken at the same or an earlier sim time (a forced publish, a reset), whose bias does
    not move.
    """
    w = standard_normals(seed, Stream.GYRO, state.index, 1, 6)[0]
    sigma = model.bias_sigma
    if state.t is None:
        bias = sigma * w[:3]  # stationary from the start
        interval = model.period
    else:
        elapsed = t - state.t
        interval = elapsed if elapsed > 0.0 else model.period
        step = max(elapsed, 0.0) / model.bias_correlation_time
        bias = math.exp(-step) * np.asarray(state.bias) + sigma * math.sqrt(-math.expm1(-2.0 * step)) * w[:3]
    noise = model.angle_random_walk / math.sqrt(interval) * w[3:]
    measured = _measure(model, np.asarray(omega, dtype=float), turn_on_bias + bias + noise)
    return measured, GyroState(index=state.index + 1, t=float(t), bias=(float(bias[0]), float(bias[1]), float(bias[2])))


def gyro_batch(model: GyroModel, seed: int, omega: np.ndarray) -> np.ndarray:
    """Readings (n, 3) rad/s of the rates ``omega`` (n, 3) sampled every 1/rate s from sample 0.

    The same equations as :func:`gyro_sample` vectorised over samples, for analysis (Allan
    deviation of long runs); the numbers agree with sample-by-sample readings to round-off
    (the bias recursion runs in scipy's lfilter, not in the same order of operations).
    """
    from scipy.signal import lfilter  # only here: analysis, not the node's path

    omega = np.asarray(omega, dtype=float).reshape(-1, 3)
    w = standard_normals(seed, Stream.GYRO, 0, len(omega), 6)
    sigma = model.bias_sigma
    a = math.exp(-model.period / model.bias_correlation_time)
    drive = sigma * math.sqrt(-math.expm1(-2.0 * model.period / model.bias_correlation_time)) * w[:, :3]
    drive[0] = sigma * w[0, :3]
    bias = lfilter([1.0], [1.0, -a], drive, axis=0)
    noise = model.angle_random_walk / math.sqrt(model.period) * w[:, 3:]
    return _measure(model, omega, gyro_turn_on_bias(model, seed) + bias + noise)


@dataclass(frozen=True)
class StarTrackerModel:
    """A star tracker aligned with the body axes.

    ``rate``: attitude solutions per second of sim time (Hz). ``noise_equivalent_angle``:
    rad (1 sigma) about each body axis (typically larger about the boresight).
    """

    rate: float = 10.0
    noise_equivalent_angle: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def covariance(self) -> np.ndarray:
        """Covariance (rad^2) of the attitude error rotation vector, body frame: diag(NEA^2)."""
        return np.diag(np.square(np.asarray(self.noise_equivalent_angle, dtype=float)))


def star_tracker_sample(model: StarTrackerModel, seed: int, index: int, orientation: np.ndarray) -> np.ndarray:
    """Measured attitude (x, y, z, w), body -> world, of sample ``index`` of the true ``orientation``.

    q_m = q ⊗ exp(δθ) with δθ = NEA ⊙ w in the body frame (the sign of q kept).
    """
    w = standard_normals(seed, Stream.STAR_TRACKER, index, 1, 3)[0]
    error = np.asarray(model.noise_equivalent_angle, dtype=float) * w
    return np.array(quat.normalize(quat.multiply(orientation, quat.exp_rotation_vector(error))), dtype=float)


# ------------------------------------------------------------- magnetometer

#: The magnetometer's faults (Basilisk's ``magnetometer`` fault states): the reading of the axes held at
#: the value it had when the window opened, held at a given value, or multiplied by a factor at random.
MAGNETOMETER_FAULTS = ("stuck_current", "stuck_value", "spiking")


@dataclass(frozen=True)
class MagnetometerFault:
    """One fault over the sim-time window ``[start, end)`` (s) on the ``axes`` (0, 1, 2 = sensor x, y, z).

    ``kind`` one of :data:`MAGNETOMETER_FAULTS`; ``value`` (T): what a ``stuck_value`` axis reads;
    ``probability``: the chance per sample and axis that a ``spiking`` axis spikes, its reading multiplied by
    ``amount``.
    """

    kind: str
    start: float = 0.0
    end: float = math.inf
    axes: tuple[int, ...] = (0, 1, 2)
    value: float = 0.0
    probability: float = 0.0
    amount: float = 1.0

    def active(self, t: float) -> bool:
        return self.start <= t < self.end


@dataclass(frozen=True)
class MagnetometerModel:
    """A three-axis magnetometer (readings in tesla along the sensor axes, nominally the body axes).

    ``rate``: samples per second of sim time (Hz). ``noise_density`` N: T/sqrt(Hz), white, sampled as the
    gyro's angle random walk is (sigma = N sqrt(rate) per sample). ``bias``: T per axis. ``scale_factor``:
    fraction per axis. ``misalignment``: rad, the small rotation vector from the body axes to the sensor axes.
    ``saturation``: T per axis (0: none). ``quantization``: T per LSB (0: none). ``faults``: by time window.
    """

    rate: float = 10.0
    noise_density: float = 0.0
    bias: tuple[float, float, float] = (0.0, 0.0, 0.0)
    scale_factor: tuple[float, float, float] = (0.0, 0.0, 0.0)
    misalignment: tuple[float, float, float] = (0.0, 0.0, 0.0)
    saturation: float = 0.0
    quantization: float = 0.0
    faults: tuple[MagnetometerFault, ...] = ()

    @property
    def noise_sigma(self) -> float:
        """1-sigma white noise of one reading per axis (T): N sqrt(rate)."""
        return self.noise_density * math.sqrt(self.rate)

    @property
    def covariance(self) -> np.ndarray:
        """Covariance (T^2) of a reading's random error, sensor axes: sigma^2 + q^2 / 12 per axis."""
        return np.eye(3) * (self.noise_sigma**2 + self.quantization**2 / 12.0)


@dataclass(frozen=True)
class MagnetometerState:
    """The magnetometer between samples: the next sample's index and the last reading (T; None before)."""

    index: int = 0
    last: tuple[float, float, float] | None = None


def magnetometer_sample(
    model: MagnetometerModel, seed: int, state: MagnetometerState, field_body: np.ndarray, t: float
) -> tuple[np.ndarray, MagnetometerState]:
    """One reading (T, sensor axes) of the true field ``field_body`` (T, body axes) at sim time ``t`` (s).

    ``m = clip(q round(((1 + s) (R_mis B) + b + sigma w) / q), -sat, sat)``, then the faults active at ``t`` in
    the order given. Sample k draws 6 normals of ``(seed, MAGNETOMETER, k)``: 3 for the noise, 3 made uniform
    (through the normal CDF) for the spikes; so every sample has its bits whatever the faults.
    """
    w = standard_normals(seed, Stream.MAGNETOMETER, state.index, 1, 6)[0]
    sensed = np.array(quat.rotate_inverse(quat.exp_rotation_vector(model.misalignment), field_body))
    reading = (1.0 + np.asarray(model.scale_factor, dtype=float)) * sensed
    reading = reading + np.asarray(model.bias, dtype=float) + model.noise_sigma * w[:3]
    if model.quantization > 0.0:
        reading = model.quantization * np.round(reading / model.quantization)
    if model.saturation > 0.0:
        reading = np.clip(reading, -model.saturation, model.saturation)
    for fault in model.faults:
        if not fault.active(t):
            continue
        for axis in fault.axes:
            if fault.kind == "stuck_current":
                if state.last is not None:
                    reading[axis] = state.last[axis]
            elif fault.kind == "stuck_value":
                reading[axis] = fault.value
            elif 0.5 * math.erfc(-w[3 + axis] / math.sqrt(2.0)) < fault.probability:
                reading[axis] *= fault.amount
    last = (float(reading[0]), float(reading[1]), float(reading[2]))
    return reading, MagnetometerState(index=state.index + 1, last=last)
