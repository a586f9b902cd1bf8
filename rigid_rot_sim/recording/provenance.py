"""Versions of the package and its dependencies, stored with every recording."""

from __future__ import annotations

import hashlib
import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path

from rigid_rot_sim import __version__

# Python distributions whose versions decide the numbers or the file format.
DISTRIBUTIONS = (
    "numpy",
    "scipy",
    "mcap",
    "mcap-ros2-support",
    "PyYAML",
    "ros-rclpy",
    "ros-rmw-fastrtps-cpp",
    "ros-common-interfaces",
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
    return text[start + len("<version>") : end].strip() if 0 <= start < end else "unknown"


_PACKAGE_DIR = Path(__file__).resolve().parents[1]


def core_fingerprint() -> str:
    """SHA-256 over the sources of ``rigid_rot_sim.core`` (paths and contents).

    The package version does not change with every edit; this does, so a re-simulation
    can tell "the numbers changed because the numerical code changed" from a real mismatch.
    """
    digest = hashlib.sha256()
    core = _PACKAGE_DIR / "core"
    for path in sorted(core.rglob("*.py")):
        digest.update(str(path.relative_to(core)).encode())
        digest.update(b"\0")
        digest.update(path.read_bytes())
        digest.update(b"\0")
    return digest.hexdigest()


def source_revision() -> str:
    """``git <sha>`` (``+modified`` with uncommitted changes) of the checkout, or ``unknown``."""
    try:
        sha = subprocess.run(
            ["git", "-C", str(_PACKAGE_DIR), "rev-parse", "--short=12", "HEAD"],
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        ).stdout.strip()
        changed = subprocess.run(
            ["git", "-C", str(_PACKAGE_DIR), "status", "--porcelain", "--untracked-files=no", "--", "."],
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return f"git {sha}" + (" +modified" if changed else "")


def package_versions() -> dict[str, str]:
    """{name: version} of rigid_rot_sim (version, source revision, core fingerprint),
    rigid_rot_msgs, Python, the platform and DISTRIBUTIONS."""
    versions = {
        "rigid_rot_sim": __version__,
        "rigid_rot_sim.revision": source_revision(),
        "rigid_rot_sim.core_sha256": core_fingerprint(),
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
