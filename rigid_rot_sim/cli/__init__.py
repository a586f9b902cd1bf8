"""The ``rigid-rot`` command line: one subcommand per module of this package.

Adding a subcommand: write ``rigid_rot_sim/cli/<name>.py`` with

    def add_parser(subparsers) -> None:
        parser = subparsers.add_parser("<name>", help="...", description="...")
        ...
        parser.set_defaults(handler=run)

    def run(args) -> int:      # the exit code
        ...

and add ``"<name>"`` to :data:`SUBCOMMANDS`. Only the module of the subcommand being run is
imported, and modules import heavy things (rclpy, matplotlib) inside their handler, so
``rigid-rot inertia`` starts fast.

Errors: a handler signals bad input by raising ValueError (or OSError for a file it cannot
read) with a message naming what is wrong; ``main`` prints it as one line and exits with
code 2, like argparse does for bad arguments.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from rigid_rot_sim.share import ensure_ament_prefix_path

#: Subcommand modules of rigid_rot_sim.cli, in the order ``--help`` lists them.
SUBCOMMANDS = [
    "inertia",
    "report",
    "stability",
    "sweep",
    "bag",
    "resim",
    "plot",
    "replay",
    "view",
    "export",
    "identify",
    "run",
    "torque",
    "wheels",
    "mtb",
]

PROG = "rigid-rot"


class _OneLineErrorParser(argparse.ArgumentParser):
    """Bad arguments: one line naming the problem (no usage dump), exit code 2."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The parser with every subcommand, or with only ``only`` (imports just that module)."""
    parser = _OneLineErrorParser(
        prog=PROG,
        description="rigid_rot_sim: rigid-body rotation simulator tools (SI units, REP 103 frames).",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in SUBCOMMANDS if only is None else [only]:
        importlib.import_module(f"{__name__}.{name}").add_parser(subparsers)
    return parser


def _requested_subcommand(argv: Sequence[str]) -> str | None:
    """The subcommand named on the command line, if it is a known one."""
    for arg in argv:
        if not arg.startswith("-"):
            return arg if arg in SUBCOMMANDS else None
    return None


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``rigid-rot``; returns the exit code (0 ok, 1 failure, 2 bad input)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    ensure_ament_prefix_path()  # the console script works without activating the venv
    parser = build_parser(only=_requested_subcommand(argv))
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except (ValueError, OSError) as exc:
        from rigid_rot_sim.core.limits import one_line

        # one short line on stderr, whatever the exception held (newlines, an echoed 1 MB value)
        print(one_line(f"{PROG} {args.command}: error: {exc}"), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
