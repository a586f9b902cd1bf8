"""The nominal inertia to compare against: from a body YAML, a scene YAML or a recorded scene."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from rigid_rot_sim.core.inertia import mass_properties
from rigid_rot_sim.scene.bounded_yaml import BoundedYAMLError, load_bounded, read_bounded
from rigid_rot_sim.scene.scene import parse_scene_text
from rigid_rot_sim.share import resolve_scene


def body_inertia(spec: dict[str, Any], source: str) -> np.ndarray:
    """A body section (``inertia_tensor``, ``principal_moments`` or ``point_masses``) -> (3, 3) kg*m^2."""
    if "inertia_tensor" in spec:
        tensor = np.asarray(spec["inertia_tensor"], dtype=float)
    elif "principal_moments" in spec:
        tensor = np.diag(np.asarray(spec["principal_moments"], dtype=float))
    elif "point_masses" in spec or "masses" in spec:
        masses = spec.get("point_masses", spec)
        tensor = mass_properties(masses["masses"], masses["positions"]).inertia_com
    else:
        raise ValueError(f"{source}: no inertia_tensor, principal_moments or point_masses")
    if tensor.shape != (3, 3) or not np.all(np.isfinite(tensor)):
        raise ValueError(f"{source}: the inertia must be a finite 3x3 tensor")
    return tensor


def load_nominal(path_or_name: str | os.PathLike[str]) -> np.ndarray:
    """The tensor of a body YAML (``config/bodies`` style, or a ``body:`` section), a scene YAML or a shipped scene."""
    path = Path(path_or_name)
    if not path.is_file():
        try:
            path = Path(resolve_scene(str(path_or_name)))
        except ValueError:
            raise ValueError(f"--nominal: no such file or shipped scene: {path_or_name}") from None
    try:
        data = load_bounded(read_bounded(path))  # YAML 1.2 numbers (1e-3), as the scene loader reads them
    except BoundedYAMLError as exc:
        raise ValueError(f"--nominal {path}: {exc}") from None
    if not isinstance(data, dict):
        raise ValueError(f"--nominal {path}: expected a mapping")
    if "body" in data and "initial" in data:
        return parse_scene_text(path.read_text(encoding="utf-8"), source=str(path)).body.inertia_array
    return body_inertia(data.get("body", data), f"--nominal {path}")


def recorded_nominal(scene_text: str | None) -> np.ndarray | None:
    """The recorded scene's tensor, or None."""
    if not scene_text:
        return None
    return parse_scene_text(scene_text, source="<recorded scene>").body.inertia_array
