"""The work-precision report: structure of its outputs and the physics of its numbers.

Runs a cut-down quick mode (two problems, short budgets); timings are never asserted.
"""

import json
import math

import pytest

from rigid_rot_sim.analysis import workprecision as wp
from rigid_rot_sim.analysis.workprecision_report import run_report
from rigid_rot_sim.cli import main
from rigid_rot_sim.core.integrators import METHODS

TINY = dict(repeats=1, budget_seconds=0.03, max_step_points=4, tolerances=(1e-3, 1e-6, 1e-9))


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    settings = wp.Settings.quick_mode(**TINY)
    results, paths = run_report(out, problem_keys=["P1", "P2"], settings=settings, progress=False)
    return out, {r.problem: r for r in results}, paths


def test_outputs_exist_and_are_readable(report):
    out, results, paths = report
    for name in ("report.md", "results.json", "P1.png", "P2.png"):
        path = out / name
        assert path.is_file() and path.stat().st_size > 1000, name
    assert (out / "P1.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    data = json.loads((out / "results.json").read_text())
    assert {"cpu", "python", "numpy", "scipy", "matplotlib"} <= set(data["machine"])
    assert [p["key"] for p in data["problems"]] == ["P1", "P2"]
    for problem in data["problems"]:
        assert [row["target"] for row in problem["summary"]] == list(wp.TARGETS)
        for point in problem["points"]:
            assert point["status"] in ("ok", "unstable", "refused")
            if point["status"] == "ok":
                assert point["seconds"] > 0 and math.isfinite(point["omega_error"])
            else:
                assert point["message"]  # a failure always says why


def test_every_method_and_scipy_baseline_appears(report):
    _, results, _ = report
    for result in results.values():
        methods = {p.method for p in result.points if p.family == "ours"}
        assert methods == set(METHODS)
        assert {p.method for p in result.points if p.family == "scipy"} == set(wp.SCIPY_METHODS)


def test_summary_table_in_markdown(report):
    out, _, _ = report
    text = (out / "report.md").read_text()
    assert "## Summary" in text and "![P1](P1.png)" in text
    for key in ("P1", "P2"):
        for target in ("1e-06", "1e-10"):
            assert f"| {key} | {target} |" in text


def test_fixed_step_errors_fall_as_step_shrinks(report):
    _, results, _ = report
    for result in results.values():
        labels = {p.label for p in result.points if p.parameter == "dt" and p.family == "ours"}
        for label in labels:
            ok = [p for p in result.points if p.label == label and p.status == "ok"]
            if len(ok) < 2 or min(p.omega_error for p in ok) < 1e-12:
                continue  # a single point, or already at the reference's accuracy
            assert wp.errors_fall_with_step(result.points, label), (result.problem, label)


def test_scipy_errors_fall_with_tolerance(report):
    _, results, _ = report
    for result in results.values():
        for method in wp.SCIPY_METHODS:
            errs = [
                p.omega_error for p in result.points if p.method == method and p.family == "scipy" and p.status == "ok"
            ]
            # the quick sweep stops a slow method (Radau under load) after its first point
            assert errs, (result.problem, method)
            if len(errs) >= 2:
                assert errs[-1] < errs[0], (result.problem, method, errs)
    swept = [
        method
        for result in results.values()
        for method in wp.SCIPY_METHODS
        if sum(p.method == method and p.family == "scipy" and p.status == "ok" for p in result.points) >= 2
    ]
    assert swept, "no scipy method got two tolerance points"


def test_structure_preserving_methods_conserve_on_free_body(report):
    _, results, _ = report
    for p in results["P1"].points:
        if p.status != "ok":
            continue
        if p.method in ("implicit_midpoint", "exact"):
            assert p.energy_drift < 1e-12 and p.momentum_drift < 1e-12, p
        if p.method == "splitting":
            assert p.momentum_drift < 1e-12, p  # compositions of exact rotations keep |L|
        if p.method == "exact":
            assert p.omega_error < 1e-12 and p.attitude_error < 1e-11


def test_fastest_at_target_is_cheapest_point_meeting_it():
    pts = [
        wp.SweepPoint("a", "ours", "a", "dt", 0.1, "ok", seconds=1.0, omega_error=1e-7),
        wp.SweepPoint("b", "ours", "b", "dt", 0.1, "ok", seconds=0.5, omega_error=1e-5),
        wp.SweepPoint("c", "ours", "c", "dt", 0.1, "ok", seconds=2.0, omega_error=1e-11),
        wp.SweepPoint("s", "scipy", "s", "tol", 1e-8, "ok", seconds=4.0, omega_error=1e-7),
        wp.SweepPoint("u", "ours", "u", "dt", 1.0, "unstable", message="boom"),
    ]
    assert wp.fastest_at(pts, 1e-6, "ours").label == "a"
    assert wp.fastest_at(pts, 1e-10, "ours").label == "c"
    assert wp.fastest_at(pts, 1e-10, "scipy") is None
    result = wp.ProblemResult("X", "x", 1.0, "ref", 0.0, pts)
    rows = wp.summary(result, (1e-6,))
    assert rows[0]["speedup"] == pytest.approx(4.0)


def test_cli_quick_on_one_problem(tmp_path, capsys):
    code = main(["report", "--quick", "--out", str(tmp_path), "--problems", "P4", "--no-progress"])
    assert code == 0
    assert (tmp_path / "report.md").is_file() and (tmp_path / "P4.png").is_file()
    assert "P4 at ω error <= 1e-10 rad/s" in capsys.readouterr().out


def test_cli_rejects_unknown_problem(tmp_path, capsys):
    assert main(["report", "--out", str(tmp_path), "--problems", "P9", "--no-progress"]) == 2
    assert "P9" in capsys.readouterr().err


def _step_point(t_end, n, error):
    return wp.SweepPoint("m", "ours", "m", "dt", t_end / n, "ok", seconds=1e-3, omega_error=error, n_steps=n)


def test_step_line_jumps_to_the_step_count_its_order_predicts():
    line = wp.DiagramLine("m", "ours", "m", (), "step")
    t_end = 10.0
    values = [t_end / (100 * 2**k) for k in range(14)]
    # a 4th-order method: 100 -> 200 steps takes the error from 1.6e-3 to 1e-4
    points = [_step_point(t_end, 100, 1.6e-3), _step_point(t_end, 200, 1e-4)]
    assert wp.observed_order(points[0], points[1]) == pytest.approx(4.0)
    goal = min(wp.TARGETS)
    n_next = round(t_end / wp.next_value(line, t_end, points, values, goal))
    # aims at half the first target not met (1e-6): (1e-4 / 5e-7) ** (1/4) = 3.76 times the steps
    assert n_next == math.ceil(200 * (1e-4 / (wp.TARGET_MARGIN * 1e-6)) ** 0.25)
    points.append(_step_point(t_end, n_next, 4e-7))
    n_last = round(t_end / wp.next_value(line, t_end, points, values, goal))
    order = wp.observed_order(points[1], points[2])  # from the last two points
    assert n_last == math.ceil(n_next * (4e-7 / (wp.TARGET_MARGIN * 1e-10)) ** (1.0 / order))
    # never finer than the sweep's range, and stops at its end
    slow = [_step_point(t_end, 100, 1e-1), _step_point(t_end, 200, 9e-2)]  # order 0.15: a huge jump
    assert wp.next_value(line, t_end, slow, values, goal) == values[-1]
    assert wp.next_value(line, t_end, [_step_point(t_end, round(t_end / values[-1]), 1e-3)], values, goal) is None


def test_tolerance_line_walks_its_list_and_unstable_points_step_on():
    tol_line = wp.DiagramLine("s", "scipy", "RK45", (), "tol")
    values = [1e-3, 1e-4, 1e-5]
    points = [wp.SweepPoint("s", "scipy", "RK45", "tol", v, "ok", seconds=1e-3, omega_error=v * 10) for v in values[:2]]
    assert wp.next_value(tol_line, 1.0, points, values, 1e-10) == 1e-5
    step_line = wp.DiagramLine("m", "ours", "m", (), "step")
    unstable = [wp.SweepPoint("m", "ours", "m", "dt", 0.5, "unstable", message="boom")]
    assert wp.next_value(step_line, 10.0, unstable, [0.5, 0.25, 0.125], 1e-10) == 0.25
