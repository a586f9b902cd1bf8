"""The pawls on what the gates let through: ``Any`` in annotations, ``# type: ignore`` and ``# noqa`` per room.

The gates (test/test_lint.py, test/test_mypy.py) have no exemption left, but three escape hatches stay
open: an annotation may say ``Any``, a line may say ``# type: ignore[...]`` or ``# noqa: ...``. Each is
sometimes right (numba's untyped API, an import that must follow a path set-up), and each was once used
to pass a gate instead of fixing the code. So their counts are frozen per room in
``test/gate_baseline.txt`` (lines ``count ROOM KIND N``) and may only go down:
:func:`test_no_count_grows` fails when a room holds more than its frozen count, and
:func:`test_the_counts_are_tight` when it holds fewer and the file was not lowered to match (the pawl
clicks down with each fix). A new room starts at zero.

``python test/test_gate_counts.py`` prints the current table in the baseline's format.

Rooms: each sub-package of ``rigid_rot_sim`` (``rigid_rot_sim/core``, ...), the package's top-level
modules (``rigid_rot_sim``), and ``test``, ``tools``, ``benchmarks``, ``launch``.
"""

from __future__ import annotations

import ast
import io
import re
import sys
import tokenize
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASELINE = ROOT / "test" / "gate_baseline.txt"
TREES = ("rigid_rot_sim", "test", "tools", "benchmarks", "launch")
KINDS = ("any", "type-ignore", "noqa")
_TYPE_IGNORE = re.compile(r"#\s*type:\s*ignore")
_NOQA = re.compile(r"#\s*noqa\b", re.IGNORECASE)


def room_of(path: Path) -> str:
    """The room of a file: ``rigid_rot_sim/<sub-package>``, ``rigid_rot_sim`` or the top-level folder."""
    parts = path.relative_to(ROOT).parts
    if parts[0] == "rigid_rot_sim" and len(parts) > 2:
        return "/".join(parts[:2])
    return parts[0]


def _annotations(tree: ast.AST) -> list[ast.expr]:
    found: list[ast.expr] = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            args = node.args
            every = [*args.posonlyargs, *args.args, *args.kwonlyargs, args.vararg, args.kwarg]
            found.extend(arg.annotation for arg in every if arg is not None and arg.annotation is not None)
            if node.returns is not None:
                found.append(node.returns)
        elif isinstance(node, ast.AnnAssign):
            found.append(node.annotation)
    return found


def _names_any(annotation: ast.expr) -> int:
    """How many times an annotation names ``Any`` (``Any``, ``typing.Any``, or inside a string annotation)."""
    count = 0
    for node in ast.walk(annotation):
        if isinstance(node, ast.Name) and node.id == "Any" or isinstance(node, ast.Attribute) and node.attr == "Any":
            count += 1
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            try:
                count += _names_any(ast.parse(node.value, mode="eval").body)
            except SyntaxError:
                pass
    return count


def file_counts(path: Path) -> Counter[str]:
    """``any``, ``type-ignore`` and ``noqa`` in one Python file (comments read as tokens, not text)."""
    source = path.read_text(encoding="utf-8")
    counts: Counter[str] = Counter()
    counts["any"] = sum(_names_any(annotation) for annotation in _annotations(ast.parse(source)))
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.COMMENT:
            counts["type-ignore"] += bool(_TYPE_IGNORE.search(token.string))
            counts["noqa"] += bool(_NOQA.search(token.string))
    return counts


def current() -> dict[tuple[str, str], int]:
    """Every (room, kind) with a non-zero count in the tree now."""
    table: Counter[tuple[str, str]] = Counter()
    for tree in TREES:
        for path in sorted((ROOT / tree).rglob("*.py")):
            if "__pycache__" in path.parts:
                continue
            for kind, n in file_counts(path).items():
                table[(room_of(path), kind)] += n
    return {key: n for key, n in sorted(table.items()) if n}


def frozen() -> dict[tuple[str, str], int]:
    """The frozen counts (``count ROOM KIND N`` lines of test/gate_baseline.txt)."""
    rows = [line.split() for line in BASELINE.read_text(encoding="utf-8").splitlines()]
    return {(row[1], row[2]): int(row[3]) for row in rows if len(row) == 4 and row[0] == "count"}


def test_the_baseline_names_known_kinds():
    unknown = sorted({kind for _, kind in frozen()} - set(KINDS))
    assert not unknown, f"test/gate_baseline.txt counts unknown kinds {unknown}; kinds are {KINDS}"


def test_no_count_grows():
    """The pawl: no room holds more ``Any`` annotations, ``type: ignore`` or ``noqa`` than frozen."""
    limits = frozen()
    grown = [
        f"{room} {kind}: {n} (frozen at {limits.get((room, kind), 0)})"
        for (room, kind), n in current().items()
        if n > limits.get((room, kind), 0)
    ]
    assert not grown, (
        "more escape hatches than test/gate_baseline.txt allows: type the code (numpy.typing aliases, "
        "core/jit.py), fix the import order or the lint instead of adding them; never raise a count:\n"
        + "\n".join(grown)
    )


def test_the_counts_are_tight():
    """A count that went down is lowered in the baseline, so the pawl holds the gain."""
    now = current()
    loose = [
        f"count {room} {kind} {now.get((room, kind), 0)}   (frozen at {n})"
        for (room, kind), n in frozen().items()
        if now.get((room, kind), 0) < n
    ]
    assert not loose, "these counts went down: lower them in test/gate_baseline.txt (delete a line at 0):\n" + (
        "\n".join(loose)
    )


def test_a_planted_escape_hatch_is_counted(tmp_path: Path):
    """Each kind is seen where the gates would let it through (so the pawl can click)."""
    planted = tmp_path / "planted.py"
    planted.write_text(
        "from typing import Any\nimport os  # noqa: F401\nx: 'list[Any]' = []  # type: ignore[assignment]\n"
        "def f(a: Any) -> dict[str, Any]:\n    return {}\n",
        encoding="utf-8",
    )
    assert file_counts(planted) == Counter({"any": 3, "type-ignore": 1, "noqa": 1})


if __name__ == "__main__":
    for (room, kind), n in current().items():
        sys.stdout.write(f"count {room} {kind} {n}\n")
