"""The rods' torque against Basilisk's MtbEffector law, the clamp, the residual dipole and the pollution."""

from __future__ import annotations

import numpy as np
import pytest

from rigid_rot_sim.core import magnetorquer
from rigid_rot_sim.core.magnetorquer import Magnetorquers


def basilisk_mtb_torque(
    gt_row_major: list[float], num_mtb: int, cmds: list[float], max_dipoles: list[float], mag_field_b: np.ndarray
) -> np.ndarray:
    """MtbEffector::computeForceTorque as documented: GtMatrix_B is a row-major 3 x numMTB payload,
    each command clamped to [-max, max] in a loop, then ``torque = -[b~] (G_t mu)``."""
    gt = np.zeros((3, num_mtb))
    for row in range(3):
        for col in range(num_mtb):
            gt[row, col] = gt_row_major[row * num_mtb + col]
    mu = list(cmds)
    for i in range(num_mtb):
        if mu[i] > max_dipoles[i]:
            mu[i] = max_dipoles[i]
        elif mu[i] < -max_dipoles[i]:
            mu[i] = -max_dipoles[i]
    bx, by, bz = mag_field_b
    b_tilde = np.array([[0.0, -bz, by], [bz, 0.0, -bx], [-by, bx, 0.0]])
    return -b_tilde @ (gt @ np.array(mu))


def test_torque_equals_basilisks_law_for_non_orthogonal_clamped_rods():
    rng = np.random.default_rng(38)
    worst = 0.0
    for n in (1, 2, 3, 4, 6):
        for _ in range(50):
            axes = rng.normal(size=(3, n))
            axes /= np.linalg.norm(axes, axis=0)  # unit but not orthogonal
            limits = rng.uniform(0.05, 0.5, n)
            cmds = rng.uniform(-1.0, 1.0, n)  # about half of them beyond their limit
            b = rng.normal(scale=3e-5, size=3)
            ours = magnetorquer.torque(axes, cmds, b, limits)
            ref = basilisk_mtb_torque(axes.reshape(-1).tolist(), n, cmds.tolist(), limits.tolist(), b)
            scale = float(np.max(np.abs(ref))) or 1.0
            worst = max(worst, float(np.max(np.abs(ours - ref))) / scale)
    assert worst <= 1e-12


def test_the_clamp_actually_limits_and_is_reported():
    rods = Magnetorquers(axes=np.eye(3), max_dipoles=[0.2, 0.2, 0.2], names=("x", "y", "z"))
    made, limited = rods.clamped([0.5, -0.1, -0.3])
    assert made.tolist() == [0.2, -0.1, -0.2]
    assert limited == [0, 2]
    # the torque of an over-limit command is the torque of the limit
    b = np.array([0.0, 0.0, 4e-5])
    assert rods.torque([5.0, 0.0, 0.0], b).tolist() == rods.torque([0.2, 0.0, 0.0], b).tolist()
    assert rods.torque([5.0, 0.0, 0.0], b)[1] == pytest.approx(-0.2 * 4e-5, rel=1e-15)


def test_residual_dipole_adds_to_the_rods_and_torque_is_normal_to_the_field():
    rng = np.random.default_rng(1)
    axes = rng.normal(size=(3, 3))
    residual = np.array([1e-3, -2e-3, 5e-4])
    rods = Magnetorquers(axes=axes, max_dipoles=[0.2, 0.3, 0.1], residual=residual)
    b = rng.normal(scale=3e-5, size=3)
    tau = rods.torque([0.1, -0.4, 0.05], b)
    expected = np.cross(rods.axes @ np.clip([0.1, -0.4, 0.05], [-0.2, -0.3, -0.1], [0.2, 0.3, 0.1]) + residual, b)
    np.testing.assert_allclose(tau, expected, rtol=0, atol=1e-20)
    assert abs(tau @ b) <= 1e-12 * np.linalg.norm(tau) * np.linalg.norm(b)
    # rods off: the residual dipole alone
    np.testing.assert_allclose(rods.torque(np.zeros(3), b), np.cross(residual, b), rtol=0, atol=1e-22)


def test_axes_are_normalised_and_bad_rods_are_refused():
    rods = Magnetorquers(axes=[[2.0], [0.0], [0.0]], max_dipoles=[0.2])
    assert rods.axes[:, 0].tolist() == [1.0, 0.0, 0.0] and rods.names == ("rod_0",)
    with pytest.raises(ValueError, match="axis must not be zero"):
        Magnetorquers(axes=np.zeros((3, 1)), max_dipoles=[0.2])
    with pytest.raises(ValueError, match="max_dipoles must be > 0"):
        Magnetorquers(axes=np.eye(3), max_dipoles=[0.2, 0.0, 0.2])
    with pytest.raises(ValueError, match="distinct names"):
        Magnetorquers(axes=np.eye(3), max_dipoles=[0.2] * 3, names=("a", "a", "b"))
    with pytest.raises(ValueError, match=r"shape \(3, n\)"):
        Magnetorquers(axes=np.eye(2), max_dipoles=[0.2] * 2)
    with pytest.raises(ValueError, match="finite"):
        Magnetorquers(axes=np.eye(3), max_dipoles=[0.2] * 3).clamped([np.nan, 0.0, 0.0])


def test_pollution_is_the_coupling_of_the_clamped_dipoles():
    coupling = np.array([[1e-6, 0.0, 2e-7], [0.0, 1e-6, 0.0], [3e-7, 0.0, 1e-6]])  # T per A*m^2
    rods = Magnetorquers(axes=np.eye(3), max_dipoles=[0.2] * 3, coupling=coupling)
    b = np.array([1e-5, 2e-5, -3e-5])
    np.testing.assert_allclose(rods.measured_field(b, [1.0, 0.0, -0.1]), b + coupling @ [0.2, 0.0, -0.1], rtol=1e-15)
    # zero coupling by default: the magnetometer sees the true field
    assert (
        Magnetorquers(axes=np.eye(3), max_dipoles=[0.2] * 3).measured_field(b, [0.2, 0.2, 0.2]).tolist() == b.tolist()
    )


def test_allocate_makes_the_body_dipole_or_scales_it_keeping_its_direction():
    rng = np.random.default_rng(7)
    axes = rng.normal(size=(3, 4))
    axes /= np.linalg.norm(axes, axis=0)
    limits = np.array([0.2, 0.2, 0.1, 0.3])
    small = np.array([0.01, -0.02, 0.015])
    np.testing.assert_allclose(axes @ magnetorquer.allocate(axes, small, limits), small, rtol=1e-12, atol=1e-15)
    big = 100.0 * small
    dipoles = magnetorquer.allocate(axes, big, limits)
    assert np.max(np.abs(dipoles) / limits) == pytest.approx(1.0, rel=1e-14)
    made = axes @ dipoles
    np.testing.assert_allclose(made / np.linalg.norm(made), big / np.linalg.norm(big), rtol=0, atol=1e-12)
    assert magnetorquer.rod_duty(dipoles, limits).max() == pytest.approx(1.0, rel=1e-14)
