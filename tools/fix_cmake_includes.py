"""Point the ROS wheels' exported CMake files at this interpreter's Python and numpy include directories.

The ROS 2 Jazzy wheels on PyPI were built in a manylinux image; their exported CMake targets name that
image's include directories (``/opt/python/cp311-cp311/...``). Run with the venv's interpreter
(``make setup`` does: ``.venv/bin/python tools/fix_cmake_includes.py``), it rewrites them, in
``sys.prefix/share/*/cmake/*.cmake``, to the ones of the running interpreter. Idempotent: a second run finds
nothing to rewrite.
"""

from __future__ import annotations

import re
import sys
import sysconfig
from pathlib import Path

import numpy as np

#: The manylinux image's include directories, by what replaces them.
NUMPY_INCLUDE = re.compile(r"/opt/python/cp\d+-cp\d+/lib/python3\.\d+/site-packages/numpy/_core/include")
PYTHON_INCLUDE = re.compile(r"/opt/python/cp\d+-cp\d+/include/python3\.\d+")


def rewrite(text: str, python_include: str, numpy_include: str) -> str:
    """``text`` with the image's include directories replaced by the given ones (numpy's first: it is longer)."""
    text = NUMPY_INCLUDE.sub(lambda _: numpy_include, text)
    return PYTHON_INCLUDE.sub(lambda _: python_include, text)


def fix_prefix(prefix: Path, python_include: str, numpy_include: str) -> int:
    """Rewrite every ``prefix/share/*/cmake/*.cmake`` that names the image's directories; return how many."""
    changed = 0
    for path in sorted(prefix.glob("share/*/cmake/*.cmake")):
        text = path.read_text(encoding="utf-8")
        new = rewrite(text, python_include, numpy_include)
        if new != text:
            path.write_text(new, encoding="utf-8")
            changed += 1
    return changed


def main() -> int:
    python_include = sysconfig.get_paths()["include"]
    numpy_include = np.get_include()
    changed = fix_prefix(Path(sys.prefix), python_include, numpy_include)
    print(f"setup: include paths fixed in {changed} CMake file(s) -> {python_include}, {numpy_include}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
