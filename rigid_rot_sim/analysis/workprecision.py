"""Work-precision measurements: error at the final time against wall-clock run time.

For each problem of :mod:`rigid_rot_sim.analysis.problems`, every integrator in
:data:`rigid_rot_sim.core.integrators.METHODS` (the splittings once per order) and
scipy's ``solve_ivp`` (RK45, DOP853, Radau, LSODA) run over a sweep:

* fixed-step methods: step counts from a first step of about 0.5 rad of rotation, by
  factors of 2 (4 in quick mode), ``max_step_points`` of them at most (the step range);
* adaptive methods (ours and scipy's): the tolerance from 1e-3, falling by 10x
  (by 1000x in quick mode), with ``rtol = atol``;
* ``exact``: one step of length t_end (torque-free problems only).

Points are chosen by error target, not swept to a time budget: once two stable points
show the observed order p (omega error ~ value**p), the next point is the one predicted
to reach half the largest target of TARGETS not met yet, within the step range above
(tolerance sweeps walk their list: scipy's error does not follow a power of the tolerance
closely enough to skip decades fairly). A line stops once a point meets
min(TARGETS) (or the reference's own certified error, if larger), when a point takes
longer than the per-point time budget or the next one is predicted to take twice that,
or after two refusals.

Timing: each point is run ``repeats`` times and the best wall-clock time is kept
(points whose first run takes over 1 s are run twice). The timed call is the whole of
what a user would run, set-up included: ``simulate(...)`` for ours, and for scipy
building the right-hand side, ``solve_ivp(...)`` and normalising the final quaternion.
The garbage collector is off while timing, for every method alike (and collects before
each run; what is alive when a line starts is frozen, ``gc.freeze``, so that collection
is quick).

Fastest method at a target error: the cheapest measured point whose omega error is at
or below the target (no interpolation between sweep points, so the figure is an upper
bound on the run time needed).
"""

from __future__ import annotations

import gc
import math
import time
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field
from typing import Any, Literal

import numpy as np
from scipy.integrate import solve_ivp

from rigid_rot_sim.analysis.metrics import attitude_error_angle, omega_error, relative_change
from rigid_rot_sim.analysis.problems import Problem, get_problem, scipy_rhs
from rigid_rot_sim.cluster import map_tasks, open_client
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.integrators import METHODS
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.steps import steps_over

SCIPY_METHODS = ("RK45", "DOP853", "Radau", "LSODA")
TARGETS = (1e-6, 1e-10)
ERROR_FLOOR = 1e-13
#: A line aims its next point at this fraction of the target it has not met yet (the error
#: model from two points is asymptotic: the margin lands the point below the target).
TARGET_MARGIN = 0.5
#: Observed orders below this are taken as this (a point still far from asymptotic must
#: not predict an absurd jump).
MIN_ORDER = 0.5
#: On a cluster every point is timed together with this scipy run on the same worker, in the
#: same task; run times are then compared as multiples of it, so that points measured on
#: different machines stay comparable.
BASELINE_METHOD = "DOP853"
BASELINE_TOL = 1e-10

#: The orders of the methods that come in several orders (one line each), as the integrators accept them.
ORDER_VARIANTS = {name: cls.orders for name, cls in METHODS.items() if len(cls.orders) > 1}
#: How each of our adaptive methods takes a tolerance.
TOLERANCE_OPTIONS: dict[str, Callable[[float], dict[str, float]]] = {
    "dop853": lambda tol: {"rtol": tol, "atol": tol},
    "taylor": lambda tol: {"tol": tol},
}


@dataclass(frozen=True)
class DiagramLine:
    """One curve of a work-precision diagram: a method with fixed options, and its sweep kind."""

    label: str
    family: Literal["ours", "scipy"]
    method: str
    options: tuple[tuple[str, Any], ...] = ()
    sweep: Literal["step", "tol", "single"] = "step"  # "single": one run of length t_end


@dataclass
class SweepPoint:
    """One run: the sweep parameter, its errors at t_end and its best run time."""

    label: str
    family: Literal["ours", "scipy"]
    method: str
    parameter: Literal["dt", "tol"]
    value: float
    status: Literal["ok", "unstable", "refused"]  # unstable: non-finite state; refused: ValueError
    message: str = ""
    seconds: float = math.nan
    repeats: int = 0
    omega_error: float = math.nan
    attitude_error: float = math.nan
    energy_drift: float = math.nan
    momentum_drift: float = math.nan
    n_steps: int = 0
    baseline_seconds: float = math.nan  # the scipy baseline timed in the same task (distributed runs)


@dataclass
class Settings:
    """Sweep and timing settings (quick mode: fewer, coarser points)."""

    quick: bool = False
    repeats: int = 5
    budget_seconds: float = 3.0
    step_factor: int = 2
    tolerances: tuple[float, ...] = tuple(10.0**-k for k in range(3, 14))
    max_step_points: int = 14
    scipy_methods: tuple[str, ...] = SCIPY_METHODS
    methods: tuple[str, ...] | None = None  # None: every method in METHODS

    @classmethod
    def quick_mode(cls, **overrides: Any) -> Settings:
        values: dict[str, Any] = dict(
            quick=True,
            repeats=2,
            budget_seconds=0.2,
            step_factor=4,
            tolerances=(1e-3, 1e-6, 1e-9, 1e-12),
            max_step_points=6,
        )
        values.update(overrides)
        return cls(**values)


@dataclass
class ProblemResult:
    problem: str
    title: str
    t_end: float
    reference: str
    reference_error: float
    points: list[SweepPoint] = field(default_factory=list)


def method_lines(methods: Iterable[str], problem: Problem) -> list[DiagramLine]:
    """The curves for our methods (one per order for the splittings)."""
    lines = []
    for name in methods:
        cls = METHODS[name]
        if name in ORDER_VARIANTS:
            for order in ORDER_VARIANTS[name]:
                lines.append(DiagramLine(f"{name}(order={order})", "ours", name, (("order", order),), "step"))
        elif cls.stability == "exact":
            lines.append(DiagramLine(name, "ours", name, (), "single"))
        elif not getattr(cls, "fixed_step", True):
            lines.append(DiagramLine(name, "ours", name, (), "tol" if name in TOLERANCE_OPTIONS else "single"))
        else:
            lines.append(DiagramLine(name, "ours", name, (), "step"))
    return lines


def scipy_lines(methods: Iterable[str]) -> list[DiagramLine]:
    return [DiagramLine(f"scipy {m}", "scipy", m, (), "tol") for m in methods]


def _best_time(run: Callable[[], Any], repeats: int) -> tuple[Any, float, int]:
    """Run ``run`` up to ``repeats`` times (twice if the first takes > 1 s); best time."""
    best = math.inf
    result = None
    done = 0
    gc_was_enabled = gc.isenabled()
    try:
        for _ in range(repeats):
            gc.collect()
            gc.disable()
            start = time.perf_counter()
            result = run()
            elapsed = time.perf_counter() - start
            if gc_was_enabled:
                gc.enable()
            best = min(best, elapsed)
            done += 1
            if done >= 2 and best > 1.0:
                break
    finally:
        if gc_was_enabled:
            gc.enable()
    return result, best, done


def _runner(
    problem: Problem, line: DiagramLine, value: float
) -> tuple[Callable[[], tuple[np.ndarray, np.ndarray, int]], Literal["dt", "tol"]]:
    """A zero-argument callable doing the full timed run, and the sweep parameter name."""
    if line.family == "scipy":
        y0 = problem.initial_vector()

        def run_scipy() -> tuple[np.ndarray, np.ndarray, int]:
            # scipy-stubs' overloads want Literal method names; ours come from the diagram's data
            settings: dict[str, Any] = {"method": line.method, "rtol": value, "atol": value}
            sol = solve_ivp(scipy_rhs(problem), (0.0, problem.t_end), y0, **settings)
            if not sol.success:
                raise NonFiniteStateError(f"solve_ivp {line.method}: {sol.message}")
            y = sol.y[:, -1]
            if not np.all(np.isfinite(y)):
                raise NonFiniteStateError(f"solve_ivp {line.method}: non-finite final state")
            return np.asarray(quat.normalize(y[:4])), y[4:7], int(sol.nfev)

        return run_scipy, "tol"

    options = dict(line.options)
    parameter: Literal["dt", "tol"]
    if line.sweep == "tol":
        options.update(TOLERANCE_OPTIONS[line.method](value))
        dt = problem.t_end
        parameter = "tol"
    else:
        dt = value
        parameter = "dt"
    n_steps = steps_over(problem.t_end, dt)

    def run_ours() -> tuple[np.ndarray, np.ndarray, int]:
        q, omega = problem.final_state(line.method, dt, **options)
        return q, omega, n_steps

    return run_ours, parameter


def measure_point(
    problem: Problem, line: DiagramLine, value: float, repeats: int, baseline: bool = False
) -> SweepPoint:
    """Run one sweep point and compare its final state with the problem's reference.

    ``baseline``: also time scipy's BASELINE_METHOD at BASELINE_TOL on the same problem,
    right before the point, into ``point.baseline_seconds``.
    """
    run, parameter = _runner(problem, line, value)
    point = SweepPoint(line.label, line.family, line.method, parameter, float(value), "ok")
    if baseline:
        base_run, _ = _runner(problem, DiagramLine("scipy baseline", "scipy", BASELINE_METHOD, (), "tol"), BASELINE_TOL)
        _, point.baseline_seconds, _ = _best_time(base_run, repeats)
    try:
        (q, omega, n), seconds, done = _best_time(run, repeats)
    except (NonFiniteStateError, ArithmeticError) as exc:
        point.status, point.message = "unstable", f"{type(exc).__name__}: " + " ".join(str(exc).split())[:300]
        return point
    except (ValueError, NotImplementedError) as exc:
        point.status, point.message = "refused", " ".join(str(exc).split())[:300]
        return point
    ref = problem.reference()
    point.seconds, point.repeats, point.n_steps = seconds, done, n
    point.omega_error = omega_error(ref.omega, omega)
    point.attitude_error = attitude_error_angle(ref.q, q)
    point.energy_drift = relative_change(problem.energy(ref.q, ref.omega), problem.energy(q, omega))
    point.momentum_drift = relative_change(problem.momentum_norm(ref.omega), problem.momentum_norm(omega))
    return point


def sweep_values(problem: Problem, line: DiagramLine, settings: Settings) -> list[float]:
    """A line's sweep values, coarse to fine: its range, and an upper bound on its points.

    :func:`run_line` starts with the first and, once two stable points show how the error
    falls, jumps between them to the values :func:`next_value` predicts for the targets.
    """
    if line.sweep == "single":
        return [problem.t_end]
    if line.sweep == "tol":
        return list(settings.tolerances)
    spin = float(np.linalg.norm(problem.omega0))
    n0 = max(4, math.ceil(problem.t_end * spin / 0.5))
    return [problem.t_end / (n0 * settings.step_factor**k) for k in range(settings.max_step_points)]


def observed_order(coarse: SweepPoint, fine: SweepPoint) -> float | None:
    """The exponent p of ``omega error ~ value**p`` between two stable points, or None if the error did not fall."""
    if not (coarse.omega_error > fine.omega_error > 0.0 and coarse.value > fine.value):
        return None
    return math.log(coarse.omega_error / fine.omega_error) / math.log(coarse.value / fine.value)


def next_value(
    line: DiagramLine, t_end: float, points: list[SweepPoint], values: list[float], goal: float
) -> float | None:
    """The next sweep value of a line after ``points`` (coarse to fine), or None to stop.

    A tolerance sweep, and a step sweep until two stable points give an
    :func:`observed_order`, takes the next of ``values``. Then a step sweep jumps to the step
    count predicted to bring the omega error to TARGET_MARGIN times the largest target it has
    not met yet (``goal``: the last one), ``n * (error / aim)**(1/p)``: at least twice the
    last count, and no finer than the finest of ``values`` (the sweep's range).
    """
    last = points[-1]
    finer = [v for v in values if v < last.value * (1.0 - 1e-9)]
    if not finer:
        return None
    ok = [p for p in points if p.status == "ok"]
    order = observed_order(ok[-2], ok[-1]) if line.sweep == "step" and len(ok) >= 2 and ok[-1] is last else None
    if order is None:
        return finer[0]
    aim = TARGET_MARGIN * max([t for t in TARGETS if goal <= t < last.omega_error] or [goal])
    shrink = (last.omega_error / aim) ** (1.0 / max(order, MIN_ORDER))
    n_steps = steps_over(t_end, last.value)
    return max(t_end / max(2 * n_steps, math.ceil(n_steps * shrink)), finer[-1])


def run_problem(problem: Problem, settings: Settings, progress: Any = None) -> ProblemResult:
    """Every line's sweep on one problem."""
    ref = problem.reference()
    result = ProblemResult(problem.key, problem.title, problem.t_end, ref.method, ref.certified_to)
    for line in problem_lines(problem, settings):
        result.points += run_line(problem, line, settings, progress)
    return result


def problem_lines(problem: Problem, settings: Settings) -> list[DiagramLine]:
    """The lines of one problem's diagram: ours, then scipy's."""
    methods = settings.methods if settings.methods is not None else tuple(METHODS)
    return method_lines(methods, problem) + scipy_lines(settings.scipy_methods)


def run_line(
    problem: Problem, line: DiagramLine, settings: Settings, progress: Any = None, baseline: bool = False
) -> list[SweepPoint]:
    """One line's sweep, coarse to fine, with points chosen by error target (:func:`next_value`).

    A line stops once a point meets min(TARGETS) (or the error floor, when the reference
    is less accurate), when a point takes longer than the time budget or the next one is
    predicted to take twice as long (fixed-step runs cost in proportion to their steps), after two refusals,
    or at the end of its range (:func:`sweep_values`).

    ``baseline``: time every point together with the scipy baseline (see measure_point).
    """
    goal = max(min(TARGETS), ERROR_FLOOR, problem.reference().certified_to)
    values = sweep_values(problem, line, settings)
    # what is alive now (numba, scipy, the references) is frozen for the line: the collection
    # before each timed run then scans only the line's own objects (a full one takes ~0.2 s)
    gc.freeze()
    try:
        return _sweep_line(problem, line, settings, values, goal, progress, baseline)
    finally:
        gc.unfreeze()


def _sweep_line(
    problem: Problem,
    line: DiagramLine,
    settings: Settings,
    values: list[float],
    goal: float,
    progress: Any,
    baseline: bool,
) -> list[SweepPoint]:
    """run_line's loop over the points of one line."""
    points: list[SweepPoint] = []
    refusals = 0
    value: float | None = values[0]
    while value is not None:
        if progress is not None:
            progress.set_postfix_str(f"{problem.key} {line.label}", refresh=False)
        point = measure_point(problem, line, value, settings.repeats, baseline)
        points.append(point)
        if progress is not None:
            progress.update(1)
        refusals = refusals + 1 if point.status == "refused" else 0
        if (
            refusals >= 2
            or point.status == "ok"
            and (point.omega_error <= goal or point.seconds > settings.budget_seconds)
        ):
            break
        value = next_value(line, problem.t_end, points, values, goal)
        if value is not None and line.sweep == "step" and point.status == "ok":
            predicted = point.seconds * point.value / value
            if predicted > 2.0 * settings.budget_seconds:
                break
    if progress is not None:
        progress.update(max(0, len(values) - len(points)))
    return points


def line_task(problem_key: str, line: DiagramLine, settings: Settings) -> list[SweepPoint]:
    """A Dask task: one line of one problem, each point timed with the scipy baseline on this worker."""
    return run_line(get_problem(problem_key), line, settings, baseline=True)


def planned_points(problems: Iterable[Problem], settings: Settings) -> int:
    """Upper bound on the number of points (for the progress bar)."""
    return sum(len(sweep_values(p, line, settings)) for p in problems for line in problem_lines(p, settings))


def cost(point: SweepPoint) -> float:
    """A point's run time in units of its scipy baseline when it has one (cluster runs), else in s."""
    return point.seconds / point.baseline_seconds if point.baseline_seconds > 0.0 else point.seconds


def fastest_at(points: Iterable[SweepPoint], target: float, family: str) -> SweepPoint | None:
    """The cheapest measured point of ``family`` whose omega error is <= target (by :func:`cost`)."""
    meeting = [p for p in points if p.family == family and p.status == "ok" and p.omega_error <= target]
    return min(meeting, key=cost) if meeting else None


def summary(result: ProblemResult, targets: Iterable[float] = TARGETS) -> list[dict[str, Any]]:
    """Per target: the fastest of ours, the fastest scipy method, and the speed-up."""
    rows = []
    for target in targets:
        ours = fastest_at(result.points, target, "ours")
        theirs = fastest_at(result.points, target, "scipy")
        rows.append(
            {
                "problem": result.problem,
                "target": target,
                "ours": None if ours is None else asdict(ours),
                "scipy": None if theirs is None else asdict(theirs),
                "speedup": (cost(theirs) / cost(ours)) if (ours and theirs) else None,
            }
        )
    return rows


def errors_fall_with_step(points: Iterable[SweepPoint], label: str, floor: float = 1e-12) -> bool:
    """True if the omega error of a fixed-step line falls from its coarsest to its finest stable point.

    Points below ``floor`` (round-off and reference accuracy) are left out.
    """
    ok = [p for p in points if p.label == label and p.status == "ok" and p.parameter == "dt"]
    ok.sort(key=lambda p: -p.value)
    errs = [p.omega_error for p in ok if p.omega_error > floor]
    return len(errs) >= 2 and errs[-1] < errs[0]


def run_problems(
    problems: dict[str, Problem],
    settings: Settings,
    bar: Any,
    scheduler: str | None = None,
    workers: int | None = None,
    cluster: bool = False,
) -> list[ProblemResult]:
    """Every line's sweep on each problem, in order; ``bar`` (tqdm) counts the points.

    With ``cluster`` every line of every problem is one Dask task (:func:`line_task`) on
    :func:`~rigid_rot_sim.cluster.open_client` ``(scheduler, workers)``, each point
    timed with the scipy baseline in that task.
    """
    if not cluster:
        results = []
        for key, problem in problems.items():
            bar.set_postfix_str(f"{key} reference", refresh=True)
            problem.reference()
            results.append(run_problem(problem, settings, bar))
        return results
    tasks = [(key, line, settings) for key, problem in problems.items() for line in problem_lines(problem, settings)]

    def done(index: int, points: list[SweepPoint]) -> None:
        key, line, _ = tasks[index]
        bar.set_postfix_str(f"{key} {line.label}", refresh=False)
        bar.update(len(sweep_values(problems[key], line, settings)))

    with open_client(scheduler, workers) as client:
        lines_points = map_tasks(client, [(line_task, args) for args in tasks], done)
    results = []
    for key, problem in problems.items():
        ref = problem.reference()
        result = ProblemResult(key, problem.title, problem.t_end, ref.method, ref.certified_to)
        for (task_key, _, _), points in zip(tasks, lines_points, strict=True):
            if task_key == key:
                result.points += points
        results.append(result)
    return results
