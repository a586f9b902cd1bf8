"""package.xml declares a rosdep key for every import of the package (and of its tests).

The imports are read from the source with ``ast`` (every ``import`` statement, guarded ones
included: an optional dependency is still one that rosdep should install), mapped to rosdep
keys, and compared with the manifest's ``exec_depend`` (``test_depend`` too for the tests).
A new third-party import fails here until it is mapped to its rosdep key below and declared.
"""

from __future__ import annotations

import ast
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Python modules -> the rosdep keys that provide them (any one of them may be declared).
#: mcap: issue 10 replaces the python3-*-pip keys, which rosdistro lacks, by mcap-ros2-support
#: (its pip package pulls in mcap): either form is accepted here.
PYTHON_KEYS: dict[str, set[str]] = {
    "numpy": {"python3-numpy"},
    "scipy": {"python3-scipy"},
    "yaml": {"python3-yaml"},
    "jsonschema": {"python3-jsonschema"},
    "matplotlib": {"python3-matplotlib"},
    "tqdm": {"python3-tqdm"},
    "mcap": {"python3-mcap-pip", "mcap-ros2-support"},
    "mcap_ros2": {"python3-mcap-ros2-support-pip", "mcap-ros2-support"},
    "pytest": {"python3-pytest"},
    "hypothesis": {"python3-hypothesis"},
    "rosbags": {"python3-rosbags-pip"},
    "websockets": {"python3-websockets"},
    "mpmath": {"python3-mpmath"},
    "numba": {"python3-numba"},
    "gymnasium": {"python3-gymnasium-pip"},
    "catkin_pkg": {"python3-catkin-pkg", "python3-catkin-pkg-modules"},
    "setuptools": {"python3-setuptools"},
}
#: Modules without any rosdep key (rosdistro's python.yaml has no dask, distributed or pyarrow):
#: optional, for sweeps only; declared for pip as setup.py's `sweep` extra, installed by make setup.
#: psutil (used by the distributed-sweep tests) is a dependency of distributed. foxglove-sdk and viser: the
#: viewer and web extras (no rosdep keys either). geomaglib: NOAA's reference IGRF/WMM code, a test's reference only
#: (test/core/test_geomagnetic.py; setup.py's tests_require, the Makefile's TEST_PINS).
PIP_ONLY = {
    "dask": "dask[distributed]",
    "distributed": "dask[distributed]",
    "psutil": "dask[distributed]",
    "pyarrow": "pyarrow",
    "foxglove": "foxglove-sdk",
    "viser": "viser",
    "geomaglib": "geomaglib",
    # envs/sb3.py's adapter subclasses Stable-Baselines3's VecEnv when it is installed (it pulls in torch: an extra)
    "stable_baselines3": "stable-baselines3",
}
#: ROS packages imported as Python modules: the key is the package name.
ROS_PACKAGES = {
    "rclpy",
    "rcl_interfaces",
    "builtin_interfaces",
    "geometry_msgs",
    "std_msgs",
    "std_srvs",
    "sensor_msgs",
    "nav_msgs",
    "rosgraph_msgs",
    "tf2_msgs",
    "simulation_interfaces",
    "diagnostic_msgs",
    "rigid_rot_msgs",
    "rosidl_generator_type_description",
    "ament_index_python",
    "launch",
    "launch_ros",
    "visualization_msgs",
}
#: Needed at run time without an import: diagnostic_msgs' .msg is read from share/ (recording/events.py).
DATA_DEPENDENCIES = {"diagnostic_msgs"}


def imported_modules(directory: Path) -> set[str]:
    """Top-level names of every absolute import under ``directory``, standard library excluded."""
    found: set[str] = set()
    for path in directory.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
            if isinstance(node, ast.Import):
                found.update(alias.name.split(".")[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                found.add(node.module.split(".")[0])
    return {name for name in found if name not in sys.stdlib_module_names}


def declared(*tags: str) -> set[str]:
    manifest = ET.parse(ROOT / "package.xml").getroot()
    return {element.text.strip() for tag in tags for element in manifest.iter(tag)}


def undeclared(modules: set[str], keys: set[str], own: set[str]) -> list[str]:
    """Modules whose rosdep key is not among ``keys`` (with the reason)."""
    problems = []
    for module in sorted(modules - own):
        if module in ROS_PACKAGES:
            if module not in keys:
                problems.append(f"{module}: add <exec_depend>{module}</exec_depend>")
        elif module in PIP_ONLY:
            if f'"{PIP_ONLY[module]}"' not in (ROOT / "setup.py").read_text(encoding="utf-8"):
                problems.append(f"{module}: no rosdep key; name {PIP_ONLY[module]!r} in setup.py's extras_require")
        elif module in PYTHON_KEYS:
            if not PYTHON_KEYS[module] & keys:
                problems.append(f"{module}: declare one of {sorted(PYTHON_KEYS[module])}")
        else:
            problems.append(
                f"{module}: not mapped to a rosdep key (add it to PYTHON_KEYS or ROS_PACKAGES, then declare it)"
            )
    return problems


def test_every_import_of_the_package_has_an_exec_depend():
    modules = imported_modules(ROOT / "rigid_rot_sim")
    assert {"rclpy", "numpy", "mcap", "simulation_interfaces", "tf2_msgs"} <= modules  # the scan finds them
    keys = declared("exec_depend", "depend")
    assert undeclared(modules, keys, own={"rigid_rot_sim"}) == []
    assert DATA_DEPENDENCIES <= keys


def test_every_import_of_the_tests_has_a_test_or_exec_depend():
    modules = imported_modules(ROOT / "test")
    own = {"rigid_rot_sim"} | {p.stem for p in (ROOT / "test").rglob("*.py")}  # helpers imported by path
    keys = declared("exec_depend", "depend", "test_depend")
    assert undeclared(modules, keys, own=own) == []


def test_an_undeclared_import_is_reported():
    assert undeclared({"numpy", "sensor_msgs", "pandas"}, {"python3-numpy"}, own=set()) == [
        "pandas: not mapped to a rosdep key (add it to PYTHON_KEYS or ROS_PACKAGES, then declare it)",
        "sensor_msgs: add <exec_depend>sensor_msgs</exec_depend>",
    ]
