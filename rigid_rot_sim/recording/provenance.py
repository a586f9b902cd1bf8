"""Versions of the package and its dependencies, stored with every recording."""

from __future__ import annotations

import platform
import sys
from importlib import metadata
from pathlib import Path

from rigid_rot_sim import __version__

# Python distributions whose versions decide the numbers or the file format.
DISTRIBUTIONS = (
    "numpy", "scipy", "mcap", "mcap-ros2-support", "PyYAML",
    "ros-rclpy", "ros-rmw-fastrtps-cpp", "ros-common-interfaces",
)


def _interface_package_version(package: str) -> str:
    """Version from ``share/<package>/package.xml`` of the installed interface package."""
    path = Path(sys.prefix) / "share" / package / "package.xml"
    try:
        text = path.read_text(encoding="utf-8")
    except OSError:
        return "not installed"
    start = text.find("<version>")
    end = text.find("</version>")
    return text[start + len("<version>"):end].strip() if 0 <= start < end else "unknown"


def package_versions() -> dict[str, str]:
    """{name: version} of rigid_rot_sim, rigid_rot_msgs, Python, the platform and DISTRIBUTIONS."""
    versions = {
        "rigid_rot_sim": __version__,
        "rigid_rot_msgs": _interface_package_version("rigid_rot_msgs"),
        "python": platform.python_version(),
        "platform": platform.platform(),
    }
    for name in DISTRIBUTIONS:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions
