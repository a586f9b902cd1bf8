"""``rigid-rot report``: run the work-precision sweeps and write report.md, results.json and the plots.

The measurements are :mod:`rigid_rot_sim.analysis.workprecision`'s; this module runs them
on the problems of :mod:`rigid_rot_sim.analysis.problems` (here or on a Dask cluster) and
writes what they found.
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path

from tqdm import tqdm

from rigid_rot_sim.analysis.plot import work_precision_plot
from rigid_rot_sim.analysis.problems import PROBLEMS, Problem, get_problem
from rigid_rot_sim.analysis.report_io import machine_info, machine_line, markdown_table, number, write_json
from rigid_rot_sim.analysis.workprecision import (
    BASELINE_METHOD,
    BASELINE_TOL,
    ProblemResult,
    Settings,
    planned_points,
    run_problems,
    summary,
)
from rigid_rot_sim.cluster import wants_cluster


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
    problem is one Dask task, each point timed with the scipy baseline in that task;
    fastest methods and speed-ups then compare run times in baseline units.
    """
    if settings is None:
        settings = Settings.quick_mode() if quick else Settings()
    keys = list(problem_keys) if problem_keys is not None else list(PROBLEMS)
    problems = {key: get_problem(key) for key in keys}
    start = time.perf_counter()
    with tqdm(
        total=planned_points(problems.values(), settings), desc="work-precision", unit="run", disable=not progress
    ) as bar:
        results = run_problems(problems, settings, bar, scheduler, workers, cluster=wants_cluster(scheduler, workers))
    paths = write_outputs(out_dir, results, settings, problems, command, time.perf_counter() - start)
    return results, paths


def write_outputs(
    out_dir: str | os.PathLike[str],
    results: list[ProblemResult],
    settings: Settings,
    problems: dict[str, Problem],
    command: str,
    elapsed: float,
) -> dict[str, str]:
    """Write report.md, results.json and one PNG per problem into ``out_dir``; returns their paths."""
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
    paths["results.json"] = str(write_json(out / "results.json", payload))
    md_path = out / "report.md"
    md_path.write_text("\n".join(_markdown(results, settings, problems, command, elapsed, machine)), encoding="utf-8")
    paths["report.md"] = str(md_path)
    return paths


def _markdown(
    results: list[ProblemResult],
    settings: Settings,
    problems: dict[str, Problem],
    command: str,
    elapsed: float,
    machine: dict[str, str],
) -> list[str]:
    md = [
        "# Work-precision report",
        "",
        f"Command: `{command}` ({'quick mode' if settings.quick else 'full run'}, {elapsed:.0f} s).  ",
        machine_line(machine),
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
        *_summary_table(results),
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
            *_points_table(result),
            "",
        ]
    return md


def _summary_table(results: list[ProblemResult]) -> list[str]:
    header = (
        "problem",
        "target ω error [rad/s]",
        "fastest of ours",
        "its run time [s]",
        "its ω error",
        "fastest scipy",
        "its run time [s]",
        "speed-up (scipy time / ours)",
    )
    rows = []
    for result in results:
        for row in summary(result):
            ours, theirs = row["ours"], row["scipy"]
            rows.append(
                (
                    result.problem,
                    f"{row['target']:g}",
                    _point_label(ours),
                    number(ours and ours["seconds"], ".3e"),
                    number(ours and ours["omega_error"], ".2e"),
                    _point_label(theirs),
                    number(theirs and theirs["seconds"], ".3e"),
                    number(row["speedup"], ".1f") + ("×" if row["speedup"] else ""),
                )
            )
    return markdown_table(header, rows)


def _point_label(point: dict | None) -> str:
    return "not reached" if point is None else f"{point['label']} ({point['parameter']}={point['value']:.3g})"


def _points_table(result: ProblemResult) -> list[str]:
    header = (
        "method",
        "parameter",
        "status",
        "run time [s]",
        "ω error [rad/s]",
        "attitude error [rad]",
        "rel. energy error",
        "rel. \\|L\\| error",
        "steps / rhs evals",
    )
    rows = (
        (
            p.label,
            f"{p.parameter}={p.value:.3g}",
            p.status if p.status == "ok" else f"{p.status}: {p.message[:80]}",
            number(p.seconds, ".3e"),
            number(p.omega_error, ".2e"),
            number(p.attitude_error, ".2e"),
            number(p.energy_drift, ".2e"),
            number(p.momentum_drift, ".2e"),
            p.n_steps or "–",
        )
        for p in result.points
    )
    return markdown_table(header, rows)
