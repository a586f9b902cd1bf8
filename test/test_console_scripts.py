"""The console scripts start from a process of *another* ROS-from-PyPI venv.

Such a process (a test harness, a controller in its own venv) has run its own venv's
ros-wheels-bootstrapper: it exports ``LD_LIBRARY_PATH`` with that venv's folders and
``_ROS_WHEELS_BOOTSTRAP_COMPLETE=1``, so this venv's bootstrapper skips, and
``librigid_rot_msgs__*.so`` (in this venv's ``lib``) was not found (issue 19).
``rigid_rot_sim.console_scripts`` re-executes the script with this venv's folders.

The other venv here is a real one: ``python -m venv`` with the real ``ros-wheels-bootstrapper``
(the package and its .pth, copied from this venv: the same released files pip installs) and a
``ros_*.libs`` folder of its own, so its interpreter bootstraps exactly as a ROS-from-PyPI venv
does; the scripts are started from that interpreter with the environment it then has.
"""

import ast
import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from rigid_rot_sim import console_scripts

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.prefix) / "bin"


def _console_scripts() -> list[str]:
    tree = ast.parse((ROOT / "setup.py").read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            for key, value in zip(node.keys, node.values, strict=True):
                if isinstance(key, ast.Constant) and key.value == "console_scripts":
                    return [element.value for element in value.elts]
    raise AssertionError("setup.py declares no console_scripts")


def test_every_console_script_checks_the_library_path_first():
    scripts = _console_scripts()
    assert len(scripts) >= 2
    for line in scripts:
        name, target = (part.strip() for part in line.split("="))
        module, function = target.split(":")
        assert module == "rigid_rot_sim.console_scripts", line
        assert callable(getattr(console_scripts, function)), line


def test_missing_library_dirs_reads_ld_library_path():
    ours = console_scripts.library_dirs()
    assert ours and ours[0] == os.path.join(sys.prefix, "lib")  # this test runs in the ROS-from-PyPI venv
    assert console_scripts.missing_library_dirs({"LD_LIBRARY_PATH": "/elsewhere/lib"}) == ours
    assert console_scripts.missing_library_dirs({"LD_LIBRARY_PATH": os.pathsep.join(["/x", *ours])}) == []
    assert console_scripts.library_dirs("/not/this/venv") == []


@pytest.fixture(scope="module")
def other_venv(tmp_path_factory) -> Path:
    """A second venv whose interpreter runs the real ros-wheels-bootstrapper at start-up."""
    other = tmp_path_factory.mktemp("other") / "venv"
    subprocess.run([sys._base_executable, "-m", "venv", "--without-pip", str(other)], check=True, timeout=120)
    site = Path(__import__("ros_wheels_bootstrapper").__file__).parents[1]
    other_site = next((other / "lib").glob("python3.*/site-packages"))
    shutil.copytree(site / "ros_wheels_bootstrapper", other_site / "ros_wheels_bootstrapper")
    shutil.copy2(site / "ros_wheels_bootstrapper.pth", other_site / "ros_wheels_bootstrapper.pth")
    (other_site / "ros_other.libs").mkdir()
    (other / "lib" / "libother_msgs__rosidl_generator_py.so").write_bytes(b"")  # what its make setup installs
    return other


def _from_other_venv(other: Path, command: list[str], timeout: float = 120.0) -> subprocess.CompletedProcess:
    """Run ``command`` as a child of the other venv's (bootstrapped) interpreter; its result."""
    parent = textwrap.dedent("""
        import json, os, subprocess, sys
        assert os.environ["_ROS_WHEELS_BOOTSTRAP_COMPLETE"] == "1", "the other venv did not bootstrap"
        child = subprocess.run(json.loads(sys.argv[1]), capture_output=True, text=True)
        print(json.dumps({"ld": os.environ["LD_LIBRARY_PATH"], "rc": child.returncode,
                          "out": child.stdout, "err": child.stderr}))
    """)
    environ = {
        k: v
        for k, v in os.environ.items()
        if k
        not in (
            "LD_LIBRARY_PATH",
            "_ROS_WHEELS_BOOTSTRAP_COMPLETE",
            console_scripts.REEXEC_GUARD,
            "VIRTUAL_ENV",
            "PYTHONPATH",
        )
    }
    done = subprocess.run(
        [str(other / "bin" / "python"), "-c", parent, json.dumps(command)],
        env=environ,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.splitlines()[-1])


def test_the_inherited_environment_hides_this_venvs_libraries(other_venv):
    """The issue reproduced: this venv's interpreter, started there without the fix, cannot import them."""
    load = "from rigid_rot_msgs.msg import RigidBodyState as T; type(T).__import_type_support__()"
    result = _from_other_venv(other_venv, [str(BIN / "python"), "-c", load])
    assert str(other_venv / "lib") in result["ld"].split(os.pathsep)
    assert os.path.join(sys.prefix, "lib") not in result["ld"].split(os.pathsep)
    assert result["rc"] != 0 and "librigid_rot_msgs__rosidl_generator_py.so" in result["err"]


def test_console_scripts_work_from_another_venvs_process(other_venv, tmp_path):
    # the node: imports every message package, then refuses the scene with one line (exit 2)
    node = _from_other_venv(
        other_venv, [str(BIN / "rigid_rot_sim_node"), "--ros-args", "-p", f"scene:={tmp_path / 'missing.yaml'}"]
    )
    assert "ImportError" not in node["err"], node["err"]
    assert node["rc"] == 2 and node["err"].strip().startswith("rigid_rot_sim: error:"), node["err"]
    # rigid-rot: a real run of the node over DDS (private domain: test/conftest.py), recorded
    bag = tmp_path / "run.mcap"
    run = _from_other_venv(
        other_venv,
        [
            str(BIN / "rigid-rot"),
            "run",
            "free_tumble",
            "--duration",
            "0.2",
            "--realtime-factor",
            "0",
            "--record",
            str(bag),
        ],
    )
    assert run["rc"] == 0, run["err"]
    assert bag.stat().st_size > 0
    resim = _from_other_venv(other_venv, [str(BIN / "rigid-rot"), "resim", str(bag)])
    assert resim["rc"] == 0 and "BIT-EXACT" in resim["out"], resim["out"] + resim["err"]
