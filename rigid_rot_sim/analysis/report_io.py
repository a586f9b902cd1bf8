"""What the work-precision report and the stability suite write alike: machine facts, numbers, tables, JSON.

Both suites store :func:`machine_info` in their JSON, describe it with
:func:`machine_line` in their markdown, print numbers with :func:`number` (a dash for
a missing or non-finite value) and draw their tables with :func:`markdown_table`.
"""

from __future__ import annotations

import json
import math
import os
import platform
import subprocess
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
import scipy


def machine_info() -> dict[str, Any]:
    """Machine, interpreter, library versions and the git commit, for a suite's JSON."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "HEAD"],
            cwd=os.path.dirname(os.path.abspath(__file__)),
            capture_output=True,
            text=True,
            timeout=5,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        commit = ""
    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:
        affinity = os.cpu_count() or 1
    return {
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "cpus_available": affinity,
        "platform": platform.platform(),
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "matplotlib": matplotlib.__version__,
        "git_commit": commit,
    }


def machine_line(machine: dict[str, Any]) -> str:
    """One markdown sentence naming the machine, the library versions and the commit of :func:`machine_info`."""
    return (
        f"Machine: {machine['cpu']}, {machine['cpus_available']} CPUs available; Python {machine['python']}, "
        f"numpy {machine['numpy']}, scipy {machine['scipy']}; commit `{machine['git_commit'][:10] or 'unknown'}`."
    )


def number(value: Any, spec: str) -> str:
    """``format(value, spec)``, or a dash for None and non-finite floats."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    return format(value, spec)


def markdown_table(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> list[str]:
    """The lines of a markdown table: the header, its rule, then one line per row."""
    return [_table_row(header), "|" + "---|" * len(header), *(_table_row(row) for row in rows)]


def _table_row(cells: Sequence[Any]) -> str:
    return "| " + " | ".join(str(cell) for cell in cells) + " |"


def write_json(path: Path, payload: Any) -> Path:
    """``payload`` as indented JSON (NaN and infinities kept as JavaScript literals); returns ``path``."""
    path.write_text(json.dumps(payload, indent=1, default=float, allow_nan=True), encoding="utf-8")
    return path
