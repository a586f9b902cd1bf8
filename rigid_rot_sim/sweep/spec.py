"""Sweep specs: a base scene plus dispersions and grids, validated into frozen dataclasses.

The format is one JSON Schema, :data:`rigid_rot_sim.sweep.schema.SWEEP_SCHEMA`
(exported as ``config/schema/sweep.schema.json``). :func:`load_sweep_spec` validates a
spec against it, then checks what a schema cannot express: the base scene (found, valid,
made only of what the sweep runs: :func:`rigid_rot_sim.scene.features.refuse_unhonoured`),
batch method, event and metric names, and dispersions that keep every body physical.
Every error is a :class:`SweepSpecError` (a ValueError) naming the file, the key and
what is wrong, in one line, like
:class:`rigid_rot_sim.scene.scene.SceneError`, e.g. ``slew.yaml:
dispersions.principal_moments.relative: 0.4 (normal, cut at 4 sigma) can make moment 1
non-positive``.

An example (SI units; body frame = the scene's body frame)::

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
      orbit_phase: {distribution: uniform, sigma: 3.14159}        # rad added to the true anomaly (orbit:)
      epoch: {distribution: uniform, sigma: 86400.0}              # s added to the epoch (a field)
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

import os
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from rigid_rot_sim.core.batch import BATCH_METHODS
from rigid_rot_sim.core.integrators.gyrostat import GYROSTAT_METHODS
from rigid_rot_sim.core.validation import TRIANGLE_RTOL
from rigid_rot_sim.scene.bounded_yaml import load_input, read_input
from rigid_rot_sim.scene.features import MEASUREMENTS, PATHS, features_of, refuse_unhonoured
from rigid_rot_sim.scene.scene import Scene, SceneError, load_scene
from rigid_rot_sim.scene.schema import validated
from rigid_rot_sim.share import resolve_scene
from rigid_rot_sim.sweep.schema import DISPERSION_KINDS, SCALAR_DISPERSIONS, SWEEP_SCHEMA

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
    "BATCH_FEATURES",
    "runs_per_sample",
    "methods_for",
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
    **{
        f"final_field_{axis}": f"T, the true field at the end, body frame, {axis} (NaN: a scene without a field)"
        for axis in "xyz"
    },
}


#: The features (:mod:`rigid_rot_sim.scene.features`) the rigid-body batch kernel (core/batch.py) runs; a scene
#: with another feature the sweep runs (wheels, gravity gradient) is run by the engine per sample
#: (:mod:`~rigid_rot_sim.sweep.engine_runs`).
BATCH_FEATURES = frozenset({"body", "initial", "schedules.body", "schedules.world", *MEASUREMENTS})
#: Dispersions that map onto no key of such a scene (they act on the batch's body-frame torque).
_BATCH_ONLY_DISPERSIONS = ("torque_scale", "torque_noise")


def runs_per_sample(scene: Scene) -> bool:
    """Whether the sweep runs ``scene`` in the engine per sample (a feature the sweep runs outside
    :data:`BATCH_FEATURES`)."""
    return bool(set(features_of(scene)) & (PATHS["sweep"] - BATCH_FEATURES))


def methods_for(scene: Scene) -> tuple[str, ...]:
    """The engine's method names a sweep of ``scene`` runs: the batch kernel's, or the gyrostat methods."""
    return tuple(GYROSTAT_METHODS) if runs_per_sample(scene) else BATCH_METHODS


class SweepSpecError(ValueError):
    """A sweep spec is invalid; the message names the file, the key and what is wrong."""


@dataclass(frozen=True)
class Dispersion:
    """A random perturbation: ``distribution`` normal (``size`` = 1 sigma) or uniform (half-width).

    ``size`` has one value per axis (one value for ``SCALAR_DISPERSIONS``); its unit depends on what is dispersed.
    """

    distribution: str
    size: tuple[float, ...]

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
    orbit_phase: Dispersion | None = None  # rad, the true anomaly at t = 0
    epoch: Dispersion | None = None  # s, the epoch
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


# ----------------------------------------------------------------------------- loading


def load_sweep_spec(path: str | os.PathLike[str], quick: bool = False) -> SweepSpec:
    """Read and validate the sweep spec at ``path`` (``quick``: with its quick overrides)."""
    path = os.fspath(path)
    return parse_sweep_text(read_input(path, "sweep spec", SweepSpecError), source=path, quick=quick)


def parse_sweep_text(text: str, source: str = "<string>", quick: bool = False) -> SweepSpec:
    """Validate a sweep spec given as YAML text."""
    return parse_sweep_spec(load_input(text, source, SweepSpecError), source=source, text=text, quick=quick)


def parse_sweep_spec(data: Any, source: str = "<string>", text: str = "", quick: bool = False) -> SweepSpec:
    """Validate a sweep spec given as parsed YAML; ``quick`` applies its ``quick`` overrides."""
    return validated(
        data,
        SWEEP_SCHEMA,
        source,
        SweepSpecError,
        lambda spec: _sweep(_with_quick(spec) if quick else spec, source, text),
    )


def with_samples(spec: SweepSpec, samples: int) -> SweepSpec:
    """The same spec with another sample count (benchmarks and tests)."""
    return replace(spec, samples=int(samples))


# ------------------------------------------- what the schema cannot say (the data passed it)


def _with_quick(spec: Mapping[str, Any]) -> dict[str, Any]:
    """The spec with its ``quick`` overrides merged in (one level deep for grid)."""
    merged = dict(spec)
    for name, value in (spec.get("quick") or {}).items():
        merged[name] = {**spec["grid"], **value} if name == "grid" else value
    return merged


def _floats(value: Any) -> tuple[float, ...]:
    """A number or a list of them, as a tuple of floats."""
    return tuple(float(v) for v in (value if isinstance(value, list) else [value]))


def _method(name: str, key: str, scene: Scene) -> str:
    methods = methods_for(scene)
    if name not in methods:
        what = "a gyrostat method (the engine per sample)" if runs_per_sample(scene) else "a batch method"
        raise ValueError(f"{key}: must be {what} for scene {scene.name} ({', '.join(methods)}), got {name!r}")
    return name


def _known(name: str, key: str, known: Mapping[str, str], what: str) -> str:
    if name not in known:
        raise ValueError(f"{key}: unknown {what} {name!r} (known: {', '.join(known)})")
    return name


def _sweep(spec: Mapping[str, Any], source: str, text: str) -> SweepSpec:
    default_name = os.path.splitext(os.path.basename(source))[0] if source != "<string>" else "sweep"
    scene = _base_scene(spec["scene"], source)
    duration = spec.get("duration", scene.duration)
    if duration is None:
        raise ValueError(f"duration: missing (the scene {scene.name} runs unbounded)")
    grid = spec["grid"]
    methods = grid.get("method", [methods_for(scene)[0]])
    methods = tuple(_method(m, f"grid.method[{i}]", scene) for i, m in enumerate(_listed(methods)))
    spin_rates = None
    if grid.get("spin_rate") is not None:
        spin_rates = _floats(grid["spin_rate"])
        if not any(scene.initial.angular_velocity):
            raise ValueError(f"grid.spin_rate: the scene {scene.name} starts at rest: no spin axis to scale")
    dispersions = _dispersions(spec.get("dispersions") or {}, np.linalg.eigvalsh(scene.body.inertia_array))
    if runs_per_sample(scene):
        for name in _BATCH_ONLY_DISPERSIONS:
            if (spec.get("dispersions") or {}).get(name) is not None:
                raise ValueError(
                    f"dispersions.{name}: maps onto no key of scene {scene.name}, which the sweep runs in the engine "
                    f"per sample ({', '.join(sorted(set(features_of(scene)) - BATCH_FEATURES))})"
                )
    _check_scene_dispersions(spec.get("dispersions") or {}, scene)
    nominal = spec.get("nominal")
    events = tuple(_known(e, f"events[{i}]", EVENTS, "event") for i, e in enumerate(spec.get("events") or ()))
    metric = _known(spec.get("metric", "final_attitude_error"), "metric", METRICS, "metric")
    if metric in EVENTS and metric not in events:
        raise ValueError(f"metric: {metric} is an event: list it under events too")
    return SweepSpec(
        name=spec.get("name", default_name).strip(),
        description=(spec.get("description") or "").strip(),
        scene=scene,
        seed=spec["seed"],
        samples=spec["samples"],
        duration=float(duration),
        methods=methods,
        dts=_floats(grid.get("dt", scene.integrator.dt)),
        spin_rates=spin_rates,
        dispersions=dispersions,
        nominal_method=None
        if nominal is None
        else _method(nominal.get("method", methods_for(scene)[0]), "nominal.method", scene),
        nominal_dt=None if nominal is None else float(nominal["dt"]),
        checkpoints=spec.get("checkpoints", 200),
        energy_tolerance=float(spec.get("energy_tolerance", 1e-3)),
        events=events,
        metric=metric,
        source=source,
        text=text,
    )


def _listed(value: Any) -> list[Any]:
    return value if isinstance(value, list) else [value]


def _base_scene(name: str, source: str) -> Scene:
    """The scene (a path relative to the spec, or a shipped scene), refused by its first feature the sweep does
    not run (:data:`rigid_rot_sim.scene.features.PATHS`)."""
    relative = os.path.join(os.path.dirname(os.path.abspath(source)), name) if source != "<string>" else name
    try:
        path = relative if os.path.isfile(relative) else resolve_scene(name)
    except ValueError as exc:
        raise ValueError(f"scene: {exc}") from None
    try:
        scene = load_scene(path)
    except SceneError as exc:
        raise ValueError(f"scene: invalid scene: {exc}") from None
    try:
        refuse_unhonoured(scene, "sweep")  # before any work: what the sweep cannot run (scene/features.py)
    except ValueError as exc:
        raise ValueError(f"scene: {exc}") from None
    return scene


#: Dispersions of a scene section -> the feature (scene/features.py) the scene needs for them to map onto.
_SCENE_DISPERSIONS = {"orbit_phase": "orbit", "epoch": "environment.magnetic_field"}


def _check_scene_dispersions(spec: Mapping[str, object], scene: Scene) -> None:
    """A dispersion of a scene section the scene lacks maps onto nothing: refused by name."""
    for name, feature in _SCENE_DISPERSIONS.items():
        if spec.get(name) is not None and feature not in features_of(scene):
            raise ValueError(f"dispersions.{name}: maps onto {feature}, which scene {scene.name} has not")


def _dispersions(spec: Mapping[str, Any], moments: np.ndarray) -> Dispersions:
    values: dict[str, Any] = {}
    for name, (size_key, _, _) in DISPERSION_KINDS.items():
        if spec.get(name) is not None:
            size = (float(spec[name][size_key]),) if name in SCALAR_DISPERSIONS else _per_axis(spec[name][size_key])
            values[name] = Dispersion(spec[name].get("distribution", "normal"), size)
    if "principal_moments" in values:
        _check_moment_dispersion(moments, values["principal_moments"])
    if "torque_scale" in values:
        worst = values["torque_scale"].extreme()
        if worst.max() >= 1.0:
            raise ValueError(
                f"dispersions.torque_scale.relative: {worst.max():g} at the extremes "
                "can reverse the torque (must stay < 1)"
            )
    noise = spec.get("torque_noise")
    if noise is not None:
        values["torque_noise_sigma"] = _per_axis(noise["sigma"])
        values["torque_noise_interval"] = float(noise.get("interval", 1.0))
    return Dispersions(**values)


def _per_axis(value: Any) -> tuple[float, float, float]:
    sizes = _floats(value)
    x, y, z = sizes if len(sizes) == 3 else (sizes[0],) * 3
    return (x, y, z)


def _check_moment_dispersion(moments: np.ndarray, dispersion: Dispersion) -> None:
    """Every moment stays > 0 and the triangle inequality holds at the dispersion's extremes."""
    key = "dispersions.principal_moments.relative"
    extreme = dispersion.extreme()
    cut = f", cut at {NORMAL_CUT_SIGMAS:g} sigma" if dispersion.distribution == "normal" else ""
    how = f"{dispersion.distribution}{cut}"
    low, high = moments * (1.0 - extreme), moments * (1.0 + extreme)
    for i in range(3):
        if not low[i] > 0.0:
            raise ValueError(
                f"{key}: {dispersion.size[i]:g} ({how}) can make moment {i + 1} ({moments[i]:g} kg*m^2) non-positive"
            )
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        if low[i] + low[j] < high[k] - TRIANGLE_RTOL * float(high.sum()):
            raise ValueError(
                f"{key}: {list(dispersion.size)} ({how}) can break the triangle inequality "
                f"I{i + 1} + I{j + 1} >= I{k + 1} "
                f"of a rigid body ({low[i]:.6g} + {low[j]:.6g} < {high[k]:.6g} kg*m^2 at the extremes)"
            )
