"""The vectorised per-sample streams are numpy's ``PCG64(SeedSequence(seed, spawn_key=(sample, stream)))``."""

import numpy as np
import pytest

from rigid_rot_sim.sweep.draws import StreamDraws, pcg64_states

SAMPLES = np.array([0, 1, 2, 7, 255, 65536, 2**31 - 1, 2**32 - 1, 2**32, 2**32 + 5, 2**40 + 3, 123456789])


@pytest.mark.parametrize("seed", [0, 1, 42, 2**32 - 1, 2**32, 2**64 + 12345, 2**200 + 7])
@pytest.mark.parametrize("stream", [0, 3, 5, 2**33])
def test_states_are_numpys(seed, stream):
    ours = pcg64_states(seed, SAMPLES, stream)
    for sample, (state, inc) in zip(SAMPLES.tolist(), ours, strict=True):
        ref = np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(sample, stream))).state["state"]
        assert (state, inc) == (ref["state"], ref["inc"]), (seed, sample, stream)


def test_draws_are_numpys_in_any_order():
    samples = np.array([9, 3, 2**32 + 1, 3, 0])
    draws = StreamDraws()
    for sample, generator in zip(samples.tolist(), draws.each(7, samples, 2), strict=True):
        ref = np.random.Generator(np.random.PCG64(np.random.SeedSequence(7, spawn_key=(sample, 2))))
        assert np.array_equal(generator.standard_normal(5), ref.standard_normal(5))
        assert np.array_equal(generator.uniform(-1.0, 1.0, (4, 3)), ref.uniform(-1.0, 1.0, (4, 3)))
        assert generator.integers(0, 2**31) == ref.integers(0, 2**31)  # uses the buffered 32-bit half


def test_negative_indices_are_refused():
    with pytest.raises(ValueError):
        pcg64_states(1, np.array([-1]), 0)
    with pytest.raises(ValueError):
        pcg64_states(-1, np.array([1]), 0)


def test_fast_state_loading_is_in_use_and_exact():
    """On this numpy the state words are written in place (checked at construction), with numpy's draws."""
    draws = StreamDraws()
    assert draws._words is not None  # the layout check passed: the fast path is what the sweeps run
    samples = np.arange(50)
    for sample, generator in zip(samples.tolist(), draws.each(3, samples, 4), strict=True):
        ref = np.random.Generator(np.random.PCG64(np.random.SeedSequence(3, spawn_key=(sample, 4))))
        # a 32-bit draw leaves half a 64-bit word buffered: the next sample's load must drop it
        assert generator.integers(0, 2**31) == ref.integers(0, 2**31)
        assert np.array_equal(generator.standard_normal(4), ref.standard_normal(4))


def _numpy_generator(seed, sample, stream):
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(sample, stream))))


def _numpy_cut_normals(seed, sample, stream, count, cut):
    rng = _numpy_generator(seed, sample, stream)
    z = rng.standard_normal(count)
    while cut > 0.0 and np.any(np.abs(z) > cut):
        bad = np.abs(z) > cut
        z[bad] = rng.standard_normal(int(bad.sum()))
    return z


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "python"])
def test_compiled_draws_are_numpys_bits(compiled):
    """normals (cut and uncut, the ziggurat's tail included) and uniforms: numpy's bits, in any sample order."""
    draws = StreamDraws()
    if not compiled:
        draws._words = None  # the path taken where numpy's state layout is not the one checked
    samples = np.array([5, 0, 2**32 + 9, 5, *range(100, 400)])
    cut = 1.5  # low enough that many samples draw again, some more than once
    normals = draws.normals(13, samples, 1, 3, cut=cut)
    again = 0
    for i, sample in enumerate(samples.tolist()):
        ref = _numpy_cut_normals(13, sample, 1, 3, cut)
        assert np.array_equal(normals[i].view(np.uint64), ref.view(np.uint64)), sample
        again += bool(np.any(np.abs(_numpy_generator(13, sample, 1).standard_normal(3)) > cut))
    assert again > 50 and np.all(np.abs(normals) <= cut)
    long = draws.normals(13, samples[:40], 4, 3000)  # 1.2e5 numbers: beyond 3.654 (the tail) about 30 times
    assert np.sum(np.abs(long) > 3.6541528853610088) > 5
    for i, sample in enumerate(samples[:40].tolist()):
        assert np.array_equal(long[i], _numpy_generator(13, sample, 4).standard_normal(3000)), sample
    uniforms = draws.uniforms(13, samples, 2, 5, -1.0, 1.0)
    for i, sample in enumerate(samples.tolist()):
        assert np.array_equal(uniforms[i], _numpy_generator(13, sample, 2).uniform(-1.0, 1.0, 5)), sample
    assert draws.normals(13, samples, 1, 0).shape == (len(samples), 0)
