"""What a sweep writes: one Parquet file of all runs, a markdown summary and plots.

* ``<name>.parquet``: one row per run (inputs and metrics as columns, :data:`COLUMNS`);
  the schema metadata key ``rigid_rot_sim.sweep`` holds JSON with the spec (text and
  file), the base scene's text, the seed, the grid, the column descriptions and the
  versions of everything that decides the numbers. Nothing in it depends on how the
  sweep ran (workers, chunks, times), so the same spec gives the same file anywhere.
* ``summary.md``: counts per verdict, percentiles of every metric (per grid point for
  the chosen metric) and how the sweep ran (workers, chunk size, time).
* ``histogram.png`` (the chosen metric, one histogram per grid point), ``scatter.png``
  (each dispersed input against the chosen metric) and, for grids over dt or spin rate,
  ``map.png`` (per method: the share of stable runs and the median metric over the grid).
"""

from __future__ import annotations

import json
import math
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from rigid_rot_sim.recording.provenance import package_versions
from rigid_rot_sim.sweep.chunks import COLUMNS
from rigid_rot_sim.sweep.runner import SweepResult
from rigid_rot_sim.sweep.spec import METRICS

__all__ = [
    "to_table",
    "write_parquet",
    "summary_markdown",
    "write_plots",
    "write_outputs",
    "METADATA_KEY",
    "PERCENTILES",
]

METADATA_KEY = b"rigid_rot_sim.sweep"
PERCENTILES = (0, 5, 50, 95, 99, 100)
#: Input columns drawn against the metric when they vary.
INPUT_COLUMNS = (
    "I1",
    "I2",
    "I3",
    "misalignment",
    "omega0_x",
    "omega0_y",
    "omega0_z",
    "attitude0_error",
    "torque_scale_x",
    "torque_scale_y",
    "torque_scale_z",
    "torque_noise_rms",
    "orbit_phase",
    "epoch_offset",
    "spin_rate",
    "dt",
)
_SWEEP_DISTRIBUTIONS = ("dask", "distributed", "pyarrow", "matplotlib", "tqdm")


def _metadata(result: SweepResult) -> dict[str, Any]:
    spec = result.spec
    versions = package_versions()
    for name in _SWEEP_DISTRIBUTIONS:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return {
        "name": spec.name,
        "description": spec.description,
        "spec_file": Path(spec.source).name,
        "spec_text": spec.text,
        "quick": result.quick,
        "scene": spec.scene.name,
        "scene_text": spec.scene.text,
        "seed": spec.seed,
        "samples": spec.samples,
        "duration": spec.duration,
        "grid": [{"method": m, "dt": dt, "spin_rate": s} for m, dt, s in spec.grid],
        "seeding": "sample s draws from numpy SeedSequence(seed, spawn_key=(s, k)), one stream k per dispersion",
        "metric": spec.metric,
        "metrics": METRICS,
        "units": "SI; body frame of the scene; quaternions scalar-last, body -> world",
        "versions": versions,
    }


def to_table(result: SweepResult) -> Any:
    """The rows as a ``pyarrow.Table`` with the sweep's metadata."""
    import pyarrow as pa

    fields = [
        pa.field(name, pa.string() if kind == "string" else getattr(pa, kind)()) for name, kind in COLUMNS.items()
    ]
    schema = pa.schema(fields, metadata={METADATA_KEY: json.dumps(_metadata(result), sort_keys=True).encode()})
    return pa.table({name: result.columns[name] for name in COLUMNS}, schema=schema)


def write_parquet(result: SweepResult, path: str | Path) -> Path:
    import pyarrow.parquet as pq

    path = Path(path)
    pq.write_table(to_table(result), path)
    return path


def _percentile_row(label: str, values: np.ndarray) -> str:
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return f"| {label} | 0 |" + " – |" * len(PERCENTILES)
    cells = " | ".join(f"{v:.4g}" for v in np.percentile(finite, PERCENTILES))
    return f"| {label} | {finite.size} | {cells} |"


def _grid_label(method: str, dt: float, spin: float) -> str:
    return f"{method}, dt={dt:g}" + ("" if math.isnan(spin) else f", |ω0|={spin:g}")


def _grid_points(columns: dict[str, Any]) -> list[tuple[int, str]]:
    points = []
    seen = set()
    for k, g in enumerate(columns["grid_point"]):
        if int(g) not in seen:
            seen.add(int(g))
            points.append(
                (int(g), _grid_label(columns["method"][k], float(columns["dt"][k]), float(columns["spin_rate"][k])))
            )
    return points


def summary_markdown(result: SweepResult, files: dict[str, str] | None = None) -> str:
    """Counts per verdict, percentiles of the metrics, and how the sweep ran."""
    spec, columns, engine = result.spec, result.columns, result.engine
    n = len(columns["run"])
    verdicts = {v: columns["verdict"].count(v) for v in ("stable", "drifting", "unstable")}
    header = (
        "| metric | runs | "
        + " | ".join(f"p{p}" if 0 < p < 100 else ("min" if p == 0 else "max") for p in PERCENTILES)
        + " |"
    )
    rule = "|---|---:|" + "---:|" * len(PERCENTILES)
    field = spec.scene.magnetic_field is not None
    metrics = [
        m
        for m in METRICS
        if (m not in ("first_flip", "nutation_range") or m in spec.events)
        and (field or not m.startswith("final_field"))
    ]
    lines = [
        f"# Sweep {spec.name}" + (" (quick)" if result.quick else ""),
        "",
        spec.description,
        "",
        f"Base scene `{spec.scene.name}`, {spec.duration:g} s; seed {spec.seed}; {spec.samples} samples × "
        f"{len(spec.grid)} grid point(s) = {n} runs. "
        f"Verdicts: {verdicts['stable']} stable, {verdicts['drifting']} drifting, "
        f"{verdicts['unstable']} unstable (failed numerically: their rows carry the error).",
        "",
        "## All runs",
        "",
        header,
        rule,
        *(_percentile_row(m, np.asarray(columns[m], dtype=float)) for m in metrics),
        "",
        f"## {spec.metric} per grid point",
        "",
        header.replace("metric", "grid point"),
        rule,
    ]
    grid_point = np.asarray(columns["grid_point"])
    metric = np.asarray(columns[spec.metric], dtype=float)
    for g, label in _grid_points(columns):
        lines.append(_percentile_row(label, metric[grid_point == g]))
    errors = [(int(r), e) for r, e in zip(columns["run"], columns["error"], strict=True) if e]
    if errors:
        lines += ["", f"## Failed runs ({len(errors)}; first 5)", ""]
        lines += [f"- run {r}: {e}" for r, e in errors[:5]]
    if engine:
        where = "a local cluster" if engine.get("local_cluster") else f"the cluster at {engine.get('scheduler')}"
        lines += [
            "",
            "## Run",
            "",
            f"On {where}: {engine.get('workers')} worker(s), {engine.get('chunks')} tasks of up to "
            f"{engine.get('chunk_size')} bodies, {engine.get('elapsed_seconds', float('nan')):.1f} s"
            + (
                f"; batch step cost measured {engine['fixed_step_seconds'] * 1e6:.0f} µs + "
                f"{engine['per_body_step_seconds'] * 1e6:.2f} µs per body "
                f"(fixed part {engine['overhead_fraction']:.0%} of a step)"
                if "fixed_step_seconds" in engine
                else ""
            )
            + ".",
        ]
    if files:
        lines += ["", "Files: " + ", ".join(f"`{Path(p).name}`" for p in files.values()), ""]
    return "\n".join(lines) + "\n"


def write_plots(result: SweepResult, out: Path) -> dict[str, str]:
    """histogram.png, scatter.png and (grids over dt or spin) map.png; returns their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    spec = result.spec
    metric = np.asarray(result.columns[spec.metric], dtype=float)
    positive = metric[np.isfinite(metric) & (metric > 0)]
    log = positive.size > 1 and positive.max() / positive.min() > 100.0
    paths = {"histogram": str(_histogram(result, metric, positive, log, out / "histogram.png", plt))}
    scatter = _scatter(result, metric, log, out / "scatter.png", plt)
    if scatter is not None:
        paths["scatter"] = str(scatter)
    if len(spec.dts) > 1 or (spec.spin_rates is not None and len(spec.spin_rates) > 1):
        paths["map"] = str(_stability_map(result, out / "map.png", plt))
    return paths


def _histogram(result: SweepResult, metric: np.ndarray, positive: np.ndarray, log: bool, path: Path, plt: Any) -> Path:
    """The metric's histogram per grid point (the first 12), log-binned when it spans more than 100x."""
    spec, columns = result.spec, result.columns
    grid_point = np.asarray(columns["grid_point"])
    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=110)
    points = _grid_points(columns)
    for g, label in points[:12]:
        values = metric[(grid_point == g) & np.isfinite(metric)]
        if log:
            values = values[values > 0]
        if values.size:
            bins: Any = np.geomspace(positive.min(), positive.max(), 40) if log else 40
            ax.hist(values, bins=bins, histtype="step", label=label)
    if log:
        ax.set_xscale("log")
    ax.set_xlabel(f"{spec.metric} ({METRICS[spec.metric].split(',')[0]})")
    ax.set_ylabel("runs")
    ax.set_title(f"{spec.name}: {spec.metric}")
    if len(points) > 1:
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def _varies(values: np.ndarray) -> bool:
    finite = values[np.isfinite(values)]
    return finite.size > 1 and bool(finite.min() < finite.max())


def _scatter(result: SweepResult, metric: np.ndarray, log: bool, path: Path, plt: Any) -> Path | None:
    """The metric against every input that varies (None when none does)."""
    spec, columns = result.spec, result.columns
    inputs = [c for c in INPUT_COLUMNS if _varies(np.asarray(columns[c], dtype=float))]
    if not inputs:
        return None
    cols = min(4, len(inputs))
    rows = math.ceil(len(inputs) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.8 * rows), dpi=100, squeeze=False)
    for ax, name in zip(axes.flat, inputs, strict=False):
        x = np.asarray(columns[name], dtype=float)
        ax.scatter(x, metric, s=4, alpha=0.5)
        ax.set_xlabel(name)
        ax.set_ylabel(spec.metric, fontsize=7)
        if log:
            ax.set_yscale("log")
    for ax in list(axes.flat)[len(inputs) :]:
        ax.axis("off")
    fig.suptitle(f"{spec.name}: inputs against {spec.metric}")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def _stability_map(result: SweepResult, path: Path, plt: Any) -> Path:
    """Per method, over dt × spin rate: the share of stable runs (colour) and the median metric (text)."""
    spec, columns = result.spec, result.columns
    spins = spec.spin_rates or (math.nan,)
    fig, axes = plt.subplots(1, len(spec.methods), figsize=(5.2 * len(spec.methods), 4.2), dpi=100, squeeze=False)
    stable = np.array([v == "stable" for v in columns["verdict"]])
    metric = np.asarray(columns[spec.metric], dtype=float)
    grid_point = np.asarray(columns["grid_point"])
    for ax, method in zip(axes[0], spec.methods, strict=True):
        share = np.full((len(spins), len(spec.dts)), np.nan)
        for g, (m, dt, spin) in enumerate(spec.grid):
            if m != method:
                continue
            mask = grid_point == g
            i = spins.index(spin) if spin is not None else 0
            j = spec.dts.index(dt)
            share[i, j] = stable[mask].mean()
            finite = metric[mask & np.isfinite(metric)]
            text = f"{np.median(finite):.1e}" if finite.size else "–"
            ax.text(j, i, text, ha="center", va="center", fontsize=6)
        image = ax.imshow(share, origin="lower", cmap="RdYlGn", vmin=0.0, vmax=1.0, aspect="auto")
        ax.set_xticks(range(len(spec.dts)), [f"{dt:g}" for dt in spec.dts], rotation=45, fontsize=7)
        ax.set_yticks(range(len(spins)), [f"{s:g}" for s in spins], fontsize=7)
        ax.set_xlabel("dt (s)")
        ax.set_ylabel("|ω0| (rad/s)")
        ax.set_title(f"{method}: share stable (colour), median {spec.metric} (text)", fontsize=8)
    fig.colorbar(image, ax=axes[0].tolist(), shrink=0.8)
    fig.savefig(path)
    plt.close(fig)
    return path


def write_outputs(result: SweepResult, out_dir: str | Path) -> dict[str, str]:
    """Parquet, summary.md and the plots into ``out_dir``; returns {what: path}."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files = {"parquet": str(write_parquet(result, out / f"{result.spec.name}.parquet"))}
    files.update(write_plots(result, out))
    files["summary"] = str(out / "summary.md")
    (out / "summary.md").write_text(summary_markdown(result, files), encoding="utf-8")
    return files
