"""Packaging of rigid_rot_sim: an ament_python package that is also a plain pip package."""

import glob
import os

from setuptools import find_packages, setup

package_name = "rigid_rot_sim"


def config_data_files():
    """(install dir, [files]) for every file under config/, keeping the tree."""
    entries = []
    for directory, _, files in sorted(os.walk("config")):
        paths = sorted(os.path.join(directory, name) for name in files)
        if paths:
            entries.append((os.path.join("share", package_name, directory), paths))
    return entries


setup(
    name=package_name,
    version="0.1.0",
    packages=find_packages(exclude=["test", "test.*"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        ("share/" + package_name + "/launch", sorted(glob.glob("launch/*.launch.py"))),
        *config_data_files(),
    ],
    python_requires=">=3.10",
    install_requires=[
        "setuptools",
        "numpy",
        "scipy",
        "pyyaml",
        "jsonschema>=4.0",
        "numba",
        "gymnasium>=1.0",
    ],  # jsonschema: Draft 2020-12
    # sweeps (`rigid-rot sweep`, --scheduler): no rosdep keys exist for these; pip installs them
    # viewer (`--foxglove`, `rigid-rot view`): the Foxglove live server, without ROS
    # web (`--web`): the body's own web page (viser), offline, without ROS for `rigid-rot view`
    # sb3: Stable-Baselines3, for envs/sb3.py's VecEnv adapter (it pulls in torch; the adapter works without it)
    extras_require={
        "sweep": ["dask[distributed]", "pyarrow"],
        "viewer": ["foxglove-sdk"],
        "web": ["viser"],
        "sb3": ["stable-baselines3"],
    },
    zip_safe=True,
    maintainer="rigid_rot_sim maintainers",
    maintainer_email="maintainers@rigid-rot-sim.org",
    description="Rigid-body rotation simulator for ROS 2 with a pure numerical core.",
    license="Apache-2.0",
    tests_require=["pytest", "hypothesis", "rosbags", "mpmath", "geomaglib"],
    entry_points={
        "console_scripts": [
            "rigid-rot = rigid_rot_sim.console_scripts:rigid_rot",
            "rigid_rot_sim_node = rigid_rot_sim.console_scripts:rigid_rot_sim_node",
            "rigid-rot-controller = rigid_rot_sim.console_scripts:rigid_rot_controller",
        ],
    },
)
