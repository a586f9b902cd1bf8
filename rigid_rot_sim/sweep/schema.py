"""The sweep spec format: its one JSON Schema.

:data:`SWEEP_SCHEMA` says which keys a sweep spec may hold, their types, required keys,
choices and bounds, with a description of each for editors. It is exported as
``config/schema/sweep.schema.json`` (docs/scenes.md shows how editors use it)::

    python -m rigid_rot_sim.sweep.schema > config/schema/sweep.schema.json

and :mod:`rigid_rot_sim.sweep.spec` validates every spec against it before the
checks a schema cannot express (the base scene, batch method, event and metric names, a
moment dispersion that stays physical).
"""

from __future__ import annotations

from typing import Any

from rigid_rot_sim.scene.schema import DIALECT, array, choice, dump, integer, mapping, nullable, number, text, vector

__all__ = ["SWEEP_SCHEMA", "DISPERSION_KINDS", "DISTRIBUTIONS", "SCALAR_DISPERSIONS"]

#: What a spec can disperse: name -> (key of the size, its unit, what is perturbed).
DISPERSION_KINDS = {
    "principal_moments": ("relative", "1", "the principal moments: I_i (1 + relative z_i)"),
    "axis_misalignment": ("sigma", "rad", "the principal axes: a rotation, rad per axis, principal frame"),
    "initial_omega": ("sigma", "rad/s", "the initial angular velocity, rad/s per axis"),
    "initial_attitude": ("sigma", "rad", "the initial attitude, rad per axis"),
    "torque_scale": ("relative", "1", "the scheduled torque: torque (1 + relative z)"),
    "orbit_phase": ("sigma", "rad", "the orbit's true anomaly at t = 0 (a scene with orbit:), rad"),
    "epoch": ("sigma", "s", "the scene's epoch, s of offset (rounded to the microsecond; a scene with a field)"),
}
#: Dispersions of one number per sample (the others: one per axis).
SCALAR_DISPERSIONS = ("orbit_phase", "epoch")
DISTRIBUTIONS = ("normal", "uniform")


def _positive(description: str) -> dict[str, Any]:
    return number(description, exclusive_minimum=0.0)


def _one_or_more(description: str, item: dict[str, Any]) -> dict[str, Any]:
    """A value, or a non-empty list of them."""
    return {"description": description, "anyOf": [item, array("A list of them.", item, min_items=1)]}


def _per_axis(description: str) -> dict[str, Any]:
    size = number("The same for every axis.", minimum=0.0)
    return {"description": description, "anyOf": [size, vector("One per axis [x, y, z].", 3, item=size)]}


def _dispersion(name: str) -> dict[str, Any]:
    size_key, unit, what = DISPERSION_KINDS[name]
    size = (
        number(f"1 sigma (normal) or the half-width (uniform), unit {unit}.", minimum=0.0)
        if name in SCALAR_DISPERSIONS
        else _per_axis(f"1 sigma (normal) or the half-width (uniform), unit {unit}; a number or [x, y, z].")
    )
    return nullable(
        mapping(
            f"Disperses {what}.",
            {
                "distribution": choice("normal (cut at 4 sigma) or uniform.", DISTRIBUTIONS, default="normal"),
                size_key: size,
            },
            required=[size_key],
        )
    )


_METHODS = _one_or_more(
    "Methods of the engine's registry: batch methods (rigid_rot_sim.core.batch.BATCH_METHODS, default rk4), or for a "
    "scene with reaction wheels or gravity gradient the gyrostat methods (gyrostat_rk4, the default, or dopri5).",
    text("A method name."),
)
_GRID = mapping(
    "The grid: every combination runs `samples` dispersed bodies.",
    {
        "method": _METHODS,
        "dt": _one_or_more("Fixed steps, s; default the scene's.", _positive("A step, s.")),
        "spin_rate": nullable(_one_or_more("|omega0| scaled to each value, rad/s.", number("rad/s.", minimum=0.0))),
    },
)
_SAMPLES = integer("Dispersed runs per grid point.", minimum=1)
_DURATION = _positive("Sim time of each run, s; default the scene's (which must then be set).")
_CHECKPOINTS = integer("States sampled per run (max |omega|, events).", minimum=1, default=200)

SWEEP_SCHEMA: dict[str, Any] = {
    "$schema": DIALECT,
    "title": "rigid_rot_sim sweep spec",
    **mapping(
        "A Monte Carlo / grid sweep over a base scene (rigid-rot sweep). SI units; body frame = the scene's.",
        {
            "name": text("Name of the sweep; defaults to the file name without .yaml."),
            "description": nullable({"description": "What the sweep studies.", "type": "string"}),
            "scene": text("The base scene: a path (relative to this file) or a shipped scene's name."),
            "seed": integer("Run inputs come from SeedSequence((seed, sample)).", minimum=0),
            "samples": _SAMPLES,
            "duration": _DURATION,
            "grid": _GRID,
            "dispersions": nullable(
                mapping(
                    "What varies between the runs of one grid point; normal draws are cut at 4 sigma.",
                    {
                        **{name: _dispersion(name) for name in DISPERSION_KINDS},
                        "torque_noise": nullable(
                            mapping(
                                "Random torque, normal, held for `interval` s.",
                                {
                                    "sigma": _per_axis("N*m per axis, body frame"),
                                    "interval": _positive("Seconds each draw is held.") | {"default": 1.0},
                                },
                                required=["sigma"],
                            )
                        ),
                    },
                )
            ),
            "nominal": nullable(
                mapping(
                    "The nominal run's integrator (default: the grid point's).",
                    {
                        "method": text("A method name, as in grid.method (default: its first)."),
                        "dt": _positive("Fixed step, s."),
                    },
                    required=["dt"],
                )
            ),
            "checkpoints": _CHECKPOINTS,
            "energy_tolerance": _positive("Relative energy drift above which a torque-free run is drifting.")
            | {"default": 1e-3},
            "events": nullable(
                array("Scene-specific events to record (first_flip, nutation_range).", text("An event name."))
            ),
            "metric": text("The metric the summary plots against the inputs.", default="final_attitude_error"),
            "quick": nullable(
                mapping(
                    "What --quick changes (grid: per key).",
                    {"samples": _SAMPLES, "duration": _DURATION, "grid": _GRID, "checkpoints": _CHECKPOINTS},
                )
            ),
        },
        required=["scene", "seed", "samples", "grid"],
    ),
}


if __name__ == "__main__":
    print(dump(SWEEP_SCHEMA), end="")
