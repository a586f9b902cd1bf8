"""``rigid-rot stability``: run the whole suite and write stability.md, stability.json and the plots.

The cases are :mod:`rigid_rot_sim.analysis.stability_cases`'; running them, the
bisection and the long horizon are :mod:`rigid_rot_sim.analysis.stability`'s.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from tqdm import tqdm

from rigid_rot_sim.analysis.plot import long_horizon_plot, stability_plot
from rigid_rot_sim.analysis.report_io import machine_info, machine_line, markdown_table, number, write_json
from rigid_rot_sim.analysis.stability import (
    BISECTION_GROWTH,
    BISECTION_STEPS,
    LONG_HORIZON_METHODS,
    MethodVariant,
    method_labels,
    run_all,
)
from rigid_rot_sim.analysis.stability_cases import catalogue


def run_suite(
    out_dir: Any,
    quick: bool = False,
    long_steps: int | None = None,
    long_methods: tuple[str | MethodVariant, ...] = LONG_HORIZON_METHODS,
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
    with tqdm(total=total, desc="stability", unit="run", disable=not progress) as bar:
        case_runs, bisection, horizon = run_all(
            cases, methods, long_methods, long_steps, quick, bar, scheduler, workers
        )
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
    payload = {
        "command": command,
        "quick": quick,
        "elapsed_seconds": time.perf_counter() - start,
        "machine": machine_info(),
        "methods": methods,
        "cases": case_rows,
        "bisection": {"steps": BISECTION_STEPS // (4 if quick else 1), "growth": BISECTION_GROWTH, "rows": bisection},
        "long_horizon": horizon,
    }
    write_outputs(out_dir, payload)
    return payload


def write_outputs(out_dir: Any, payload: dict[str, Any]) -> None:
    """Write stability.json, stability.png, long_horizon.png and stability.md of a suite's ``payload``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "stability.json", payload)
    stability_plot(payload["cases"], payload["methods"], out / "stability.png")
    long_horizon_plot(payload["long_horizon"], out / "long_horizon.png")
    (out / "stability.md").write_text(_markdown(payload), encoding="utf-8")


def _verdict(run: dict[str, Any]) -> str:
    if run["passed"]:
        return "pass"
    return {"unstable": "**unstable**", "refused": "refused"}.get(run["status"], "fail")


def _markdown(payload: dict[str, Any]) -> str:
    methods = payload["methods"]
    bis = payload["bisection"]
    md = [
        "# Stability suite",
        "",
        f"Command: `{payload['command']}` ({'quick mode' if payload['quick'] else 'full run'}, "
        f"{payload['elapsed_seconds']:.0f} s). " + machine_line(payload["machine"]),
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
        *markdown_table(
            ("case", *methods),
            ((case["name"], *(_verdict(case["runs"][m]) for m in methods)) for case in payload["cases"]),
        ),
        "",
        "## Largest stable step of the explicit methods (bisection)",
        "",
        f"Stable = {bis['steps']} steps without non-finite values and with energy and |L| grown by at most "
        f"{bis['growth']:.0%}. Advice: `run.advice.practical_step_limit`: 2√2 / ν for rk4 and lie_rk4 from linear "
        "theory (ν the linearised gyroscopic frequency bound |ω|·max_i sqrt(|(Ii−Ij)(Ii−Ik)|/(Ij Ik))); for "
        "implicit_midpoint (Newton solve) 4 / ν and for splitting 2 rad / |ω|, both measured by this bisection. "
        "Explicit Euler has no stable step in theory (growth factor sqrt(1 + (ν dt)²) per step), so its bisected "
        f"step is only the step whose growth stays under {bis['growth']:.0%} over {bis['steps']} steps.",
        "",
        *markdown_table(
            ("case", "method", "largest stable dt [s]", "advice dt [s]", "measured / advice"),
            (
                (
                    row["case"],
                    row["method"],
                    number(row["largest_stable_dt"], ".4g"),
                    number(row["theory_dt"], ".4g"),
                    number(row["ratio"], ".3f"),
                )
                for row in bis["rows"]
            ),
        ),
        "",
        "## Long horizon: bounded or secular energy drift",
        "",
        "P1's body (I = diag(1, 2, 3) kg·m², ω0 = (1, 0.1, 0.5) rad/s), dt = 10 ms. Secular = the mean relative "
        "energy error over the last tenth exceeds twice its maximum over the first tenth and 1e-11 (round-off).",
        "",
        "![long horizon](long_horizon.png)",
        "",
        *markdown_table(
            (
                "method",
                "steps",
                "run time [s]",
                "max error, first tenth",
                "mean error, last tenth",
                "final error",
                "verdict",
            ),
            (
                (
                    row["method"],
                    f"{row['steps']:.0e}",
                    f"{row['seconds']:.1f}",
                    number(row["first_tenth_max"], ".2g"),
                    number(row["last_tenth_mean"], ".2g"),
                    number(row["final"], ".2g"),
                    row["status"] if row["status"] != "stable" else ("**secular**" if row["secular"] else "bounded"),
                )
                for row in payload["long_horizon"]
            ),
        ),
        "",
        "## Cases in detail",
        "",
    ]
    for case in payload["cases"]:
        md += [
            f"### {case['name']}",
            "",
            f"{case['description']}; {case['steps']} steps. Criterion: {case['criterion']}. "
            f"Reference: {case['reference'] or 'none'}.",
            "",
            *markdown_table(
                (
                    "method",
                    "status",
                    "pass",
                    "energy drift",
                    "momentum drift",
                    "\\| \\|q\\|−1 \\|",
                    "ω error [rad/s]",
                    "attitude error [rad]",
                    "run time [s]",
                    "note",
                ),
                (_run_cells(method, case["runs"][method]) for method in methods),
            ),
            "",
        ]
    return "\n".join(md)


def _run_cells(method: str, run: dict[str, Any]) -> tuple[str, ...]:
    return (
        method,
        run["status"],
        "yes" if run["passed"] else "no",
        number(run["energy_drift"], ".2g"),
        number(run["momentum_drift"], ".2g"),
        number(run["quaternion_norm_error"], ".2g"),
        number(run["omega_error"], ".2g"),
        number(run["attitude_error"], ".2g"),
        number(run["seconds"], ".3f"),
        run["message"][:160],
    )
