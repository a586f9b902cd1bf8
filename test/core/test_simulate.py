"""simulate(): validation, the time grid, user-frame outputs, torque forms, failures."""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.dynamics import RigidBody
from rigid_rot_sim.core.exact import torque_free_solution
from rigid_rot_sim.core.integrators import METHODS, NonFiniteStateError
from rigid_rot_sim.core.simulate import Trajectory, simulate
from rigid_rot_sim.core.steps import step_grid
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque

MOMENTS = (1.0, 2.0, 3.0)
OMEGA0 = (1.0, 0.1, 0.5)
Q0 = Rotation.from_rotvec([0.3, -0.2, 0.5]).as_quat()
AXES = Rotation.from_rotvec([0.4, -0.9, 0.3])
TENSOR = AXES.as_matrix() @ np.diag([2.0, 3.0, 4.5]) @ AXES.as_matrix().T


def same_attitudes(q, q_ref, atol):
    return float(np.max((Rotation.from_quat(q).inv() * Rotation.from_quat(q_ref)).magnitude())) < atol


# --- validation -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"inertia": (1.0, -2.0, 3.0)}, r"inertia\[1\] must be > 0"),
        ({"inertia": (1.0, 2.0, np.nan)}, r"inertia\[2\] must be finite"),
        ({"inertia": (1.0, 1.0, 3.0)}, "inertia .* triangle inequality"),
        ({"inertia": np.diag([1.0, 1.0, 3.0])}, "triangle inequality"),
        ({"inertia": [[1.0, 0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]}, "inertia must be symmetric"),
        ({"omega0": (1.0, np.nan, 0.0)}, r"omega0\[1\] must be finite"),
        ({"omega0": (1.0, 0.0)}, "omega0 must have shape"),
        ({"q0": (0.0, 0.0, 0.0, 0.0)}, "q0 must be a non-zero quaternion"),
        ({"q0": (0.0, np.inf, 0.0, 1.0)}, r"q0\[1\] must be finite"),
        ({"dt": 0.0}, "dt must be > 0"),
        ({"dt": -0.1}, "dt must be > 0"),
        ({"dt": np.nan}, "dt must be finite"),
        ({"t_end": -1.0}, "t_end must be >= 0"),
        ({"t_end": np.inf}, "t_end must be finite"),
        ({"method": "rk45"}, "unknown integrator 'rk45'; valid methods: "),
        ({"torque": (0.0, np.nan, 0.0)}, r"torque\[1\] must be finite"),
        ({"save_every": 0}, "save_every must be an integer >= 1"),
        ({"save_every": 1.5}, "save_every must be an integer >= 1"),
        ({"bogus_option": 3}, "bogus_option"),
    ],
)
def test_bad_arguments_are_value_errors_naming_them(kwargs, match):
    args = {"inertia": MOMENTS, "omega0": OMEGA0, "t_end": 1.0, "dt": 0.1, "method": "rk4"}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        simulate(**args)


# --- time grid ------------------------------------------------------------------------------


def test_grid_rule():
    assert step_grid(1.0, 0.1) == (10, 0.0)  # 1.0 / 0.1 is 10 up to rounding
    n, last = step_grid(1.05, 0.1)
    assert n == 10 and last == pytest.approx(0.05)
    assert step_grid(0.0, 0.1) == (0, 0.0)
    n, last = step_grid(0.03, 0.1)
    assert n == 0 and last == pytest.approx(0.03)


@pytest.mark.parametrize(
    "t_end, save_every, expected_t",
    [
        (1.0, 1, np.linspace(0.0, 1.0, 11)),
        (1.0, 5, [0.0, 0.5, 1.0]),
        (1.0, 3, [0.0, 0.3, 0.6, 0.9, 1.0]),
        (1.05, 1, [*np.linspace(0.0, 1.0, 11), 1.05]),
        (0.0, 1, [0.0]),
        (0.04, 1, [0.0, 0.04]),
    ],
)
def test_samples_land_on_the_grid_and_on_t_end(t_end, save_every, expected_t):
    traj = simulate(MOMENTS, OMEGA0, t_end, 0.1, "rk4", save_every=save_every)
    assert np.allclose(traj.t, expected_t, rtol=0, atol=1e-12)
    assert traj.t[-1] == t_end
    n = len(expected_t)
    assert traj.q.shape == (n, 4) and traj.omega.shape == (n, 3)
    assert traj.energy.shape == (n,) and traj.L_world.shape == (n, 3)


@pytest.mark.parametrize("method", sorted(METHODS))
def test_last_partial_step_reaches_t_end(method):
    """t_end = 1.234 with dt = 0.1: 12 steps and one of 0.034 s; the state is the exact one at t_end."""
    traj = simulate(
        MOMENTS,
        OMEGA0,
        1.234,
        0.1 if METHODS[method].orders[0] >= 4 or not METHODS[method].fixed_step else 0.001,
        method,
        q0=Q0,
    )
    exact = torque_free_solution(MOMENTS, OMEGA0, Q0)
    tol = {1: 1e-2, 2: 1e-5}.get(METHODS[method].orders[0], 1e-6)
    assert traj.t[-1] == 1.234
    assert np.max(np.abs(traj.omega[-1] - exact.omega(1.234))) < tol
    assert same_attitudes(traj.q[-1], exact.quaternion(1.234), tol)


def test_save_every_keeps_a_subset_of_the_same_steps():
    full = simulate(MOMENTS, OMEGA0, 2.0, 0.01, "rk4", q0=Q0)
    sparse = simulate(MOMENTS, OMEGA0, 2.0, 0.01, "rk4", q0=Q0, save_every=20)
    assert np.allclose(sparse.t, full.t[::20])
    assert np.array_equal(sparse.omega, full.omega[::20])
    assert np.array_equal(sparse.q, full.q[::20])


# --- invariants and frames ------------------------------------------------------------------


def test_trajectory_is_frozen_and_reports_invariants():
    traj = simulate(MOMENTS, OMEGA0, 5.0, 0.01, "implicit_midpoint", q0=Q0)
    assert isinstance(traj, Trajectory) and traj.method == "implicit_midpoint"
    with pytest.raises(AttributeError):
        traj.t = None
    T = 0.5 * np.sum(np.asarray(MOMENTS) * traj.omega**2, axis=1)
    assert np.allclose(traj.energy, T, rtol=1e-15)
    assert np.allclose(traj.energy, traj.energy[0], rtol=1e-13)
    assert np.allclose(traj.L_world, traj.L_world[0], rtol=0, atol=1e-13)
    assert np.allclose(traj.L_world, Rotation.from_quat(traj.q).apply(np.asarray(MOMENTS) * traj.omega))
    assert np.allclose(np.linalg.norm(traj.q, axis=1), 1.0, rtol=0, atol=4e-16)


@pytest.mark.parametrize("method", ["rk4", "splitting", "implicit_midpoint", "dop853"])
def test_full_tensor_outputs_are_in_the_user_body_frame(method):
    """A body given by a non-diagonal tensor: outputs match the exact principal-frame solution
    mapped back with body_from_principal, and L_world = R(q) J omega from the outputs alone."""
    omega0 = np.array([0.7, -0.3, 0.4])
    traj = simulate(TENSOR, omega0, 3.0, 0.01, method, q0=Q0, save_every=10)
    body = RigidBody.from_inertia(TENSOR)
    exact = torque_free_solution(
        body.principal_moments, body.vector_to_principal(omega0), body.attitude_to_principal(Q0)
    )
    omega_ref = body.vector_from_principal(exact.omega(traj.t))
    q_ref = body.attitude_from_principal(exact.quaternion(traj.t))
    tol = 1e-4 if method in ("splitting", "implicit_midpoint") else 1e-8  # order 2 at dt = 0.01
    assert np.max(np.abs(traj.omega - omega_ref)) < tol
    assert same_attitudes(traj.q, q_ref, tol)
    assert np.allclose(traj.q[0], Q0) and np.allclose(traj.omega[0], omega0)
    L_world = Rotation.from_quat(traj.q).apply(traj.omega @ TENSOR.T)
    assert np.allclose(L_world, traj.L_world, atol=1e-12)
    assert np.allclose(traj.L_world, Rotation.from_quat(Q0).apply(TENSOR @ omega0), atol=tol)
    assert np.allclose(traj.energy, 0.5 * np.einsum("ni,ij,nj->n", traj.omega, TENSOR, traj.omega))


# --- torque ---------------------------------------------------------------------------------


@pytest.mark.parametrize("method", sorted(set(METHODS) - {"exact"}))
def test_constant_body_torque_on_a_sphere_is_exact(method):
    N = np.array([0.2, -0.1, 0.05])
    omega0 = np.array([0.3, 0.8, -0.5])
    traj = simulate((1.5, 1.5, 1.5), omega0, 2.0, 0.05, method, q0=Q0, torque=N)
    assert np.allclose(traj.omega, omega0 + np.outer(traj.t, N) / 1.5, rtol=0, atol=1e-12)


def test_exact_refuses_torque():
    with pytest.raises(ValueError, match="torque"):
        simulate(MOMENTS, OMEGA0, 1.0, 0.1, "exact", torque=(0.1, 0.0, 0.0))


@pytest.mark.parametrize("inertia", [MOMENTS, TENSOR], ids=["principal", "tensor"])
@pytest.mark.parametrize("method", ["rk4", "lie_rk4", "dop853", "splitting"])
def test_world_frame_torque_gives_linear_L_world(inertia, method):
    N_world = np.array([0.03, -0.02, 0.05])

    def torque(t, q, omega):  # a fixed world vector seen from the (user) body
        return Rotation.from_quat(q).apply(N_world, inverse=True)

    traj = simulate(inertia, OMEGA0, 4.0, 0.005, method, q0=Q0, torque=torque, save_every=40)
    L0 = traj.L_world[0]
    tol = 1e-5 if method == "splitting" else 1e-9
    assert np.allclose(traj.L_world, L0 + np.outer(traj.t, N_world), rtol=0, atol=tol * np.linalg.norm(L0))


def test_constant_torque_vector_is_in_the_user_body_frame():
    """A torque vector and the equivalent callable give the same motion for a tensor body."""
    N = np.array([0.1, -0.05, 0.02])
    as_vector = simulate(TENSOR, OMEGA0, 2.0, 0.01, "rk4", q0=Q0, torque=N)
    as_model = simulate(TENSOR, OMEGA0, 2.0, 0.01, "rk4", q0=Q0, torque=ConstantTorque(N))
    as_callable = simulate(TENSOR, OMEGA0, 2.0, 0.01, "rk4", q0=Q0, torque=lambda t, q, w: N)
    assert np.allclose(as_vector.omega, as_callable.omega, rtol=0, atol=1e-13)
    assert np.allclose(as_model.omega, as_callable.omega, rtol=0, atol=1e-13)
    # and dL_world/dt = R(q) N: the L_world change over the first step, by the trapezoidal rule
    dL = (as_vector.L_world[1] - as_vector.L_world[0]) / 0.01
    mean_torque_world = 0.5 * (Rotation.from_quat(as_vector.q[:2]).apply(N).sum(axis=0))
    assert np.allclose(dL, mean_torque_world, rtol=0, atol=1e-4 * np.linalg.norm(N))


def test_gravity_torque_model_in_the_user_body_frame():
    gravity = GravityTorque(np.array([0.0, 0.1, 0.3]), 4.0)
    as_model = simulate(TENSOR, OMEGA0, 2.0, 0.01, "rk4", q0=Q0, torque=gravity)
    as_callable = simulate(TENSOR, OMEGA0, 2.0, 0.01, "rk4", q0=Q0, torque=lambda t, q, w: gravity(t, q, w))
    assert np.allclose(as_model.omega, as_callable.omega, rtol=0, atol=1e-12)
    assert same_attitudes(as_model.q, as_callable.q, 1e-12)
    # the world-z component of L is conserved under gravity about a fixed pivot
    assert np.allclose(as_model.L_world[:, 2], as_model.L_world[0, 2], atol=1e-9)


# --- failures -------------------------------------------------------------------------------


def test_non_finite_state_is_reported_with_step_and_time():
    def torque(t, q, omega):
        return np.array([0.0, 0.0, np.inf if t > 0.25 else 0.0])

    with pytest.raises(NonFiniteStateError) as info:
        simulate(MOMENTS, OMEGA0, 1.0, 0.01, "rk4", torque=torque)
    match = re.search(r"step (\d+), t = ([0-9.]+) s", str(info.value))
    assert match and int(match.group(1)) == 26 and float(match.group(2)) == pytest.approx(0.26)


@pytest.mark.parametrize(
    "module_name",
    [
        "rigid_rot_sim.core.simulate",
        "rigid_rot_sim.core.integrators",
        "rigid_rot_sim.scene.bounded_yaml",
        "rigid_rot_sim.scene.names",
        "rigid_rot_sim.run.pacing",
    ],
)
def test_docstring_examples_run(module_name):
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module(module_name))
    assert result.attempted > 0 and result.failed == 0


# --- fixed cost: what simulate caches and computes on demand ---------------------------------


@pytest.mark.parametrize("inertia", [MOMENTS, TENSOR], ids=["principal", "tensor"])
def test_invariants_on_demand_are_those_of_the_returned_states(inertia):
    traj = simulate(inertia, OMEGA0, t_end=1.0, dt=0.1, method="rk4", q0=Q0, torque=(0.1, 0.0, -0.2))
    tensor = np.diag(MOMENTS) if np.ndim(inertia) == 1 else TENSOR
    l_body = traj.omega @ tensor.T
    np.testing.assert_allclose(traj.energy, 0.5 * np.sum(traj.omega * l_body, axis=1), rtol=1e-14)
    np.testing.assert_allclose(traj.L_world, Rotation.from_quat(traj.q).apply(l_body), rtol=1e-13, atol=1e-15)
    assert traj.energy is traj.energy  # computed once


def test_cached_body_is_shared_read_only_and_keyed_by_value():
    from rigid_rot_sim.core.simulate import rigid_body

    body, principal = rigid_body([2.0, 3.0, 4.0])
    again, _ = rigid_body(np.array([2.0, 3.0, 4.0]))
    assert again is body and principal
    with pytest.raises(ValueError):
        body.principal_moments[0] = 1.0
    other, _ = rigid_body((2.0, 3.0, 4.5))
    assert other is not body and other.principal_moments[2] == 4.5
    tensor_body, tensor_principal = rigid_body(TENSOR)
    assert not tensor_principal and np.allclose(np.sort(tensor_body.principal_moments), [2.0, 3.0, 4.5])


def test_repeated_calls_give_the_same_bits():
    first = simulate(TENSOR, OMEGA0, t_end=2.0, dt=0.5, method="taylor", q0=Q0, torque=(0.1, 0.0, -0.2))
    second = simulate(
        TENSOR.tolist(), list(OMEGA0), t_end=2.0, dt=0.5, method="taylor", q0=list(Q0), torque=[0.1, 0.0, -0.2]
    )
    for a, b in ((first.q, second.q), (first.omega, second.omega), (first.L_world, second.L_world)):
        assert np.array_equal(a, b)
