"""rigid_rot_sim.identify from truth we choose: rosbags-written bags of trajectories with known full
inertia tensors (scipy DOP853 at tight tolerances, test/identify/identify_truth.py), known noise and biases.
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from identify_truth import INERTIA, excitation, gyro, simulate, write_bag  # beside this file

from rigid_rot_sim.identify import Measurements, PiecewiseTorque, identify
from rigid_rot_sim.identify.bag import BagInputs, read_bag
from rigid_rot_sim.identify.fit import INERTIA_NAMES
from rigid_rot_sim.identify.report import body_yaml, validate
from rigid_rot_sim.scene.scene import parse_scene

OMEGA0 = np.array([0.3, -0.2, 0.4])
VALUES = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
INPUTS = BagInputs(imu="/robot/imu", torque=("/robot/torque",))


@pytest.fixture(scope="module")
def excited():
    """20 s at 100 Hz of random torque steps (one a second) about all axes, body frame."""
    times, values = excitation(20.0, 1.0, 0.01, seed=1)
    return simulate(INERTIA, OMEGA0, 20.0, 100.0, times, values)


def six(tensor: np.ndarray) -> np.ndarray:
    return np.array([tensor[i, j] for i, j in VALUES])


def test_noise_free_bag_recovers_the_full_tensor(tmp_path, excited):
    bag = write_bag(tmp_path / "bag", excited, excited.omega)
    data = read_bag(bag, INPUTS)
    result = identify(data.measurements)
    assert result.identifiable == "full"
    assert np.max(np.abs(result.inertia - INERTIA)) / np.max(np.abs(INERTIA)) < 1e-6
    assert result.unobservable == ()
    assert np.allclose(result.principal_moments, np.linalg.eigvalsh(INERTIA), rtol=1e-6)


def test_errors_are_within_3_sigma_and_sigma_matches_the_spread_over_seeds(excited):
    """Gyro white noise 2e-3 rad/s; 8 fixed seeds: each value within 3 reported sigma of the truth,
    and the reported sigma within a factor 2 of the spread of the estimates across the seeds."""
    torque = PiecewiseTorque(excited.command_times, excited.commands)
    estimates, sigmas = [], []
    for seed in range(8):
        m = Measurements(excited.t, gyro(excited, 2e-3, np.zeros(3), seed), torque)
        result = identify(m)
        estimates.append(six(result.inertia))
        sigmas.append(six(result.inertia_sigma))
        assert np.all(np.abs(estimates[-1] - six(INERTIA)) < 3.0 * sigmas[-1]), seed
    spread = np.std(np.array(estimates), axis=0, ddof=1)
    ratio = np.mean(sigmas, axis=0) / spread
    assert np.all((ratio > 0.5) & (ratio < 2.0)), dict(zip(INERTIA_NAMES, ratio, strict=True))


def test_torque_free_bag_gives_the_ratios_and_says_so(tmp_path):
    free = simulate(INERTIA, np.array([0.5, 0.1, 0.6]), 20.0, 100.0, np.zeros(0), np.zeros((0, 3)))
    bag = write_bag(tmp_path / "bag", free, free.omega, torque_topics=())
    result = identify(read_bag(bag, BagInputs(imu="/robot/imu")).measurements)
    assert result.identifiable == "ratios"
    assert np.trace(result.inertia) == pytest.approx(1.0)
    assert np.allclose(result.inertia, INERTIA / np.trace(INERTIA), atol=1e-6)
    assert any("unobservable" in w for w in result.warnings)
    with pytest.raises(ValueError, match="ratios"):
        body_yaml(result)


def test_torque_bias_and_gyro_bias_are_recovered(tmp_path):
    times, values = excitation(30.0, 1.0, 0.01, seed=2)
    tau_b = np.array([1e-3, -5e-4, 2e-4])
    gyro_b = np.array([2e-3, -1e-3, 5e-4])
    truth = simulate(INERTIA, OMEGA0, 30.0, 100.0, times, values, torque_bias=tau_b)
    bag = write_bag(tmp_path / "bag", truth, gyro(truth, 5e-4, gyro_b, seed=3))
    result = identify(read_bag(bag, INPUTS).measurements, estimate=("inertia", "torque_bias", "gyro_bias"))
    assert result.torque_bias is not None and result.torque_bias_sigma is not None
    assert result.gyro_bias is not None and result.gyro_bias_sigma is not None
    assert np.all(np.abs(result.torque_bias - tau_b) < 3.0 * result.torque_bias_sigma)
    assert np.all(np.abs(result.gyro_bias - gyro_b) < 3.0 * result.gyro_bias_sigma)
    assert np.all(result.torque_bias_sigma < 0.1 * np.abs(tau_b).max())
    assert np.all(np.abs(six(result.inertia) - six(INERTIA)) < 3.0 * six(result.inertia_sigma))


def test_world_frame_torque_is_turned_with_the_bag_attitude(tmp_path, excited):
    times, values = excited.command_times, excited.commands
    truth = simulate(INERTIA, OMEGA0, 20.0, 100.0, times, values, frame="world")
    bag = write_bag(tmp_path / "bag", truth, truth.omega, with_orientation=True)
    result = identify(read_bag(bag, INPUTS).measurements)
    assert np.max(np.abs(result.inertia - INERTIA)) / np.max(np.abs(INERTIA)) < 1e-4
    # read as if in the body frame, the same commands give a wrong model: the frame matters
    wrong = identify(Measurements(truth.t, truth.omega, PiecewiseTorque(times, values)))
    assert np.max(np.abs(wrong.inertia - INERTIA)) / np.max(np.abs(INERTIA)) > 1e-2
    assert result.warnings == () and any("noise floor" in w for w in wrong.warnings)  # and it says so


def test_world_frame_torque_without_attitude_is_refused(tmp_path, excited):
    truth = simulate(INERTIA, OMEGA0, 2.0, 100.0, excited.command_times[:2], excited.commands[:2], frame="world")
    bag = write_bag(tmp_path / "bag", truth, truth.omega)
    with pytest.raises(ValueError, match="world frame needs an attitude"):
        read_bag(bag, INPUTS)


def test_vector3_rates_and_summed_torque_topics(tmp_path, excited):
    bag = write_bag(tmp_path / "bag", excited, excited.omega, torque_topics=("/a", "/b"), vector_topic="/rate")
    data = read_bag(bag, BagInputs(angular_velocity="/rate", torque=("/a", "/b")))
    result = identify(data.measurements)
    assert np.max(np.abs(result.inertia - INERTIA)) / np.max(np.abs(INERTIA)) < 1e-6
    half = identify(read_bag(bag, BagInputs(angular_velocity="/rate", torque=("/a",))).measurements)
    assert np.allclose(half.inertia, INERTIA / 2.0, rtol=1e-5, atol=1e-9)  # half the torque, half the inertia


def test_validation_rms_drops_from_nominal_to_identified(excited):
    torque = PiecewiseTorque(excited.command_times, excited.commands)
    m = Measurements(excited.t, gyro(excited, 1e-3, np.zeros(3), 5), torque, excited.q)
    result = identify(m)
    validation = validate(m, result, np.diag([0.02, 0.03, 0.04]))
    assert validation.nominal is not None
    assert validation.identified.omega_rms < 2e-3 < 10 * 2e-3 < validation.nominal.omega_rms
    assert validation.identified.attitude_rms is not None and validation.nominal.attitude_rms is not None
    assert validation.identified.attitude_rms < 0.1 * validation.nominal.attitude_rms


def test_rotation_about_one_axis_leaves_parameters_unobservable():
    times = np.array([0.0, 2.0, 4.0])
    values = np.array([[0.0, 0.0, 0.01], [0.0, 0.0, -0.01], [0.0, 0.0, 0.005]])
    diagonal = np.diag([0.02, 0.03, 0.04])
    truth = simulate(diagonal, np.array([0.0, 0.0, 0.2]), 6.0, 100.0, times, values)
    readings = gyro(truth, 1e-4, np.zeros(3), seed=0)
    result = identify(Measurements(truth.t, readings, PiecewiseTorque(times, values)))
    assert result.unobservable
    text = " ".join(result.unobservable)
    assert "Ixx" in text and "1 independent axis only" in text


def test_written_body_yaml_is_a_body_the_scene_loader_accepts(excited):
    result = identify(Measurements(excited.t, excited.omega, PiecewiseTorque(excited.command_times, excited.commands)))
    body = yaml.safe_load(body_yaml(result))["body"]
    scene = parse_scene({"name": "check", "body": body, "initial": {"angular_velocity": [0.0, 0.0, 0.1]}})
    assert np.allclose(scene.body.inertia_array, INERTIA, rtol=1e-6)


def test_too_few_samples_and_unknown_estimates_are_refused(excited):
    m = Measurements(excited.t, excited.omega, PiecewiseTorque(excited.command_times, excited.commands))
    with pytest.raises(ValueError, match="at least"):
        identify(m.window(0.0, 0.05))
    with pytest.raises(ValueError, match="unknown"):
        identify(m, estimate=("mass",))


def test_the_identify_kernel_is_precompiled_with_the_types_identify_calls_it_with(excited):
    """``make setup``'s precompile compiles the identify kernel, and the fit and the validation replays
    call it with exactly those types: the first ``rigid-rot identify`` compiles nothing (issue 40)."""
    from rigid_rot_sim.core import precompile
    from rigid_rot_sim.core.sensitivities import integrate_segments

    assert precompile.entry_points()["sensitivities.integrate_segments"] is integrate_segments
    precompile.exercise()
    compiled = set(integrate_segments.signatures)
    assert len(compiled) == 1
    torque = PiecewiseTorque(excited.command_times, excited.commands)
    m = Measurements(excited.t, gyro(excited, 1e-3, np.zeros(3), 5), torque, excited.q)
    validate(m, identify(m, estimate=("inertia", "torque_bias", "gyro_bias")), np.diag([0.02, 0.03, 0.04]))
    assert set(integrate_segments.signatures) == compiled  # no signature of its own: nothing compiled at run time
