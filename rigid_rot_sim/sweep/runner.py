"""A sweep's run: its chunks as tasks on the cluster, their rows gathered in run order.

:func:`run_sweep` opens (or is given) a ``distributed.Client`` (:mod:`rigid_rot_sim.cluster`),
chooses the chunk size from a measured step cost, submits one nominal run per spin rate and
one task per chunk (:func:`rigid_rot_sim.sweep.chunks.run_chunk`, a pure function of the spec
and the chunk, so a rescheduled task gives the same bits) and assembles the rows into a
:class:`SweepResult`. :func:`run_local` computes the same rows in this process, without Dask.
"""

from __future__ import annotations

import contextlib
import itertools
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from tqdm import tqdm

from rigid_rot_sim.cluster import map_tasks, open_client, scheduler_address
from rigid_rot_sim.sweep.chunks import COLUMNS, Chunk, choose_chunk_size, plan_chunks, run_chunk, run_nominal
from rigid_rot_sim.sweep.spec import SweepSpec

__all__ = ["SweepResult", "run_local", "run_sweep"]


@dataclass
class SweepResult:
    """The rows of a sweep (columns in :data:`COLUMNS` order, sorted by run) and how it ran."""

    spec: SweepSpec
    columns: dict[str, Any]
    quick: bool
    engine: dict[str, Any] = field(default_factory=dict)


def _assemble(parts: list[dict[str, Any]]) -> dict[str, Any]:
    columns: dict[str, Any] = {}
    for name, kind in COLUMNS.items():
        if kind == "string":
            columns[name] = list(itertools.chain.from_iterable(part[name] for part in parts))
        else:
            columns[name] = np.concatenate([np.asarray(part[name]) for part in parts])
    if np.all(np.diff(columns["run"]) > 0):  # the chunks came in run order (the usual case): nothing to move
        return columns
    order = np.argsort(columns["run"], kind="stable")
    return {
        name: (values[order] if isinstance(values, np.ndarray) else [values[i] for i in order])
        for name, values in columns.items()
    }


def run_sweep(
    spec: SweepSpec,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    chunk_size: int | None = None,
    quick: bool = False,
    progress: bool = True,
    on_chunk_done: Callable[[int, int], None] | None = None,
    client: Any = None,
) -> SweepResult:
    """Run every chunk of ``spec`` on Dask and gather the rows.

    ``chunk_size`` (bodies per task) defaults to :func:`choose_chunk_size` from a cost
    measured here; the rows do not depend on it. ``on_chunk_done(done, total)`` is called
    in this thread as chunks finish. ``client``: an open ``distributed.Client`` to use
    instead of opening one from ``scheduler`` / ``workers``.
    """
    start = time.perf_counter()
    local = client is None and scheduler_address(scheduler) is None
    with contextlib.ExitStack() as stack:
        if client is None:
            client = stack.enter_context(open_client(scheduler, workers))
        n_workers = len(client.scheduler_info(n_workers=-1)["workers"])
        figures: dict[str, float] = {}
        if chunk_size is None:
            chunk_size, figures = choose_chunk_size(spec, n_workers)
        chunks = plan_chunks(spec, chunk_size)
        nominals = {}
        if spec.nominal_method is not None:
            # one nominal run per spin rate, a dependency of the chunks of that spin rate
            token = uuid.uuid4().hex[:12]
            for spin in dict.fromkeys(s for _, _, s in spec.grid):
                nominals[spin] = client.submit(
                    run_nominal, spec, spin, key=f"rigid-rot-nominal-{token}-{spin}", pure=False
                )
        calls = [(run_chunk, (spec, chunk, nominals.get(spec.grid[chunk.grid_point][2]))) for chunk in chunks]
        try:
            with tqdm(total=spec.n_runs, desc=f"sweep {spec.name}", unit="run", disable=not progress) as bar:
                finished = 0

                def chunk_done(index: int, _: Any) -> None:
                    nonlocal finished
                    finished += 1
                    bar.update(chunks[index].size)
                    if on_chunk_done is not None:
                        on_chunk_done(finished, len(chunks))

                parts = map_tasks(client, calls, on_done=chunk_done)
        finally:
            # done, interrupted (Ctrl-C) or failed: leave nothing running on a shared cluster
            with contextlib.suppress(Exception):
                client.cancel(list(nominals.values()), force=True)
        engine = {
            "scheduler": client.scheduler.address,
            "local_cluster": local,
            "workers": n_workers,
            "chunks": len(chunks),
            "chunk_size": chunk_size,
            **figures,
        }
    engine["elapsed_seconds"] = time.perf_counter() - start
    return SweepResult(spec=spec, columns=_assemble(parts), quick=quick, engine=engine)


def run_local(spec: SweepSpec, chunks: list[Chunk] | None = None, chunk_size: int = 64) -> dict[str, Any]:
    """The rows of ``spec`` computed in this process, without Dask (tests, debugging)."""
    return _assemble([run_chunk(spec, chunk) for chunk in (chunks or plan_chunks(spec, chunk_size))])
