"""One home for each rule: a rule written a second time drifts, so these find its second spelling.

Read from the source text (ast), like test_structure.py. Each rule names its home and what a second
spelling looks like:

* steps on a grid (``core/steps.py``): ``round(x / dt)`` (a step count or the nearest step) and a
  relative tolerance on a period or step count (``1e-9 * period``) are asked of
  :func:`~rigid_rot_sim.core.steps.whole_steps`, :func:`~rigid_rot_sim.core.steps.nearest_step` and
  :func:`~rigid_rot_sim.core.steps.steps_over`;
* the principal <-> body frame conversion (``core/frames.py``): no ``rotate(body_from_principal, ...)``
  or ``rotate_inverse(principal_from_body, ...)`` elsewhere;
* compiling a kernel (``core/jit.py``): no ``numba.njit`` / ``numba.jit`` outside it (use
  :func:`~rigid_rot_sim.core.jit.compiled`, which caches and refuses fastmath).

:func:`test_each_rule_finds_a_planted_second_home` shows each rule failing on one.
"""

from __future__ import annotations

import ast
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "rigid_rot_sim"


def _names(node: ast.AST) -> set[str]:
    """Every name and attribute name in an expression."""
    found = set()
    for sub in ast.walk(node):
        if isinstance(sub, ast.Name):
            found.add(sub.id)
        elif isinstance(sub, ast.Attribute):
            found.add(sub.attr)
    return found


def _called(node: ast.Call) -> str:
    function = node.func
    if isinstance(function, ast.Name):
        return function.id
    if isinstance(function, ast.Attribute):
        return function.attr
    return ""


def steps_rule(tree: ast.AST) -> Iterator[tuple[int, str]]:
    """``round(x / <...dt...>)``, and a tolerance ``1e-9 * period`` (or a step count), outside core/steps.py."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and _called(node) == "round" and node.args:
            ratio = node.args[0]
            if isinstance(ratio, ast.BinOp) and isinstance(ratio.op, ast.Div) and "dt" in _names(ratio.right):
                yield node.lineno, f"round({ast.unparse(ratio)}): ask core/steps.py"
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
            sides = (node.left, node.right)
            tolerance = any(isinstance(s, ast.Constant) and s.value == 1e-9 for s in sides)
            on_grid = any(name in ("period", "steps") or name.endswith("_period") for name in _names(node))
            if tolerance and on_grid:
                yield node.lineno, f"{ast.unparse(node)}: a period of whole steps is core/steps.whole_steps"


def frames_rule(tree: ast.AST) -> Iterator[tuple[int, str]]:
    """A rotation by the principal <-> body quaternion outside core/frames.py."""
    frame_names = {"body_from_principal", "principal_from_body"}
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and _called(node) in ("rotate", "rotate_inverse", "multiply") and node.args:
            if _names(node.args[0]) & frame_names:
                yield node.lineno, f"{ast.unparse(node.func)}({ast.unparse(node.args[0])}, ...): ask core/frames.py"


def jit_rule(tree: ast.AST) -> Iterator[tuple[int, str]]:
    """``numba.njit`` / ``numba.jit`` (or an imported ``njit``) outside core/jit.py."""
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module == "numba":
            for alias in node.names:
                if alias.name in ("njit", "jit"):
                    yield node.lineno, f"from numba import {alias.name}: compile with core/jit.compiled"
        elif isinstance(node, ast.Attribute) and node.attr in ("njit", "jit"):
            if isinstance(node.value, ast.Name) and node.value.id == "numba":
                yield node.lineno, f"numba.{node.attr}: compile with core/jit.compiled"


RULES: dict[str, tuple[str, Callable[[ast.AST], Iterator[tuple[int, str]]]]] = {
    "steps": ("core/steps.py", steps_rule),
    "frames": ("core/frames.py", frames_rule),
    "jit": ("core/jit.py", jit_rule),
}


def second_homes(rule: str) -> dict[str, list[str]]:
    """File (relative to the package) -> what the rule finds there, outside the rule's home."""
    home, finder = RULES[rule]
    found: dict[str, list[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        name = path.relative_to(PACKAGE).as_posix()
        if name == home:
            continue
        hits = [f"{name}:{line}: {what}" for line, what in finder(ast.parse(path.read_text(encoding="utf-8")))]
        if hits:
            found[name] = hits
    return found


@pytest.mark.parametrize("rule", sorted(RULES))
def test_each_rule_has_one_home(rule: str):
    found = second_homes(rule)
    new = [hit for hits in found.values() for hit in hits]
    assert not new, f"a second home of the {rule} rule (its home is {RULES[rule][0]}):\n" + "\n".join(new)


PLANTED = {
    "steps": [
        "n = round(duration / self.dt)",
        "k = max(1, round(t_end / dt))",
        "ok = abs(n * dt - period) <= 1e-9 * period",
    ],
    "frames": [
        "v = quat.rotate(body_from_principal, w)",
        "u = rotate_inverse(self.principal_from_body, torque)",
    ],
    "jit": [
        "from numba import njit",
        "@numba.njit(cache=True)\ndef f(x):\n    return x",
        "g = numba.jit(nopython=True)(f)",
    ],
}


@pytest.mark.parametrize("rule", sorted(RULES))
def test_each_rule_finds_a_planted_second_home(rule: str):
    _, finder = RULES[rule]
    for source in PLANTED[rule]:
        assert list(finder(ast.parse(source))), f"the {rule} rule misses {source!r}"


@pytest.mark.parametrize("rule", sorted(RULES))
def test_each_home_holds_its_rule(rule: str):
    """The rule finds its own home's spelling (so it looks for the right thing)."""
    home, finder = RULES[rule]
    assert list(finder(ast.parse((PACKAGE / home).read_text(encoding="utf-8")))), f"{home} has no {rule} rule"
