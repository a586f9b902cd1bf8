"""``rigid-rot stability``: every integrator on the catalogue of stiff and extreme cases.

Writes stability.md, stability.json, stability.png (pass/fail and energy drift per case
and method) and long_horizon.png into ``--out`` (default ``out/stability``). The full run
includes a long horizon of 1e7 steps per structure-preserving method (several minutes);
``--quick`` shortens every case and the long horizon to 1e5 steps.
"""

from __future__ import annotations

import argparse
import sys

from rigid_rot_sim.cli.suite_options import add_suite_options, check_workers


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "stability",
        help="stability suite: stiff and extreme cases, largest stable steps, long-horizon drift",
        description=__doc__.split("\n\n")[0],
    )
    parser.add_argument(
        "--out", default="out/stability", metavar="DIR", help="output directory (default: out/stability)"
    )
    parser.add_argument("--quick", action="store_true", help="shorter cases and a 1e5-step long horizon")
    parser.add_argument(
        "--long-steps", type=int, metavar="N", help="steps of the long horizon (default 1e7, quick 1e5)"
    )
    add_suite_options(parser, "cases")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from rigid_rot_sim.analysis.stability_report import run_suite

    if args.long_steps is not None and args.long_steps < 10:
        raise ValueError(f"--long-steps must be >= 10, got {args.long_steps}")
    command = "rigid-rot stability" + (" --quick" if args.quick else "") + f" --out {args.out}"
    if args.long_steps is not None:
        command += f" --long-steps {args.long_steps}"
    check_workers(args)
    payload = run_suite(
        args.out,
        quick=args.quick,
        long_steps=args.long_steps,
        command=command,
        progress=not args.no_progress,
        scheduler=args.scheduler,
        workers=args.workers,
    )
    failures = 0
    for case in payload["cases"]:
        bad = [m for m, run in case["runs"].items() if run["status"] == "unstable"]
        failures += len(bad)
        print(
            f"{case['name']}: pass {sum(r['passed'] for r in case['runs'].values())}/{len(case['runs'])}"
            + (f"; unstable: {', '.join(bad)}" if bad else "")
        )
    for row in payload["long_horizon"]:
        verdict = row["status"] if row["status"] != "stable" else ("secular" if row["secular"] else "bounded")
        print(
            f"long horizon {row['method']}: {verdict} (energy error {row['final']:.2g} after {row['steps']:.0e} steps)"
        )
    print(f"wrote {args.out}/stability.md, stability.json, stability.png, long_horizon.png", file=sys.stderr)
    return 0
