"""A plain ``colcon build`` at the root of the checkout finds both packages (issue 40).

rigid_rot_msgs sits inside the root package (the fixed layout) and colcon does not look inside a
folder it identified as a package; ``colcon_defaults.yaml`` (colcon-defaults' workspace file) names
both base paths. Checked with the real colcon (the Makefile's COLCON_PINS, pip-installed into a
throwaway venv: never into .venv), on ``colcon list``, which discovers as ``colcon build`` does.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGE_FILES = ("package.xml", "setup.py", "setup.cfg", "resource", "rigid_rot_msgs")

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def colcon(tmp_path_factory) -> Path:
    pins = subprocess.run(
        ["make", "-s", "-C", str(REPO), "print-colcon-pins"], capture_output=True, text=True, check=True
    ).stdout.split()
    venv = tmp_path_factory.mktemp("colcon") / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    subprocess.run(  # this interpreter's pip, installing into the throwaway venv
        [sys.executable, "-m", "pip", "install", "-q", "--disable-pip-version-check", "--target",
         str(next((venv / "lib").glob("python*")) / "site-packages"), *pins],
        check=True, timeout=600,
    )  # fmt: skip
    return venv


def listed(colcon: Path, root: Path) -> list[str]:
    """``colcon list`` run in ``root``: the names of the packages it discovers."""
    done = subprocess.run(
        [str(colcon / "bin" / "python"), "-m", "colcon", "--log-base", "/dev/null", "list", "--names-only"],
        cwd=root, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return sorted(done.stdout.split())


def test_a_plain_colcon_list_at_the_root_finds_both_packages(colcon, tmp_path):
    assert listed(colcon, REPO) == ["rigid_rot_msgs", "rigid_rot_sim"]
    # without the defaults file: the failure it prevents (only the root package)
    for name in PACKAGE_FILES:
        source = REPO / name
        (shutil.copytree if source.is_dir() else shutil.copy)(source, tmp_path / name)
    assert listed(colcon, tmp_path) == ["rigid_rot_sim"]
    shutil.copy(REPO / "colcon_defaults.yaml", tmp_path)
    assert listed(colcon, tmp_path) == ["rigid_rot_msgs", "rigid_rot_sim"]
