"""The compiled checkpoint trackers give the numpy formulas' bits, failed (NaN) bodies included."""

import numpy as np

from rigid_rot_sim.sweep.checkpoints import CheckpointTrack, row_norms


def _numpy_trackers(moments, omegas, times):
    """The sweep's trackers as plain array code (the formulas the compiled loop must reproduce)."""
    n = moments.shape[0]
    rows = np.arange(n)
    intermediate = np.argsort(moments, axis=1)[:, 1]
    major = np.argmax(moments, axis=1)
    sign0 = np.sign(omegas[0][rows, intermediate])
    first_flip = np.full(n, np.nan)
    previous = (0.0, omegas[0][rows, intermediate].copy())
    nut_min, nut_max = np.full(n, np.inf), np.full(n, -np.inf)
    max_omega = np.linalg.norm(omegas[0], axis=1)
    for t, omega in zip(times, omegas, strict=True):
        np.maximum(max_omega, np.linalg.norm(omega, axis=1), out=max_omega)
        momentum = moments * omega
        cos = np.abs(momentum[rows, major]) / np.maximum(np.linalg.norm(momentum, axis=1), np.finfo(float).tiny)
        angle = np.arccos(np.clip(cos, 0.0, 1.0))
        np.minimum(nut_min, angle, out=nut_min)
        np.maximum(nut_max, angle, out=nut_max)
        w_int = omega[rows, intermediate]
        flipped = np.isnan(first_flip) & (sign0 != 0) & (np.sign(w_int) == -sign0)
        t0, w0 = previous
        frac = w0[flipped] / (w0[flipped] - w_int[flipped])
        first_flip[flipped] = t0 + frac * (t - t0)
        previous = (t, w_int.copy())
    return max_omega, nut_max - nut_min, first_flip


def test_trackers_match_the_array_formulas_bit_for_bit():
    rng = np.random.default_rng(3)
    n, checkpoints = 500, 12
    moments = rng.uniform(1.0, 3.0, (n, 3))
    times = np.concatenate(([0.0], np.cumsum(rng.uniform(0.1, 0.5, checkpoints))))
    # rates that wander through zero on every axis, so that many bodies flip at some checkpoint
    omegas = [rng.normal(size=(n, 3))]
    for _ in range(checkpoints):
        omegas.append(omegas[-1] + 0.6 * rng.normal(size=(n, 3)))
    omegas[0][:5, :] = 0.0  # no rate: sign0 = 0 never flips, zero momentum (the tiny floor)
    for k in range(4, checkpoints + 1):  # bodies failing part-way: NaN from then on
        omegas[k][5:20] = np.nan
    track = CheckpointTrack(moments, omegas[0])
    for t, omega in zip(times, omegas, strict=True):
        track.observe(t, omega)
    max_omega, nutation, flip = _numpy_trackers(moments, omegas, times)
    assert np.isfinite(track.first_flip).sum() > n // 4  # the flip branch is exercised
    assert np.isnan(track.max_omega[5:20]).all() and np.isnan(track.nutation_range()[5:20]).all()
    for ours, theirs in ((track.max_omega, max_omega), (track.nutation_range(), nutation), (track.first_flip, flip)):
        assert np.array_equal(ours, theirs, equal_nan=True)


def test_row_norms_are_numpys_bits():
    rng = np.random.default_rng(8)
    x = rng.normal(size=(3000, 3)) * rng.choice([1e-160, 1.0, 1e150], size=(3000, 1))
    x[:10] = np.nan
    x[10:20] = 0.0
    x[20, 1] = np.inf
    assert np.array_equal(row_norms(x), np.linalg.norm(x, axis=1), equal_nan=True)
    assert np.array_equal(row_norms(np.asfortranarray(x)), np.linalg.norm(x, axis=1), equal_nan=True)  # any layout
