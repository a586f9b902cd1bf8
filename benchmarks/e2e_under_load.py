"""The end-to-end tests, N times in a row, while K busy processes load the CPU (prints figures).

    .venv/bin/python benchmarks/e2e_under_load.py                     # 5 repeats, 4 busy processes
    .venv/bin/python benchmarks/e2e_under_load.py --repeats 8 --busy 3
    .venv/bin/python benchmarks/e2e_under_load.py --repeats 2 --busy 0 -- -k tf   # extra pytest arguments

Why: CI may run on a busy machine, and an e2e suite that fails by chance teaches people to
ignore red. The e2e tests must assert only on what the node guarantees (issue 10), so they
must pass every time here too. Each repeat is a fresh ``python -m pytest test/e2e`` (its own
ROS domain, test/conftest.py); the busy processes are plain Python spin loops started by this
script (and stopped by it, by their pids, at the end or on Ctrl-C / SIGTERM). Prints one line
per repeat (exit code, passed / failed counts, wall time, load average) and the totals;
exit code 0 only when every repeat passed.
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BUSY_LOOP = "while True:\n    pass\n"


def start_busy(count: int) -> list[subprocess.Popen]:
    """``count`` CPU-bound processes (one core each, at normal priority)."""
    return [subprocess.Popen([sys.executable, "-c", BUSY_LOOP], stdin=subprocess.DEVNULL) for _ in range(count)]


def stop(processes: list[subprocess.Popen]) -> None:
    for process in processes:
        if process.poll() is None:
            process.terminate()
    for process in processes:
        try:
            process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def counts(summary: str) -> dict[str, int]:
    """{'passed': n, 'failed': n, ...} from pytest's last line (e.g. '3 failed, 14 passed in 80.1s')."""
    return {word: int(number) for number, word in re.findall(r"(\d+) (passed|failed|errors?|skipped)", summary)}


def run_once(pytest_args: list[str], log_path: Path) -> tuple[int, dict[str, int], float, list[str]]:
    """One ``pytest test/e2e`` run: exit code, counts, wall seconds, names of failed tests."""
    command = [
        sys.executable,
        "-m",
        "pytest",
        str(ROOT / "test" / "e2e"),
        "-q",
        "-rfE",
        "-p",
        "no:cacheprovider",
        *pytest_args,
    ]
    started = time.monotonic()
    with open(log_path, "w") as log:
        code = subprocess.run(
            command, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL
        ).returncode
    elapsed = time.monotonic() - started
    text = log_path.read_text(errors="replace")
    lines = [line for line in text.splitlines() if line.strip()]
    failed = [line.split(" ", 1)[1].split(" - ")[0] for line in lines if line.startswith(("FAILED ", "ERROR "))]
    return code, counts(lines[-1] if lines else ""), elapsed, failed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5, help="runs of the e2e tests (default 5)")
    parser.add_argument("--busy", type=int, default=4, help="busy processes during the runs (default 4)")
    parser.add_argument(
        "--logs", type=Path, default=ROOT / "out" / "e2e_under_load", help="one pytest log per run here"
    )
    parser.add_argument("pytest_args", nargs="*", help="extra pytest arguments (after --)")
    args = parser.parse_args(argv)
    if args.repeats < 1 or args.busy < 0:
        parser.error("--repeats must be >= 1 and --busy >= 0")
    args.logs.mkdir(parents=True, exist_ok=True)

    signal.signal(signal.SIGTERM, lambda *_: (_ for _ in ()).throw(KeyboardInterrupt()))
    busy = start_busy(args.busy)
    results = []
    print(
        f"e2e under load: {args.repeats} runs of pytest test/e2e, {args.busy} busy processes, "
        f"{os.cpu_count()} CPUs, load average before {os.getloadavg()[0]:.1f}",
        flush=True,
    )
    try:
        for index in range(1, args.repeats + 1):
            code, tally, elapsed, failed = run_once(args.pytest_args, args.logs / f"run_{index}.log")
            load = os.getloadavg()[0]
            results.append((code, tally, failed))
            print(
                f"run {index}/{args.repeats}: exit {code}, {tally.get('passed', 0)} passed, "
                f"{tally.get('failed', 0) + tally.get('error', 0) + tally.get('errors', 0)} failed, "
                f"{elapsed:.0f} s, load average {load:.1f}" + (f"; failed: {', '.join(failed)}" if failed else ""),
                flush=True,
            )
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
    finally:
        stop(busy)
    ok = sum(1 for code, _, _ in results if code == 0)
    tests_passed = sum(t.get("passed", 0) for _, t, _ in results)
    tests_failed = sum(t.get("failed", 0) + t.get("error", 0) + t.get("errors", 0) for _, t, _ in results)
    print(
        f"summary: {ok} of {len(results)} runs passed ({len(results) - ok} failed); "
        f"tests: {tests_passed} passed, {tests_failed} failed; logs in {args.logs}"
    )
    return 0 if results and ok == len(results) == args.repeats else 1


if __name__ == "__main__":
    raise SystemExit(main())
