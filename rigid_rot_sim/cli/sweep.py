"""``rigid-rot sweep SPEC.yaml``: a Monte Carlo / parameter sweep on Dask.

Writes ``<name>.parquet`` (one row per run), ``summary.md`` and plots into ``--out``
(default ``out/sweeps/<name>``) and prints the summary. By default the runs go to a
local Dask cluster of ``--workers`` processes (default: one per CPU); with
``--scheduler tcp://HOST:PORT`` (or ``DASK_SCHEDULER_ADDRESS``) to an existing cluster
started with ``dask scheduler`` and ``dask worker``. The rows do not depend on where,
how or in how many pieces the runs ran.
"""

from __future__ import annotations

import argparse
import sys

from rigid_rot_sim.cli.argtypes import positive_integer


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "sweep",
        help="Monte Carlo dispersions and parameter sweeps of a scene, on Dask",
        description=__doc__.split("\n\n")[0],
    )
    parser.add_argument("spec", metavar="SPEC.yaml", help="sweep spec (see config/sweeps/)")
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="existing Dask scheduler, e.g. tcp://host:8786 (default: $DASK_SCHEDULER_ADDRESS, else a local cluster)",
    )
    parser.add_argument(
        "--workers",
        type=positive_integer,
        metavar="N",
        help="local cluster size (default: one per CPU); with a scheduler: wait for N workers",
    )
    parser.add_argument("--out", metavar="DIR", help="output directory (default: out/sweeps/<name>)")
    parser.add_argument("--quick", action="store_true", help="the spec's quick sizes (fewer samples, shorter runs)")
    parser.add_argument(
        "--chunk-size",
        type=positive_integer,
        metavar="N",
        help="bodies per task (default: chosen from a measured step cost; rows do not depend on it)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from rigid_rot_sim.cluster import require
    from rigid_rot_sim.sweep.runner import run_sweep

    require("distributed", "pyarrow", "matplotlib")
    from rigid_rot_sim.sweep.output import summary_markdown, write_outputs
    from rigid_rot_sim.sweep.spec import load_sweep_spec

    spec = load_sweep_spec(args.spec, quick=args.quick)
    out = args.out or f"out/sweeps/{spec.name}"
    result = run_sweep(
        spec,
        scheduler=args.scheduler,
        workers=args.workers,
        chunk_size=args.chunk_size,
        quick=args.quick,
        progress=not args.no_progress,
    )
    files = write_outputs(result, out)
    print(summary_markdown(result, files))
    print(f"wrote {', '.join(files.values())}", file=sys.stderr)
    return 0
