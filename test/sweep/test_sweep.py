"""Sweep runs in this process (no Dask): seeding, chunking, failures as rows, physics, outputs."""

import json

import numpy as np
import pyarrow.parquet as pq
import pytest

from rigid_rot_sim.cluster import scheduler_address
from rigid_rot_sim.sweep.chunks import COLUMNS, Chunk, _sample_draws, plan_chunks, run_chunk, sample_inputs
from rigid_rot_sim.sweep.output import METADATA_KEY, write_outputs
from rigid_rot_sim.sweep.runner import SweepResult, run_local
from rigid_rot_sim.sweep.spec import parse_sweep_text

# rk4 at dt = 0.5 s on a 30 rad/s spin blows up; the other grid points do not
MIXED = """
scene: free_tumble
seed: 11
samples: 7
duration: 4.0
grid: {method: [rk4, implicit_midpoint], dt: [0.02, 0.5], spin_rate: [2.0, 30.0]}
dispersions:
  principal_moments: {relative: 0.02}
  axis_misalignment: {sigma: 1.0e-3}
  initial_omega: {sigma: 1.0e-2}
  initial_attitude: {sigma: 1.0e-3}
checkpoints: 20
events: [first_flip, nutation_range]
"""

SLEW = """
scene: spacecraft_slew
seed: 5
samples: 6
duration: 60.0
grid: {method: [rk4], dt: [0.05]}
dispersions:
  principal_moments: {relative: 0.05}
  torque_scale: {relative: 0.02}
  torque_noise: {sigma: 1.0e-3, interval: 2.0}
checkpoints: 30
"""


def same_columns(a, b):
    for name, kind in COLUMNS.items():
        if kind == "string":
            assert list(a[name]) == list(b[name]), name
        else:
            assert np.array_equal(np.asarray(a[name]), np.asarray(b[name]), equal_nan=True), name


@pytest.fixture(scope="module")
def mixed():
    spec = parse_sweep_text(MIXED, "mixed.yaml")
    return spec, run_local(spec, chunk_size=7)


def test_rows_do_not_depend_on_chunking(mixed):
    spec, rows = mixed
    same_columns(rows, run_local(spec, chunk_size=2))
    # one run alone, as a retry of a one-body task would compute it
    alone = run_chunk(spec, Chunk(grid_point=5, start=3, stop=4))
    row = int(np.flatnonzero(rows["run"] == 5 * spec.samples + 3)[0])
    for name in ("final_attitude_error", "final_omega_x", "max_omega", "energy_drift", "first_flip"):
        assert np.array_equal(alone[name][0], rows[name][row], equal_nan=True), name


@pytest.mark.parametrize("text", [MIXED, SLEW, SLEW.replace("  torque_noise: {sigma: 1.0e-3, interval: 2.0}\n", "")])
def test_rows_do_not_depend_on_how_a_run_is_cut_into_kernel_calls(text, monkeypatch):
    """Stretches under unchanged torques run as one recording call, at most _RECORDED_BYTES of rates per call,
    and as one call per segment after a failure: every way gives the same bits, failed runs and errors included."""
    from rigid_rot_sim.core.integrators.base import NonFiniteStateError
    from rigid_rot_sim.sweep import chunks as sweep

    spec = parse_sweep_text(text, "cuts.yaml")
    joined = run_local(spec, chunk_size=7)
    monkeypatch.setattr(sweep, "_RECORDED_BYTES", 0)  # two segments per call
    same_columns(joined, run_local(spec, chunk_size=7))

    def refused(*args, **kwargs):
        raise NonFiniteStateError("joined call refused: run the segments one at a time")

    monkeypatch.setattr(sweep, "advance_batch_recording", refused)
    same_columns(joined, run_local(spec, chunk_size=7))
    if text is MIXED:
        assert any(verdict == "unstable" for verdict in joined["verdict"])


def test_a_numerically_failing_run_is_a_row_with_its_error(mixed):
    spec, rows = mixed
    assert len(rows["run"]) == spec.n_runs and list(rows["run"]) == list(range(spec.n_runs))
    unstable = [i for i, v in enumerate(rows["verdict"]) if v == "unstable"]
    assert unstable, "rk4 at 15 rad per step must blow up"
    for i in unstable:
        assert rows["method"][i] == "rk4" and rows["dt"][i] == 0.5 and rows["spin_rate"][i] == 30.0
        assert "NonFiniteStateError" in rows["error"][i] and np.isnan(rows["final_omega_x"][i])
    # the rest of those chunks finished, with their own numbers
    finished = [i for i, v in enumerate(rows["verdict"]) if v != "unstable"]
    assert len(finished) == spec.n_runs - len(unstable)
    assert all(rows["error"][i] is None for i in finished)
    assert np.all(np.isfinite(rows["final_omega_x"][finished]))


def test_implicit_midpoint_conserves_what_the_physics_conserves(mixed):
    _, rows = mixed
    midpoint = np.array([m == "implicit_midpoint" for m in rows["method"]])
    # torque-free: T and |L| conserved to round-off by the midpoint rule at any step
    assert np.all(rows["energy_drift"][midpoint] < 1e-12) and np.all(rows["momentum_drift"][midpoint] < 1e-12)
    assert all(v == "stable" for v, m in zip(rows["verdict"], midpoint, strict=True) if m)
    # near a major-axis spin the nutation angle stays small and bounded; no intermediate flip at 2 rad/s in 4 s
    assert np.all(rows["nutation_range"][midpoint] < 0.2)


def test_samples_draw_from_their_own_seed():
    spec = parse_sweep_text(MIXED, "mixed.yaml")
    a, b = sample_inputs(spec, 3), sample_inputs(spec, 3)
    assert all(np.array_equal(a[k], b[k]) for k in a)
    c = sample_inputs(spec, 4)
    assert not np.array_equal(a["moments"], c["moments"])
    # one dispersion switched off does not change another's draws
    fewer = parse_sweep_text(MIXED.replace("  initial_omega: {sigma: 1.0e-2}\n", ""), "mixed.yaml")
    assert np.array_equal(sample_inputs(fewer, 3)["moments"], a["moments"])
    assert not sample_inputs(fewer, 3)["omega"].any()
    # the normal draws are cut at 4 sigma
    draws = np.array([sample_inputs(spec, s)["moments"] for s in range(300)])
    assert np.abs(draws).max() <= 4 * 0.02


def test_undispersed_runs_equal_the_nominal_bit_for_bit():
    spec = parse_sweep_text(SLEW.split("dispersions:")[0], "plain.yaml")
    rows = run_local(spec, chunk_size=4)
    assert np.all(rows["final_attitude_error"] == 0.0) and np.all(rows["final_omega_error"] == 0.0)


def test_slew_rows_are_physical_and_outputs_are_written(tmp_path):
    spec = parse_sweep_text(SLEW, str(tmp_path / "slew.yaml"))
    rows = run_local(spec, chunk_size=3)
    # driven: no conservation columns; the slew ends near rest, |omega| bounded by the impulse
    assert np.all(np.isnan(rows["energy_drift"]))
    assert all(v == "stable" for v in rows["verdict"])
    final = np.linalg.norm(np.c_[rows["final_omega_x"], rows["final_omega_y"], rows["final_omega_z"]], axis=1)
    assert np.all(final < 0.1 * rows["max_omega"])
    assert np.all((rows["final_attitude_error"] > 0) & (rows["final_attitude_error"] < 0.5))
    result = SweepResult(spec=spec, columns=rows, quick=False, engine={"workers": 1, "chunks": 2, "chunk_size": 3})
    files = write_outputs(result, tmp_path / "out")
    table = pq.read_table(files["parquet"])
    assert table.column_names == list(COLUMNS) and table.num_rows == spec.n_runs
    meta = json.loads(table.schema.metadata[METADATA_KEY])
    assert meta["seed"] == 5 and meta["spec_text"] == SLEW and "spacecraft_slew" in meta["scene_text"]
    assert meta["versions"]["numpy"] == np.__version__ and meta["versions"]["pyarrow"] != "not installed"
    assert np.array_equal(table.column("final_attitude_error").to_numpy(), rows["final_attitude_error"])
    summary = (tmp_path / "out" / "summary.md").read_text()
    median = np.percentile(rows["final_attitude_error"], 50)
    assert f"| final_attitude_error | {spec.n_runs} |" in summary and f"{median:.4g}" in summary
    for name in ("histogram", "scatter"):
        assert (tmp_path / "out" / f"{name}.png").stat().st_size > 10_000


def test_plan_chunks_covers_every_sample_once():
    spec = parse_sweep_text(MIXED, "mixed.yaml")
    chunks = plan_chunks(spec, 3)
    covered = sorted((c.grid_point, s) for c in chunks for s in range(c.start, c.stop))
    assert covered == [(g, s) for g in range(len(spec.grid)) for s in range(spec.samples)]


def test_scheduler_address_comes_from_the_option_or_the_environment(monkeypatch):
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    assert scheduler_address(None) is None
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", "tcp://10.0.0.1:8786")
    assert scheduler_address(None) == "tcp://10.0.0.1:8786"
    assert scheduler_address("tcp://127.0.0.1:1") == "tcp://127.0.0.1:1"


def test_first_flip_obeys_the_scaling_law_of_eulers_equations():
    """omega -> k omega, t -> t / k maps solutions onto solutions: at dt / k, rk4 takes the same steps.

    Every step is a checkpoint in both runs, so the interpolated crossings map onto each other too.
    """
    spec = parse_sweep_text(
        """
scene: intermediate_axis_flip
seed: 0
samples: 1
duration: 7.0
grid: {method: [rk4], dt: [0.008, 0.002], spin_rate: [2.0, 8.0]}
checkpoints: 3500
events: [first_flip]
metric: first_flip
""",
        "flip.yaml",
    )
    rows = run_local(spec)
    triples = zip(rows["dt"], rows["spin_rate"], rows["first_flip"], strict=True)
    flip = {(float(dt), float(spin)): t for dt, spin, t in triples}
    slow, fast = flip[(0.008, 2.0)], flip[(0.002, 8.0)]
    assert 1.0 < fast < slow < 7.0
    assert slow / fast == pytest.approx(4.0, rel=1e-9)
    # torque-free: energy and |L| conserved to rk4's accuracy at about 0.016 rad per step
    assert np.all(rows["energy_drift"] < 1e-6) and np.all(rows["momentum_drift"] < 1e-6)


def _numpy_draw(seed, sample, stream, size):
    """A normal dispersion's draw from a fresh numpy generator, cut at 4 sigmas as the spec says."""
    rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(sample, stream))))
    z = rng.standard_normal(3)
    while np.any(np.abs(z) > 4.0):
        bad = np.abs(z) > 4.0
        z[bad] = rng.standard_normal(int(bad.sum()))
    return z * size


def test_batched_draws_are_each_samples_own_stream():
    """A chunk's draws (built together) are each sample's numpy stream, a draw beyond the cut included."""
    spec = parse_sweep_text(MIXED.replace("samples: 7", "samples: 6600"), "mixed.yaml")
    # sample 6578's first initial_omega draw (stream 2) has a component beyond 4 sigmas: it is drawn again
    first = np.random.Generator(np.random.PCG64(np.random.SeedSequence(11, spawn_key=(6578, 2)))).standard_normal(3)
    assert np.any(np.abs(first) > 4.0)
    samples = np.arange(6570, 6590)
    batch = _sample_draws(spec, samples)
    for i, sample in enumerate(samples.tolist()):
        omega = _numpy_draw(11, sample, 2, 1.0e-2)
        assert np.array_equal(batch["omega"][i], omega), sample
        assert np.array_equal(sample_inputs(spec, sample)["omega"], omega), sample
        assert np.all(np.abs(omega) <= 4.0e-2)
        assert np.array_equal(batch["moments"][i], _numpy_draw(11, sample, 0, 0.02))
