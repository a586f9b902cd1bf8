"""B-cross against its closed form through the integrators; B-dot's duty cycle; momentum unloading."""

from __future__ import annotations

import numpy as np
import pytest

from rigid_rot_sim.core import magnetic_control as mc
from rigid_rot_sim.core import magnetorquer
from rigid_rot_sim.core.quaternion import rotate, rotate_inverse
from rigid_rot_sim.core.simulate import simulate

J = 0.05  # kg*m^2, a spherical body
K = 5e-3  # N*m*s: exp(-K t / J) = exp(-0.1 t)
B_WORLD = np.array([1.5e-5, -2.0e-5, 3.0e-5])  # T, fixed in the world
RODS = np.array([[1.0, 0.6, 0.0], [0.0, 0.8, 0.6], [0.0, 0.0, 0.8]])  # non-orthogonal unit columns
NO_LIMIT = np.full(3, 1e6)


def bcross_torque(t: float, q: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """The B-cross law flown through rods: field into the body, dipole, split on the rods, torque."""
    b_body = np.array(rotate_inverse(q, B_WORLD))
    dipoles = magnetorquer.allocate(RODS, mc.bcross_dipole(omega, b_body, K), NO_LIMIT)
    return magnetorquer.torque(RODS, dipoles, b_body, NO_LIMIT)


@pytest.mark.parametrize(
    ("method", "options"), [("rk4", {}), ("dop853", {"rtol": 1e-13, "atol": 1e-15}), ("lie_rk4", {})]
)
def test_bcross_on_a_sphere_in_a_fixed_field_matches_the_closed_form(method, options):
    omega0 = np.array([0.3, -0.2, 0.25])
    traj = simulate(
        (J, J, J), omega0, t_end=40.0, dt=0.01, method=method, torque=bcross_torque, save_every=100, **options
    )
    b_hat = B_WORLD / np.linalg.norm(B_WORLD)
    w0 = omega0  # q0 = identity: world and body agree at t = 0
    par0 = (w0 @ b_hat) * b_hat
    perp0 = w0 - par0
    for t, q, w in zip(traj.t, traj.q, traj.omega, strict=True):
        w_world = np.array(rotate(q, w))
        par = (w_world @ b_hat) * b_hat
        perp = w_world - par
        np.testing.assert_allclose(par, par0, rtol=1e-9, atol=1e-9 * np.linalg.norm(par0))
        exact_perp = perp0 * np.exp(-K * t / J)
        assert np.linalg.norm(perp - exact_perp) <= 1e-9 * np.linalg.norm(exact_perp)
    # and it did decay: after 40 s the perpendicular part is e^-4 of where it started
    assert np.linalg.norm(np.array(rotate(traj.q[-1], traj.omega[-1])) - par0) < 0.02 * np.linalg.norm(perp0)


def test_bcross_torque_is_minus_k_omega_perp():
    rng = np.random.default_rng(3)
    for _ in range(20):
        w, b = rng.normal(size=3), rng.normal(scale=3e-5, size=3)
        tau = np.cross(mc.bcross_dipole(w, b, 0.7), b)
        perp = w - (w @ b) / (b @ b) * b
        np.testing.assert_allclose(tau, -0.7 * perp, rtol=1e-12, atol=1e-15)
    assert mc.bcross_dipole([1.0, 2.0, 3.0], np.zeros(3), 1.0).tolist() == [0.0, 0.0, 0.0]


def test_bdot_in_a_body_spinning_in_a_fixed_field_approaches_bcross():
    # body spinning at w in a world-fixed field: db/dt = -w x b in the body, so -k db/dt = k w x b
    w = np.array([0.1, -0.05, 0.08])
    b = np.array([2e-5, 1e-5, -3e-5])
    assert np.allclose(mc.bdot_dipole(-np.cross(w, b), 3e4), 3e4 * np.cross(w, b), rtol=1e-15)


def test_bdot_duty_cycle_senses_with_rods_off_then_holds_the_difference():
    schedule = mc.BDotSchedule(gain=2.0, sample_period=0.1, cycle_samples=10, sensing_samples=4, settle_samples=1)
    assert schedule.duty == pytest.approx(0.6)
    fields = [np.array([1.0, 0.0, 0.0]) * (k * k) for k in range(25)]  # a known, non-linear field
    state = mc.BDotState.initial()
    commands = []
    for k, b in enumerate(fields):
        state, m = mc.bdot_step(schedule, state, k, b)
        commands.append(m)
    # rods off through the sensing window (samples 0-3 and 10-13, 20-23) ...
    for k in (0, 1, 2, 3, 10, 11, 12, 13, 20, 21, 22, 23):
        assert commands[k].tolist() == [0.0, 0.0, 0.0]
    # ... then -k (b[3] - b[1]) / (2 * 0.1) held from sample 4 to 9, from the window's own samples
    for k in range(4, 10):
        assert commands[k].tolist() == [-2.0 * (9.0 - 1.0) / 0.2, 0.0, 0.0]
    for k in range(14, 20):
        assert commands[k].tolist() == [-2.0 * (169.0 - 121.0) / 0.2, 0.0, 0.0]


def test_bdot_without_duty_cycle_differences_consecutive_samples():
    schedule = mc.BDotSchedule(gain=1.0, sample_period=0.5, sensing_samples=0)
    state = mc.BDotState.initial()
    state, m0 = mc.bdot_step(schedule, state, 0, [1.0, 2.0, 3.0])
    state, m1 = mc.bdot_step(schedule, state, 1, [2.0, 2.0, 1.0])
    assert m0.tolist() == [0.0, 0.0, 0.0]
    assert m1.tolist() == [-2.0, 0.0, 4.0]


def test_bdot_schedule_refuses_a_window_with_no_difference_or_no_torquing():
    with pytest.raises(ValueError, match="sensing_samples"):
        mc.BDotSchedule(gain=1.0, sample_period=0.1, cycle_samples=10, sensing_samples=2, settle_samples=1)
    with pytest.raises(ValueError, match="cycle_samples"):
        mc.BDotSchedule(gain=1.0, sample_period=0.1, cycle_samples=3, sensing_samples=3, settle_samples=0)
    with pytest.raises(ValueError, match="gain"):
        mc.BDotSchedule(gain=-1.0, sample_period=0.1)


def test_unloading_dumps_wheel_momentum_perpendicular_to_the_field_and_spares_the_body():
    rng = np.random.default_rng(11)
    wheel_axes = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.577, 0.577, 0.577]])
    wheel_axes /= np.linalg.norm(wheel_axes, axis=1)[:, None]
    h = mc.wheel_momentum(wheel_axes, [1e-4] * 4, rng.uniform(-300, 300, 4))
    b = rng.normal(scale=3e-5, size=3)
    m = mc.unloading_dipole(h, b, 0.01)
    tau = np.cross(m, b)
    h_perp = h - (h @ b) / (b @ b) * b
    np.testing.assert_allclose(tau, -0.01 * h_perp, rtol=1e-12, atol=1e-18)
    u = mc.unloading_wheel_torque(wheel_axes, tau)
    np.testing.assert_allclose(wheel_axes.T @ u, tau, rtol=1e-12, atol=1e-18)  # the body feels tau - sum u g = 0
