"""The stability suite's runner: every integrator on the catalogue of stiff and extreme cases.

The cases are :mod:`rigid_rot_sim.analysis.stability_cases` (data); the outputs are
written by :mod:`rigid_rot_sim.analysis.stability_report`. Each
:class:`~rigid_rot_sim.analysis.stability_cases.Case` is a body, an initial state, a step ``dt`` and a horizon (a
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
bound of :func:`rigid_rot_sim.run.advice.max_stable_dt`.

A long horizon of 1e7 steps (1e5 in quick mode) separates bounded from secular energy
drift: :func:`long_horizon` fits nothing, it compares the energy error over the last
tenth of the run with its maximum over the first tenth (a bounded error reaches its
full size within the first tenth; a secular one keeps growing).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from rigid_rot_sim.analysis.metrics import attitude_error_angle, omega_error, relative_change
from rigid_rot_sim.analysis.problems import P1, Problem
from rigid_rot_sim.analysis.stability_cases import Case, Criterion, case_named
from rigid_rot_sim.cluster import map_tasks, open_client, wants_cluster
from rigid_rot_sim.core.exact import torque_free_solution
from rigid_rot_sim.core.integrators import METHODS, get_method
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.integrators.gyrostat import GYROSTAT_METHODS, get_gyrostat_method
from rigid_rot_sim.core.torque import ConstantTorque
from rigid_rot_sim.core.wheels import gyrostat_energy, total_momentum_body
from rigid_rot_sim.run import advice

#: Growth of energy or momentum beyond this (relative) counts as unstable.
GROWTH_LIMIT = 1.0
#: Samples of the invariants per run.
SAMPLES = 200
#: Steps per trial in the bisection for the largest stable step, and the growth it allows.
BISECTION_STEPS = 1000
BISECTION_GROWTH = 0.01
#: Fixed-step methods whose largest stable step is bisected (the explicit ones, and the
#: measured solver / accuracy limits of implicit_midpoint and splitting).
BISECTED = advice.EXPLICIT_FIXED_STEP + advice.MEASURED_STEP_LIMITS

#: A method as the suite runs it: registry name and keyword options, e.g. ("splitting", (("order", 4),)).
MethodVariant = tuple[str, tuple[tuple[str, Any], ...]]


def method_label(method: str | MethodVariant) -> str:
    """The report's name of a method variant: ``("splitting", (("order", 4),))`` -> 'splitting(order=4)'."""
    if isinstance(method, str):
        return method
    name, options = method
    return f"{name}({', '.join(f'{key}={value}' for key, value in options)})" if options else name


@dataclass
class CaseRun:
    """What one method did on one case."""

    method: str
    status: Literal["stable", "unstable", "refused"]
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


# ---------------------------------------------------------------- running


def _invariants(problem: Problem, q: np.ndarray, omega: np.ndarray, speeds: Any = None) -> tuple[float, float, float]:
    """(energy, momentum 1, momentum 2): |L| (twice) for a free body, (E, p_phi, p_psi) for a heavy top,
    total energy and |H| (body + wheels, twice) for a gyrostat (``speeds``: its wheel speeds, rad/s)."""
    if problem.wheels is not None and speeds is not None:
        norm = float(np.linalg.norm(total_momentum_body(problem.moments, problem.wheels, omega, speeds)))
        return float(gyrostat_energy(problem.moments, problem.wheels, omega, speeds)), norm, norm
    if problem.top is not None:
        energy, p_phi, p_psi = problem.top.invariants(q, omega)
        return float(energy), float(p_phi), float(p_psi)
    norm = problem.momentum_norm(omega)
    return problem.energy(q, omega), norm, norm


def _integrator(method: str, case: Case, dt: float, torque: Any) -> Any:
    """The integrator of ``method`` (a registry name) on ``case``'s body, at step ``dt``, with the case's options."""
    problem = case.problem
    options = case.options.get(method, {})
    if problem.wheels is not None:  # a gyrostat: only the gyrostat methods carry the wheels (ValueError: refused)
        return get_gyrostat_method(method)(
            problem.moments,
            dt,
            torque,
            q0=problem.q0,
            omega0=problem.omega0,
            wheels=problem.wheels,
            wheel_speeds0=problem.wheel_speeds0,
            **options,
        )
    if method not in METHODS and method in GYROSTAT_METHODS:
        raise ValueError(f"{method} runs gyrostats only (reaction wheels, gravity gradient): this case has no wheels")
    return get_method(method)(problem.moments, dt, torque, q0=problem.q0, omega0=problem.omega0, **options)


def run_case(case: Case, method: str) -> CaseRun:
    """One method on one case (all steps, ~SAMPLES samples of the invariants)."""
    problem = case.problem
    run = CaseRun(method, "stable")
    n = case.n_steps
    dt = problem.t_end / n
    samples = min(SAMPLES, n)
    chunks = np.diff(np.linspace(0, n, samples + 1).round().astype(int))
    start = time.perf_counter()
    try:
        if case.impulse is not None:
            integrator = _integrator(method, case, dt, ConstantTorque(np.asarray(case.impulse)))
            integrator.advance(1)
            integrator.torque = None
            chunks[0] -= 1
        else:
            integrator = _integrator(method, case, dt, problem.torque)
        # conserved from here on (right after the kick, for an impulse)
        first = _invariants(problem, integrator.q, integrator.omega, getattr(integrator, "wheel_speeds", None))
        drift_e = drift_m = qnorm = 0.0
        for chunk in chunks:
            if chunk:
                integrator.advance(int(chunk))
            q, omega = integrator.q, integrator.omega
            qnorm = max(qnorm, abs(float(np.linalg.norm(q)) - 1.0))
            if case.conserved:
                e, m1, m2 = _invariants(problem, q, omega, getattr(integrator, "wheel_speeds", None))
                drift_e = max(drift_e, relative_change(first[0], e))
                drift_m = max(drift_m, relative_change(first[1], m1), relative_change(first[2], m2))
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
            drift_e, drift_m = relative_change(re, e), relative_change(rm1, m1)
    run.energy_drift, run.momentum_drift = drift_e, drift_m
    run.passed = _passes(case.criterion, run)
    if case.same_as is not None and run.status == "stable":
        twin = dataclasses.replace(case, problem=case.same_as, same_as=None)
        other = _integrator(method, twin, dt, case.same_as.torque)
        other.advance(n)
        gap = max(
            omega_error(other.omega, integrator.omega) / float(np.linalg.norm(other.omega)),
            attitude_error_angle(other.q, integrator.q),
        )
        run.passed = gap <= case.same_tol
        run.message = f"relative difference from the unit-scale run {gap:.2g}"
    if case.flip_time_tol is not None and run.passed:
        run.passed, note = _flip_times_match(case, method, case.flip_time_tol)
        run.message = note
    return run


def _passes(criterion: Criterion, run: CaseRun) -> bool:
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


def _flip_times_match(case: Case, method: str, tolerance: float) -> tuple[bool, str]:
    """Compare the flip times (sign changes of omega_2) with the exact solution's."""
    problem = case.problem
    n = case.n_steps
    integrator = _integrator(method, case, problem.t_end / n, problem.torque)
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
        integrator = _integrator(method, case, dt, problem.torque)
        e0, m0, _ = _invariants(problem, integrator.q, integrator.omega, getattr(integrator, "wheel_speeds", None))
        for _ in range(10):
            integrator.advance(steps // 10)
            e, m, _ = _invariants(problem, integrator.q, integrator.omega, getattr(integrator, "wheel_speeds", None))
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
    status: Literal["stable", "unstable"] = "stable"
    message: str = ""


#: Energy errors below this are round-off (a random walk of ~1e-16 per step over 1e7 steps).
ROUNDOFF_FLOOR = 1e-11

LONG_HORIZON_METHODS: tuple[MethodVariant, ...] = (
    ("rk4", ()),
    ("lie_rk4", ()),
    ("implicit_midpoint", ()),
    ("splitting", (("order", 2),)),
    ("splitting", (("order", 4),)),
)


def long_horizon(method: str | MethodVariant, steps: int, dt: float = 0.01, samples: int = 1000) -> LongHorizon:
    """P1's body for ``steps`` steps of ``dt``: is the relative energy error bounded or secular?

    ``method``: a registry name or a (name, options) variant. Secular when the mean error
    over the last tenth exceeds twice the maximum over the first tenth and the round-off
    floor (1e-11).
    """
    problem = P1
    name, options = (method, ()) if isinstance(method, str) else method
    integrator = get_method(name)(problem.moments, dt, None, q0=problem.q0, omega0=problem.omega0, **dict(options))
    label = method_label(method)
    e0 = problem.energy(problem.q0, problem.omega0)
    chunks = np.diff(np.linspace(0, steps, samples + 1).round().astype(int))
    errors = np.empty(samples)
    start = time.perf_counter()
    try:
        for k, chunk in enumerate(chunks):
            integrator.advance(int(chunk))
            errors[k] = relative_change(e0, problem.energy(integrator.q, integrator.omega))
    except (NonFiniteStateError, ArithmeticError) as exc:
        return LongHorizon(
            label,
            steps,
            dt,
            time.perf_counter() - start,
            math.nan,
            math.nan,
            math.nan,
            True,
            "unstable",
            str(exc)[:240],
        )
    seconds = time.perf_counter() - start
    tenth = max(1, samples // 10)
    first, last = float(errors[:tenth].max()), float(errors[-tenth:].mean())
    secular = last > max(2.0 * first, ROUNDOFF_FLOOR)
    return LongHorizon(label, steps, dt, seconds, first, last, float(errors[-1]), secular)


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


def case_task(name: str, quick: bool, method: str) -> dict[str, Any]:
    """A Dask task: :func:`run_case` of the catalogue's case ``name`` (rebuilt on the worker)."""
    return dataclasses.asdict(run_case(case_named(name, quick), method))


def bisection_task(name: str, quick: bool, method: str) -> dict[str, Any]:
    """A Dask task: :func:`bisection_row` of the catalogue's case ``name``."""
    return bisection_row(case_named(name, quick), method, BISECTION_STEPS // (4 if quick else 1))


def long_horizon_task(method: str | MethodVariant, steps: int) -> dict[str, Any]:
    """A Dask task: :func:`long_horizon` as a dict."""
    return dataclasses.asdict(long_horizon(method, steps))


def method_labels() -> list[str]:
    """The columns of the suite: every registered method with its default options, then the methods that
    run gyrostats only (``dopri5``: refused on the cases without wheels)."""
    return list(METHODS) + [name for name in GYROSTAT_METHODS if name not in METHODS]


# ---------------------------------------------------------------- the whole suite, here or on a cluster


def run_all(
    cases: list[Case],
    methods: list[str],
    long_methods: tuple[str | MethodVariant, ...],
    long_steps: int,
    quick: bool,
    bar: Any,
    scheduler: str | None = None,
    workers: int | None = None,
) -> tuple[dict[str, dict[str, Any]], list[dict[str, Any]], list[dict[str, Any]]]:
    """Every method on every case, the bisections and the long horizons, as dicts.

    Returns ``({case: {method: run}}, bisection rows, long horizons)``; ``bar`` (tqdm)
    counts one step per run, one for all the bisections and one per long horizon. With
    ``scheduler`` or ``workers`` (or DASK_SCHEDULER_ADDRESS) each is one Dask task; the
    results are the same (run times aside).
    """
    if wants_cluster(scheduler, workers):
        with open_client(scheduler, workers) as client:
            return _run_on_cluster(client, cases, methods, long_methods, long_steps, quick, bar)
    return _run_here(cases, methods, long_methods, long_steps, quick, bar)


def _run_here(cases, methods, long_methods, long_steps, quick, bar):
    """The suite in this process."""
    case_runs: dict[str, dict[str, Any]] = {}
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
        bar.set_postfix_str(f"long horizon {method_label(method)}", refresh=True)
        horizon.append(dataclasses.asdict(long_horizon(method, long_steps)))
        bar.update(1)
    return case_runs, bisection, horizon


def _run_on_cluster(client, cases, methods, long_methods, long_steps, quick, bar):
    """The same as :func:`_run_here`, every run, bisection and long horizon one Dask task."""
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
    for (name, _, method), run in zip(runs_args, results[:first_bisection], strict=True):
        case_runs.setdefault(name, {})[method] = run
    return case_runs, results[first_bisection:first_horizon], results[first_horizon:]
