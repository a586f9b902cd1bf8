"""``rigid-rot report``: work-precision diagrams of every integrator against scipy's solve_ivp.

Writes report.md, results.json and one PNG per problem into ``--out`` (default
``out/report``). Each line's points are chosen by error target (the targets 1e-6 and
1e-10 rad/s): the full run takes under 3 minutes on two cores; ``--quick`` runs coarser
sweeps with fewer repeats.
"""

from __future__ import annotations

import argparse
import sys

from rigid_rot_sim.cli.suite_options import add_suite_options, check_workers


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "report",
        help="work-precision report: error against run time for every integrator and scipy",
        description=__doc__.split("\n\n")[0],
    )
    parser.add_argument("--out", default="out/report", metavar="DIR", help="output directory (default: out/report)")
    parser.add_argument("--quick", action="store_true", help="coarse sweeps and short timing budgets (< 2 min)")
    parser.add_argument("--problems", nargs="+", metavar="KEY", help="only these problems (default: all; e.g. P1 P2)")
    add_suite_options(parser, "points", ", each timed with a scipy baseline")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from rigid_rot_sim.analysis.workprecision import TARGETS, summary
    from rigid_rot_sim.analysis.workprecision_report import run_report

    command = "rigid-rot report" + (" --quick" if args.quick else "") + f" --out {args.out}"
    if args.problems:
        command += " --problems " + " ".join(args.problems)
    check_workers(args)
    results, paths = run_report(
        args.out,
        quick=args.quick,
        problem_keys=args.problems,
        command=command,
        progress=not args.no_progress,
        scheduler=args.scheduler,
        workers=args.workers,
    )
    for result in results:
        for row in summary(result, TARGETS):
            ours, theirs = row["ours"], row["scipy"]
            text = f"{result.problem} at ω error <= {row['target']:g} rad/s: "
            text += "ours not reached" if ours is None else f"{ours['label']} {ours['seconds']:.3e} s"
            if ours is not None and ours["baseline_seconds"] > 0:
                text += f" ({ours['seconds'] / ours['baseline_seconds']:.3g} x its scipy baseline)"
            text += "; scipy not reached" if theirs is None else f"; scipy {theirs['label']} {theirs['seconds']:.3e} s"
            if theirs is not None and theirs["baseline_seconds"] > 0:
                text += f" ({theirs['seconds'] / theirs['baseline_seconds']:.3g} x its scipy baseline)"
            if row["speedup"]:
                text += f"; speed-up {row['speedup']:.1f}x"
            print(text)
    print(f"wrote {paths['report.md']}, {paths['results.json']} and {len(results)} plots", file=sys.stderr)
    return 0
