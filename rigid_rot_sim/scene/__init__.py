"""Input formats: scene files read within limits (PyYAML), checked against JSON Schemas (jsonschema).

* :mod:`.scene` - :class:`~.scene.Scene` and :func:`~.scene.load_scene`, the YAML description of one run;
* :mod:`.features` - the features (torque sources, sensors) a scene uses, what each path that runs
  scenes honours, and :func:`~.features.refuse_unhonoured`, the one check of it;
* :mod:`.scene_schema` - the scene format as one JSON Schema, the output table;
* :mod:`.schema` - schema helpers and jsonschema errors as one-line English;
* :mod:`.bounded_yaml` - YAML read within size and depth limits, without aliases;
* :mod:`.names` - ROS topic and frame names checked as ROS checks them (no ROS import);
* :mod:`.spacecraft` and :mod:`.spacecraft_schema` - a spacecraft's reaction wheels, their
  torque schedule and the gravity gradient, and their schema;
* :mod:`.orbit` - the orbit, the Earth's field and the magnetometer of a scene, and their schema.

Built on :mod:`rigid_rot_sim.core` (limits, inertia, the integrator registry); imports nothing
from :mod:`rigid_rot_sim.run` or above.
"""

from __future__ import annotations

from typing import Any

__all__ = ["Scene", "SceneError", "load_scene", "parse_scene", "parse_scene_text"]


def __getattr__(name: str) -> Any:
    """The names of :mod:`.scene`, loaded on first use (``python -m rigid_rot_sim.scene.scene_schema``
    then runs the schema module without having imported it first)."""
    if name not in __all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from rigid_rot_sim.scene import scene

    return getattr(scene, name)
