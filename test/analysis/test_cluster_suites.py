"""`rigid-rot report` and `rigid-rot stability` on a Dask cluster: the same tables as a local run.

Run times differ between runs; everything else (which lines and points, errors, drifts,
verdicts, bisected steps) must be the same whether the work ran here or on workers.
"""

import json
import math

import pytest

from rigid_rot_sim.analysis import workprecision as wp
from rigid_rot_sim.analysis.stability_report import run_suite
from rigid_rot_sim.analysis.workprecision_report import run_report

TINY = dict(
    repeats=1,
    budget_seconds=0.03,
    max_step_points=3,
    tolerances=(1e-3, 1e-6),
    methods=("rk4", "implicit_midpoint", "exact"),
    scipy_methods=("RK45", "DOP853"),
)
TIMES = {"seconds", "baseline_seconds", "repeats"}


@pytest.fixture(scope="module")
def cluster():
    """A local dask.distributed cluster of two single-thread worker processes, reached by address."""
    from distributed import LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address="127.0.0.1:0")
    try:
        yield cluster.scheduler_address
    finally:
        cluster.close()


def without_times(row):
    """The row without its run times, as JSON text (so that NaN equals NaN)."""
    return json.dumps({k: v for k, v in row.items() if k not in TIMES}, sort_keys=True)


def test_report_on_a_cluster_times_every_point_with_its_scipy_baseline(tmp_path, cluster):
    settings = wp.Settings.quick_mode(**TINY)
    here, _ = run_report(tmp_path / "here", problem_keys=["P1"], settings=settings, progress=False)
    there, paths = run_report(
        tmp_path / "there", problem_keys=["P1"], settings=settings, progress=False, scheduler=cluster
    )
    here_points, there_points = here[0].points, there[0].points
    assert {p.label for p in here_points} == {p.label for p in there_points}
    # the time budget may stop a line one point earlier or later; the points both ran agree exactly
    by_key = {(p.label, p.value): p for p in here_points}
    common = [(by_key[(p.label, p.value)], p) for p in there_points if (p.label, p.value) in by_key]
    assert len(common) >= len(here_points) // 2
    for a, b in common:
        assert (a.status, a.omega_error, a.attitude_error, a.n_steps) == (
            b.status,
            b.omega_error,
            b.attitude_error,
            b.n_steps,
        ) or (math.isnan(a.omega_error) and math.isnan(b.omega_error) and a.status == b.status)
    assert all(p.baseline_seconds > 0 for p in there_points if p.status == "ok")
    assert all(math.isnan(p.baseline_seconds) for p in here_points)
    # the same results table shape
    here_json = json.loads((tmp_path / "here" / "results.json").read_text())
    there_json = json.loads((tmp_path / "there" / "results.json").read_text())
    assert here_json.keys() == there_json.keys()
    assert here_json["problems"][0].keys() == there_json["problems"][0].keys()
    assert here_json["problems"][0]["points"][0].keys() == there_json["problems"][0]["points"][0].keys()
    assert "timed together with scipy DOP853" in (tmp_path / "there" / "report.md").read_text()
    # speed-ups compare run times in units of the baseline measured next to each point
    for row in wp.summary(there[0]):
        if row["speedup"]:
            ours, theirs = row["ours"], row["scipy"]
            expected = (theirs["seconds"] / theirs["baseline_seconds"]) / (ours["seconds"] / ours["baseline_seconds"])
            assert row["speedup"] == pytest.approx(expected)


def test_stability_suite_on_a_cluster_matches_a_local_run(tmp_path, cluster):
    kwargs = dict(
        quick=True,
        long_steps=2000,
        long_methods=("rk4", "implicit_midpoint"),
        case_names=["symmetric", "high spin 10 rad/step"],
        methods=["rk4", "implicit_midpoint", "splitting"],
        progress=False,
    )
    here = run_suite(tmp_path / "here", **kwargs)
    there = run_suite(tmp_path / "there", scheduler=cluster, **kwargs)
    assert [c["name"] for c in here["cases"]] == [c["name"] for c in there["cases"]]
    for a, b in zip(here["cases"], there["cases"], strict=True):
        assert {m: without_times(r) for m, r in a["runs"].items()} == {
            m: without_times(r) for m, r in b["runs"].items()
        }
    assert json.dumps(here["bisection"]) == json.dumps(there["bisection"])
    assert [without_times(r) for r in here["long_horizon"]] == [without_times(r) for r in there["long_horizon"]]
    assert (tmp_path / "there" / "stability.png").stat().st_size > 1000
