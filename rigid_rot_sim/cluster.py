"""Dask clusters for independent tasks: the sweep, the work-precision report and the stability suite.

Generic (nothing here knows a sweep or a report), on the ground floor so that
:mod:`rigid_rot_sim.analysis` and :mod:`rigid_rot_sim.sweep` both use it and neither loads
the other; dask and numba are imported inside the functions that need them. No engine of
our own: work is cut into tasks submitted to a ``distributed.Client``, on a local cluster by
default or an existing one, and :func:`map_tasks` gathers their results in order; the
scheduler reschedules the tasks of a worker that dies. (A sweep's tasks are its chunks:
:mod:`rigid_rot_sim.sweep.runner`.)

Where the cluster comes from:

* ``scheduler`` (``--scheduler tcp://HOST:PORT``) or the ``DASK_SCHEDULER_ADDRESS``
  environment variable: an existing cluster started with ``dask scheduler`` and
  ``dask worker ADDRESS`` (each worker needs rigid_rot_sim and the same pins installed);
  ``workers``, if given, is how many workers to wait for before submitting.
* otherwise a ``LocalCluster`` of ``workers`` single-threaded worker processes (default:
  the CPUs this process may use), closed at the end.
"""

from __future__ import annotations

import contextlib
import importlib.util
import logging
import os
import signal
import threading
import uuid
from collections.abc import Callable, Iterator
from typing import Any

__all__ = [
    "require",
    "open_client",
    "map_tasks",
    "wants_cluster",
    "scheduler_address",
    "available_cpus",
    "one_numba_thread",
]

#: How long to wait for a scheduler to answer, and for ``workers`` workers to join, s.
CONNECT_TIMEOUT = 30.0
WORKERS_TIMEOUT = 120.0


def require(*modules: str) -> None:
    """OSError (one line, what to install) unless every module can be imported.

    Sweeps and cluster runs need packages a plain ROS install may lack; say so before any work.
    """
    missing = [name for name in modules if importlib.util.find_spec(name) is None]
    if missing:
        raise OSError(
            f"{', '.join(missing)} not installed: sweeps and --scheduler/--workers need dask.distributed and pyarrow "
            "(`make setup` installs the pinned versions; or pip install dask distributed pyarrow)"
        )


def available_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def scheduler_address(scheduler: str | None) -> str | None:
    """``scheduler``, else ``$DASK_SCHEDULER_ADDRESS``, else None (a local cluster)."""
    return scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS") or None


#: How the local cluster (scheduler, nannies, workers) differs from Dask's defaults, each measured on a sweep:
#:
#: * glibc's own malloc trimming: Dask's nanny starts workers with ``MALLOC_TRIM_THRESHOLD_=65536``
#:   (memory back to the OS early), which makes every chunk-sized temporary array (~100 kB) a fresh
#:   mapping with its page faults: ~10 % of a sweep task (the same in one process with that variable).
#:   None unsets it (distributed.nanny); the thread-count variables stay (one thread per worker).
#: * no statistical profiler (a stack sample every 10 ms, for the dashboard) and the system monitor
#:   every 2 s instead of 0.5 s (scheduler and workers): both wake an event loop into the GIL a
#:   compiled kernel holds, or onto a core a worker needs.
#: * the memory limit watched every 0.5 s instead of 0.1 s: each look is a psutil call in this
#:   process per worker, and a worker's own; a sweep task's memory grows with its chunk, not
#:   within 0.5 s.
#: * the event loops' tick (a check that the loop is responsive, logged after 3 s) every 0.5 s
#:   instead of 20 ms: 50 wake-ups a second per scheduler, nanny and worker took ~45 ms of CPU a
#:   second in this process and ~18 in each worker while the cluster idled (7.5 and ~3 now).
_LOCAL_CLUSTER_CONFIG = {
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
    "distributed.worker.profile.enabled": False,
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "500ms",
    "distributed.admin.tick.interval": "500ms",
}


@contextlib.contextmanager
def open_client(scheduler: str | None = None, workers: int | None = None) -> Iterator[Any]:
    """A ``distributed.Client`` on the cluster the options name (see the module docstring)."""
    require("distributed")
    import dask
    from distributed import Client, LocalCluster

    if workers is not None and workers < 1:
        raise ValueError(f"--workers must be >= 1, got {workers}")
    address = scheduler_address(scheduler)
    if address is not None:
        try:
            client = Client(address, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError) as exc:
            raise OSError(f"cannot reach the Dask scheduler at {address}: {' '.join(str(exc).split())}") from None
        try:
            client.wait_for_workers(workers or 1, timeout=WORKERS_TIMEOUT)
            yield client
        finally:
            client.close()
        return
    # the scheduler first (a Ctrl-C meanwhile is taken once it runs: a half-built cluster cannot be
    # closed, and distributed's atexit would wait 10 s for it), then the workers
    with _sigint_deferred() as interrupted, dask.config.set(_LOCAL_CLUSTER_CONFIG):
        cluster = LocalCluster(
            n_workers=0,
            threads_per_worker=1,
            processes=True,
            dashboard_address="127.0.0.1:0",  # its HTTP server on a free port: never a clash with a running cluster
            silence_logs=logging.ERROR,
        )
        # results straight from the workers (all on this machine), not relayed by the scheduler
        client = Client(cluster, direct_to_workers=True)
    try:
        if interrupted:
            raise KeyboardInterrupt
        n_workers = workers or available_cpus()
        with dask.config.set(_LOCAL_CLUSTER_CONFIG):  # read as the nannies start their workers
            cluster.scale(n_workers)
            client.wait_for_workers(n_workers, timeout=WORKERS_TIMEOUT)
        yield client
    except BaseException:
        # interrupted (Ctrl-C) or failed: stop our worker processes now rather than wait for
        # their running tasks (a polite close waits for them, here or in distributed's atexit)
        for name in ("distributed", "tornado"):  # the comms we cut would log tracebacks
            logging.getLogger(name).setLevel(logging.CRITICAL)
        _kill_worker_processes(cluster)
        with contextlib.suppress(Exception):
            client.close(timeout=1)
        with contextlib.suppress(Exception):
            cluster.close(timeout=1)
        raise
    client.close()
    cluster.close()


def wants_cluster(scheduler: str | None, workers: int | None) -> bool:
    """True when the options (or DASK_SCHEDULER_ADDRESS) ask for Dask rather than this process."""
    return scheduler_address(scheduler) is not None or workers is not None


def map_tasks(
    client: Any,
    calls: list[tuple[Callable[..., Any], tuple[Any, ...]]],
    on_done: Callable[[int, Any], None] | None = None,
) -> list[Any]:
    """``[function(*args) for function, args in calls]``, each call one task on ``client``.

    Results come back in the order of ``calls``. ``client`` None runs the calls here,
    one after the other. ``on_done(index, result)`` is called in this thread as each
    finishes (for a progress bar). An argument may be a future of ``client`` (a task
    that several calls depend on). When interrupted (Ctrl-C) or when a call fails, the
    calls still pending are cancelled: nothing is left running on a shared cluster.
    """
    results: list[Any] = []
    if client is None:
        for index, (function, args) in enumerate(calls):
            results.append(function(*args))
            if on_done is not None:
                on_done(index, results[-1])
        return results
    from distributed import as_completed

    token = uuid.uuid4().hex[:12]
    keys = [
        f"rigid-rot-{getattr(function, '__name__', 'task')}-{token}-{index}"
        for index, (function, _) in enumerate(calls)
    ]
    # one map: the scheduler gets every task in one message (a client sends one message per
    # 10 ms, so tasks submitted one by one would reach the second worker ~10 ms late)
    futures = {future: index for index, future in enumerate(client.map(_on_one_thread, calls, key=keys, pure=False))}
    results = [None] * len(calls)
    try:
        for future in as_completed(list(futures)):
            index = futures[future]
            results[index] = future.result()
            future.release()
            if on_done is not None:
                on_done(index, results[index])
    except BaseException:
        with contextlib.suppress(Exception):
            client.cancel(list(futures), force=True)
        raise
    return results


@contextlib.contextmanager
def one_numba_thread() -> Iterator[None]:
    """numba's parallel kernels on one thread inside the block (numba's setting is per thread: this one only).

    Parallel and serial kernels give the same bits; this is about sharing the cores.
    """
    import numba

    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(threads)


def _on_one_thread(call: tuple[Callable[..., Any], tuple[Any, ...]]) -> Any:
    """``function(*args)`` of ``call = (function, args)`` under :func:`one_numba_thread`: the cluster
    runs one task per worker thread, and a task's kernels fanning out over every core as well
    (numba's default) would oversubscribe them."""
    function, args = call
    with one_numba_thread():
        return function(*args)


@contextlib.contextmanager
def _sigint_deferred() -> Iterator[list[bool]]:
    """Hold SIGINT back inside the block; the yielded list is non-empty if one arrived."""
    received: list[bool] = []
    if threading.current_thread() is not threading.main_thread():
        yield received
        return
    previous = signal.getsignal(signal.SIGINT)
    if previous is signal.SIG_IGN:
        yield received
        return
    signal.signal(signal.SIGINT, lambda signum, frame: received.append(True))
    try:
        yield received
    finally:
        signal.signal(signal.SIGINT, previous)


def _kill_worker_processes(cluster: Any) -> None:
    """SIGKILL the worker processes a LocalCluster's nannies started (ours, by pid)."""
    for nanny in list(getattr(cluster, "workers", {}).values()):
        pid = getattr(getattr(getattr(nanny, "process", None), "process", None), "pid", None)
        if pid:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
