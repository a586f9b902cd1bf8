"""The e2e and slow tests N times in a row under two busy loops, and a summary of every failure (issue 41).

    .venv/bin/python tools/suite_under_load.py                   # 10 rounds (an hour or more on 2 cores)
    .venv/bin/python tools/suite_under_load.py --rounds 2
    .venv/bin/python tools/suite_under_load.py --rounds 3 --busy 2 -- -k lockstep   # extra pytest arguments

Each round is a fresh ``python -m pytest test -m "e2e or slow"`` (its own ROS domain: test/conftest.py) while
``--busy`` processes (``python -c 'while True: pass'``, default 2: one per core of a 2-core machine) load
the CPU; they are started and stopped by this script, by their pids (also on Ctrl-C / SIGTERM). It prints one
line per round (exit code, passed / failed, wall time, load average, the failed tests) and then, per test that
failed at least once, in how many rounds, with the first line of its error: a flake is a test that fails in
some rounds and passes in others. Exit code 0 only when every round passed. One pytest log per round
in ``--logs`` (default out/suite_under_load/). The e2e tests alone, with more busy loops:
benchmarks/e2e_under_load.py (whose busy loops and summary parsing this script shares).
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from e2e_under_load import counts, start_busy, stop  # noqa: E402  # the busy loops and pytest's summary line


def one_round(pytest_args: list[str], log_path: Path) -> tuple[int, dict[str, int], float, dict[str, str]]:
    """One ``pytest -m "e2e or slow"`` run: exit code, counts, wall seconds, failed test -> first error line."""
    command = [sys.executable, "-m", "pytest", "test", "-m", "e2e or slow", "-q", "-rfE", "-p", "no:cacheprovider"]
    started = time.monotonic()
    with open(log_path, "w") as log:
        code = subprocess.run(
            [*command, *pytest_args], cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL
        ).returncode
    elapsed = time.monotonic() - started
    lines = [line for line in log_path.read_text(errors="replace").splitlines() if line.strip()]
    failed: dict[str, str] = {}
    for line in lines:
        if line.startswith(("FAILED ", "ERROR ")):
            name, _, why = line.split(" ", 1)[1].partition(" - ")
            failed[name] = why[:160]
    return code, counts(lines[-1] if lines else ""), elapsed, failed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=10, help="runs of the e2e and slow tests (default 10)")
    parser.add_argument("--busy", type=int, default=2, help="busy loops during the runs (default 2)")
    parser.add_argument("--logs", type=Path, default=ROOT / "out" / "suite_under_load", help="a pytest log per round")
    parser.add_argument("pytest_args", nargs="*", help="extra pytest arguments (after --)")
    args = parser.parse_args(argv)
    if args.rounds < 1 or args.busy < 0:
        parser.error("--rounds must be >= 1 and --busy >= 0")
    args.logs.mkdir(parents=True, exist_ok=True)
    signal.signal(signal.SIGTERM, lambda *_: (_ for _ in ()).throw(KeyboardInterrupt()))
    print(
        f"suite under load: {args.rounds} rounds of pytest -m 'e2e or slow', {args.busy} busy loops, "
        f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f} before",
        flush=True,
    )
    busy = start_busy(args.busy)
    rounds: list[int] = []
    failures: Counter[str] = Counter()
    reasons: dict[str, str] = {}
    try:
        for number in range(1, args.rounds + 1):
            code, tally, elapsed, failed = one_round(args.pytest_args, args.logs / f"round_{number}.log")
            rounds.append(code)
            failures.update(failed.keys())
            for name, why in failed.items():
                reasons.setdefault(name, why)
            print(
                f"round {number}/{args.rounds}: exit {code}, {tally.get('passed', 0)} passed, "
                f"{tally.get('failed', 0) + tally.get('error', 0) + tally.get('errors', 0)} failed, "
                f"{elapsed:.0f} s, load average {os.getloadavg()[0]:.1f}"
                + (f"; failed: {', '.join(failed)}" if failed else ""),
                flush=True,
            )
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
    finally:
        stop(busy)
    green = sum(1 for code in rounds if code == 0)
    print(f"summary: {green} of {len(rounds)} rounds green ({args.busy} busy loops); logs in {args.logs}")
    for name, times in failures.most_common():
        print(f"  {name}: failed in {times} of {len(rounds)} rounds; first: {reasons[name]}")
    return 0 if len(rounds) == args.rounds and green == args.rounds else 1


if __name__ == "__main__":
    raise SystemExit(main())
