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
