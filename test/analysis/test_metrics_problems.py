"""Error metrics and the work-precision problems' references."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rigid_rot_sim.analysis import metrics, problems


@pytest.mark.parametrize("angle", [1e-15, 1e-9, 1e-4, 0.5, 3.0, math.pi])
def test_attitude_error_angle_is_accurate_for_tiny_and_large_angles(angle):
    q_ref = Rotation.from_rotvec([0.3, -1.2, 0.7]).as_quat()
    axis = np.array([1.0, 2.0, -2.0]) / 3.0
    q = (Rotation.from_quat(q_ref) * Rotation.from_rotvec(angle * axis)).as_quat()
    assert metrics.attitude_error_angle(q_ref, q) == pytest.approx(angle, rel=1e-9, abs=1e-16)
    # the sign of a quaternion does not change the rotation
    assert metrics.attitude_error_angle(-q_ref, q) == pytest.approx(angle, rel=1e-9, abs=1e-16)


def test_omega_error_and_relative_change():
    assert metrics.omega_error([1.0, 2.0, 3.0], [1.0, 2.5, 2.0]) == 1.0
    assert metrics.relative_change(2.0, 2.5) == 0.25
    assert metrics.relative_change(0.0, 1e-3) == 1e-3


@pytest.mark.parametrize("key", ["P1", "P1b", "P4"])
def test_exact_references_conserve_energy_and_momentum(key):
    problem = problems.get_problem(key)
    ref = problem.reference()
    e0 = problem.energy(problem.q0, problem.omega0)
    assert problem.energy(ref.q, ref.omega) == pytest.approx(e0, rel=1e-13)
    l0 = Rotation.from_quat(problem.q0).apply(problem.moments * problem.omega0)
    l_end = Rotation.from_quat(ref.q).apply(problem.moments * ref.omega)
    np.testing.assert_allclose(l_end, l0, atol=1e-12 * np.linalg.norm(l0))


def test_p1b_reference_has_flipped_about_the_intermediate_axis():
    # near the intermediate axis the body flips: omega_2 changes sign along the way
    from rigid_rot_sim.core.exact import torque_free_solution

    p = problems.get_problem("P1b")
    w2 = torque_free_solution(p.moments, p.omega0, p.q0).omega(np.linspace(0, p.t_end, 4001))[:, 1]
    assert np.any(w2 < -1.9) and np.any(w2 > 1.9)


def test_p2_reference_is_certified_and_obeys_angular_impulse():
    p = problems.get_problem("P2")
    ref = p.reference()
    assert 0.0 < ref.certified_to <= problems.CERTIFY_TOL
    # world-frame dL/dt = R(q) N: the change of L_world is the integral of the world torque,
    # so |L| cannot change by more than |N| t_end
    l0 = p.momentum_norm(p.omega0)
    assert abs(p.momentum_norm(ref.omega) - l0) <= np.linalg.norm(p.torque.value) * p.t_end


def test_unknown_problem_lists_valid_keys():
    with pytest.raises(ValueError, match="P1"):
        problems.get_problem("P9")


@pytest.mark.parametrize("key", ["P3", "P3b"])
def test_heavy_top_references_start_at_the_initial_state(key):
    import dataclasses

    p = problems.get_problem(key)
    start = dataclasses.replace(p, key=f"{key}-start", t_end=1e-12)
    ref = start.reference_factory(start)
    np.testing.assert_allclose(ref.omega, p.omega0, atol=1e-9)
    assert metrics.attitude_error_angle(p.q0, ref.q) < 1e-9


@pytest.mark.parametrize("key", ["P3", "P3b"])
def test_heavy_top_references_keep_energy_and_both_momenta(key):
    p = problems.get_problem(key)
    ref = p.reference()
    initial = p.top.invariants(np.asarray(p.q0), np.asarray(p.omega0))
    final = p.top.invariants(ref.q, ref.omega)
    np.testing.assert_allclose(final, initial, rtol=1e-10, atol=1e-12)


def test_separatrix_reference_approaches_the_vertical():
    p = problems.get_problem("P3")
    ref = p.reference()
    # cos(theta) = z of the body symmetry axis in the world: 1/cos(theta) = 1 + 1/cosh(gamma t)
    axis_z = Rotation.from_quat(ref.q).apply([0.0, 0.0, 1.0])[2]
    i1 = p.top.pivot_moments[0]
    gamma = math.sqrt(p.top.mass * p.top.gravity * p.top.com_distance / i1)
    assert 1.0 / axis_z == pytest.approx(1.0 + 1.0 / math.cosh(gamma * p.t_end), rel=1e-12)
    assert math.acos(axis_z) < 0.1


def test_final_state_runs_a_method_to_the_end_of_the_problem():
    p = problems.get_problem("P4")
    ref = p.reference()
    q, omega = p.final_state("exact", p.t_end)  # one step of length t_end: the exact flow itself
    assert metrics.omega_error(ref.omega, omega) < 1e-10 and metrics.attitude_error_angle(ref.q, q) < 1e-10
    q4, omega4 = p.final_state("rk4", p.t_end / 2000)
    assert 0.0 < metrics.omega_error(ref.omega, omega4) < 1e-6
