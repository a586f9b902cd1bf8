"""``rigid-rot plot BAG [--out DIR]``: PNGs of a recorded run.

Writes ``omega.png`` (ω components), ``drift.png`` (relative energy and |L| change),
``torque.png`` (torque applied, command times) and ``polhode.png`` (ω on the energy
ellipsoid, principal frame) to DIR (default: ``<bag stem>_plots`` next to the bag).
"""

from __future__ import annotations


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "plot", help="plot a recorded run to PNG files", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("bag", metavar="BAG.mcap")
    parser.add_argument("--out", metavar="DIR", help="output directory (default: <bag stem>_plots)")
    parser.set_defaults(handler=run)


def run(args) -> int:
    from rigid_rot_sim.recording.plot import plot_run

    for path in plot_run(args.bag, args.out):
        print(path)
    return 0
