"""Sweeps on a real dask.distributed cluster: `dask scheduler` and two `dask worker` subprocesses.

The same spec on the external cluster, on the local default cluster and in this process
gives identical rows; a worker killed in the middle of a sweep costs time, not results.
"""

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from rigid_rot_sim.cli import main
from rigid_rot_sim.sweep.chunks import COLUMNS
from rigid_rot_sim.sweep.runner import run_local, run_sweep
from rigid_rot_sim.sweep.spec import load_sweep_spec

pytestmark = pytest.mark.slow

DASK = str(Path(sys.executable).parent / "dask")
START_TIMEOUT = 120.0

SPEC = """
scene: free_tumble
seed: 99
samples: 12
duration: {duration}
grid: {{method: [rk4, implicit_midpoint], dt: [0.01, 0.5], spin_rate: [2.0, 30.0]}}
dispersions:
  principal_moments: {{relative: 0.02}}
  axis_misalignment: {{sigma: 1.0e-3}}
  initial_omega: {{sigma: 1.0e-2}}
checkpoints: 10
events: [first_flip]
"""


def wait_for(condition, timeout, what):
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise TimeoutError(f"timed out after {timeout:g} s waiting for {what}")
        time.sleep(0.05)


class Cluster:
    def __init__(self, address, workers):
        self.address = address
        self.workers = workers  # name -> Popen


@pytest.fixture
def dask_cluster(tmp_path):
    """`dask scheduler` on a free localhost port and two single-thread `dask worker`s; always torn down."""
    from distributed import Client

    processes = []
    scheduler_file = tmp_path / "scheduler.json"
    log = open(tmp_path / "cluster.log", "w")
    try:
        processes.append(
            subprocess.Popen(
                [
                    DASK,
                    "scheduler",
                    "--host",
                    "127.0.0.1",
                    "--port",
                    "0",
                    "--no-dashboard",
                    "--scheduler-file",
                    str(scheduler_file),
                ],
                stdout=log,
                stderr=subprocess.STDOUT,
            )
        )

        def address():
            try:
                return json.loads(scheduler_file.read_text())["address"]
            except (OSError, ValueError, KeyError):
                return None

        wait_for(lambda: address() is not None or processes[0].poll() is not None, START_TIMEOUT, "the scheduler file")
        assert processes[0].poll() is None, (tmp_path / "cluster.log").read_text()
        workers = {}
        for name in ("w1", "w2"):
            workers[name] = subprocess.Popen(
                [
                    DASK,
                    "worker",
                    address(),
                    "--nthreads",
                    "1",
                    "--no-nanny",
                    "--no-dashboard",
                    "--name",
                    name,
                    "--host",
                    "127.0.0.1",
                    "--death-timeout",
                    "60",
                ],
                stdout=log,
                stderr=subprocess.STDOUT,
            )
            processes.append(workers[name])
        with Client(address(), timeout=START_TIMEOUT) as client:
            client.wait_for_workers(2, timeout=START_TIMEOUT)
        yield Cluster(address(), workers)
    finally:
        # workers first, while their scheduler still answers (a worker closing against a vanished
        # scheduler can hang), then the scheduler; SIGKILL whatever does not exit in time
        for process in reversed(processes):
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
            try:
                process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        log.close()


def write_spec(tmp_path, duration):
    path = tmp_path / "small.yaml"
    path.write_text(SPEC.format(duration=duration))
    return path


def test_external_cluster_and_local_default_write_identical_parquet(tmp_path, dask_cluster, capsys):
    path = write_spec(tmp_path, 3.0)
    assert (
        main(
            [
                "sweep",
                str(path),
                "--scheduler",
                dask_cluster.address,
                "--chunk-size",
                "5",
                "--out",
                str(tmp_path / "remote"),
                "--no-progress",
            ]
        )
        == 0
    )
    assert main(["sweep", str(path), "--workers", "2", "--out", str(tmp_path / "local"), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert f"On the cluster at {dask_cluster.address}" in out and "On a local cluster: 2 worker(s)" in out
    # the same bytes: rows, NaNs of the failed runs, schema and metadata (spec, seed, versions)
    remote_file, local_file = tmp_path / "remote" / "small.parquet", tmp_path / "local" / "small.parquet"
    assert remote_file.read_bytes() == local_file.read_bytes()
    remote = pq.read_table(remote_file)
    assert remote.num_rows == load_sweep_spec(path).n_runs
    verdicts = set(remote.column("verdict").to_pylist())
    assert {"stable", "unstable"} <= verdicts  # the failing rows travel too


def test_killing_a_worker_mid_sweep_changes_no_result(tmp_path, dask_cluster):
    from distributed import Client

    spec = load_sweep_spec(write_spec(tmp_path, 10.0))
    victim = dask_cluster.workers["w2"]
    killed = {}

    with Client(dask_cluster.address, timeout=START_TIMEOUT) as client:

        def on_chunk_done(done, total):
            if killed:
                return
            names = {addr: info["name"] for addr, info in client.scheduler_info(n_workers=-1)["workers"].items()}
            busy = [names.get(addr) for addr, keys in client.processing().items() if keys]
            if "w2" in busy and done < total:
                victim.send_signal(signal.SIGKILL)
                killed.update(at=time.perf_counter(), done=done, total=total)

        start = time.perf_counter()
        result = run_sweep(spec, client=client, chunk_size=2, progress=False, on_chunk_done=on_chunk_done)
        end = time.perf_counter()
        assert killed, "w2 never had a task in flight to kill"
        assert victim.wait(timeout=30) == -signal.SIGKILL
        wait_for(
            lambda: len(client.scheduler_info(n_workers=-1)["workers"]) == 1, START_TIMEOUT, "the scheduler to drop w2"
        )
    print(
        f"worker w2 killed after {killed['done']}/{killed['total']} chunks; sweep done {end - killed['at']:.1f} s "
        f"later, {end - start:.1f} s in all"
    )
    reference = run_local(spec, chunk_size=spec.samples)
    for name, kind in COLUMNS.items():
        a, b = result.columns[name], reference[name]
        assert (list(a) == list(b)) if kind == "string" else np.array_equal(a, b, equal_nan=True), name


def test_ctrl_c_stops_a_sweep_on_the_local_cluster_and_its_workers(tmp_path):
    """SIGINT mid-sweep: exit code 130 promptly (not at the end of the sweep), no worker left behind."""
    import psutil

    path = write_spec(tmp_path, 200.0)  # minutes of work: only an honoured SIGINT ends it soon
    process = subprocess.Popen(
        [
            str(Path(sys.executable).parent / "rigid-rot"),
            "sweep",
            str(path),
            "--workers",
            "2",
            "--chunk-size",
            "2",
            "--out",
            str(tmp_path / "out"),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # not inherited as ignored
    )
    try:
        stderr = bytearray()

        def read():
            while chunk := process.stderr.read1(4096):
                stderr.extend(chunk)

        import threading

        threading.Thread(target=read, daemon=True).start()
        wait_for(lambda: b"sweep small:" in stderr or process.poll() is not None, START_TIMEOUT, "the progress bar")
        children = psutil.Process(process.pid).children(recursive=True)
        assert process.poll() is None and children, bytes(stderr).decode()
        process.send_signal(signal.SIGINT)
        start = time.monotonic()
        assert process.wait(timeout=30) == 130
        print(f"sweep stopped {time.monotonic() - start:.2f} s after SIGINT")
        gone, alive = psutil.wait_procs(children, timeout=30)
        assert not alive
        assert not (tmp_path / "out").exists()
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()


def test_tasks_run_their_kernels_on_one_thread(dask_cluster):
    """The cluster parallelises over tasks: a task's numba kernels do not fan out over the cores as well."""
    import numba
    from distributed import Client

    from rigid_rot_sim.cluster import map_tasks

    with Client(dask_cluster.address, timeout=START_TIMEOUT) as client:

        def plain() -> list[int]:  # numba.get_num_threads as a bare task on the workers
            return client.gather([client.submit(numba.get_num_threads, pure=False) for _ in range(4)])

        before = plain()
        assert before == [numba.config.NUMBA_NUM_THREADS] * 4 and before[0] > 1  # what a task would get otherwise
        assert map_tasks(client, [(numba.get_num_threads, ())] * 4) == [1, 1, 1, 1]
        assert plain() == before  # the worker threads' own setting is restored after each task


def _worker_settings() -> dict:
    import os

    import dask
    from distributed import get_worker

    worker = get_worker()
    return {
        "trim": os.environ.get("MALLOC_TRIM_THRESHOLD_"),
        "threads": os.environ.get("OMP_NUM_THREADS"),
        "profile": dask.config.get("distributed.worker.profile.enabled"),
        "memory_watch_s": worker.memory_manager.memory_monitor_interval,
        "system_monitor_ms": worker.periodic_callbacks["monitor"].callback_time,
        "tick_ms": worker.periodic_callbacks["tick"].callback_time,
    }


def test_local_workers_keep_glibcs_malloc_and_skip_the_profiler(monkeypatch):
    """Dask's nanny would set MALLOC_TRIM_THRESHOLD_ (page faults on every chunk-sized array) and sample stacks;
    its monitors would wake the scheduler's and the workers' event loops 5x as often; results would come
    through the scheduler."""
    from rigid_rot_sim.cluster import open_client

    # a plain LocalCluster started earlier in this process (test_cluster_suites) leaves the variable in
    # os.environ, where workers would inherit it (a variable the user exports is theirs to keep)
    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)

    with open_client(None, 1) as client:
        settings = client.submit(_worker_settings, pure=False).result()
        (nanny,) = client.cluster.workers.values()
        nanny_watch_s = nanny.memory_manager.memory_monitor_interval
        scheduler = client.cluster.scheduler
        scheduler_ms = (
            scheduler.periodic_callbacks["monitor"].callback_time,
            scheduler.periodic_callbacks["tick"].callback_time,
        )
        nanny_tick_ms = nanny.periodic_callbacks["tick"].callback_time
        direct = client.direct_to_workers
    assert settings == {
        "trim": None,
        "threads": "1",
        "profile": False,
        "memory_watch_s": 0.5,
        "system_monitor_ms": 2000.0,
        "tick_ms": 500.0,
    }
    assert (nanny_watch_s, nanny_tick_ms, scheduler_ms, direct) == (0.5, 500.0, (2000.0, 500.0), True)
