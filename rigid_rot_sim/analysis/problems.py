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
=====  =====================================================================  ==============================

Every problem starts at t = 0 from the identity attitude unless stated; states are in the
principal frame (the moments are given in that frame, in the order listed).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
from scipy.integrate import solve_ivp

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.dynamics import euler_rhs_components, kinetic_energy
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque

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
    frame); ``torque_kind`` is the matching :data:`rigid_rot_sim.core.advice.TORQUE_KINDS`
    entry. ``reference_factory`` computes the :class:`Reference` (called once, cached).
    """

    key: str
    title: str
    principal_moments: tuple[float, float, float]
    omega0: tuple[float, float, float]
    t_end: float
    reference_factory: Callable[["Problem"], Reference] = field(repr=False, compare=False)
    q0: tuple[float, float, float, float] = IDENTITY
    torque: Any = None
    torque_kind: str = "none"
    reference_note: str = ""

    @property
    def moments(self) -> np.ndarray:
        return np.asarray(self.principal_moments, dtype=float)

    def reference(self) -> Reference:
        """The reference final state (computed on first use, then cached per problem key)."""
        return _cached_reference(self)

    def energy(self, q: Any, omega: Any) -> float:
        """Total energy, J: kinetic, plus gravity's potential for a heavy top (pivot at height 0)."""
        energy = float(kinetic_energy(self.moments, omega))
        if isinstance(self.torque, GravityTorque):
            # height of the centre of mass above the pivot: z of R(q) lever_arm
            energy += self.torque.weight * quat.rotate(q, self.torque.lever_arm)[2]
        return energy

    def momentum_norm(self, omega: Any) -> float:
        """|L| = |I omega|, kg m^2/s."""
        return float(np.linalg.norm(self.moments * np.asarray(omega, dtype=float)))


_REFERENCES: dict[str, Reference] = {}


def _cached_reference(problem: Problem) -> Reference:
    if problem.key not in _REFERENCES:
        _REFERENCES[problem.key] = problem.reference_factory(problem)
    return _REFERENCES[problem.key]


def scipy_rhs(problem: Problem) -> Callable[[float, np.ndarray], np.ndarray]:
    """``fun(t, y)`` for ``solve_ivp`` with y = (qx, qy, qz, qw, w1, w2, w3).

    The right-hand side a careful user of solve_ivp would write: Euler's equations and
    ``q' = 1/2 q (x) (omega, 0)`` on floats, one array built per call.
    """
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


def _exact_reference(problem: Problem) -> Reference:
    from rigid_rot_sim.core.exact import torque_free_solution

    solution = torque_free_solution(problem.moments, problem.omega0, problem.q0)
    q, omega = solution.state(problem.t_end)
    return Reference(np.asarray(q, float), np.asarray(omega, float), f"exact ({solution.case})")


def _certified_reference(problem: Problem) -> Reference:
    """scipy DOP853 at rtol = atol = 1e-14, checked against our taylor method at tol = 1e-15.

    (scipy Radau at rtol = atol = 1e-13 is the second method while taylor is not registered.)
    """
    from rigid_rot_sim.analysis.metrics import attitude_error_angle, omega_error
    from rigid_rot_sim.analysis.workprecision import run_to_end
    from rigid_rot_sim.core.integrators import METHODS

    y0 = np.concatenate((problem.q0, problem.omega0))
    with warnings.catch_warnings():
        # scipy raises rtol to 100 eps = 2.2e-14 and says so; the reference is what it is
        warnings.simplefilter("ignore", UserWarning)
        sol = solve_ivp(scipy_rhs(problem), (0.0, problem.t_end), y0, method="DOP853", rtol=1e-14, atol=1e-14)
    if not sol.success:
        raise RuntimeError(f"{problem.key}: reference DOP853 failed: {sol.message}")
    q_ref = np.asarray(quat.normalize(sol.y[:4, -1]))
    w_ref = sol.y[4:, -1]
    if "taylor" in METHODS:
        second = "taylor tol=1e-15"
        q_check, w_check = run_to_end(problem, "taylor", problem.t_end, {"tol": 1e-15})
    else:
        second = "scipy Radau rtol=atol=1e-13"
        check = solve_ivp(scipy_rhs(problem), (0.0, problem.t_end), y0, method="Radau", rtol=1e-13, atol=1e-13)
        q_check, w_check = quat.normalize(check.y[:4, -1]), check.y[4:, -1]
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
    reference_factory=_exact_reference,
    reference_note="exact elliptic-function solution (core/exact.py)",
)

P1B = Problem(
    key="P1b",
    title="near the intermediate axis (flips)",
    principal_moments=(1.0, 2.0, 3.0),
    omega0=(0.01, 2.0, 0.01),
    t_end=100.0,
    reference_factory=_exact_reference,
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

P4 = Problem(
    key="P4",
    title="Basilisk's case",
    principal_moments=(500.0, 200.0, 300.0),
    omega0=(0.5, -0.4, 0.7),
    t_end=10.0,
    reference_factory=_exact_reference,
    reference_note="exact elliptic-function solution (core/exact.py)",
)

#: Problems by key, in report order (the heavy-top problems are added by heavy_top_cases).
PROBLEMS: dict[str, Problem] = {p.key: p for p in (P1, P1B, P2, P4)}


def get_problem(key: str) -> Problem:
    """The problem named ``key``; ValueError listing the valid keys otherwise."""
    try:
        return PROBLEMS[key]
    except KeyError:
        raise ValueError(f"problem must be one of {list(PROBLEMS)}, got {key!r}") from None


def omega_scale(problem: Problem) -> float:
    """|omega0| in rad/s (used to pick step sweeps)."""
    return math.sqrt(sum(w * w for w in problem.omega0))
