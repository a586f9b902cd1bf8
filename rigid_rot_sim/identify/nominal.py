"""The nominal inertia to compare against: from a body YAML, a scene YAML or a recorded scene."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from rigid_rot_sim.scene.bounded_yaml import load_input, read_input
from rigid_rot_sim.scene.scene import parse_body, parse_scene, parse_scene_text
from rigid_rot_sim.share import resolve_scene


def load_nominal(path_or_name: str | os.PathLike[str]) -> np.ndarray:
    """The tensor of a body YAML (``config/bodies`` style, or a ``body:`` section), a scene YAML or a shipped scene.

    Read as a scene is read (:mod:`rigid_rot_sim.scene.bounded_yaml`, then
    :func:`~rigid_rot_sim.scene.scene.parse_scene` or :func:`~rigid_rot_sim.scene.scene.parse_body`)."""
    path = Path(path_or_name)
    if not path.is_file():
        try:
            path = Path(resolve_scene(str(path_or_name)))
        except ValueError:
            raise ValueError(f"--nominal: no such file or shipped scene: {path_or_name}") from None
    source = f"--nominal {path}"
    text = read_input(str(path), "--nominal", ValueError)
    data = load_input(text, source, ValueError)
    if not isinstance(data, dict):
        raise ValueError(f"{source}: expected a mapping")
    if "body" in data and "initial" in data:
        return parse_scene(data, source=str(path), text=text).body.inertia_array
    body = data.get("body", data)
    if "masses" in body and "point_masses" not in body:  # a bare point_masses block
        body = {"point_masses": body}
    return parse_body(body, source).inertia_array


def recorded_nominal(scene_text: str | None) -> np.ndarray | None:
    """The recorded scene's tensor, or None."""
    if not scene_text:
        return None
    return parse_scene_text(scene_text, source="<recorded scene>").body.inertia_array
