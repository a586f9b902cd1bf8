"""``rigid-rot resim BAG [--integrator NAME]``: re-run a recording without ROS and compare.

Rebuilds the run from the scene, integrator and simulation event log stored in the bag
and compares every re-simulated state with the recorded one: the maximum deviation of
attitude (rad), ω and L, and a verdict. With the recorded integrator the states must be
bit-identical (exit code 1 if not); with another one the report shows what that
integrator changes on this run.
"""

from __future__ import annotations


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "resim", help="re-simulate a recording and compare states", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("bag", metavar="BAG.mcap")
    parser.add_argument("--integrator", metavar="NAME", help="integrator to re-run with (default: the recorded one)")
    parser.set_defaults(handler=run)


def run(args) -> int:
    from rigid_rot_sim.recording.resim import resimulate

    report = resimulate(args.bag, method=args.integrator)
    print(report.format())
    if report.method == report.recorded_method and not report.identical:
        return 1
    return 0
