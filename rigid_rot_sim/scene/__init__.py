"""Input formats: scene files read within limits (PyYAML), checked against JSON Schemas (jsonschema).

* :mod:`.scene` - :class:`~.scene.Scene` and :func:`~.scene.load_scene`, the YAML description of one run;
* :mod:`.scene_schema` - the scene format as one JSON Schema, the output table;
* :mod:`.schema` - schema helpers and jsonschema errors as one-line English;
* :mod:`.bounded_yaml` - YAML read within size and depth limits, without aliases;
* :mod:`.names` - ROS topic and frame names checked as ROS checks them (no ROS import).

Built on :mod:`rigid_rot_sim.core` (limits, inertia, the integrator registry); imports nothing
from :mod:`rigid_rot_sim.run` or above.
"""

from rigid_rot_sim.scene.scene import Scene, SceneError, load_scene, parse_scene, parse_scene_text

__all__ = ["Scene", "SceneError", "load_scene", "parse_scene", "parse_scene_text"]
