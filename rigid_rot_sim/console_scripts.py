"""The console scripts (``rigid-rot``, ``rigid_rot_sim_node``): the library path first, then the command.

In a ROS-from-PyPI venv, ``ros-wheels-bootstrapper`` (a .pth file) re-executes every Python
start once with ``LD_LIBRARY_PATH`` extended by ``<venv>/lib`` (where ``make setup`` installs
``librigid_rot_msgs__*.so`` and the vendored interface libraries) and the wheels' ``ros_*.libs``
folders, and sets ``_ROS_WHEELS_BOOTSTRAP_COMPLETE=1`` so that it does not do it again. A
process of *another* such venv (a test harness, a controller in its own venv) exports both
to its children: a console script of this venv started from there skips its own bootstrap and
dies with ``ImportError: librigid_rot_msgs__rosidl_generator_py.so: cannot open shared object
file``. The dynamic loader reads ``LD_LIBRARY_PATH`` only when a process starts, so
:func:`ensure_library_path` re-executes the script (same pid, as the bootstrapper does) with
this venv's folders put first, when they are missing, before anything imports a ROS library.

It does nothing outside a ROS-from-PyPI venv (an apt or colcon install finds its libraries
through the sourced setup files or the system's paths) and re-executes at most once
(``_RIGID_ROT_LIBRARY_PREFIX``). Every console script of ``setup.py`` goes through here
(``test/test_console_scripts.py`` checks it).
"""

from __future__ import annotations

import importlib.util
import os
import sys
from collections.abc import Mapping
from pathlib import Path

#: Set to ``sys.prefix`` on the re-executed process, so that it never loops.
REEXEC_GUARD = "_RIGID_ROT_LIBRARY_PREFIX"


def library_dirs(prefix: str = sys.prefix) -> list[str]:
    """The folders the bootstrapper of the venv at ``prefix`` puts on ``LD_LIBRARY_PATH``.

    Empty when ``prefix`` is not a ROS-from-PyPI venv (no ``ros_wheels_bootstrapper`` in it).
    """
    spec = importlib.util.find_spec("ros_wheels_bootstrapper")
    origin = spec.origin if spec is not None else None
    if origin is None or not origin.startswith(os.path.join(prefix, "")):
        return []
    site_packages = Path(origin).resolve().parents[1]
    dirs = [os.path.join(prefix, "lib")]
    dirs += sorted(str(p.resolve()) for p in site_packages.glob("ros_*.libs") if p.is_dir())
    return dirs


def missing_library_dirs(environ: Mapping[str, str], prefix: str = sys.prefix) -> list[str]:
    """This venv's library folders that ``environ``'s ``LD_LIBRARY_PATH`` lacks."""
    present: set[str] = set()
    for part in environ.get("LD_LIBRARY_PATH", "").split(os.pathsep):
        if part:
            present.update((part.rstrip("/"), os.path.realpath(part)))
    return [d for d in library_dirs(prefix) if d.rstrip("/") not in present and os.path.realpath(d) not in present]


def ensure_library_path() -> None:
    """Re-execute this process with this venv's library folders first when they are missing (Linux)."""
    if not sys.platform.startswith("linux") or os.environ.get(REEXEC_GUARD) == sys.prefix:
        return
    missing = missing_library_dirs(os.environ)
    if not missing:
        return
    environ = dict(os.environ)
    rest = [p for p in environ.get("LD_LIBRARY_PATH", "").split(os.pathsep) if p and p not in missing]
    environ["LD_LIBRARY_PATH"] = os.pathsep.join(library_dirs() + [p for p in rest if p not in library_dirs()])
    environ["_ROS_WHEELS_BOOTSTRAP_COMPLETE"] = "1"
    environ[REEXEC_GUARD] = sys.prefix
    sys.stdout.flush()
    sys.stderr.flush()
    os.execve(sys.executable, sys.orig_argv, environ)


def ensure_kernels() -> None:
    """Before a node starts: compile the kernels if this install never did (a colcon build), saying so."""
    from rigid_rot_sim.core.precompile import ensure_compiled

    spent = ensure_compiled(lambda text: print(f"[rigid_rot_sim] {text}", file=sys.stderr, flush=True))
    if spent:
        print(f"[rigid_rot_sim] kernels compiled in {spent:.1f} s; starting", file=sys.stderr, flush=True)


def rigid_rot() -> int:
    """``rigid-rot``: :func:`rigid_rot_sim.cli.main` (``run`` starts a node: the kernels first)."""
    ensure_library_path()
    if sys.argv[1:2] == ["run"]:
        ensure_kernels()
    from rigid_rot_sim.cli import main

    return main()


def rigid_rot_sim_node() -> int:
    """``rigid_rot_sim_node``: :func:`rigid_rot_sim.ros.node.main` (the kernels compiled first if never)."""
    ensure_library_path()
    ensure_kernels()
    from rigid_rot_sim.ros.node import main

    return main()


def rigid_rot_controller() -> int:
    """``rigid-rot-controller``: :func:`rigid_rot_sim.ros.controller.main`."""
    ensure_library_path()
    from rigid_rot_sim.ros.controller import main

    return main()
