"""Make the running venv a ROS 2 workspace for this checkout: ``python tools/install_workspace.py CHECKOUT``.

1. The share directory and the ament index marker that ``colcon build`` installs from setup.py's data_files
   (an editable pip install skips data_files): relative symlinks to the checkout, so the share directory
   stays in step with the sources as the editable install does (like ``colcon build --symlink-install``),
   and the links move with the checkout that holds the venv.
2. ``bin/activate`` exports AMENT_PREFIX_PATH and CMAKE_PREFIX_PATH (the venv prepended), ROS_VERSION,
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


def install(checkout: Path, prefix: Path) -> Path:
    """Link the share directory and the ament index entry, extend bin/activate; return the share directory."""
    share = prefix / "share" / PACKAGE
    for name in SHARED:
        link(checkout / name, share / name)
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
        f"setup: {share} and the ament index entry link to {checkout}; "
        f"{Path(sys.prefix) / 'bin' / 'activate'} sets AMENT_PREFIX_PATH & co."
    )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
