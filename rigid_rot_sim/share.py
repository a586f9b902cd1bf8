"""Where the package's installed files are: the ament index, with the checkout as fallback.

``make setup`` installs the share directory (package.xml, config/, launch/) and the ament
index marker into the venv; ``colcon build`` installs the same from setup.py's data_files.
:func:`share_directory` asks the ament index first (``get_package_share_directory``), so the
scenes of an installed package are found wherever it is installed; a source checkout that
was never installed (development) falls back to the checkout itself.

:func:`ensure_ament_prefix_path` lets the console scripts work without activating the venv:
when the interpreter's prefix holds an ament index that lists rigid_rot_sim but
``AMENT_PREFIX_PATH`` does not name it, the prefix is appended (a sourced ROS keeps
precedence), as ``. .venv/bin/activate`` would have done.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

PACKAGE = "rigid_rot_sim"
CHECKOUT = Path(__file__).resolve().parents[1]


def _indexed_prefix() -> Path | None:
    prefix = Path(sys.prefix)
    marker = prefix / "share" / "ament_index" / "resource_index" / "packages" / PACKAGE
    return prefix if marker.is_file() else None


def ensure_ament_prefix_path() -> None:
    """Add the interpreter's prefix to ``AMENT_PREFIX_PATH`` when it is an installed prefix not listed."""
    prefix = _indexed_prefix()
    if prefix is None:
        return
    entries = [entry for entry in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if entry]
    if any(Path(entry).resolve() == prefix.resolve() for entry in entries):
        return
    os.environ["AMENT_PREFIX_PATH"] = os.pathsep.join([*entries, str(prefix)])


def share_directory() -> Path:
    """The package's share directory from the ament index, else the checkout (development)."""
    ensure_ament_prefix_path()
    try:
        from ament_index_python.packages import PackageNotFoundError, get_package_share_directory
    except ImportError:
        return CHECKOUT
    try:
        return Path(get_package_share_directory(PACKAGE))
    except (PackageNotFoundError, LookupError, ValueError, OSError):  # not installed; ValueError: no prefix path set
        return CHECKOUT


def scene_search_dirs() -> list[Path]:
    """Where scene names are looked up: the installed config/scenes, then the checkout's."""
    dirs = [share_directory() / "config" / "scenes", CHECKOUT / "config" / "scenes"]
    return list(dict.fromkeys(dirs))


def resolve_scene(scene: str) -> str:
    """A scene path (returned absolute) or a shipped scene's name; ValueError if neither exists."""
    if os.path.isfile(scene):
        return os.path.abspath(scene)
    name = scene if scene.endswith(".yaml") else scene + ".yaml"
    if os.sep not in name:
        for directory in scene_search_dirs():
            candidate = directory / name
            if candidate.is_file():
                return str(candidate)
    shipped = sorted({p.stem for d in scene_search_dirs() if d.is_dir() for p in d.glob("*.yaml")})
    raise ValueError(f"scene {scene!r} not found (a path, or one of: {', '.join(shipped) or 'none shipped'})")
