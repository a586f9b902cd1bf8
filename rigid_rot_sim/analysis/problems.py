"""The work-precision problems P1 to P4 as data, each with its reference final state.

=====  =====================================================================  ==============================
key    problem                                                                reference at t_end
=====  =====================================================================  ==============================
P1     triaxial free body, I = diag(1, 2, 3) kg m^2, w0 = (1, 0.1, 0.5) rad/s  exact (Jacobi elliptic, Pi)
P1b    same body near the intermediate axis, w0 = (0.01, 2, 0.01) rad/s        exact (flips at the right times)
P2     P1's body under a constant body torque (0.1, -0.05, 0.02) N m, 20 s     DOP853 at rtol = atol = 1e-14,
                                                                              certified by a second method
P3     heavy symmetric top on its separatrix (closed form), and a general      closed form / quadrature
       heavy top (P3b) with its conserved E, p_phi, p_psi
P4     Basilisk's case, I = diag(500, 200, 300), w0 = (0.5, -0.4, 0.7), 10 s  exact
P5     gyrostat: P1's body with a free wheel (J = 0.05 kg m^2 about            DOP853 at rtol = atol = 1e-14,
       (1, 1, 1)/sqrt(3), 40 rad/s), w0 = (1, 0.1, 0.5) rad/s, 20 s             certified by our dopri5
=====  =====================================================================  ==============================

P5 is run by the gyrostat methods only (``gyrostat_rk4``; the others are refused): its state carries
the wheel speed, the report compares the body's final (q, omega).

Every problem starts at t = 0 from the identity attitude unless stated; states are in the
principal frame (the moments are given in that frame, in the order listed).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import ellipj

from rigid_rot_sim.analysis.metrics import attitude_error_angle, omega_error
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.dynamics import euler_rhs_components, kinetic_energy
from rigid_rot_sim.core.exact import torque_free_solution
from rigid_rot_sim.core.heavy_top import (
    HeavyTop,
    heavy_top_reference,
    separatrix_solution,
    separatrix_state,
)
from rigid_rot_sim.core.simulate import simulate
from rigid_rot_sim.core.steps import steps_over
from rigid_rot_sim.core.torque import ConstantTorque
from rigid_rot_sim.core.wheels import NO_ORBIT, WheelModel, gyrostat_rhs, hub_inertia, wheel_model

IDENTITY = (0.0, 0.0, 0.0, 1.0)

#: Agreement (omega max-norm, rad/s, and attitude angle, rad) the two reference solutions
#: of a torqued problem must reach before the reference is accepted.
CERTIFY_TOL = 1e-11


@dataclass(frozen=True)
class Reference:
    """Reference final state of a problem: ``q`` (4,), ``omega`` (3,) rad/s, and how it was obtained."""

    q: np.ndarray
    omega: np.ndarray
    method: str
    certified_to: float = 0.0  # estimated error of the reference itself (0 for closed forms)


@dataclass(frozen=True)
class Problem:
    """One benchmark: body, initial state, horizon, torque, and its reference.

    ``torque`` is None, a :class:`ConstantTorque` or a :class:`GravityTorque` (principal
    frame); ``torque_kind`` is the matching :data:`rigid_rot_sim.run.advice.TORQUE_KINDS`
    entry. ``reference_factory`` computes the :class:`Reference` (called once, cached).
    """

    key: str
    title: str
    principal_moments: tuple[float, float, float]
    omega0: tuple[float, float, float]
    t_end: float
    reference_factory: Callable[[Problem], Reference] = field(repr=False, compare=False)
    q0: tuple[float, float, float, float] = IDENTITY
    torque: Any = None
    torque_kind: str = "none"
    reference_note: str = ""
    top: Any = None  # the HeavyTop of a heavy-top problem (moments are its pivot moments)
    wheels: WheelModel | None = None  # a gyrostat's free wheels (principal frame), with their initial speeds:
    wheel_speeds0: tuple[float, ...] = ()

    def initial_vector(self) -> np.ndarray:
        """The initial state for solve_ivp: (q, omega), and the wheel speeds of a gyrostat."""
        return np.concatenate((self.q0, self.omega0, self.wheel_speeds0))

    @property
    def moments(self) -> np.ndarray:
        return np.asarray(self.principal_moments, dtype=float)

    def reference(self) -> Reference:
        """The reference final state (computed on first use, then cached per problem key)."""
        return _cached_reference(self)

    def energy(self, q: Any, omega: Any) -> float:
        """Total energy, J: kinetic, plus gravity's potential for a heavy top (pivot at height 0)."""
        if self.top is not None:
            return float(self.top.invariants(np.asarray(q, dtype=float), omega)[0])
        return float(kinetic_energy(self.moments, omega))

    def momentum_norm(self, omega: Any) -> float:
        """|L| = |I omega|, kg m^2/s."""
        return float(np.linalg.norm(self.moments * np.asarray(omega, dtype=float)))

    def final_state(self, method: str, dt: float, **options: Any) -> tuple[np.ndarray, np.ndarray]:
        """Final ``(q, omega)`` of ``method`` at step ``dt`` (adaptive: output interval), as a user runs it.

        One ``core.simulate.simulate(...)`` call from t = 0 to ``t_end``, keeping only the
        final state; ``options`` go to the integrator.
        """
        n_steps = steps_over(self.t_end, dt)
        if self.wheels is not None:  # only the gyrostat methods carry the wheels (ValueError: refused)
            traj = simulate(
                self.moments,
                self.omega0,
                self.t_end,
                self.t_end / n_steps,
                method,
                self.q0,
                self.torque,
                save_every=n_steps,
                wheels=self.wheels,
                wheel_speeds0=self.wheel_speeds0,
                **options,
            )
        else:
            traj = simulate(
                self.moments, self.omega0, self.t_end, dt, method, self.q0, self.torque, save_every=n_steps, **options
            )
        return np.asarray(traj.q[-1]), np.asarray(traj.omega[-1])


_REFERENCES: dict[tuple, Reference] = {}


def _cached_reference(problem: Problem) -> Reference:
    # keyed by the initial value problem, not the key alone: the stability suite's quick and full
    # cases share a key but not a horizon, and one process may build both
    cache_key = (
        problem.key,
        problem.t_end,
        problem.principal_moments,
        problem.omega0,
        problem.q0,
        problem.wheel_speeds0,
    )
    if cache_key not in _REFERENCES:
        _REFERENCES[cache_key] = problem.reference_factory(problem)
    return _REFERENCES[cache_key]


def scipy_rhs(problem: Problem) -> Callable[[float, np.ndarray], np.ndarray]:
    """``fun(t, y)`` for ``solve_ivp`` with y = (qx, qy, qz, qw, w1, w2, w3).

    The right-hand side a careful user of solve_ivp would write: Euler's equations and
    ``q' = 1/2 q (x) (omega, 0)`` on floats, one array built per call.
    """
    if problem.wheels is not None:
        return _gyrostat_scipy_rhs(problem)
    i1, i2, i3 = problem.principal_moments
    torque = problem.torque
    constant = torque.value.tolist() if isinstance(torque, ConstantTorque) else None

    def fun(t: float, y: np.ndarray) -> np.ndarray:
        qx, qy, qz, qw, w1, w2, w3 = y.tolist()
        if torque is None:
            n1 = n2 = n3 = 0.0
        elif constant is not None:
            n1, n2, n3 = constant
        else:
            n1, n2, n3 = torque(t, y[:4], y[4:]).tolist()
        dqx, dqy, dqz, dqw = quat.multiply((qx, qy, qz, qw), (0.5 * w1, 0.5 * w2, 0.5 * w3, 0.0))
        a1, a2, a3 = euler_rhs_components(i1, i2, i3, w1, w2, w3, n1, n2, n3)
        return np.array((dqx, dqy, dqz, dqw, a1, a2, a3))

    return fun


def _gyrostat_scipy_rhs(problem: Problem) -> Callable[[float, np.ndarray], np.ndarray]:
    """``fun(t, y)`` with y = (q, omega, wheel speeds): the core's gyrostat formula, run by Python."""
    assert problem.wheels is not None
    moments, wheels = problem.moments, problem.wheels.compiled()
    hub_inverse = np.linalg.inv(hub_inertia(moments, problem.wheels))
    external, orbit = np.zeros(3), NO_ORBIT.compiled()
    commands = np.zeros(problem.wheels.count)

    def fun(t: float, y: np.ndarray) -> np.ndarray:
        dy = np.empty_like(y)
        gyrostat_rhs(t, y, moments, wheels, hub_inverse, external, orbit, commands, dy, np.empty(len(commands)))
        return dy

    return fun


def _gyrostat_reference(problem: Problem) -> Reference:
    """scipy DOP853 at rtol = atol = 1e-14 on (q, omega, Omega), checked against our dopri5 at rtol = 1e-13."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        sol = solve_ivp(
            scipy_rhs(problem), (0.0, problem.t_end), problem.initial_vector(), method="DOP853", rtol=1e-14, atol=1e-14
        )
    if not sol.success:
        raise RuntimeError(f"{problem.key}: reference DOP853 failed: {sol.message}")
    q_ref = np.asarray(quat.normalize(sol.y[:4, -1]))
    w_ref = sol.y[4:7, -1]
    second = "dopri5 rtol=1e-13"
    q_check, w_check = problem.final_state("dopri5", problem.t_end, rtol=1e-13, atol=1e-15)
    gap = max(omega_error(w_ref, w_check), attitude_error_angle(q_ref, q_check))
    if not gap <= 1e-10:
        raise RuntimeError(f"{problem.key}: DOP853 and {second} references disagree by {gap:.3g} (> 1e-10)")
    return Reference(q_ref, w_ref, f"scipy DOP853 rtol=atol=1e-14, certified by {second} (gap {gap:.1e})", gap)


def exact_reference(problem: Problem) -> Reference:
    """The torque-free final state in closed form (Jacobi elliptic functions, core/exact.py)."""
    solution = torque_free_solution(problem.moments, problem.omega0, problem.q0)
    q, omega = solution.state(problem.t_end)
    return Reference(np.asarray(q, float), np.asarray(omega, float), f"exact ({solution.case})")


def _certified_reference(problem: Problem) -> Reference:
    """scipy DOP853 at rtol = atol = 1e-14, checked against our taylor method at tol = 1e-15."""
    y0 = np.concatenate((problem.q0, problem.omega0))
    with warnings.catch_warnings():
        # scipy raises rtol to 100 eps = 2.2e-14 and says so; the reference is what it is
        warnings.simplefilter("ignore", UserWarning)
        sol = solve_ivp(scipy_rhs(problem), (0.0, problem.t_end), y0, method="DOP853", rtol=1e-14, atol=1e-14)
    if not sol.success:
        raise RuntimeError(f"{problem.key}: reference DOP853 failed: {sol.message}")
    q_ref = np.asarray(quat.normalize(sol.y[:4, -1]))
    w_ref = sol.y[4:, -1]
    second = "taylor tol=1e-15"
    q_check, w_check = problem.final_state("taylor", problem.t_end, tol=1e-15)
    gap = max(omega_error(w_ref, w_check), attitude_error_angle(q_ref, q_check))
    if not gap <= CERTIFY_TOL:
        raise RuntimeError(f"{problem.key}: DOP853 and {second} references disagree by {gap:.3g} (> {CERTIFY_TOL:g})")
    return Reference(q_ref, w_ref, f"scipy DOP853 rtol=atol=1e-14, certified by {second} (gap {gap:.1e})", gap)


P1 = Problem(
    key="P1",
    title="triaxial torque-free body",
    principal_moments=(1.0, 2.0, 3.0),
    omega0=(1.0, 0.1, 0.5),
    t_end=100.0,
    reference_factory=exact_reference,
    reference_note="exact elliptic-function solution (core/exact.py)",
)

P1B = Problem(
    key="P1b",
    title="near the intermediate axis (flips)",
    principal_moments=(1.0, 2.0, 3.0),
    omega0=(0.01, 2.0, 0.01),
    t_end=100.0,
    reference_factory=exact_reference,
    reference_note="exact elliptic-function solution (core/exact.py)",
)

P2 = Problem(
    key="P2",
    title="constant body torque",
    principal_moments=(1.0, 2.0, 3.0),
    omega0=(1.0, 0.1, 0.5),
    t_end=20.0,
    torque=ConstantTorque(np.array([0.1, -0.05, 0.02])),
    torque_kind="constant",
    reference_factory=_certified_reference,
    reference_note="scipy DOP853 at rtol = atol = 1e-14, certified against taylor at tol = 1e-15",
)

#: The heavy top of P3 and P3b: 0.5 kg, centre of mass 5 cm above the pivot,
#: moments about the centre of mass (4, 4, 6) g m^2 (pivot moments (5.25, 5.25, 6) g m^2).
TOP = HeavyTop(mass=0.5, gravity=9.81, com_distance=0.05, com_moments=(0.004, 0.004, 0.006))


def _separatrix_reference(problem: Problem) -> Reference:
    """Closed form 1/cos(theta) = 1 + 1/cosh(gamma t), with the angle rates it implies."""
    top = problem.top
    i1, _, i3 = top.pivot_moments
    mgl = top.mass * top.gravity * top.com_distance
    gamma = math.sqrt(mgl / i1)
    p_psi = math.sqrt(3.0 * i1 * mgl)
    t = problem.t_end
    theta, phi, psi = (float(x) for x in separatrix_solution(top, t))
    u = math.cos(theta)
    sech = 1.0 / math.cosh(gamma * t)
    # u = 1 / (1 + sech(gamma t))  =>  u' = gamma sech tanh / (1 + sech)^2;  theta' = -u' / sin(theta)
    u_dot = gamma * sech * math.tanh(gamma * t) / (1.0 + sech) ** 2
    phi_dot = p_psi / (i1 * (1.0 + u))  # (p_phi - p_psi u) / (I1 (1 - u^2)) with p_phi = p_psi
    psi_dot = p_psi / i3 - u * phi_dot
    q, omega = top.state_from_euler(theta, phi, psi, -u_dot / math.sin(theta), phi_dot, psi_dot)
    return Reference(np.asarray(q, float), np.asarray(omega, float), "closed-form separatrix (core/heavy_top.py)")


def general_top_reference(problem: Problem) -> Reference:
    """u = cos(theta) by Jacobi functions, phi and psi by quadrature (core/heavy_top.py)."""
    top = problem.top
    ref = heavy_top_reference(top, problem.q0, problem.omega0)
    t = problem.t_end
    theta, phi, psi = (float(np.asarray(x).reshape(-1)[0]) for x in ref.euler_angles(t))
    u1, u2 = ref.turning_points
    sn, cn, dn, _ = ellipj(ref.nu * t + ref.w0, ref.k2)
    u_dot = 2.0 * (u2 - u1) * ref.nu * sn * cn * dn  # d/dt of u1 + (u2 - u1) sn^2(nu t + w0)
    i1, _, i3 = top.pivot_moments
    u = math.cos(theta)
    phi_dot = (ref.p_phi - ref.p_psi * u) / (i1 * (1.0 - u * u))
    psi_dot = ref.p_psi / i3 - u * phi_dot
    q, omega = top.state_from_euler(theta, phi, psi, -u_dot / math.sin(theta), phi_dot, psi_dot)
    return Reference(np.asarray(q, float), np.asarray(omega, float), "Jacobi u(t) + quadrature of phi, psi", 1e-12)


_SEPARATRIX_Q0, _SEPARATRIX_OMEGA0 = separatrix_state(TOP)
# theta0 = pi/3 with theta0' = 1 rad/s: mid-nutation (starting at a turning point would make
# the reference phase sensitive to the rounding of the roots of f(u), as sqrt of it)
_TOP_Q0, _TOP_OMEGA0 = TOP.state_from_euler(math.pi / 3.0, 0.0, 0.0, 1.0, 0.0, 30.0)

P3 = Problem(
    key="P3",
    title="heavy top on its separatrix (axis creeping up to the vertical)",
    principal_moments=tuple(TOP.pivot_moments.tolist()),
    omega0=tuple(_SEPARATRIX_OMEGA0.tolist()),
    q0=tuple(_SEPARATRIX_Q0.tolist()),
    t_end=1.0,
    torque=TOP.torque,
    torque_kind="gravity",
    top=TOP,
    reference_factory=_separatrix_reference,
    reference_note="closed form 1/cos(theta) = 1 + 1/cosh(gamma t); theta(1 s) = 0.066 rad",
)

P3B = Problem(
    key="P3b",
    title="general heavy top (fast spin, nutation)",
    principal_moments=tuple(TOP.pivot_moments.tolist()),
    omega0=tuple(_TOP_OMEGA0.tolist()),
    q0=tuple(_TOP_Q0.tolist()),
    t_end=2.0,
    torque=TOP.torque,
    torque_kind="gravity",
    top=TOP,
    reference_factory=general_top_reference,
    reference_note="u = cos(theta) in Jacobi functions, phi and psi by adaptive quadrature",
)

P4 = Problem(
    key="P4",
    title="Basilisk's case",
    principal_moments=(500.0, 200.0, 300.0),
    omega0=(0.5, -0.4, 0.7),
    t_end=10.0,
    reference_factory=exact_reference,
    reference_note="exact elliptic-function solution (core/exact.py)",
)

P5 = Problem(
    key="P5",
    title="gyrostat (a free reaction wheel)",
    principal_moments=(1.0, 2.0, 3.0),
    omega0=(1.0, 0.1, 0.5),
    t_end=20.0,
    torque_kind="spacecraft",
    wheels=wheel_model(np.diag((1.0, 2.0, 3.0)), ["wheel"], [[1.0, 1.0, 1.0]], [0.05], [1.0], [1000.0]),
    wheel_speeds0=(40.0,),
    reference_factory=_gyrostat_reference,
    reference_note="scipy DOP853 at rtol = atol = 1e-14 on (q, omega, Omega), certified against dopri5 at rtol = 1e-13",
)

#: Problems by key, in report order.
PROBLEMS: dict[str, Problem] = {p.key: p for p in (P1, P1B, P2, P3, P3B, P4, P5)}


def get_problem(key: str) -> Problem:
    """The problem named ``key``; ValueError listing the valid keys otherwise."""
    try:
        return PROBLEMS[key]
    except KeyError:
        raise ValueError(f"problem must be one of {list(PROBLEMS)}, got {key!r}") from None


def omega_scale(problem: Problem) -> float:
    """|omega0| in rad/s (used to pick step sweeps)."""
    return math.sqrt(sum(w * w for w in problem.omega0))
