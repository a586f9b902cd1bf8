"""Style gate: ``ruff check`` and ``ruff format --check`` are clean, and the ratchet only shrinks.

pyproject.toml's ``[tool.ruff.lint.per-file-ignores]`` lists, per file, the rules that file broke when the
gate was introduced (too many engineers were editing the package to reformat it at once). A file that now
passes a listed rule fails ``test_the_ratchet_only_shrinks`` until the entry is removed, so each fix is
kept. The pawl: ``test_no_exemption_is_added`` fails when pyproject.toml lists an entry that the frozen
baseline ``test/gate_baseline.txt`` does not (new files get no entry: they follow the rules from the start).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import tomllib

ROOT = Path(__file__).resolve().parents[1]
RUFF = Path(sys.executable).with_name("ruff")
BASELINE = ROOT / "test" / "gate_baseline.txt"
#: At most this many (file, rule) pairs in the baseline: it may shrink, never grow (issue 28 left 4, each
#: in a file another branch was rewriting; before issue 28 there were 123 files with an entry).
MAX_RUFF_ENTRIES = 4


def ruff(*args: str) -> subprocess.CompletedProcess[str]:
    assert RUFF.is_file(), f"{RUFF} is missing: `make setup` installs ruff (the Makefile's TEST_PINS)"
    return subprocess.run(
        [str(RUFF), "check", "--no-cache", *args, "."], cwd=ROOT, capture_output=True, text=True, timeout=300
    )


def ratchet() -> dict[str, list[str]]:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    return config["tool"]["ruff"]["lint"].get("per-file-ignores", {})


def test_ruff_is_clean():
    result = ruff("--output-format", "concise")
    assert result.returncode == 0, (
        "ruff finds style errors (rules and line length 120 in pyproject.toml). Fix them; "
        f"`.venv/bin/ruff check --fix PATH` does the safe ones:\n{result.stdout}{result.stderr}"
    )


def test_the_ratchet_only_shrinks():
    """Every per-file ignore is still needed: the file exists and still breaks each rule listed for it."""
    result = ruff("--output-format", "json", "--exit-zero", "--config", "lint.per-file-ignores = {}")
    assert result.returncode == 0, result.stderr
    broken: dict[str, set[str]] = {}
    for error in json.loads(result.stdout):
        path = Path(error["filename"]).resolve().relative_to(ROOT).as_posix()
        broken.setdefault(path, set()).add(error["code"])
    stale = []
    for path, codes in ratchet().items():
        if not (ROOT / path).is_file():
            stale.append(f"{path}: no such file (moved or deleted): remove its entry")
            continue
        fixed = sorted(set(codes) - broken.get(path, set()))
        if fixed:
            stale.append(f"{path}: passes {', '.join(fixed)} now: remove them from its entry")
    assert not stale, (
        "pyproject.toml [tool.ruff.lint.per-file-ignores] is a ratchet; these entries are no longer needed:\n"
        + "\n".join(stale)
    )


def test_ruff_format_is_clean():
    """The whole tree is in ``ruff format``'s style (one mechanical commit made it so; new code keeps it)."""
    assert RUFF.is_file(), f"{RUFF} is missing: `make setup` installs ruff (the Makefile's TEST_PINS)"
    result = subprocess.run(
        [str(RUFF), "format", "--check", "--no-cache", "."], cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, (
        f"files not in ruff format's style; `.venv/bin/ruff format PATH` fixes them:\n{result.stdout}{result.stderr}"
    )


def baseline(kind: str) -> set[tuple[str, ...]]:
    """The frozen entries of ``kind`` (``ruff``: (path, rule); ``mypy``: (module,)) in test/gate_baseline.txt."""
    rows = [line.split() for line in BASELINE.read_text(encoding="utf-8").splitlines()]
    return {tuple(row[1:]) for row in rows if row and row[0] == kind}


def test_no_exemption_is_added():
    """The pawl: every per-file ignore is in the frozen baseline, and the baseline only shrinks."""
    listed = {(path, rule) for path, rules in ratchet().items() for rule in rules}
    frozen = baseline("ruff")
    added = sorted(f"{path}: {rule}" for path, rule in listed - frozen)
    assert not added, (
        "pyproject.toml [tool.ruff.lint.per-file-ignores] gained entries that test/gate_baseline.txt does not "
        "hold. Never add an exemption: fix the code instead.\n" + "\n".join(added)
    )
    gone = sorted(f"ruff {path} {rule}" for path, rule in frozen - listed)
    assert not gone, "these exemptions left pyproject.toml: delete their lines from test/gate_baseline.txt\n" + (
        "\n".join(gone)
    )
    assert len(frozen) <= MAX_RUFF_ENTRIES, "test/gate_baseline.txt grew: it may only shrink"
