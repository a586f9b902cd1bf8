"""What a scene asks of the physics, and what each path that runs scenes honours.

One scene model, several paths that step it: the run engine (:class:`~rigid_rot_sim.run.simulator.Simulator`,
which the node drives), ``resim`` (the engine fed a recording's commands), the sweep (its batch
kernels or the engine per sample) and the arrays of :func:`~rigid_rot_sim.core.simulate.simulate`
(which takes no scene: ``simulate`` below is what a scene's parts map onto its arguments). A *feature*
is a part of a scene that acts on the state, named by its scene key (``schedules.world``,
``spacecraft.wheels.friction``, ...): :func:`features_of` lists those a scene uses. :data:`PATHS`
declares, per path, the features it runs; :func:`refuse_unhonoured` is the one check every path makes
before any work: a ``ValueError`` naming the first feature the path does not run, in one line (the CLI
turns it into stderr and exit 2). A path never runs a scene without one of its sources. The Gymnasium
envs take no scene today (they build their bodies from arguments): an env that takes one declares its
path here and calls :func:`refuse_unhonoured` in its constructor.

Every field of :class:`~rigid_rot_sim.scene.scene.Scene`, recursively, is classified in
:data:`FEATURE_FIELDS` (a field a feature reads) or in :data:`SETTINGS` (a field that acts on no state:
names, rates, QoS, the path's own numerics); ``test/scene/test_features.py`` walks the dataclass tree
and fails on a field classified nowhere, so a new scene key is either run or refused by every path.

Registering a new source or sensor (issues 37, 38): one line per feature, one per path.

1. :data:`FEATURES`: ``"environment.magnetic_field": lambda scene: scene.environment.field is not None,``
   (its scene key, and when a scene uses it);
2. :data:`FEATURE_FIELDS`: the new ``Scene`` fields it reads, ``"spacecraft.magnetorquers": "spacecraft.magnetorquers"``
   (a field that acts on no state goes in :data:`SETTINGS` with the reason);
3. :data:`PATHS`: add the key to each path that runs it (``engine`` and ``resim`` once the stepper
   does); a path left alone refuses scenes using it, by name, and the conformance suite
   (``test/conformance/test_conformance.py``) checks every path that declares it against the engine.

Measurements (:data:`MEASUREMENTS`: the sensors) act on no state: a path without their outputs (the
sweep, ``simulate``) honours them by leaving them out of its results. A sensor whose reading feeds a
torque (a B-dot controller on a magnetometer) makes that controller a source, declared as above.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from rigid_rot_sim.scene.scene import Scene

__all__ = ["FEATURES", "FEATURE_FIELDS", "SETTINGS", "MEASUREMENTS", "PATHS", "features_of", "refuse_unhonoured"]

#: Every feature, by scene key, in the order :func:`features_of` lists them: whether ``scene`` uses it.
FEATURES: Mapping[str, Callable[[Scene], bool]] = {
    "body": lambda scene: True,
    "initial": lambda scene: True,
    "schedules.body": lambda scene: any(s.frame == "body" for s in scene.schedules),
    "schedules.world": lambda scene: any(s.frame == "world" for s in scene.schedules),
    "topic_inputs": lambda scene: bool(scene.topic_inputs),
    "lockstep": lambda scene: scene.lockstep is not None,
    "gravity": lambda scene: scene.gravity is not None,
    "spacecraft.wheels": lambda scene: bool(scene.spacecraft.wheels),
    "spacecraft.wheels.friction": lambda scene: any(w.coulomb or w.viscous for w in scene.spacecraft.wheels),
    "spacecraft.wheel_schedule": lambda scene: scene.spacecraft.wheel_schedule is not None,
    "joint_state_topics": lambda scene: scene.joint_state_topics is not None,
    "spacecraft.gravity_gradient": lambda scene: scene.spacecraft.gravity_gradient is not None,
    "spacecraft.magnetorquers": lambda scene: bool(scene.spacecraft.rods),
    "spacecraft.magnetorquers.coupling": lambda scene: any(any(r.magnetometer_coupling) for r in scene.spacecraft.rods),
    "sensors.gyro": lambda scene: scene.sensors.gyro is not None,
    "sensors.star_tracker": lambda scene: scene.sensors.star_tracker is not None,
    "orbit": lambda scene: scene.orbit is not None,
    "environment.magnetic_field": lambda scene: scene.magnetic_field is not None,
    "sensors.magnetometer": lambda scene: scene.sensors.magnetometer is not None,
}

#: Features that act on no state (measurements of it): see the module docstring.
MEASUREMENTS = frozenset({"sensors.gyro", "sensors.star_tracker", "sensors.magnetometer"})

#: Scene fields (dotted, through the dataclass tree) that a feature reads -> that feature. A field
#: naming a dataclass covers its fields (a new field of the gyro model is the gyro's).
FEATURE_FIELDS: Mapping[str, str] = {
    "body.inertia": "body",
    "body.mass": "gravity",
    "body.center_of_mass": "gravity",
    "initial": "initial",
    "schedules": "schedules.body",  # and schedules.world, by each schedule's frame
    "topic_inputs": "topic_inputs",
    "lockstep": "lockstep",
    "gravity": "gravity",
    "spacecraft.wheels.name": "spacecraft.wheels",
    "spacecraft.wheels.axis": "spacecraft.wheels",
    "spacecraft.wheels.inertia": "spacecraft.wheels",
    "spacecraft.wheels.max_torque": "spacecraft.wheels",
    "spacecraft.wheels.max_speed": "spacecraft.wheels",
    "spacecraft.wheels.initial_speed": "spacecraft.wheels",
    "spacecraft.wheels.coulomb": "spacecraft.wheels.friction",
    "spacecraft.wheels.viscous": "spacecraft.wheels.friction",
    "spacecraft.wheels.stiction_speed": "spacecraft.wheels.friction",
    "spacecraft.wheel_schedule": "spacecraft.wheel_schedule",
    "spacecraft.gravity_gradient": "spacecraft.gravity_gradient",
    "spacecraft.rods.name": "spacecraft.magnetorquers",
    "spacecraft.rods.axis": "spacecraft.magnetorquers",
    "spacecraft.rods.max_dipole": "spacecraft.magnetorquers",
    "spacecraft.rods.magnetometer_coupling": "spacecraft.magnetorquers.coupling",
    "spacecraft.residual_dipole": "spacecraft.magnetorquers",
    "joint_state_topics": "joint_state_topics",
    "sensors.gyro": "sensors.gyro",
    "sensors.star_tracker": "sensors.star_tracker",
    "sensors.magnetometer": "sensors.magnetometer",
    "orbit": "orbit",
    "magnetic_field": "environment.magnetic_field",
    "epoch": "environment.magnetic_field",  # the field's date and the Earth's rotation angle
}

#: Scene fields that act on no state -> why.
SETTINGS: Mapping[str, str] = {
    "name": "a label",
    "description": "a label",
    "source": "where the scene was read from",
    "text": "the YAML as given",
    "body.given_as": "how the inertia was written (body.inertia holds it)",
    "body.masses": "the point masses the inertia came from (body.inertia holds it)",
    "body.positions": "the point masses the inertia came from (body.inertia holds it)",
    "frames": "names of the frames",
    "integrator": "the numerics: each path runs its method and step (the engine the scene's, the sweep its grid)",
    "duration": "how long a path runs (the sweep's spec may set its own)",
    "real_time_factor": "wall-clock pacing of the node",
    "outputs": "publication rates of the node",
    "qos": "QoS of the node's outputs",
    "recording": "where the node records",
    "foxglove": "a node's live viewer",
    "web": "a node's live viewer",
    "commands": "limits on the commands a running node receives (topic_inputs, ~/apply_torque)",
    "simulation_interfaces_namespace": "where the node serves simulation_interfaces",
    "sensors.seed": "the seed of the sensors' noise (drawn only for the sensors)",
}

_ALL = frozenset(FEATURES)
#: What no path runs yet: the rods' field at the magnetometer (the engine's magnetometer reads the Earth's alone).
_WAITING = frozenset({"spacecraft.magnetorquers.coupling"})
_SWEEP = frozenset(
    {
        "body",
        "initial",
        "schedules.body",
        "schedules.world",
        "spacecraft.wheels",  # these four: the engine per sample (sweep/engine_runs.py)
        "spacecraft.wheels.friction",
        "spacecraft.wheel_schedule",
        "spacecraft.gravity_gradient",
        "orbit",  # the gravity gradient on it: the engine per sample; dispersions.orbit_phase
        "environment.magnetic_field",  # acts on no state: the metric final_field_* (T, body); dispersions.epoch
        *MEASUREMENTS,  # no sensor columns: the bodies' states do not depend on them
    }
)

#: What each path runs (a feature outside its set is refused by :func:`refuse_unhonoured`).
PATHS: Mapping[str, frozenset[str]] = {
    # the run engine, rigid_rot_sim.run.simulator.Simulator (the node and lockstep drive it)
    "engine": _ALL - _WAITING,
    # rigid_rot_sim.recording.resim: the engine fed the recorded commands and seeds
    "resim": _ALL - _WAITING,
    # rigid_rot_sim.sweep: the batch kernels, the engine per sample where none applies
    "sweep": _SWEEP,
    # core.simulate.simulate / simulate_gyrostat: what a scene maps onto their arguments with the engine's bits
    # (a schedule is not one: their torque is constant or a callable evaluated within the step)
    "simulate": frozenset(
        {
            "body",
            "initial",
            "spacecraft.wheels",
            "spacecraft.wheels.friction",
            "spacecraft.wheel_schedule",  # wheel_torque=segments
            "spacecraft.gravity_gradient",  # orbit=
            "orbit",  # orbit=core.wheels.kepler_orbit_model(scene.orbit), the gradient's orbit
            "environment.magnetic_field",  # acts on no state (a torque that reads it is its own feature)
            *MEASUREMENTS,
        }
    ),
}


def features_of(scene: Scene) -> tuple[str, ...]:
    """The features (scene keys, :data:`FEATURES` order) that ``scene`` uses."""
    return tuple(key for key, used in FEATURES.items() if used(scene))


def refuse_unhonoured(scene: Scene, path: str) -> None:
    """ValueError naming the first feature of ``scene`` that ``path`` (a key of :data:`PATHS`) does not run."""
    honoured = PATHS[path]
    for key in features_of(scene):
        if key not in honoured:
            runs = ", ".join(key for key in FEATURES if key in honoured and key not in ("body", "initial"))
            raise ValueError(f"{key}: not run by the {path} path (scene {scene.name}; it runs {runs or 'no source'})")
