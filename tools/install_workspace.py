"""Make the running venv a ROS 2 workspace for this checkout: ``python tools/install_workspace.py CHECKOUT``.

1. The share directory and the ament index marker that ``colcon build`` installs from setup.py's data_files
   (an editable pip install skips data_files), laid out as ``colcon build --symlink-install`` does: real
   directories holding one relative symlink per file. ``ros2 launch`` finds a launch file by an ``os.walk``
   of the share directory, which does not descend into a symlinked directory (so a link per directory
   hides every file below it); a file link is listed like a file, and its contents stay in step with the
   sources as the editable install does. Links of files no longer in the checkout are removed.
2. ``lib/rigid_rot_sim/``: a relative symlink to each of the package's console scripts in ``bin/``, where
   ``ros2 run`` looks (``get_executable_paths``: the executable files under ``<prefix>/lib/<package>``).
3. ``bin/activate`` exports AMENT_PREFIX_PATH and CMAKE_PREFIX_PATH (the venv prepended), ROS_VERSION,
   ROS_PYTHON_VERSION and ROS_DISTRO, as a sourced setup.bash does, and ``deactivate`` restores the
   previous values.

Idempotent: links already right are kept, and the block between the markers in ``bin/activate`` is
replaced, never appended twice. Run with the venv's interpreter (``make setup`` does).
"""

from __future__ import annotations

import os
import re
import shutil
import sys
from pathlib import Path

PACKAGE = "rigid_rot_sim"
#: Checkout entries linked into share/rigid_rot_sim.
SHARED = ("package.xml", "config", "launch")
#: Variables bin/activate sets: "prepend" puts the venv in front of the list, anything else is the value.
VARIABLES = (
    ("AMENT_PREFIX_PATH", "prepend"),
    ("CMAKE_PREFIX_PATH", "prepend"),
    ("ROS_VERSION", "2"),
    ("ROS_PYTHON_VERSION", "3"),
    ("ROS_DISTRO", "jazzy"),
)
BEGIN = "# >>> rigid_rot_sim workspace (make setup) >>>"
END = "# <<< rigid_rot_sim workspace <<<"
DEACTIVATE = "deactivate () {\n"


def link(target: Path, path: Path) -> None:
    """Make ``path`` a relative symlink to ``target``, replacing whatever is there (unless already right)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    relative = os.path.relpath(target, path.parent)
    if path.is_symlink() and os.readlink(path) == relative:
        return
    if path.is_symlink() or path.is_file():
        path.unlink()
    elif path.is_dir():
        shutil.rmtree(path)
    path.symlink_to(relative)


def link_tree(source: Path, target: Path) -> list[Path]:
    """Mirror ``source`` (a file or a directory) at ``target``: real directories, one relative link per file.

    Returns the links. What ``target`` held that is not in ``source`` (a stale link, an old directory
    link) is removed.
    """
    if source.is_file():
        link(source, target)
        return [target]
    if target.is_symlink() or target.is_file():
        target.unlink()  # the directory link of an older set-up
    target.mkdir(parents=True, exist_ok=True)
    wanted = {entry.name for entry in source.iterdir() if not entry.name.startswith((".", "__pycache__"))}
    for entry in target.iterdir():
        if entry.name not in wanted:
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry)
            else:
                entry.unlink()
    links = []
    for name in sorted(wanted):
        links += link_tree(source / name, target / name)
    return links


def console_scripts(package: str = PACKAGE) -> list[str]:
    """The names of the installed distribution's console scripts (setup.py's entry points)."""
    from importlib.metadata import distribution

    return sorted(e.name for e in distribution(package).entry_points if e.group == "console_scripts")


def link_executables(prefix: Path, names: list[str]) -> Path:
    """``<prefix>/lib/<package>/<name>`` -> ``<prefix>/bin/<name>`` for every console script; the directory."""
    directory = prefix / "lib" / PACKAGE
    directory.mkdir(parents=True, exist_ok=True)
    for entry in directory.iterdir():
        if entry.name not in names:
            entry.unlink()
    for name in names:
        script = prefix / "bin" / name
        if not script.is_file():
            raise SystemExit(f"setup: {script} is not installed (pip install the package first)")
        link(script, directory / name)
    return directory


def restore_lines() -> list[str]:
    """The lines that ``deactivate`` runs first: each variable back to its value before activation."""
    lines = [f"    {BEGIN}"]
    for name, _ in VARIABLES:
        old = f"_RIGID_ROT_OLD_{name}"
        lines += [
            f'    if [ -n "${{{old}+x}}" ] ; then',
            f'        if [ "${old}" = "@unset@" ] ; then unset {name} ; else {name}="${old}" ; export {name} ; fi',
            f"        unset {old}",
            "    fi",
        ]
    lines.append(f"    {END}")
    return lines


def apply_lines() -> list[str]:
    """The lines appended to ``bin/activate``: remember each variable, then set it."""
    lines = [BEGIN]
    for name, value in VARIABLES:
        lines.append(f'_RIGID_ROT_OLD_{name}="${{{name}-@unset@}}"')
        if value == "prepend":
            lines += [
                f'case ":${{{name}:-}}:" in',
                '    *":$VIRTUAL_ENV:"*) ;;',
                f'    *) {name}="$VIRTUAL_ENV${{{name}:+:${name}}}" ; export {name} ;;',
                "esac",
            ]
        else:
            lines.append(f"{name}={value} ; export {name}")
    lines.append(END)
    return lines


def extend_activate(text: str, path: Path) -> str:
    """``text`` (a venv's activate script) with this file's block in ``deactivate`` and at the end, once."""
    text = re.sub(r"\n[ \t]*" + re.escape(BEGIN) + r".*?" + re.escape(END), "", text, flags=re.S)
    if DEACTIVATE not in text:
        raise SystemExit(f"setup: {path}: no 'deactivate () {{' to extend (not a venv activate script?)")
    text = text.replace(DEACTIVATE, DEACTIVATE + "\n".join(restore_lines()) + "\n", 1)
    return text.rstrip("\n") + "\n\n" + "\n".join(apply_lines()) + "\n"


def install(checkout: Path, prefix: Path, executables: list[str] | None = None) -> Path:
    """Lay out the share directory, the ament index entry and lib/<package>, extend bin/activate.

    ``executables``: the console scripts to link (default: the installed distribution's). Returns the
    share directory.
    """
    share = prefix / "share" / PACKAGE
    for name in SHARED:
        link_tree(checkout / name, share / name)
    link_executables(prefix, console_scripts() if executables is None else executables)
    index = prefix / "share" / "ament_index" / "resource_index" / "packages"
    link(checkout / "resource" / PACKAGE, index / PACKAGE)
    activate = prefix / "bin" / "activate"
    activate.write_text(extend_activate(activate.read_text(encoding="utf-8"), activate), encoding="utf-8")
    return share


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        raise SystemExit("usage: python tools/install_workspace.py CHECKOUT")
    checkout = Path(argv[1]).resolve()
    share = install(checkout, Path(sys.prefix))
    print(
        f"setup: {share} (a link per file) and the ament index entry link to {checkout}; "
        f"{Path(sys.prefix) / 'lib' / PACKAGE} holds the console scripts (ros2 run); "
        f"{Path(sys.prefix) / 'bin' / 'activate'} sets AMENT_PREFIX_PATH & co."
    )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
