"""Work-precision measurements: error at the final time against wall-clock run time.

For each problem of :mod:`rigid_rot_sim.analysis.problems`, every integrator in
:data:`rigid_rot_sim.core.integrators.METHODS` (the splittings once per order) and
scipy's ``solve_ivp`` (RK45, DOP853, Radau, LSODA) run over a sweep:

* fixed-step methods: the number of steps doubles (quadruples in quick mode) from a
  first step of about 0.5 rad of rotation;
* adaptive methods (ours and scipy's): the tolerance falls by 10x from 1e-3
  (by 1000x in quick mode), with ``rtol = atol``;
* ``exact``: one step of length t_end (torque-free problems only).

A sweep stops once a point takes longer than the per-point time budget or its omega
error is below the error floor (1e-13, or the reference's own certified error).

Timing: each point is run ``repeats`` times and the best wall-clock time is kept
(points whose first run takes over 1 s are run twice). The timed call is the whole of
what a user would run, set-up included: ``simulate(...)`` for ours, and for scipy
building the right-hand side, ``solve_ivp(...)`` and normalising the final quaternion.
The garbage collector is off while timing, for every method alike.

Fastest method at a target error: the cheapest measured point whose omega error is at
or below the target (no interpolation between sweep points, so the figure is an upper
bound on the run time needed).
"""

from __future__ import annotations

import gc
import math
import os
import platform
import subprocess
import sys
import time
from dataclasses import asdict, dataclass, field
from typing import Any, Callable, Iterable, Sequence

import numpy as np

from rigid_rot_sim.analysis.metrics import attitude_error_angle, omega_error, relative_change
from rigid_rot_sim.analysis.problems import Problem, scipy_rhs
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.integrators.base import NonFiniteStateError

SCIPY_METHODS = ("RK45", "DOP853", "Radau", "LSODA")
TARGETS = (1e-6, 1e-10)
ERROR_FLOOR = 1e-13
#: On a cluster every point is timed together with this scipy run on the same worker, in the
#: same task; run times are then compared as multiples of it, so that points measured on
#: different machines stay comparable.
BASELINE_METHOD = "DOP853"
BASELINE_TOL = 1e-10

#: Options per order for the methods that come in several orders.
ORDER_VARIANTS = {"splitting": (2, 4, 6), "exact_split": (2, 4)}
#: How each of our adaptive methods takes a tolerance.
TOLERANCE_OPTIONS: dict[str, Callable[[float], dict[str, float]]] = {
    "dop853": lambda tol: {"rtol": tol, "atol": tol},
    "taylor": lambda tol: {"tol": tol},
}


@dataclass(frozen=True)
class Line:
    """One curve of a work-precision diagram: a method with fixed options, and its sweep kind."""

    label: str
    family: str  # "ours" or "scipy"
    method: str
    options: tuple[tuple[str, Any], ...] = ()
    sweep: str = "step"  # "step", "tol" or "single"


@dataclass
class Point:
    """One run: the sweep parameter, its errors at t_end and its best run time."""

    label: str
    family: str
    method: str
    parameter: str  # "dt" or "tol"
    value: float
    status: str  # "ok", "unstable" (non-finite state) or "refused" (ValueError)
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
    def quick_mode(cls, **overrides: Any) -> "Settings":
        values = dict(
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
    points: list[Point] = field(default_factory=list)


def our_lines(methods: Iterable[str], problem: Problem) -> list[Line]:
    """The curves for our methods (one per order for the splittings)."""
    from rigid_rot_sim.core.integrators import METHODS

    lines = []
    for name in methods:
        cls = METHODS[name]
        if name in ORDER_VARIANTS:
            for order in ORDER_VARIANTS[name]:
                lines.append(Line(f"{name}(order={order})", "ours", name, (("order", order),), "step"))
        elif name == "exact":
            lines.append(Line(name, "ours", name, (), "single"))
        elif not getattr(cls, "fixed_step", True):
            lines.append(Line(name, "ours", name, (), "tol" if name in TOLERANCE_OPTIONS else "single"))
        else:
            lines.append(Line(name, "ours", name, (), "step"))
    return lines


def scipy_lines(methods: Iterable[str]) -> list[Line]:
    return [Line(f"scipy {m}", "scipy", m, (), "tol") for m in methods]


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


def _runner(problem: Problem, line: Line, value: float) -> tuple[Callable[[], tuple[np.ndarray, np.ndarray, int]], str]:
    """A zero-argument callable doing the full timed run, and the sweep parameter name."""
    if line.family == "scipy":
        from scipy.integrate import solve_ivp

        y0 = np.concatenate((problem.q0, problem.omega0))

        def run_scipy() -> tuple[np.ndarray, np.ndarray, int]:
            sol = solve_ivp(scipy_rhs(problem), (0.0, problem.t_end), y0, method=line.method, rtol=value, atol=value)
            if not sol.success:
                raise NonFiniteStateError(f"solve_ivp {line.method}: {sol.message}")
            y = sol.y[:, -1]
            if not np.all(np.isfinite(y)):
                raise NonFiniteStateError(f"solve_ivp {line.method}: non-finite final state")
            return np.asarray(quat.normalize(y[:4])), y[4:], int(sol.nfev)

        return run_scipy, "tol"

    options = dict(line.options)
    if line.sweep == "tol":
        options.update(TOLERANCE_OPTIONS[line.method](value))
        dt = problem.t_end
        parameter = "tol"
    else:
        dt = value
        parameter = "dt"
    n_steps = max(1, round(problem.t_end / dt))

    def run_ours() -> tuple[np.ndarray, np.ndarray, int]:
        q, omega = run_to_end(problem, line.method, dt, options)
        return q, omega, n_steps

    return run_ours, parameter


def run_to_end(problem: Problem, method: str, dt: float, options: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Final ``(q, omega)`` of ``method`` on ``problem`` at step ``dt``, as a user runs it.

    Through ``core.simulate.simulate`` (keeping only the final state) when it is
    available, else through the integrator's step API directly.
    """
    try:
        from rigid_rot_sim.core.simulate import simulate
    except ImportError:
        simulate = None
    n_steps = max(1, round(problem.t_end / dt))
    if simulate is not None:
        traj = simulate(
            problem.moments,
            problem.omega0,
            problem.t_end,
            dt,
            method,
            problem.q0,
            problem.torque,
            save_every=n_steps,
            **options,
        )
        return np.asarray(traj.q[-1]), np.asarray(traj.omega[-1])
    from rigid_rot_sim.core.integrators import get_method

    integrator = get_method(method)(
        problem.moments, problem.t_end / n_steps, problem.torque, q0=problem.q0, omega0=problem.omega0, **options
    )
    advance = getattr(integrator, "advance", None)
    if advance is not None:
        advance(n_steps)
    else:
        for _ in range(n_steps):
            integrator.step()
    return np.asarray(integrator.q), np.asarray(integrator.omega)


def measure_point(problem: Problem, line: Line, value: float, repeats: int, baseline: bool = False) -> Point:
    """Run one sweep point and compare its final state with the problem's reference.

    ``baseline``: also time scipy's BASELINE_METHOD at BASELINE_TOL on the same problem,
    right before the point, into ``point.baseline_seconds``.
    """
    run, parameter = _runner(problem, line, value)
    point = Point(line.label, line.family, line.method, parameter, float(value), "ok")
    if baseline:
        base_run, _ = _runner(problem, Line("scipy baseline", "scipy", BASELINE_METHOD, (), "tol"), BASELINE_TOL)
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


def sweep_values(problem: Problem, line: Line, settings: Settings) -> list[float]:
    """The sweep parameter values of a line, coarse to fine."""
    if line.sweep == "single":
        return [problem.t_end]
    if line.sweep == "tol":
        return list(settings.tolerances)
    spin = float(np.linalg.norm(problem.omega0))
    n0 = max(4, math.ceil(problem.t_end * spin / 0.5))
    return [problem.t_end / (n0 * settings.step_factor**k) for k in range(settings.max_step_points)]


def run_problem(problem: Problem, settings: Settings, progress: Any = None) -> ProblemResult:
    """Every line's sweep on one problem."""
    ref = problem.reference()
    result = ProblemResult(problem.key, problem.title, problem.t_end, ref.method, ref.certified_to)
    for line in problem_lines(problem, settings):
        result.points += run_line(problem, line, settings, progress)
    return result


def problem_lines(problem: Problem, settings: Settings) -> list[Line]:
    """The lines of one problem's diagram: ours, then scipy's."""
    from rigid_rot_sim.core.integrators import METHODS

    methods = settings.methods if settings.methods is not None else tuple(METHODS)
    return our_lines(methods, problem) + scipy_lines(settings.scipy_methods)


def run_line(problem: Problem, line: Line, settings: Settings, progress: Any = None, baseline: bool = False) -> list[Point]:
    """One line's sweep, coarse to fine, until a point exceeds the time budget or the error floor.

    ``baseline``: time every point together with the scipy baseline (see measure_point).
    """
    floor = max(ERROR_FLOOR, problem.reference().certified_to)
    values = sweep_values(problem, line, settings)
    points = []
    refusals = 0
    for k, value in enumerate(values):
        if progress is not None:
            progress.set_postfix_str(f"{problem.key} {line.label}", refresh=False)
        point = measure_point(problem, line, value, settings.repeats, baseline)
        points.append(point)
        if progress is not None:
            progress.update(1)
        refusals = refusals + 1 if point.status == "refused" else 0
        # a fixed-step run costs in proportion to its steps: skip a next point that
        # would take more than twice the budget
        predicted = point.seconds * (value / values[k + 1]) if line.sweep == "step" and k + 1 < len(values) else 0.0
        stop = refusals >= 2 or (
            point.status == "ok"
            and (
                point.seconds > settings.budget_seconds
                or predicted > 2.0 * settings.budget_seconds
                or point.omega_error < floor
            )
        )
        if stop:
            if progress is not None:
                progress.update(len(values) - k - 1)
            break
    return points


def line_task(problem_key: str, line: Line, settings: Settings) -> list[Point]:
    """A Dask task: one line of one problem, each point timed with the scipy baseline on this worker."""
    from rigid_rot_sim.analysis.problems import get_problem

    return run_line(get_problem(problem_key), line, settings, baseline=True)


def planned_points(problems: Iterable[Problem], settings: Settings) -> int:
    """Upper bound on the number of points (for the progress bar)."""
    from rigid_rot_sim.core.integrators import METHODS

    methods = settings.methods if settings.methods is not None else tuple(METHODS)
    return sum(
        len(sweep_values(p, line, settings))
        for p in problems
        for line in our_lines(methods, p) + scipy_lines(settings.scipy_methods)
    )


def cost(point: Point) -> float:
    """A point's run time in units of its scipy baseline when it has one (cluster runs), else in s."""
    return point.seconds / point.baseline_seconds if point.baseline_seconds > 0.0 else point.seconds


def fastest_at(points: Iterable[Point], target: float, family: str) -> Point | None:
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


def errors_fall_with_step(points: Iterable[Point], label: str, floor: float = 1e-12) -> bool:
    """True if the omega error of a fixed-step line falls from its coarsest to its finest stable point.

    Points below ``floor`` (round-off and reference accuracy) are left out.
    """
    ok = [p for p in points if p.label == label and p.status == "ok" and p.parameter == "dt"]
    ok.sort(key=lambda p: -p.value)
    errs = [p.omega_error for p in ok if p.omega_error > floor]
    return len(errs) >= 2 and errs[-1] < errs[0]


def machine_info() -> dict[str, Any]:
    """Machine, interpreter, library versions and the git commit, for results.json."""
    import matplotlib
    import scipy

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "HEAD"],
            cwd=os.path.dirname(os.path.abspath(__file__)),
            capture_output=True,
            text=True,
            timeout=5,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        commit = ""
    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:
        affinity = os.cpu_count()
    return {
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "cpus_available": affinity,
        "platform": platform.platform(),
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "matplotlib": matplotlib.__version__,
        "git_commit": commit,
    }


def _fmt(value: float | None, spec: str = ".3g") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    return format(value, spec)


def _summary_markdown(results: list[ProblemResult]) -> list[str]:
    lines = [
        "| problem | target ω error [rad/s] | fastest of ours | its run time [s] | its ω error | "
        "fastest scipy | its run time [s] | speed-up (scipy time / ours) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for result in results:
        for row in summary(result):
            ours, theirs = row["ours"], row["scipy"]
            ours_label = "not reached" if ours is None else f"{ours['label']} ({ours['parameter']}={ours['value']:.3g})"
            theirs_label = (
                "not reached" if theirs is None else f"{theirs['label']} ({theirs['parameter']}={theirs['value']:.3g})"
            )
            lines.append(
                f"| {result.problem} | {row['target']:g} | {ours_label} | {_fmt(ours and ours['seconds'], '.3e')} | "
                f"{_fmt(ours and ours['omega_error'], '.2e')} | {theirs_label} | "
                f"{_fmt(theirs and theirs['seconds'], '.3e')} | {_fmt(row['speedup'], '.1f')}{'×' if row['speedup'] else ''} |"
            )
    return lines


def _points_markdown(result: ProblemResult) -> list[str]:
    lines = [
        "| method | parameter | status | run time [s] | ω error [rad/s] | attitude error [rad] | "
        "rel. energy error | rel. \\|L\\| error | steps / rhs evals |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for p in result.points:
        status = p.status if p.status == "ok" else f"{p.status}: {p.message[:80]}"
        lines.append(
            f"| {p.label} | {p.parameter}={p.value:.3g} | {status} | {_fmt(p.seconds, '.3e')} | "
            f"{_fmt(p.omega_error, '.2e')} | {_fmt(p.attitude_error, '.2e')} | {_fmt(p.energy_drift, '.2e')} | "
            f"{_fmt(p.momentum_drift, '.2e')} | {p.n_steps or '–'} |"
        )
    return lines


def write_outputs(
    out_dir: str | os.PathLike[str],
    results: list[ProblemResult],
    settings: Settings,
    problems: dict[str, Problem],
    command: str,
    elapsed: float,
) -> dict[str, str]:
    """Write report.md, results.json and one PNG per problem into ``out_dir``; returns their paths."""
    import json
    from pathlib import Path

    from rigid_rot_sim.analysis.plotting import work_precision_plot

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    machine = machine_info()
    paths: dict[str, str] = {}
    for result in results:
        problem = problems[result.problem]
        png = work_precision_plot(
            result.points,
            f"{result.problem}: {problem.title}, T = {problem.t_end:g} s",
            out / f"{result.problem}.png",
        )
        paths[result.problem] = str(png)
    payload = {
        "command": command,
        "elapsed_seconds": elapsed,
        "machine": machine,
        "settings": {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(settings).items()},
        "timing": "best of `repeats` runs (2 if the first run takes > 1 s), set-up included, gc off",
        "fastest_rule": "cheapest measured point with omega error <= target (no interpolation)",
        "problems": [
            {
                "key": r.problem,
                "title": r.title,
                "principal_moments": list(problems[r.problem].principal_moments),
                "omega0": list(problems[r.problem].omega0),
                "t_end": r.t_end,
                "torque_kind": problems[r.problem].torque_kind,
                "reference": r.reference,
                "reference_error": r.reference_error,
                "points": [asdict(p) for p in r.points],
                "summary": summary(r),
            }
            for r in results
        ],
    }
    json_path = out / "results.json"
    json_path.write_text(json.dumps(payload, indent=1, default=float, allow_nan=True), encoding="utf-8")
    paths["results.json"] = str(json_path)

    md = [
        "# Work-precision report",
        "",
        f"Command: `{command}` ({'quick mode' if settings.quick else 'full run'}, {elapsed:.0f} s).  ",
        f"Machine: {machine['cpu']}, {machine['cpus_available']} CPUs available; Python {machine['python']}, "
        f"numpy {machine['numpy']}, scipy {machine['scipy']}; commit `{machine['git_commit'][:10] or 'unknown'}`.",
        "",
        "Errors are at the final time against each problem's reference: ω max-norm (rad/s), the attitude angle "
        "2·atan2(|vec(Δq)|, |w(Δq)|) with Δq = q_ref⁻¹ ⊗ q (rad), and the relative errors of the total energy and "
        "of |L| against the reference's. Run time: best of "
        f"{settings.repeats} runs (2 when the first run takes over 1 s), set-up included "
        "(`simulate(...)` for ours; building the right-hand side, `solve_ivp` and normalising q for scipy), "
        "garbage collector off, every method alike. Adaptive methods sweep rtol = atol; fixed-step methods sweep dt. "
        "**Fastest at a target** = the cheapest measured sweep point whose ω error is at or below the target "
        "(no interpolation between points, so a run time is an upper bound).",
        *(
            [
                "",
                f"Run on a Dask cluster: every point was timed together with scipy {BASELINE_METHOD} at rtol = atol = "
                f"{BASELINE_TOL:g} in the same task on the same worker; the fastest method and the speed-up compare "
                "run times as multiples of that baseline (`baseline_seconds` in results.json), so points measured on "
                "different machines stay comparable.",
            ]
            if any(p.baseline_seconds > 0.0 for r in results for p in r.points)
            else []
        ),
        "",
        "## Summary",
        "",
        *_summary_markdown(results),
        "",
    ]
    for result in results:
        problem = problems[result.problem]
        md += [
            f"## {result.problem}: {problem.title}",
            "",
            f"I = diag{tuple(problem.principal_moments)} kg·m², ω0 = {tuple(problem.omega0)} rad/s, "
            f"T = {problem.t_end:g} s, torque: {problem.torque_kind}. Reference: {result.reference}.",
            "",
            f"![{result.problem}]({result.problem}.png)",
            "",
            *_points_markdown(result),
            "",
        ]
    md_path = out / "report.md"
    md_path.write_text("\n".join(md), encoding="utf-8")
    paths["report.md"] = str(md_path)
    return paths


def run_report(
    out_dir: str | os.PathLike[str],
    quick: bool = False,
    problem_keys: Sequence[str] | None = None,
    settings: Settings | None = None,
    command: str = "rigid-rot report",
    progress: bool = True,
    scheduler: str | None = None,
    workers: int | None = None,
) -> tuple[list[ProblemResult], dict[str, str]]:
    """Run the sweeps on the problems (all by default) and write the outputs.

    With ``scheduler`` or ``workers`` (or DASK_SCHEDULER_ADDRESS) every line of every
    problem is one Dask task (:func:`line_task`), each point timed with the scipy baseline
    in that task; fastest methods and speed-ups then compare run times in baseline units.
    """
    from tqdm import tqdm

    from rigid_rot_sim.analysis.engine import map_tasks, open_client, wants_cluster
    from rigid_rot_sim.analysis.problems import PROBLEMS, get_problem

    if settings is None:
        settings = Settings.quick_mode() if quick else Settings()
    keys = list(problem_keys) if problem_keys is not None else list(PROBLEMS)
    problems = {key: get_problem(key) for key in keys}
    start = time.perf_counter()
    results = []
    with tqdm(
        total=planned_points(problems.values(), settings), desc="work-precision", unit="run", disable=not progress
    ) as bar:
        if not wants_cluster(scheduler, workers):
            for key in keys:
                bar.set_postfix_str(f"{key} reference", refresh=True)
                problems[key].reference()
                results.append(run_problem(problems[key], settings, bar))
        else:
            tasks = [(key, line, settings) for key in keys for line in problem_lines(problems[key], settings)]

            def done(index: int, points: list[Point]) -> None:
                key, line, _ = tasks[index]
                bar.set_postfix_str(f"{key} {line.label}", refresh=False)
                bar.update(len(sweep_values(problems[key], line, settings)))

            with open_client(scheduler, workers) as client:
                lines_points = map_tasks(client, [(line_task, args) for args in tasks], done)
            for key in keys:
                ref = problems[key].reference()
                result = ProblemResult(key, problems[key].title, problems[key].t_end, ref.method, ref.certified_to)
                for (task_key, _, _), points in zip(tasks, lines_points):
                    if task_key == key:
                        result.points += points
                results.append(result)
    paths = write_outputs(out_dir, results, settings, problems, command, time.perf_counter() - start)
    return results, paths
