"""The stability suite: every integrator on a catalogue of stiff and extreme cases.

Each :class:`Case` is a body, an initial state, a step ``dt`` and a horizon (a
:class:`~rigid_rot_sim.analysis.problems.Problem` plus the step), and a pass criterion
on what a run measures:

* ``status``: ``stable`` (finite, energy and momentum grew by less than 100 %),
  ``unstable`` (a :class:`NonFiniteStateError`, an arithmetic error, or growth beyond
  that), or ``refused`` (the method raised ValueError for this case, e.g. ``exact``
  under a torque); the message is kept, never a NaN;
* the maximum relative drift of the energy and of the conserved momenta over the run
  (|L| for a free body; p_phi and p_psi for a heavy top), sampled ~200 times, counted from
  the end of the last torque (for torqued cases the error against the reference instead);
* the maximum quaternion norm error ``| |q| - 1 |``;
* the error against the exact (or certified) solution at the end, where one exists;
* the run time (one run, set-up included).

For the explicit fixed-step methods (euler, rk4, lie_rk4) :func:`largest_stable_step`
finds the largest stable step by bisection; the suite compares it with the linear
bound of :func:`rigid_rot_sim.core.advice.max_stable_dt`.

A long horizon of 1e7 steps (1e5 in quick mode) separates bounded from secular energy
drift: :func:`long_horizon` fits nothing, it compares the energy error over the last
tenth of the run with its maximum over the first tenth (a bounded error reaches its
full size within the first tenth; a secular one keeps growing).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from rigid_rot_sim.analysis import problems as P
from rigid_rot_sim.analysis.metrics import attitude_error_angle, omega_error
from rigid_rot_sim.core import advice
from rigid_rot_sim.core.integrators import METHODS, get_method
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.torque import ConstantTorque

#: Growth of energy or momentum beyond this (relative) counts as unstable.
GROWTH_LIMIT = 1.0
#: Samples of the invariants per run.
SAMPLES = 200
#: Steps per trial in the bisection for the largest stable step, and the growth it allows.
BISECTION_STEPS = 1000
BISECTION_GROWTH = 0.01
#: Fixed-step methods whose largest stable step is bisected (the explicit ones, and the
#: solver / accuracy limits of implicit_midpoint and splitting).
BISECTED = ("euler", "rk4", "lie_rk4", "implicit_midpoint", "splitting")


@dataclass(frozen=True)
class Criterion:
    """Pass thresholds (inclusive); None skips a check."""

    energy_drift: float | None = None
    momentum_drift: float | None = None
    quaternion_norm: float | None = 1e-12
    omega_error: float | None = None
    attitude_error: float | None = None
    text: str = ""

    def describe(self) -> str:
        parts = [self.text] if self.text else []
        for name, label in (
            ("energy_drift", "energy drift"),
            ("momentum_drift", "momentum drift"),
            ("quaternion_norm", "| |q| - 1 |"),
            ("omega_error", "ω error [rad/s]"),
            ("attitude_error", "attitude error [rad]"),
        ):
            value = getattr(self, name)
            if value is not None:
                parts.append(f"{label} ≤ {value:g}")
        return "; ".join(parts)


@dataclass(frozen=True)
class Case:
    """One stability case: a problem, the step, and what passing means.

    ``impulse`` (N*m, principal frame) is a torque applied for the first step only, as
    the node applies a one-step topic command (the integrator's torque is replaced after
    one step). ``reference`` says whether ``problem.reference()`` exists for this case.
    """

    name: str
    description: str
    problem: P.Problem
    dt: float
    criterion: Criterion
    reference: bool = True
    impulse: tuple[float, float, float] | None = None
    bisect: bool = False
    conserved: bool = True  # energy and momenta conserved (after the impulse, if any)
    same_as: P.Problem | None = None  # a problem whose omega(t), q(t) this case must reproduce
    same_tol: float = 1e-9  # relative omega and attitude agreement with ``same_as``, same method and dt
    options: dict[str, dict[str, Any]] = field(default_factory=dict)  # per-method options

    @property
    def n_steps(self) -> int:
        return max(1, round(self.problem.t_end / self.dt))


@dataclass
class Run:
    """What one method did on one case."""

    method: str
    status: str
    message: str = ""
    passed: bool = False
    energy_drift: float = math.nan
    momentum_drift: float = math.nan
    quaternion_norm_error: float = math.nan
    omega_error: float = math.nan
    attitude_error: float = math.nan
    seconds: float = math.nan
    largest_stable_dt: float | None = None
    theory_stable_dt: float | None = None


# ---------------------------------------------------------------- the catalogue


def _free(key: str, title: str, moments, omega0, t_end: float, **kw: Any) -> P.Problem:
    return P.Problem(
        key=key,
        title=title,
        principal_moments=tuple(float(m) for m in moments),
        omega0=tuple(float(w) for w in omega0),
        t_end=t_end,
        reference_factory=P._exact_reference,
        **kw,
    )


def _impulse_reference(problem: P.Problem) -> P.Reference:
    """Constant torque over the first step (scipy DOP853 at 1e-13), then the exact free flow."""
    from scipy.integrate import solve_ivp

    from rigid_rot_sim.core import quaternion as quat
    from rigid_rot_sim.core.exact import torque_free_solution

    dt = problem.t_end / IMPULSE_STEPS
    kicked = dataclasses.replace(problem, torque=ConstantTorque(np.asarray(IMPULSE_TORQUE)))
    y = solve_ivp(
        P.scipy_rhs(kicked), (0.0, dt), np.concatenate((problem.q0, problem.omega0)),
        method="DOP853", rtol=1e-13, atol=1e-13,
    ).y[:, -1]
    q1 = np.asarray(quat.normalize(y[:4]))
    solution = torque_free_solution(problem.moments, y[4:], q1, t0=dt)
    q, omega = solution.state(problem.t_end)
    return P.Reference(np.asarray(q), np.asarray(omega), "DOP853 rtol=atol=1e-13 over the kick, then exact", 1e-12)


IMPULSE_TORQUE = (50.0, -20.0, 30.0)
IMPULSE_STEPS = 1000


def _scaled_p2(scale: float) -> P.Problem:
    """P2 with every moment and the torque multiplied by ``scale``: omega(t) and q(t) are unchanged."""
    return dataclasses.replace(
        P.P2,
        key=f"P2x{scale:g}",
        title=f"P2 scaled by {scale:g}",
        principal_moments=tuple(scale * m for m in P.P2.principal_moments),
        torque=ConstantTorque(scale * P.P2.torque.value),
        reference_factory=lambda problem: P.P2.reference(),
    )


def catalogue(quick: bool = False) -> list[Case]:
    """The cases, shortened (fewer steps, same dt) in quick mode."""
    short = 0.2 if quick else 1.0
    top = P.TOP
    sleeping_q0, sleeping_w0 = top.state_from_euler(0.05, 0.0, 0.0, 0.0, 0.0, 300.0)
    bounded = Criterion(energy_drift=1e-3, momentum_drift=1e-3, text="bounded to 0.1 %")

    def accurate(problem: P.Problem) -> Criterion:
        """Bounded to 0.1 %, omega error <= 0.1 % of |omega0| and attitude error <= 0.01 rad at the end."""
        scale = float(np.linalg.norm(problem.omega0))
        return dataclasses.replace(bounded, omega_error=1e-3 * scale, attitude_error=1e-2,
                                   text="bounded to 0.1 %, ω error ≤ 0.1 % of |ω0|")

    cases: list[Case] = []
    for ratio in (1e-2, 1e-4, 1e-6):
        cases.append(
            Case(
                name=f"thin rod {ratio:g}",
                description=f"slender body I = (1, 1 + {ratio / 2:g}, {ratio:g}) kg m², spinning 5 rad/s about its "
                "axis while tumbling, dt = 10 ms",
                problem=(rod := _free(
                    f"rod{ratio:g}", "thin rod", (1.0, 1.0 + ratio / 2, ratio), (0.3, 0.2, 5.0), 10.0 * short
                )),
                dt=0.01,
                criterion=accurate(rod),
                bisect=True,
            )
        )
    cases += [
        Case(
            name="MuJoCo rod",
            description="MuJoCo's diverging case diaginertia (0.00017231, 0.00000658, 0.00017243) kg m², "
            "ω0 = (2, 50, 3) rad/s, dt = 1 ms",
            problem=(mujoco := _free(
                "mujoco", "MuJoCo rod", (0.00017231, 0.00000658, 0.00017243), (2.0, 50.0, 3.0), 10.0 * short
            )),
            dt=1e-3,
            criterion=accurate(mujoco),
            bisect=True,
        ),
        Case(
            name="near-spherical 1e-9",
            description="moments equal to 1e-9 relative: I = (1, 1 + 1e-9, 1 + 2e-9) kg m², dt = 10 ms",
            problem=(near := _free(
                "nearsphere", "near-spherical", (1.0, 1.0 + 1e-9, 1.0 + 2e-9), (1.0, 2.0, 3.0), 100.0 * short
            )),
            dt=0.01,
            criterion=accurate(near),
        ),
        Case(
            name="symmetric",
            description="exactly symmetric I = (2, 2, 1) kg m², ω0 = (0.5, 0.3, 4) rad/s, dt = 10 ms",
            problem=(sym := _free("symmetric", "symmetric", (2.0, 2.0, 1.0), (0.5, 0.3, 4.0), 100.0 * short)),
            dt=0.01,
            criterion=accurate(sym),
            bisect=True,
        ),
    ]
    for rotation in (1.0, 3.0, 10.0):
        omega0 = np.array([10.0, 1.0, 5.0])
        dt = rotation / float(np.linalg.norm(omega0))
        cases.append(
            Case(
                name=f"high spin {rotation:g} rad/step",
                description=f"I = (1, 2, 3) kg m², |ω| = {np.linalg.norm(omega0):.3g} rad/s, ω·dt = {rotation:g} rad "
                "per step, 1000 steps",
                problem=_free(f"spin{rotation:g}", "high spin", (1.0, 2.0, 3.0), omega0, dt * 1000 * short),
                dt=dt,
                criterion=Criterion(energy_drift=1e-2, momentum_drift=1e-2, text="bounded to 1 %"),
                bisect=rotation == 1.0,
            )
        )
    cases += [
        Case(
            name="intermediate-axis flips",
            description="ω0 = (1e-3, 1, 1e-3) rad/s about the intermediate axis of I = (1, 2, 3) kg m²: "
            "about 30 flips in 500 s, dt = 50 ms",
            problem=_free("flips", "flips", (1.0, 2.0, 3.0), (1e-3, 1.0, 1e-3), 500.0 * short),
            dt=0.05,
            criterion=dataclasses.replace(bounded, text="bounded to 0.1 %, flip times within 0.1 s"),
        ),
        Case(
            name="scale 1e-9",
            description="P2 with moments (1, 2, 3)e-9 kg m² and torque scaled alike (ω(t) unchanged), dt = 10 ms",
            problem=_scaled_p2(1e-9),
            dt=0.01,
            criterion=Criterion(text="same ω(t), q(t) as the unit-scale run of the same method to 1e-9"),
            conserved=False,
            same_as=P.P2,
        ),
        Case(
            name="scale 1e9",
            description="P2 with moments (1, 2, 3)e9 kg m² and torque scaled alike, dt = 10 ms",
            problem=_scaled_p2(1e9),
            dt=0.01,
            criterion=Criterion(text="same ω(t), q(t) as the unit-scale run of the same method to 1e-9"),
            conserved=False,
            same_as=P.P2,
        ),
        Case(
            name="sleeping top",
            description="heavy top (P3's) at θ0 = 0.05 rad spinning 300 rad/s: stiff nutation "
            f"(~{300 * top.pivot_moments[2] / top.pivot_moments[0]:.0f} rad/s), dt = 1 ms",
            problem=dataclasses.replace(
                P.P3B,
                key="sleeping",
                title="sleeping top",
                q0=tuple(sleeping_q0.tolist()),
                omega0=tuple(sleeping_w0.tolist()),
                t_end=2.0 * short,
                reference_factory=P._general_top_reference,
            ),
            dt=1e-3,
            criterion=Criterion(energy_drift=1e-4, momentum_drift=1e-4, omega_error=0.3, text="E, p_φ, p_ψ to 1e-4, ω error ≤ 0.1 % of |ω0|"),
        ),
        Case(
            name="separatrix top → θ = 0",
            description="P3's separatrix top run until θ ≈ 1e-3 rad (the z-x-z Euler-angle singularity), dt = 1 ms",
            problem=dataclasses.replace(P.P3, key="separatrix_long", t_end=1.6 if not quick else 1.0),
            dt=1e-3,
            criterion=Criterion(energy_drift=1e-4, momentum_drift=1e-4, omega_error=1e-2, text="E, p_φ, p_ψ to 1e-4, ω error ≤ 0.1 % of |ω0|"),
        ),
        Case(
            name="impulsive torque",
            description=f"I = (1, 2, 3) kg m², ω0 = (1, 0.1, 0.5) rad/s, a torque {IMPULSE_TORQUE} N m for one "
            "10 ms step, then free",
            problem=_free(
                "impulse", "impulse", (1.0, 2.0, 3.0), (1.0, 0.1, 0.5), 0.01 * IMPULSE_STEPS,
                reference_note="kick by DOP853, then exact",
            ),
            dt=0.01,
            impulse=IMPULSE_TORQUE,
            criterion=dataclasses.replace(bounded, omega_error=1e-3, attitude_error=1e-2,
                                          text="after the kick: bounded to 0.1 %; ω error ≤ 1e-3 rad/s"),
        ),
    ]
    cases[-1] = dataclasses.replace(
        cases[-1], problem=dataclasses.replace(cases[-1].problem, reference_factory=_impulse_reference)
    )
    return cases


# ---------------------------------------------------------------- running


def _invariants(problem: P.Problem, q: np.ndarray, omega: np.ndarray) -> tuple[float, float, float]:
    """(energy, momentum 1, momentum 2): |L| (twice) for a free body, (E, p_phi, p_psi) for a heavy top."""
    if problem.top is not None:
        energy, p_phi, p_psi = problem.top.invariants(q, omega)
        return float(energy), float(p_phi), float(p_psi)
    norm = problem.momentum_norm(omega)
    return problem.energy(q, omega), norm, norm


def _relative(value: float, reference: float) -> float:
    scale = abs(reference)
    return abs(value - reference) / scale if scale > 0 else abs(value - reference)


def _make(method: str, case: Case, dt: float, torque: Any) -> Any:
    problem = case.problem
    name, options = _method_and_options(method)
    options.update(case.options.get(method, {}))
    return get_method(name)(problem.moments, dt, torque, q0=problem.q0, omega0=problem.omega0, **options)


def _method_and_options(label: str) -> tuple[str, dict[str, Any]]:
    """'splitting(order=4)' -> ('splitting', {'order': 4})."""
    if "(" not in label:
        return label, {}
    name, rest = label.split("(", 1)
    options = {}
    for item in rest.rstrip(")").split(","):
        key, value = item.split("=")
        options[key.strip()] = int(value) if value.strip().isdigit() else float(value)
    return name, options


def run_case(case: Case, method: str) -> Run:
    """One method on one case (all steps, ~SAMPLES samples of the invariants)."""
    problem = case.problem
    run = Run(method, "stable")
    n = case.n_steps
    dt = problem.t_end / n
    samples = min(SAMPLES, n)
    chunks = np.diff(np.linspace(0, n, samples + 1).round().astype(int))
    start = time.perf_counter()
    try:
        if case.impulse is not None:
            integrator = _make(method, case, dt, ConstantTorque(np.asarray(case.impulse)))
            integrator.advance(1)
            integrator.torque = None
            chunks[0] -= 1
        else:
            integrator = _make(method, case, dt, problem.torque)
        # conserved from here on (right after the kick, for an impulse)
        first = _invariants(problem, integrator.q, integrator.omega)
        drift_e = drift_m = qnorm = 0.0
        for chunk in chunks:
            if chunk:
                integrator.advance(int(chunk))
            q, omega = integrator.q, integrator.omega
            qnorm = max(qnorm, abs(float(np.linalg.norm(q)) - 1.0))
            if case.conserved:
                e, m1, m2 = _invariants(problem, q, omega)
                drift_e = max(drift_e, _relative(e, first[0]))
                drift_m = max(drift_m, _relative(m1, first[1]), _relative(m2, first[2]))
                if drift_e > GROWTH_LIMIT or drift_m > GROWTH_LIMIT:
                    raise NonFiniteStateError(
                        f"{method}: energy or momentum changed by more than {GROWTH_LIMIT:.0%} "
                        f"by t = {integrator.t:.6g} s (energy {drift_e:.3g}, momentum {drift_m:.3g})"
                    )
        run.seconds = time.perf_counter() - start
    except (NonFiniteStateError, ArithmeticError) as exc:
        run.status, run.message = "unstable", f"{type(exc).__name__}: " + " ".join(str(exc).split())[:240]
        run.seconds = time.perf_counter() - start
        return run
    except (ValueError, NotImplementedError) as exc:
        run.status, run.message = "refused", " ".join(str(exc).split())[:240]
        return run
    run.quaternion_norm_error = qnorm
    if case.reference:
        ref = problem.reference()
        run.omega_error = omega_error(ref.omega, integrator.omega)
        run.attitude_error = attitude_error_angle(ref.q, integrator.q)
        if not case.conserved:
            e, m1, _ = _invariants(problem, integrator.q, integrator.omega)
            re, rm1, _ = _invariants(problem, ref.q, ref.omega)
            drift_e, drift_m = _relative(e, re), _relative(m1, rm1)
    run.energy_drift, run.momentum_drift = drift_e, drift_m
    run.passed = _passes(case.criterion, run)
    if case.same_as is not None and run.status == "stable":
        twin = dataclasses.replace(case, problem=case.same_as, same_as=None)
        other = _make(method, twin, dt, case.same_as.torque)
        other.advance(n)
        gap = max(
            omega_error(other.omega, integrator.omega) / float(np.linalg.norm(other.omega)),
            attitude_error_angle(other.q, integrator.q),
        )
        run.passed = gap <= case.same_tol
        run.message = f"relative difference from the unit-scale run {gap:.2g}"
    if case.name == "intermediate-axis flips" and run.passed:
        run.passed, note = _flip_times_match(case, method)
        run.message = note
    return run


def _passes(criterion: Criterion, run: Run) -> bool:
    checks = (
        (criterion.energy_drift, run.energy_drift),
        (criterion.momentum_drift, run.momentum_drift),
        (criterion.quaternion_norm, run.quaternion_norm_error),
        (criterion.omega_error, run.omega_error),
        (criterion.attitude_error, run.attitude_error),
    )
    return run.status == "stable" and all(limit is None or value <= limit for limit, value in checks)


def _flip_times(omega2: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Times where omega_2 changes sign (linear interpolation)."""
    idx = np.nonzero(np.sign(omega2[1:]) != np.sign(omega2[:-1]))[0]
    return t[idx] - omega2[idx] * (t[idx + 1] - t[idx]) / (omega2[idx + 1] - omega2[idx])


def _flip_times_match(case: Case, method: str, tolerance: float = 0.1) -> tuple[bool, str]:
    """Compare the flip times (sign changes of omega_2) with the exact solution's."""
    from rigid_rot_sim.core.exact import torque_free_solution

    problem = case.problem
    n = case.n_steps
    integrator = _make(method, case, problem.t_end / n, problem.torque)
    t = np.linspace(0.0, problem.t_end, n + 1)
    omega2 = np.empty(n + 1)
    omega2[0] = problem.omega0[1]
    for k in range(1, n + 1):
        integrator.advance(1)
        omega2[k] = integrator.omega[1]
    exact = torque_free_solution(problem.moments, problem.omega0, problem.q0).omega(t)[:, 1]
    ours, theirs = _flip_times(omega2, t), _flip_times(exact, t)
    if ours.size != theirs.size:
        return False, f"{ours.size} flips, exact {theirs.size}"
    worst = float(np.max(np.abs(ours - theirs))) if ours.size else 0.0
    return worst <= tolerance, f"{ours.size} flips (exact {theirs.size}), worst flip-time error {worst:.2g} s"


def _is_stable(case: Case, method: str, dt: float, steps: int) -> bool:
    """``steps`` steps of ``dt`` stay finite with energy and momentum growth <= BISECTION_GROWTH."""
    problem = case.problem
    try:
        integrator = _make(method, case, dt, problem.torque)
        e0, m0, _ = _invariants(problem, integrator.q, integrator.omega)
        for _ in range(10):
            integrator.advance(steps // 10)
            e, m, _ = _invariants(problem, integrator.q, integrator.omega)
            if e > e0 * (1 + BISECTION_GROWTH) or m > m0 * (1 + BISECTION_GROWTH):
                return False
    except (NonFiniteStateError, ArithmeticError):
        return False
    return True


def largest_stable_step(case: Case, method: str, steps: int = BISECTION_STEPS, rel_tol: float = 0.01) -> float:
    """Largest dt (s) for which ``steps`` steps stay stable (bisection in log dt, to ``rel_tol``).

    Bracketed from the case's own dt by factors of 2; returns 0.0 if even dt / 2^20 is
    unstable and inf if 2^20 dt is stable.
    """
    lo = hi = case.dt
    if _is_stable(case, method, lo, steps):
        for _ in range(20):
            hi = 2.0 * lo
            if not _is_stable(case, method, hi, steps):
                break
            lo = hi
        else:
            return math.inf
    else:
        for _ in range(20):
            lo = hi / 2.0
            if _is_stable(case, method, lo, steps):
                break
            hi = lo
        else:
            return 0.0
    while hi / lo > 1.0 + rel_tol:
        mid = math.sqrt(lo * hi)
        if _is_stable(case, method, mid, steps):
            lo = mid
        else:
            hi = mid
    return lo


@dataclass
class LongHorizon:
    """Energy error over a long run: bounded or secular."""

    method: str
    steps: int
    dt: float
    seconds: float
    first_tenth_max: float
    last_tenth_mean: float
    final: float
    secular: bool
    status: str = "stable"
    message: str = ""


#: Energy errors below this are round-off (a random walk of ~1e-16 per step over 1e7 steps).
ROUNDOFF_FLOOR = 1e-11

LONG_HORIZON_METHODS = ("rk4", "lie_rk4", "implicit_midpoint", "splitting(order=2)", "splitting(order=4)")


def long_horizon(method: str, steps: int, dt: float = 0.01, samples: int = 1000) -> LongHorizon:
    """P1's body for ``steps`` steps of ``dt``: is the relative energy error bounded or secular?

    Secular when the mean error over the last tenth exceeds twice the maximum over the
    first tenth and the round-off floor (1e-11).
    """
    problem = P.P1
    name, options = _method_and_options(method)
    integrator = get_method(name)(problem.moments, dt, None, q0=problem.q0, omega0=problem.omega0, **options)
    e0 = problem.energy(problem.q0, problem.omega0)
    chunks = np.diff(np.linspace(0, steps, samples + 1).round().astype(int))
    errors = np.empty(samples)
    start = time.perf_counter()
    try:
        for k, chunk in enumerate(chunks):
            integrator.advance(int(chunk))
            errors[k] = _relative(problem.energy(integrator.q, integrator.omega), e0)
    except (NonFiniteStateError, ArithmeticError) as exc:
        return LongHorizon(method, steps, dt, time.perf_counter() - start, math.nan, math.nan, math.nan, True,
                           "unstable", str(exc)[:240])
    seconds = time.perf_counter() - start
    tenth = max(1, samples // 10)
    first, last = float(errors[:tenth].max()), float(errors[-tenth:].mean())
    secular = last > max(2.0 * first, ROUNDOFF_FLOOR)
    return LongHorizon(method, steps, dt, seconds, first, last, float(errors[-1]), secular)


def bisection_row(case: Case, method: str, steps: int) -> dict[str, Any]:
    """Largest stable step of ``method`` on ``case``, with the theory bound."""
    spin = float(np.linalg.norm(case.problem.omega0))
    measured = largest_stable_step(case, method, steps)
    theory = advice.practical_step_limit(method, case.problem.moments, spin)
    return {
        "case": case.name,
        "method": method,
        "steps": steps,
        "largest_stable_dt": measured,
        "theory_dt": theory,
        "ratio": measured / theory if 0 < theory < math.inf else None,
    }


def bisection_rows(cases: list[Case], quick: bool = False) -> list[dict[str, Any]]:
    """Largest stable step of each explicit method on each case marked ``bisect``, with the theory bound."""
    steps = BISECTION_STEPS // (4 if quick else 1)
    return [bisection_row(case, method, steps) for case in cases if case.bisect for method in BISECTED]


def _case(name: str, quick: bool) -> Case:
    return next(case for case in catalogue(quick) if case.name == name)


def case_task(name: str, quick: bool, method: str) -> dict[str, Any]:
    """A Dask task: :func:`run_case` of the catalogue's case ``name`` (rebuilt on the worker)."""
    return dataclasses.asdict(run_case(_case(name, quick), method))


def bisection_task(name: str, quick: bool, method: str) -> dict[str, Any]:
    """A Dask task: :func:`bisection_row` of the catalogue's case ``name``."""
    return bisection_row(_case(name, quick), method, BISECTION_STEPS // (4 if quick else 1))


def long_horizon_task(method: str, steps: int) -> dict[str, Any]:
    """A Dask task: :func:`long_horizon` as a dict."""
    return dataclasses.asdict(long_horizon(method, steps))


def method_labels() -> list[str]:
    """The columns of the suite: every registered method with its default options."""
    return list(METHODS)


# ---------------------------------------------------------------- the suite and its outputs


def _run_here(cases, methods, long_methods, long_steps, quick, progress, total):
    """The suite in this process: ({case: {method: run}}, bisection rows, long horizons)."""
    from tqdm import tqdm

    case_runs: dict[str, dict[str, Any]] = {}
    with tqdm(total=total, desc="stability", unit="run", disable=not progress) as bar:
        for case in cases:
            runs = case_runs.setdefault(case.name, {})
            for method in methods:
                bar.set_postfix_str(f"{case.name} {method}", refresh=False)
                runs[method] = dataclasses.asdict(run_case(case, method))
                bar.update(1)
        bar.set_postfix_str("bisection", refresh=True)
        bisection = bisection_rows(cases, quick)
        bar.update(1)
        horizon = []
        for method in long_methods:
            bar.set_postfix_str(f"long horizon {method}", refresh=True)
            horizon.append(dataclasses.asdict(long_horizon(method, long_steps)))
            bar.update(1)
    return case_runs, bisection, horizon


def _run_on_cluster(client, cases, methods, long_methods, long_steps, quick, bar):
    """The same as :func:`_run_here`, every run, bisection and long horizon one Dask task."""
    from rigid_rot_sim.analysis.engine import map_tasks

    runs_args = [(case.name, quick, method) for case in cases for method in methods]
    bisect_args = [(case.name, quick, method) for case in cases if case.bisect for method in BISECTED]
    horizon_args = [(method, long_steps) for method in long_methods]
    calls = (
        [(case_task, a) for a in runs_args]
        + [(bisection_task, a) for a in bisect_args]
        + [(long_horizon_task, a) for a in horizon_args]
    )
    first_bisection, first_horizon = len(runs_args), len(runs_args) + len(bisect_args)
    bisections_left = [len(bisect_args)]

    def done(index: int, _: Any) -> None:
        if first_bisection <= index < first_horizon:
            bisections_left[0] -= 1
            if bisections_left[0] == 0:
                bar.update(1)  # the bisections are one step of the bar, as in a local run
        else:
            bar.update(1)

    results = map_tasks(client, calls, done)
    if not bisect_args:
        bar.update(1)
    case_runs: dict[str, dict[str, Any]] = {}
    for (name, _, method), run in zip(runs_args, results[:first_bisection]):
        case_runs.setdefault(name, {})[method] = run
    return case_runs, results[first_bisection:first_horizon], results[first_horizon:]


def run_suite(
    out_dir: Any,
    quick: bool = False,
    long_steps: int | None = None,
    long_methods: tuple[str, ...] = LONG_HORIZON_METHODS,
    case_names: list[str] | None = None,
    methods: list[str] | None = None,
    command: str = "rigid-rot stability",
    progress: bool = True,
    scheduler: str | None = None,
    workers: int | None = None,
) -> dict[str, Any]:
    """Run the catalogue, the bisections and the long horizon; write stability.md/.json/.png.

    With ``scheduler`` or ``workers`` (or DASK_SCHEDULER_ADDRESS) every run, bisection and
    long horizon is one Dask task; the results are the same (run times aside).
    """
    import json
    from pathlib import Path

    from tqdm import tqdm

    from rigid_rot_sim.analysis.engine import open_client, wants_cluster
    from rigid_rot_sim.analysis.plotting import long_horizon_plot, stability_plot
    from rigid_rot_sim.analysis.workprecision import machine_info

    cases = catalogue(quick)
    if case_names is not None:
        unknown = sorted(set(case_names) - {c.name for c in cases})
        if unknown:
            raise ValueError(f"case_names: unknown case(s) {unknown}; valid: {[c.name for c in cases]}")
        cases = [c for c in cases if c.name in case_names]
    methods = list(methods) if methods is not None else method_labels()
    if long_steps is None:
        long_steps = 100_000 if quick else 10_000_000
    start = time.perf_counter()
    case_rows: list[dict[str, Any]] = []
    total = len(cases) * len(methods) + len(long_methods) + 1
    if wants_cluster(scheduler, workers):
        with tqdm(total=total, desc="stability", unit="run", disable=not progress) as bar, \
                open_client(scheduler, workers) as client:
            case_runs, bisection, horizon = _run_on_cluster(client, cases, methods, long_methods, long_steps, quick, bar)
    else:
        case_runs, bisection, horizon = _run_here(cases, methods, long_methods, long_steps, quick, progress, total)
    for case in cases:
        case_rows.append(
            {
                "name": case.name,
                "description": case.description,
                "principal_moments": list(case.problem.principal_moments),
                "omega0": list(case.problem.omega0),
                "dt": case.dt,
                "steps": case.n_steps,
                "criterion": case.criterion.describe(),
                "reference": case.problem.reference().method if case.reference else None,
                "runs": case_runs[case.name],
            }
        )
    elapsed = time.perf_counter() - start
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    payload = {
        "command": command,
        "quick": quick,
        "elapsed_seconds": elapsed,
        "machine": machine_info(),
        "methods": methods,
        "cases": case_rows,
        "bisection": {"steps": BISECTION_STEPS // (4 if quick else 1), "growth": BISECTION_GROWTH, "rows": bisection},
        "long_horizon": horizon,
    }
    (out / "stability.json").write_text(json.dumps(payload, indent=1, allow_nan=True), encoding="utf-8")
    stability_plot(case_rows, methods, out / "stability.png")
    long_horizon_plot(horizon, out / "long_horizon.png")
    (out / "stability.md").write_text(_markdown(payload), encoding="utf-8")
    return payload


def _g(value: Any, spec: str = ".2g") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    return format(value, spec)


def _markdown(payload: dict[str, Any]) -> str:
    machine = payload["machine"]
    methods = payload["methods"]
    md = [
        "# Stability suite",
        "",
        f"Command: `{payload['command']}` ({'quick mode' if payload['quick'] else 'full run'}, "
        f"{payload['elapsed_seconds']:.0f} s). Machine: {machine['cpu']}, {machine['cpus_available']} CPUs; "
        f"numpy {machine['numpy']}, scipy {machine['scipy']}; commit `{machine['git_commit'][:10]}`.",
        "",
        "Status: **stable** (finite; energy and momenta changed by less than 100 %), **unstable** (non-finite state, "
        "a solver failure, or growth beyond that; the message says which and when), **refused** (the method "
        "declined the case with ValueError). Pass = stable and within the case's criterion. Drifts are the maximum "
        "relative change over ~200 samples (|L| for free bodies; p_φ and p_ψ for heavy tops; for torqued cases "
        "the error against the reference at the end). Errors are at the final time against the reference.",
        "",
        "![stability](stability.png)",
        "",
        "## Pass / fail overview",
        "",
        "| case | " + " | ".join(methods) + " |",
        "|---|" + "---|" * len(methods),
    ]
    for case in payload["cases"]:
        cells = []
        for method in methods:
            run = case["runs"][method]
            cells.append(
                "pass" if run["passed"] else ("**unstable**" if run["status"] == "unstable" else
                                              ("refused" if run["status"] == "refused" else "fail"))
            )
        md.append(f"| {case['name']} | " + " | ".join(cells) + " |")
    md += ["", "## Largest stable step of the explicit methods (bisection)", ""]
    bis = payload["bisection"]
    md += [
        f"Stable = {bis['steps']} steps without non-finite values and with energy and |L| grown by at most "
        f"{bis['growth']:.0%}. Advice: `core.advice.practical_step_limit`: 2√2 / ν for rk4 and lie_rk4 from linear "
        "theory (ν the linearised gyroscopic frequency bound |ω|·max_i sqrt(|(Ii−Ij)(Ii−Ik)|/(Ij Ik))); for "
        "implicit_midpoint (Newton solve) 4 / ν and for splitting 2 rad / |ω|, both measured by this bisection. "
        "Explicit Euler has no stable step in theory (growth factor sqrt(1 + (ν dt)²) per step), so its bisected "
        f"step is only the step whose growth stays under {bis['growth']:.0%} over {bis['steps']} steps.",
        "",
        "| case | method | largest stable dt [s] | advice dt [s] | measured / advice |",
        "|---|---|---|---|---|",
    ]
    for row in bis["rows"]:
        md.append(
            f"| {row['case']} | {row['method']} | {_g(row['largest_stable_dt'], '.4g')} | "
            f"{_g(row['theory_dt'], '.4g')} | {_g(row['ratio'], '.3f')} |"
        )
    md += [
        "",
        "## Long horizon: bounded or secular energy drift",
        "",
        "P1's body (I = diag(1, 2, 3) kg·m², ω0 = (1, 0.1, 0.5) rad/s), dt = 10 ms. Secular = the mean relative "
        "energy error over the last tenth exceeds twice its maximum over the first tenth and 1e-11 (round-off).",
        "",
        "![long horizon](long_horizon.png)",
        "",
        "| method | steps | run time [s] | max error, first tenth | mean error, last tenth | final error | verdict |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in payload["long_horizon"]:
        verdict = row["status"] if row["status"] != "stable" else ("**secular**" if row["secular"] else "bounded")
        md.append(
            f"| {row['method']} | {row['steps']:.0e} | {row['seconds']:.1f} | {_g(row['first_tenth_max'])} | "
            f"{_g(row['last_tenth_mean'])} | {_g(row['final'])} | {verdict} |"
        )
    md += ["", "## Cases in detail", ""]
    for case in payload["cases"]:
        md += [
            f"### {case['name']}",
            "",
            f"{case['description']}; {case['steps']} steps. Criterion: {case['criterion']}. "
            f"Reference: {case['reference'] or 'none'}.",
            "",
            "| method | status | pass | energy drift | momentum drift | \\| \\|q\\|−1 \\| | ω error [rad/s] | "
            "attitude error [rad] | run time [s] | note |",
            "|---|---|---|---|---|---|---|---|---|---|",
        ]
        for method in methods:
            run = case["runs"][method]
            md.append(
                f"| {method} | {run['status']} | {'yes' if run['passed'] else 'no'} | {_g(run['energy_drift'])} | "
                f"{_g(run['momentum_drift'])} | {_g(run['quaternion_norm_error'])} | {_g(run['omega_error'])} | "
                f"{_g(run['attitude_error'])} | {_g(run['seconds'], '.3f')} | {run['message'][:160]} |"
            )
        md.append("")
    return "\n".join(md)
