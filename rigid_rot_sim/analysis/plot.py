"""Figures of the work-precision report and the stability suite (matplotlib, Agg backend).

Each function writes one PNG and returns its path; nothing is shown on screen.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt

#: Errors below this (exact to round-off) are drawn at it, so that they stay on a log axis.
ERROR_CLIP = 1e-16

#: Distinct line styles: ours solid, scipy dashed.
_MARKERS = "os^vD<>pPhX*"


def work_precision_plot(
    points: Iterable[Any],
    title: str,
    path: str | Path,
    targets: Sequence[float] = (1e-6, 1e-10),
) -> Path:
    """Omega error at the final time (rad/s) against run time (s), log-log, a line per method.

    ``points`` are :class:`rigid_rot_sim.analysis.workprecision.SweepPoint` (or dicts with the
    same keys); only finished runs ("ok") are drawn.
    """
    rows = [p if isinstance(p, dict) else vars(p) for p in points]
    labels: list[str] = []
    for row in rows:
        if row["label"] not in labels:
            labels.append(row["label"])
    fig, ax = plt.subplots(figsize=(11, 6.5), dpi=110)
    cmap = plt.get_cmap("tab20")
    for k, label in enumerate(labels):
        # sweep order (coarse to fine), so each line follows its sweep even where timing is noisy
        line = [r for r in rows if r["label"] == label and r["status"] == "ok" and math.isfinite(r["seconds"])]
        if not line:
            continue
        scipy = line[0]["family"] == "scipy"
        ax.loglog(
            [r["seconds"] for r in line],
            [max(r["omega_error"], ERROR_CLIP) for r in line],
            linestyle="--" if scipy else "-",
            marker=_MARKERS[k % len(_MARKERS)],
            markersize=4,
            linewidth=1.4,
            color="black" if scipy and "DOP853" in label else cmap(k % 20),
            label=label,
        )
    for target in targets:
        ax.axhline(target, color="grey", linestyle=":", linewidth=0.8)
        ax.annotate(
            f"target {target:g}",
            xy=(1.0, target),
            xycoords=("axes fraction", "data"),
            ha="right",
            va="bottom",
            fontsize=8,
            color="grey",
        )
    ax.set_xlabel("run time, best of repeats [s]")
    ax.set_ylabel(f"ω error at final time, max-norm [rad/s] (values < {ERROR_CLIP:g} drawn at it)")
    ax.set_title(title)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(
        fontsize=8,
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        title="solid: ours\ndashed: scipy solve_ivp",
        title_fontsize=8,
    )
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path


def stability_plot(cases: Sequence[dict[str, Any]], methods: Sequence[str], path: str | Path) -> Path:
    """Heat map: max relative energy drift per case (rows) and method (columns).

    Cells are coloured by log10 of the drift; unstable runs are marked 'X' and
    refusals 'R' (not coloured).
    """
    grid = np.full((len(cases), len(methods)), np.nan)
    marks: dict[tuple[int, int], str] = {}
    for i, case in enumerate(cases):
        for j, method in enumerate(methods):
            run = case["runs"].get(method)
            if run is None:
                marks[(i, j)] = "–"
                continue
            if run["status"] == "unstable":
                marks[(i, j)] = "X"
            elif run["status"] == "refused":
                marks[(i, j)] = "R"
            else:
                drift = run.get("energy_drift", math.nan)
                grid[i, j] = math.log10(max(drift, 1e-17)) if math.isfinite(drift) else np.nan
                if not run.get("passed", True):
                    marks[(i, j)] = "✗"
    fig, ax = plt.subplots(figsize=(1.1 * len(methods) + 4, 0.42 * len(cases) + 2.2), dpi=110)
    image = ax.imshow(grid, cmap="viridis", vmin=-16, vmax=0, aspect="auto")
    for (i, j), mark in marks.items():
        ax.text(j, i, mark, ha="center", va="center", color="red" if mark in "X✗" else "black", fontsize=10)
    ax.set_xticks(range(len(methods)), labels=methods, rotation=40, ha="right", fontsize=8)
    ax.set_yticks(range(len(cases)), labels=[c["name"] for c in cases], fontsize=8)
    colorbar = fig.colorbar(image, ax=ax)
    colorbar.set_label("log10 max relative energy drift [-]")
    ax.set_title("Stability suite: max relative energy drift (X unstable, R refused, ✗ failed criterion)")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path


def long_horizon_plot(rows: Sequence[dict[str, Any]], path: str | Path) -> Path:
    """Bar chart: relative energy error over the first and the last tenth of the long run, per method."""
    fig, ax = plt.subplots(figsize=(9, 5), dpi=110)
    labels = [r["method"] for r in rows]
    x = np.arange(len(rows))
    first = [max(r["first_tenth_max"], 1e-17) if math.isfinite(r["first_tenth_max"]) else np.nan for r in rows]
    last = [max(r["last_tenth_mean"], 1e-17) if math.isfinite(r["last_tenth_mean"]) else np.nan for r in rows]
    ax.bar(x - 0.2, first, 0.4, label="max over the first tenth")
    ax.bar(x + 0.2, last, 0.4, label="mean over the last tenth")
    ax.set_yscale("log")
    ax.set_xticks(
        x,
        labels=[f"{m}\n({'secular' if r['secular'] else 'bounded'})" for m, r in zip(labels, rows, strict=True)],
        fontsize=8,
    )
    steps = rows[0]["steps"] if rows else 0
    ax.set_ylabel("relative energy error |E − E0| / E0 [-]")
    ax.set_title(f"Long horizon: {steps:.0e} steps of dt = {rows[0]['dt'] if rows else 0:g} s on P1's body")
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path
