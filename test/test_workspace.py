"""The venv as a sourced ROS 2 workspace (``make setup``) and the installed share directory.

``. .venv/bin/activate`` sets AMENT_PREFIX_PATH (prepended) & co. and ``deactivate`` restores
them; the ament index finds rigid_rot_sim and rigid_rot_msgs; the console scripts work without
activation and find the shipped scenes through the index; setup.py's data_files hold what a
colcon install needs.
"""

import os
import runpy
import subprocess
import sys
from pathlib import Path

import pytest
import setuptools

from rigid_rot_sim import share

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
PREFIX = Path(sys.prefix)
PRINT_SHARES = (
    "from ament_index_python.packages import get_package_share_directory as g; "
    "print(g('rigid_rot_sim')); print(g('rigid_rot_msgs'))"
)


def clean_env(**extra: str) -> dict[str, str]:
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH", "ROS_DISTRO", "VIRTUAL_ENV")
    }
    return {**env, **extra}


def bash(script: str, **extra: str) -> list[str]:
    done = subprocess.run(
        ["bash", "-c", script], env=clean_env(**extra), capture_output=True, text=True, timeout=120, cwd=ROOT
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout.splitlines()


def test_activate_makes_a_sourced_workspace_and_deactivate_restores_it():
    activate = PREFIX / "bin" / "activate"
    lines = bash(
        f'. "{activate}" && python -c "{PRINT_SHARES}" && echo "$AMENT_PREFIX_PATH|$ROS_DISTRO"'
        f' && . "{activate}" && echo "$AMENT_PREFIX_PATH" && deactivate'
        ' && echo "${AMENT_PREFIX_PATH-unset}|${ROS_DISTRO-unset}"',
        AMENT_PREFIX_PATH="/opt/other",
    )
    assert lines[0] == str(PREFIX / "share" / "rigid_rot_sim")
    assert lines[1] == str(PREFIX / "share" / "rigid_rot_msgs")
    assert lines[2] == f"{PREFIX}:/opt/other|jazzy"  # prepended, the previous value kept
    assert lines[3] == f"{PREFIX}:/opt/other"  # activating twice adds nothing
    assert lines[4] == "/opt/other|unset"  # deactivate restores


def test_share_directory_from_the_ament_index_holds_package_files():
    share.ensure_ament_prefix_path()
    from ament_index_python.packages import get_package_share_directory

    directory = Path(get_package_share_directory("rigid_rot_sim"))
    assert directory == PREFIX / "share" / "rigid_rot_sim" == share.share_directory()
    assert (directory / "package.xml").read_text() == (ROOT / "package.xml").read_text()
    assert (directory / "launch" / "rigid_rot_sim.launch.py").is_file()
    shipped = sorted(p.name for p in (directory / "config" / "scenes").glob("*.yaml"))
    assert shipped == sorted(p.name for p in (ROOT / "config" / "scenes").glob("*.yaml")) and shipped
    assert share.resolve_scene("heavy_top") == str(directory / "config" / "scenes" / "heavy_top.yaml")


def test_console_script_without_activation_finds_scenes_through_the_index(tmp_path):
    rigid_rot = PREFIX / "bin" / "rigid-rot"
    done = subprocess.run(
        [str(rigid_rot), "run", "free_tumble", "--duration", "0.1", "--realtime-factor", "0"],
        env=clean_env(),
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert f"({PREFIX / 'share' / 'rigid_rot_sim' / 'config' / 'scenes' / 'free_tumble.yaml'})" in done.stderr
    unknown = subprocess.run(
        [str(rigid_rot), "run", "no_such_scene"],
        env=clean_env(),
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert unknown.returncode == 2 and "heavy_top" in unknown.stderr and len(unknown.stderr.strip().splitlines()) == 1


def test_setup_py_installs_share_files_for_colcon(monkeypatch):
    captured = {}
    monkeypatch.setattr(setuptools, "setup", lambda **kwargs: captured.update(kwargs))
    monkeypatch.chdir(ROOT)
    runpy.run_path(str(ROOT / "setup.py"))
    files = {os.path.join(directory, os.path.basename(f)) for directory, names in captured["data_files"] for f in names}
    assert "share/ament_index/resource_index/packages/rigid_rot_sim" in files
    assert "share/rigid_rot_sim/package.xml" in files
    assert "share/rigid_rot_sim/launch/rigid_rot_sim.launch.py" in files
    assert {f"share/rigid_rot_sim/config/scenes/{p.name}" for p in (ROOT / "config" / "scenes").glob("*.yaml")} <= files


# ------------------------------------------------------------------ ros2 run / ros2 launch (upstream logic)
# ros2cli and launch_ros are not on PyPI: their lookups are re-implemented here as upstream writes them
# (ros2/ros2cli ros2pkg/api/__init__.py get_executable_paths; ros2/launch_ros ros2launch/api/api.py
# get_share_file_path_from_package), and what they find is run as `ros2 run` runs it (the path, then argv).


def upstream_executable_paths(package_name: str) -> list[str]:
    """``ros2pkg.api.get_executable_paths``: executable files under ``<prefix>/lib/<package>`` (os.walk)."""
    from ament_index_python import get_package_prefix

    base_path = os.path.join(get_package_prefix(package_name), "lib", package_name)
    executable_paths = []
    for dirpath, dirnames, filenames in os.walk(base_path):
        dirnames[:] = [d for d in dirnames if d[0] not in ["."]]
        dirnames.sort()
        for filename in sorted(filenames):
            path = os.path.join(dirpath, filename)
            if os.access(path, os.X_OK):
                executable_paths.append(path)
    return executable_paths


def upstream_share_file_paths(package_name: str, file_name: str) -> list[str]:
    """``ros2launch.api.get_share_file_path_from_package``'s matches: an os.walk of the share directory
    (which does not follow a symlinked directory)."""
    from ament_index_python.packages import get_package_share_directory

    matching = []
    for root, _, files in os.walk(get_package_share_directory(package_name)):
        matching += [os.path.join(root, name) for name in files if name == file_name]
    return matching


def test_ros2_run_finds_every_console_script_and_runs_the_node(tmp_path):
    share.ensure_ament_prefix_path()
    paths = upstream_executable_paths("rigid_rot_sim")
    assert sorted(os.path.basename(p) for p in paths) == ["rigid-rot", "rigid-rot-controller", "rigid_rot_sim_node"]
    (node,) = [p for p in paths if os.path.basename(p) == "rigid_rot_sim_node"]
    assert Path(node).parent == PREFIX / "lib" / "rigid_rot_sim"
    # `ros2 run rigid_rot_sim rigid_rot_sim_node --ros-args ...`: the found path with the arguments, from anywhere
    done = subprocess.run(
        [node, "--ros-args", "-p", "scene:=free_tumble", "-p", "duration:=0.05", "-p", "real_time_factor:=0.0"],
        env=clean_env(AMENT_PREFIX_PATH=str(PREFIX)),
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "duration reached" in done.stderr


def test_ros2_launch_finds_the_launch_file_and_the_params_file_in_the_share_directory(tmp_path):
    share.ensure_ament_prefix_path()
    (launch_file,) = upstream_share_file_paths("rigid_rot_sim", "rigid_rot_sim.launch.py")
    assert Path(launch_file).read_text() == (ROOT / "launch" / "rigid_rot_sim.launch.py").read_text()
    (params_file,) = upstream_share_file_paths("rigid_rot_sim", "example.yaml")
    for name in ("launch", "config", "config/scenes"):  # real directories: os.walk descends into them
        directory = PREFIX / "share" / "rigid_rot_sim" / name
        assert directory.is_dir() and not directory.is_symlink(), name
    shipped = {p.name for p in (ROOT / "config" / "scenes").glob("*.yaml")}
    for scene in shipped:
        assert upstream_share_file_paths("rigid_rot_sim", scene), scene
    # the shipped params file names its scene by name: it works from any directory
    node = PREFIX / "bin" / "rigid_rot_sim_node"
    done = subprocess.run(
        [str(node), "--ros-args", "--params-file", params_file, "-p", "duration:=0.05", "-p", "real_time_factor:=0.0"],
        env=clean_env(),
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "scene 'torque_driven'" in done.stderr
    assert str(PREFIX / "share" / "rigid_rot_sim" / "config" / "scenes" / "torque_driven.yaml") in done.stderr


def test_install_workspace_lays_out_links_per_file_and_removes_stale_ones(tmp_path):
    tools = runpy.run_path(str(ROOT / "tools" / "install_workspace.py"))
    checkout, prefix = tmp_path / "checkout", tmp_path / "prefix"
    (checkout / "config" / "scenes").mkdir(parents=True)
    (checkout / "config" / "scenes" / "a.yaml").write_text("a")
    (checkout / "launch").mkdir()
    (checkout / "launch" / "x.launch.py").write_text("x")
    (checkout / "package.xml").write_text("<package/>")
    (checkout / "resource").mkdir()
    (checkout / "resource" / "rigid_rot_sim").write_text("")
    (prefix / "bin").mkdir(parents=True)
    (prefix / "bin" / "activate").write_text("deactivate () {\n    true\n}\n")
    (prefix / "bin" / "tool").write_text("#!/bin/sh\n")
    (prefix / "bin" / "tool").chmod(0o755)
    # an older set-up: a link per directory, which os.walk does not descend into
    (prefix / "share" / "rigid_rot_sim").mkdir(parents=True)
    (prefix / "share" / "rigid_rot_sim" / "config").symlink_to(checkout / "config")
    tools["install"](checkout, prefix, ["tool"])
    shared = prefix / "share" / "rigid_rot_sim"
    assert (shared / "config").is_dir() and not (shared / "config").is_symlink()
    assert (shared / "config" / "scenes" / "a.yaml").is_symlink()
    assert (shared / "config" / "scenes" / "a.yaml").read_text() == "a"
    walked = [name for _, _, files in os.walk(shared) for name in files]
    assert sorted(walked) == ["a.yaml", "package.xml", "x.launch.py"]
    assert os.access(prefix / "lib" / "rigid_rot_sim" / "tool", os.X_OK)
    (checkout / "config" / "scenes" / "a.yaml").unlink()  # gone from the checkout: gone from the share directory
    (checkout / "config" / "scenes" / "b.yaml").write_text("b")
    tools["install"](checkout, prefix, ["tool"])
    assert sorted(p.name for p in (shared / "config" / "scenes").iterdir()) == ["b.yaml"]
