"""The options ``rigid-rot report`` and ``rigid-rot stability`` share: where the work runs, and the progress bar.

Not a subcommand: the two subcommand modules add these to their parsers.
"""

from __future__ import annotations

import argparse


def add_suite_options(parser: argparse.ArgumentParser, tasks: str, scheduler_note: str = "") -> None:
    """``--scheduler``, ``--workers`` and ``--no-progress``; ``tasks`` names what runs on Dask ("points")."""
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help=f"run the {tasks} on this Dask scheduler "
        f"(tcp://host:port; default $DASK_SCHEDULER_ADDRESS){scheduler_note}",
    )
    parser.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help=f"run the {tasks} on a local Dask cluster of N workers (with --scheduler: wait for N workers)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def check_workers(args: argparse.Namespace) -> None:
    """ValueError (one line, exit code 2) for a ``--workers`` below 1."""
    if args.workers is not None and args.workers < 1:
        raise ValueError(f"--workers must be >= 1, got {args.workers}")
