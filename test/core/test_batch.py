"""Tests for rigid_rot_sim.core.batch (N bodies advanced at once)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core import batch
from rigid_rot_sim.core.integrators.base import NonFiniteStateError

MOMENTS = np.array([1.0, 2.0, 3.0])
OMEGA0 = np.array([1.0, 0.1, 0.5])
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def reference(moments, omega0, q0, t_end, torque=(0.0, 0.0, 0.0)):
    """Tight DOP853 on Euler's equations and q' = 1/2 q (x) (omega, 0), written out here."""

    def rhs(t, y):
        x, yy, z, w = y[:4]
        wx, wy, wz = y[4:]
        dq = 0.5 * np.array(
            [w * wx + yy * wz - z * wy, w * wy + z * wx - x * wz, w * wz + x * wy - yy * wx, -x * wx - yy * wy - z * wz]
        )
        return np.concatenate([dq, (np.cross(moments * y[4:], y[4:]) + torque) / moments])

    y = solve_ivp(rhs, (0, t_end), np.r_[q0, omega0], method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    return y[:4] / np.linalg.norm(y[:4]), y[4:]


def attitude_angle(q_a, q_b):
    return (Rotation.from_quat(q_a).inv() * Rotation.from_quat(q_b)).magnitude()


@pytest.mark.parametrize("method, order", [("rk4", 4), ("implicit_midpoint", 2)])
def test_convergence_order_against_reference(method, order):
    torque = np.array([0.1, -0.05, 0.02])
    q_ref, w_ref = reference(MOMENTS, OMEGA0, IDENTITY, 5.0, torque)
    errors = []
    for n in (100, 200, 400):
        q, w = batch.advance_batch(method, MOMENTS, [IDENTITY], [OMEGA0], 5.0 / n, n, torque)
        errors.append(max(np.abs(w[0] - w_ref).max(), attitude_angle(q_ref, q[0])))
    observed = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(observed - order) < 0.3), observed


def test_bodies_are_independent_and_match_single_runs():
    rng = np.random.default_rng(7)
    n = 5
    moments = np.sort(rng.uniform(1.0, 2.0, size=(n, 3)), axis=1)
    omega = rng.normal(size=(n, 3))
    q = Rotation.random(n, random_state=3).as_quat()
    torque = rng.normal(size=(n, 3)) * 0.1
    for method in batch.BATCH_METHODS:
        q_all, w_all = batch.advance_batch(method, moments, q, omega, 0.01, 50, torque)
        for k in range(n):
            q_one, w_one = batch.advance_batch(method, moments[k], q[k : k + 1], omega[k : k + 1], 0.01, 50, torque[k])
            np.testing.assert_allclose(w_all[k], w_one[0], rtol=0, atol=1e-14)
            np.testing.assert_allclose(q_all[k], q_one[0], rtol=0, atol=1e-14)


def test_implicit_midpoint_conserves_energy_momentum_at_large_steps():
    # 5 rad per step: far beyond any explicit method's stability limit
    dt = 5.0 / np.linalg.norm(OMEGA0)
    rng = np.random.default_rng(2)
    omega = rng.normal(size=(20, 3))
    q0 = Rotation.random(20, random_state=4).as_quat()
    q, w = batch.advance_batch("implicit_midpoint", MOMENTS, q0, omega, dt, 200)
    energy0 = 0.5 * np.sum(MOMENTS * omega**2, axis=1)
    energy = 0.5 * np.sum(MOMENTS * w**2, axis=1)
    np.testing.assert_allclose(energy, energy0, rtol=1e-12)
    l_world0 = Rotation.from_quat(q0).apply(MOMENTS * omega)
    l_world = Rotation.from_quat(q).apply(MOMENTS * w)
    np.testing.assert_allclose(l_world, l_world0, rtol=0, atol=1e-12 * np.abs(l_world0).max())
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-15)


@pytest.mark.parametrize("method", batch.BATCH_METHODS)
def test_sphere_under_constant_torque_is_linear_in_time(method):
    moments = np.full(3, 2.5)
    torque = np.array([0.3, -0.2, 0.1])
    q, w = batch.advance_batch(method, moments, [IDENTITY], [OMEGA0], 0.1, 100, torque)
    np.testing.assert_allclose(w[0], OMEGA0 + torque * 10.0 / moments, rtol=0, atol=1e-13)


def test_rk4_blows_up_with_named_step_not_nan():
    # rk4 beyond its stability limit (nu dt >> 2 sqrt 2) grows without bound
    with pytest.raises(NonFiniteStateError, match="step"):
        batch.advance_batch("rk4", MOMENTS, [IDENTITY], [[10.0, 1.0, 5.0]], 2.0, 10_000)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(method="verlet"), "method"),
        (dict(principal_moments=[1.0, 0.0, 2.0]), r"principal_moments\[0, 1\]"),
        (dict(omega=[[1.0, np.nan, 0.0]]), r"omega\[0, 1\]"),
        (dict(q=[[0.0, 0.0, 0.0, 0.0]]), r"q\[0\]"),
        (dict(dt=-1.0), "dt"),
        (dict(n_steps=2.5), "n_steps"),
        (dict(torque_body=[1.0, 2.0]), "torque_body"),
    ],
)
def test_bad_input_names_argument(kwargs, name):
    args = dict(method="rk4", principal_moments=MOMENTS, q=[IDENTITY], omega=[OMEGA0], dt=0.1, n_steps=3)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        batch.advance_batch(**args)


@pytest.mark.parametrize("method", batch.BATCH_METHODS)
def test_matches_single_body_integrator_to_round_off(method):
    from rigid_rot_sim.core.integrators import get_method
    from rigid_rot_sim.core.torque import ConstantTorque

    rng = np.random.default_rng(11)
    moments = np.sort(rng.uniform(0.5, 2.0, size=(4, 3)), axis=1)
    omega = rng.normal(size=(4, 3))
    q = Rotation.random(4, random_state=5).as_quat()
    torque = 0.1 * rng.normal(size=(4, 3))
    q_all, w_all = batch.advance_batch(method, moments, q, omega, 0.05, 200, torque)
    for k in range(4):
        single = get_method(method)(moments[k], 0.05, ConstantTorque(torque[k]), q0=q[k], omega0=omega[k])
        single.advance(200)
        np.testing.assert_allclose(w_all[k], single.omega, rtol=0, atol=1e-12)
        # q and -q are the same rotation
        assert attitude_angle(single.q, q_all[k]) < 1e-12


@pytest.mark.parametrize("method, dt", [("rk4", 0.05), ("implicit_midpoint", 0.01), ("implicit_midpoint", 0.5)])
def test_a_body_gets_the_same_bits_in_any_batch(method, dt):
    """Sweeps chunk runs into batches of any size: a body's result must not depend on its neighbours."""
    rng = np.random.default_rng(1)
    n = 23
    moments = np.sort(rng.uniform(1.0, 2.0, size=(n, 3)), axis=1)
    omega = rng.normal(size=(n, 3)) * 5.0
    q = Rotation.random(n, random_state=3).as_quat()
    torque = rng.normal(size=(n, 3)) * 0.1
    q_all, w_all = batch.advance_batch(method, moments, q, omega, dt, 100, torque)
    for k in range(n):
        q_one, w_one = batch.advance_batch(method, moments[k], q[k : k + 1], omega[k : k + 1], dt, 100, torque[k])
        assert np.array_equal(w_one[0], w_all[k]) and np.array_equal(q_one[0], q_all[k]), k


def test_simd_rk4_gives_every_body_the_bits_of_the_single_body_kernel():
    """The structure-of-arrays rk4 (chunks of bodies, parallel here) against RK4 body by body and the per-body loop."""
    from rigid_rot_sim.core.integrators import get_method
    from rigid_rot_sim.core.torque import ConstantTorque

    rng = np.random.default_rng(21)
    n = 2 * batch._SOA_CHUNK + 77  # two full chunks and a partial one
    moments = np.sort(rng.uniform(0.5, 3.0, size=(n, 3)), axis=1)
    omega = rng.normal(size=(n, 3)) * 3.0
    q = rng.normal(size=(n, 4))  # not normalised: both paths normalise on entry
    torque = 0.1 * rng.normal(size=(n, 3))
    torque[::4] = 0.0  # free bodies
    torque[1::5, 1] = -0.0  # a signed zero inside a torque
    torque[2::9] = (0.0, -0.0, 0.0)  # an all-zero torque with a signed zero: a free body
    omega[3] = (0.0, 0.0, 0.0)  # a body at rest (the small-angle branch)
    steps = 200  # n * steps >= the parallel threshold
    q_soa, w_soa = batch.advance_batch("rk4", moments, q, omega, 0.01, steps, torque)
    q_ref, w_ref = batch.advance_batch("rk4", moments, q, omega, 0.01, steps, torque, layout="per_body")
    assert np.array_equal(q_soa, q_ref) and np.array_equal(w_soa, w_ref)
    for k in (0, 1, 2, 3, 5, 511, 512, n - 1):
        single = get_method("rk4")(moments[k], 0.01, ConstantTorque(torque[k]), q0=q[k], omega0=omega[k])
        single.advance(steps)
        assert np.array_equal(single.q, q_soa[k]) and np.array_equal(single.omega, w_soa[k]), k


@pytest.mark.parametrize("n_steps", [50, 5_000])  # serial, parallel
def test_simd_rk4_reports_the_failing_step_and_body_as_the_per_body_loop(n_steps):
    n = 40
    omega = np.tile([1.0, 0.1, 0.5], (n, 1))
    omega[17] = (10.0, 1.0, 5.0)  # beyond rk4's stability limit at dt = 2: blows up
    omega[29] = (12.0, 1.0, 5.0)
    messages = []
    for layout in ("soa", "per_body"):
        with pytest.raises(NonFiniteStateError) as failure:
            batch.advance_batch("rk4", MOMENTS, np.tile(IDENTITY, (n, 1)), omega, 2.0, n_steps, layout=layout)
        messages.append(str(failure.value))
    assert messages[0] == messages[1] and "body" in messages[0]


def test_unknown_layout_is_refused():
    with pytest.raises(ValueError, match="layout"):
        batch.advance_batch("rk4", MOMENTS, [IDENTITY], [OMEGA0], 0.1, 1, layout="aos")


@pytest.mark.parametrize(
    "method, layout",
    [
        ("rk4", "soa"),
        ("rk4", "per_body"),
        ("implicit_midpoint", "soa"),
        ("splitting", "soa"),
        ("exact_split", "soa"),
        ("exact", "soa"),
    ],
)
@pytest.mark.parametrize("n", [7, 4 * batch._SOA_CHUNK + 3])  # serial; parallel, over SIMD chunks and a partial one
def test_recording_gives_the_bits_of_calls_cut_at_the_records(method, layout, n):
    """One call keeping the rates at checkpoints = calls cut there, the first normalising q, the others continuing."""
    rng = np.random.default_rng(31)
    moments = np.sort(rng.uniform(0.5, 3.0, size=(n, 3)), axis=1)
    omega = rng.normal(size=(n, 3))
    q = rng.normal(size=(n, 4))  # not normalised: the first cut normalises it
    torque = None if method == "exact" else 0.1 * rng.normal(size=(n, 3))
    record_steps = [3, 4, 40, 120]
    q_rec, w_rec, w_at = batch.advance_batch_recording(
        method, moments, q, omega, 0.02, record_steps, torque, layout=layout
    )
    q_cut, w_cut = q, omega
    begun = 0
    for k, end in enumerate(record_steps):
        q_cut, w_cut = batch.advance_batch(
            method, moments, q_cut, w_cut, 0.02, end - begun, torque, normalize_q=k == 0, layout=layout
        )
        assert np.array_equal(w_at[k], w_cut), k
        begun = end
    assert w_at.shape == (len(record_steps), n, 3)
    assert np.array_equal(q_rec, q_cut) and np.array_equal(w_rec, w_cut)  # the run ends at the last record


@pytest.mark.parametrize("record_steps", [[], [0, 3], [3, 3], [5, 2], [[1, 2]], [1.0, 2.0]])
def test_recording_refuses_steps_that_are_not_increasing_positive_integers(record_steps):
    with pytest.raises(ValueError, match="record_steps"):
        batch.advance_batch_recording("rk4", MOMENTS, [IDENTITY], [OMEGA0], 0.1, record_steps)


@pytest.mark.parametrize("layout", ["soa", "per_body"])
def test_recording_reports_a_failure_as_advance_batch(layout):
    n = 40
    omega = np.tile([1.0, 0.1, 0.5], (n, 1))
    omega[17] = (10.0, 1.0, 5.0)  # beyond rk4's stability limit at dt = 2: blows up
    with pytest.raises(NonFiniteStateError) as plain:
        batch.advance_batch("rk4", MOMENTS, np.tile(IDENTITY, (n, 1)), omega, 2.0, 50, layout=layout)
    with pytest.raises(NonFiniteStateError) as recording:
        batch.advance_batch_recording(
            "rk4", MOMENTS, np.tile(IDENTITY, (n, 1)), omega, 2.0, [10, 20, 50], layout=layout
        )
    assert str(recording.value) == str(plain.value)
