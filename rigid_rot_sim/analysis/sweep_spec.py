"""Sweep specs: a base scene plus dispersions and grids, validated into frozen dataclasses.

Every error is a :class:`SweepSpecError` (a ValueError) naming the file, the key and
what is wrong, in one line, like :class:`rigid_rot_sim.core.scene.SceneError`, e.g.
``slew.yaml: dispersions.principal_moments.relative: 0.4 (normal, cut at 4 sigma) can
make moment 1 non-positive``.

Schema (SI units; body frame = the scene's body frame)::

    name: slew_dispersion              # optional, defaults to the file stem
    description: "..."                 # optional
    scene: spacecraft_slew             # a path (relative to this file) or a shipped scene's name
    seed: 20261123                     # integer >= 0; run inputs come from SeedSequence((seed, sample))
    samples: 2000                      # dispersed runs per grid point (>= 1)
    duration: 60.0                     # s; default the scene's (which must then be set)
    grid:                              # every combination runs `samples` dispersed bodies
      method: [rk4]                    # batch methods (rigid_rot_sim.core.batch.BATCH_METHODS)
      dt: [0.01]                       # s, > 0
      spin_rate: [1.0, 4.0]            # optional: |omega0| scaled to each value (rad/s)
    dispersions:                       # all optional; normal draws are cut at 4 sigma
      principal_moments: {distribution: normal, relative: 0.05}   # I_i (1 + relative z_i)
      axis_misalignment: {distribution: normal, sigma: 1.0e-3}    # rad per axis, principal frame
      initial_omega: {distribution: normal, sigma: 1.0e-4}        # rad/s per axis (or [x, y, z])
      initial_attitude: {distribution: normal, sigma: 1.0e-3}     # rad per axis
      torque_scale: {distribution: normal, relative: 0.02}        # scheduled torque * (1 + relative z)
      torque_noise: {sigma: 1.0e-3, interval: 1.0}                # N*m per axis (body), held `interval` s
    nominal: {method: rk4, dt: 0.001}  # optional: the nominal run's integrator (default: the grid point's)
    checkpoints: 200                   # states sampled per run (max |omega|, events)
    energy_tolerance: 1.0e-3           # relative drift above which a torque-free run is "drifting"
    events: [first_flip]               # scene-specific events (EVENTS)
    metric: final_attitude_error       # the metric the summary plots against the inputs
    quick: {samples: 32, duration: 20.0, grid: {dt: [0.01]}}   # what --quick changes

For ``distribution: uniform`` the ``relative`` / ``sigma`` value is the half-width.
A moment dispersion is checked at its extremes (4 sigma, or the half-width): every
moment must stay positive and satisfy the triangle inequality of a rigid body.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from typing import Any, Mapping

import numpy as np
import yaml

from rigid_rot_sim.core.batch import BATCH_METHODS
# the scene parser's helpers, so that a sweep spec's errors read like a scene's
from rigid_rot_sim.core.scene import Scene, SceneError, _Ctx, _mapping, parse_scene_text
from rigid_rot_sim.core.scene import _number as _scene_number
from rigid_rot_sim.core.validation import TRIANGLE_RTOL

__all__ = [
    "SweepSpecError",
    "Dispersion",
    "Dispersions",
    "SweepSpec",
    "load_sweep_spec",
    "parse_sweep_spec",
    "EVENTS",
    "METRICS",
    "NORMAL_CUT_SIGMAS",
]

#: Normal draws beyond this many sigmas are drawn again (so a spec can be checked at its extremes).
NORMAL_CUT_SIGMAS = 4.0
#: Scene-specific events a spec can ask for (columns of the output).
EVENTS = {
    "first_flip": "time (s) of the first intermediate-axis flip: omega about the intermediate axis changes sign",
    "nutation_range": "range (rad) of the angle between the major principal axis and L over the run",
}
#: Per-run metrics (columns of the output), and what they are.
METRICS = {
    "final_attitude_error": "rad, angle between the run's final attitude and the nominal run's",
    "final_omega_error": "rad/s, |omega - omega_nominal| at the end (body frame)",
    "max_omega": "rad/s, largest |omega| at the checkpoints",
    "energy_drift": "relative change of the kinetic energy (torque-free runs)",
    "momentum_drift": "relative change of |L| (torque-free runs)",
    "first_flip": EVENTS["first_flip"],
    "nutation_range": EVENTS["nutation_range"],
}
_DISPERSION_KINDS = {
    # name: (size key, unit of the size)
    "principal_moments": ("relative", "1"),
    "axis_misalignment": ("sigma", "rad"),
    "initial_omega": ("sigma", "rad/s"),
    "initial_attitude": ("sigma", "rad"),
    "torque_scale": ("relative", "1"),
}
_TOP_KEYS = (
    "name", "description", "scene", "seed", "samples", "duration", "grid", "dispersions", "nominal",
    "checkpoints", "energy_tolerance", "events", "metric", "quick",
)


class SweepSpecError(ValueError):
    """A sweep spec is invalid; the message names the file, the key and what is wrong."""


@dataclass(frozen=True)
class Dispersion:
    """A random perturbation: ``distribution`` normal (``size`` = 1 sigma) or uniform (half-width).

    ``size`` has one value per axis; its unit depends on what is dispersed.
    """

    distribution: str
    size: tuple[float, float, float]

    def extreme(self) -> np.ndarray:
        """The largest |perturbation| per axis a draw can give."""
        factor = NORMAL_CUT_SIGMAS if self.distribution == "normal" else 1.0
        return factor * np.asarray(self.size)


@dataclass(frozen=True)
class Dispersions:
    """What varies between the runs of one grid point (None: not dispersed)."""

    principal_moments: Dispersion | None = None
    axis_misalignment: Dispersion | None = None
    initial_omega: Dispersion | None = None
    initial_attitude: Dispersion | None = None
    torque_scale: Dispersion | None = None
    torque_noise_sigma: tuple[float, float, float] | None = None  # N*m per axis, normal
    torque_noise_interval: float = 1.0  # s the noise is held


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: ``scene`` is the base scene; every grid point runs ``samples`` bodies."""

    name: str
    scene: Scene
    seed: int
    samples: int
    duration: float
    methods: tuple[str, ...]
    dts: tuple[float, ...]
    spin_rates: tuple[float, ...] | None
    dispersions: Dispersions
    nominal_method: str | None
    nominal_dt: float | None
    checkpoints: int
    energy_tolerance: float
    events: tuple[str, ...]
    metric: str
    description: str = ""
    source: str = "<string>"
    text: str = ""

    @property
    def grid(self) -> list[tuple[str, float, float | None]]:
        """The grid points (method, dt, spin rate or None), in run order."""
        spins = self.spin_rates if self.spin_rates is not None else (None,)
        return [(m, dt, s) for m in self.methods for dt in self.dts for s in spins]

    @property
    def n_runs(self) -> int:
        return len(self.grid) * self.samples


def _ctx(source: str) -> _Ctx:
    return _Ctx(source, SweepSpecError)


def _number(ctx: _Ctx, value: Any, key: str, *, positive: bool = False, nonnegative: bool = False) -> float:
    if positive:
        return _scene_number(ctx, value, key, minimum=0.0, strict=True)
    return _scene_number(ctx, value, key, minimum=0.0 if nonnegative else None)


def _integer(ctx: _Ctx, value: Any, key: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ctx.error(key, f"must be an integer, got {value!r}")
    if value < minimum:
        raise ctx.error(key, f"must be >= {minimum}, got {value}")
    return int(value)


def _number_list(ctx: _Ctx, value: Any, key: str, **checks: bool) -> tuple[float, ...]:
    items = value if isinstance(value, (list, tuple)) else [value]
    if not items:
        raise ctx.error(key, "must not be empty")
    return tuple(_number(ctx, v, f"{key}[{i}]", **checks) for i, v in enumerate(items))


def _per_axis(ctx: _Ctx, value: Any, key: str) -> tuple[float, float, float]:
    if isinstance(value, (list, tuple)):
        if len(value) != 3:
            raise ctx.error(key, f"must be a number or a list of 3 numbers, got {value!r}")
        return tuple(_number(ctx, v, f"{key}[{i}]", nonnegative=True) for i, v in enumerate(value))  # type: ignore[return-value]
    size = _number(ctx, value, key, nonnegative=True)
    return (size, size, size)


def _dispersion(ctx: _Ctx, raw: Any, key: str, size_key: str) -> Dispersion:
    spec = _mapping(ctx, raw, key, ("distribution", size_key))
    distribution = spec.get("distribution", "normal")
    if distribution not in ("normal", "uniform"):
        raise ctx.error(f"{key}.distribution", f"must be normal or uniform, got {distribution!r}")
    if size_key not in spec:
        raise ctx.error(key, f"needs {size_key} (1 sigma for normal, the half-width for uniform)")
    return Dispersion(distribution, _per_axis(ctx, spec[size_key], f"{key}.{size_key}"))


def _check_moment_dispersion(ctx: _Ctx, moments: np.ndarray, dispersion: Dispersion) -> None:
    """Every moment stays > 0 and the triangle inequality holds at the dispersion's extremes."""
    key = "dispersions.principal_moments.relative"
    extreme = dispersion.extreme()
    how = f"{dispersion.distribution}{', cut at %g sigma' % NORMAL_CUT_SIGMAS if dispersion.distribution == 'normal' else ''}"
    low, high = moments * (1.0 - extreme), moments * (1.0 + extreme)
    for i in range(3):
        if not low[i] > 0.0:
            raise ctx.error(key, f"{dispersion.size[i]:g} ({how}) can make moment {i + 1} ({moments[i]:g} kg*m^2) non-positive")
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        if low[i] + low[j] < high[k] - TRIANGLE_RTOL * float(high.sum()):
            raise ctx.error(
                key,
                f"{list(dispersion.size)} ({how}) can break the triangle inequality I{i + 1} + I{j + 1} >= I{k + 1} "
                f"of a rigid body ({low[i]:.6g} + {low[j]:.6g} < {high[k]:.6g} kg*m^2 at the extremes)",
            )


def _parse_dispersions(ctx: _Ctx, raw: Any, moments: np.ndarray) -> Dispersions:
    if raw is None:
        return Dispersions()
    spec = _mapping(ctx, raw, "dispersions", (*_DISPERSION_KINDS, "torque_noise"))
    values: dict[str, Any] = {}
    for name, (size_key, _) in _DISPERSION_KINDS.items():
        if spec.get(name) is not None:
            values[name] = _dispersion(ctx, spec[name], f"dispersions.{name}", size_key)
    if "principal_moments" in values:
        _check_moment_dispersion(ctx, moments, values["principal_moments"])
    if "torque_scale" in values:
        worst = values["torque_scale"].extreme()
        if worst.max() >= 1.0:
            raise ctx.error("dispersions.torque_scale.relative", f"{worst.max():g} at the extremes can reverse the torque (must stay < 1)")
    noise = spec.get("torque_noise")
    if noise is not None:
        noise = _mapping(ctx, noise, "dispersions.torque_noise", ("sigma", "interval"))
        if "sigma" not in noise:
            raise ctx.error("dispersions.torque_noise", "needs sigma (N*m per axis, body frame)")
        values["torque_noise_sigma"] = _per_axis(ctx, noise["sigma"], "dispersions.torque_noise.sigma")
        values["torque_noise_interval"] = _number(ctx, noise.get("interval", 1.0), "dispersions.torque_noise.interval", positive=True)
    return Dispersions(**values)


def _resolve_scene(ctx: _Ctx, value: Any, source: str) -> Scene:
    if not isinstance(value, str) or not value.strip():
        raise ctx.error("scene", f"must be a scene path or a shipped scene's name, got {value!r}")
    relative = os.path.join(os.path.dirname(os.path.abspath(source)), value) if source != "<string>" else value
    if os.path.isfile(relative):
        path = relative
    else:
        from rigid_rot_sim.cli.run import resolve_scene  # the shipped scenes' one lookup

        try:
            path = resolve_scene(value)
        except ValueError as exc:
            raise ctx.error("scene", str(exc)) from None
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
        return parse_scene_text(text, source=path)
    except OSError as exc:
        raise ctx.error("scene", f"cannot read {path}: {exc.strerror}") from None
    except SceneError as exc:
        raise ctx.error("scene", f"invalid scene: {exc}") from None


def _apply_quick(ctx: _Ctx, spec: Mapping[str, Any]) -> dict[str, Any]:
    """The spec with its ``quick`` overrides merged in (one level deep for grid)."""
    quick = _mapping(ctx, spec.get("quick") or {}, "quick", ("samples", "duration", "grid", "checkpoints"))
    merged = dict(spec)
    for name, value in quick.items():
        if name == "grid":
            grid = dict(_mapping(ctx, spec.get("grid") or {}, "grid", ("method", "dt", "spin_rate")))
            grid.update(_mapping(ctx, value, "quick.grid", ("method", "dt", "spin_rate")))
            merged["grid"] = grid
        else:
            merged[name] = value
    return merged


def parse_sweep_spec(data: Any, source: str = "<string>", text: str = "", quick: bool = False) -> SweepSpec:
    """Validate a sweep spec given as parsed YAML; ``quick`` applies its ``quick`` overrides."""
    ctx = _ctx(source)
    spec = _mapping(ctx, data, "", _TOP_KEYS)
    for required in ("scene", "seed", "samples", "grid"):
        if required not in spec:
            raise ctx.error(required, "missing")
    if quick:
        spec = _apply_quick(ctx, spec)
    else:
        _apply_quick(ctx, spec)  # validate it all the same
    default_name = os.path.splitext(os.path.basename(source))[0] if source != "<string>" else "sweep"
    name = spec.get("name", default_name)
    if not isinstance(name, str) or not name.strip():
        raise ctx.error("name", f"must be a non-empty string, got {name!r}")
    description = spec.get("description", "") or ""
    if not isinstance(description, str):
        raise ctx.error("description", "must be a string")
    scene = _resolve_scene(ctx, spec["scene"], source)
    if scene.gravity is not None or scene.topic_inputs:
        raise ctx.error(
            "scene",
            f"{scene.name} is driven by {scene.torque_kind}: sweeps run torque-free and scheduled-torque scenes "
            "(the batch core holds a body-frame torque per step)",
        )
    seed = _integer(ctx, spec["seed"], "seed", 0)
    samples = _integer(ctx, spec["samples"], "samples", 1)
    duration = spec.get("duration", scene.duration)
    if duration is None:
        raise ctx.error("duration", f"missing (the scene {scene.name} runs unbounded)")
    duration = _number(ctx, duration, "duration", positive=True)

    grid = _mapping(ctx, spec["grid"], "grid", ("method", "dt", "spin_rate"))
    raw_methods = grid.get("method", ["rk4"])
    methods = tuple(raw_methods) if isinstance(raw_methods, (list, tuple)) else (raw_methods,)
    for i, method in enumerate(methods):
        if method not in BATCH_METHODS:
            raise ctx.error(f"grid.method[{i}]", f"must be a batch method ({', '.join(BATCH_METHODS)}), got {method!r}")
    dts = _number_list(ctx, grid.get("dt", scene.integrator.dt), "grid.dt", positive=True)
    spin_rates = None
    if grid.get("spin_rate") is not None:
        spin_rates = _number_list(ctx, grid["spin_rate"], "grid.spin_rate", nonnegative=True)
        if not any(scene.initial.angular_velocity):
            raise ctx.error("grid.spin_rate", f"the scene {scene.name} starts at rest: no spin axis to scale")

    dispersions = _parse_dispersions(ctx, spec.get("dispersions"), np.linalg.eigvalsh(scene.body.inertia_array))
    nominal_method = nominal_dt = None
    if spec.get("nominal") is not None:
        nominal = _mapping(ctx, spec["nominal"], "nominal", ("method", "dt"))
        nominal_method = nominal.get("method", "rk4")
        if nominal_method not in BATCH_METHODS:
            raise ctx.error("nominal.method", f"must be a batch method ({', '.join(BATCH_METHODS)}), got {nominal_method!r}")
        if "dt" not in nominal:
            raise ctx.error("nominal", "needs dt (s)")
        nominal_dt = _number(ctx, nominal["dt"], "nominal.dt", positive=True)
    checkpoints = _integer(ctx, spec.get("checkpoints", 200), "checkpoints", 1)
    energy_tolerance = _number(ctx, spec.get("energy_tolerance", 1e-3), "energy_tolerance", positive=True)
    raw_events = spec.get("events") or []
    if not isinstance(raw_events, (list, tuple)):
        raise ctx.error("events", f"must be a list of event names, got {raw_events!r}")
    for i, event in enumerate(raw_events):
        if event not in EVENTS:
            raise ctx.error(f"events[{i}]", f"unknown event {event!r} (known: {', '.join(EVENTS)})")
    metric = spec.get("metric", "final_attitude_error")
    if metric not in METRICS:
        raise ctx.error("metric", f"unknown metric {metric!r} (known: {', '.join(METRICS)})")
    if metric in EVENTS and metric not in raw_events:
        raise ctx.error("metric", f"{metric} is an event: list it under events too")
    return SweepSpec(
        name=name.strip(),
        description=description.strip(),
        scene=scene,
        seed=seed,
        samples=samples,
        duration=duration,
        methods=methods,
        dts=dts,
        spin_rates=spin_rates,
        dispersions=dispersions,
        nominal_method=nominal_method,
        nominal_dt=nominal_dt,
        checkpoints=checkpoints,
        energy_tolerance=energy_tolerance,
        events=tuple(raw_events),
        metric=metric,
        source=source,
        text=text,
    )


def parse_sweep_text(text: str, source: str = "<string>", quick: bool = False) -> SweepSpec:
    """Validate a sweep spec given as YAML text."""
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise SweepSpecError(f"{os.path.basename(source)}: not valid YAML: {' '.join(str(exc).split())}") from None
    return parse_sweep_spec(data, source=source, text=text, quick=quick)


def load_sweep_spec(path: str | os.PathLike[str], quick: bool = False) -> SweepSpec:
    """Read and validate the sweep spec at ``path`` (``quick``: with its quick overrides)."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as exc:
        raise SweepSpecError(f"{path}: cannot read sweep spec: {exc.strerror}") from None
    return parse_sweep_text(text, source=path, quick=quick)


def with_samples(spec: SweepSpec, samples: int) -> SweepSpec:
    """The same spec with another sample count (benchmarks and tests)."""
    return replace(spec, samples=int(samples))
