"""numpy's per-sample streams ``PCG64(SeedSequence(seed, spawn_key=(sample, stream)))``, many samples at once.

Building one such generator costs numpy 10-30 µs (a SeedSequence, then a PCG64 seeded from
it), more than a short run's physics in the batch core. The same generator states are
computed here for a whole chunk of samples in one compiled loop (~50 ns a sample): numpy's
SeedSequence hash (its ``mix_entropy`` and ``generate_state``, 32-bit words in uint64) and
PCG64's seeding (``pcg_setseq_128_srandom_r``, 128-bit arithmetic on two uint64 words).
:class:`StreamDraws` loads each state into one generator in turn, so every draw is numpy's
own, bit for bit (``test/sweep/test_draws.py`` compares the states and draws with numpy's).

A sweep's draws are a few numbers per sample and stream. Drawn from Python, each sample
costs ~2 µs of calls, as much as the physics of a short run; :meth:`StreamDraws.normals`
and :meth:`StreamDraws.uniforms` load the states and draw in one compiled loop instead,
through numba's ``Generator`` support, whose ``standard_normal`` and ``uniform`` are ports of
numpy's (the ziggurat with its tables) calling the same PCG64 through its ``ctypes``
interface: the same bits, ~70 ns per sample.
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Iterator

import numpy as np

from rigid_rot_sim.core.jit import compiled

__all__ = ["pcg64_state_words", "pcg64_states", "StreamDraws"]

_M32 = 0xFFFF_FFFF
_M64 = (1 << 64) - 1
# numpy/random/bit_generator.pyx
_POOL_SIZE = 4
_INIT_A, _MULT_A = 0x43B0D7E5, 0x931E8875
_INIT_B, _MULT_B = 0x8B51F9DD, 0x58F38DED
_MIX_MULT_L, _MIX_MULT_R = 0xCA01F9DD, 0x4973F715
_XSHIFT = 16
# numpy/random/src/pcg64/pcg64.h: PCG_DEFAULT_MULTIPLIER_128
_PCG_MULT = (2549297995355413924 << 64) + 4865540595714422341


def _words(value: int) -> list[int]:
    """A non-negative int as little-endian 32-bit words (0 is one word), as SeedSequence coerces it."""
    if value < 0:
        raise ValueError(f"seeds and spawn keys must be >= 0, got {value}")
    words = [value & _M32]
    value >>= 32
    while value:
        words.append(value & _M32)
        value >>= 32
    return words


# the constants as uint64 for the compiled loop (numba turns mixed int64/uint64 arithmetic into floats)
_U = np.uint64
_K_M32, _K_0, _K_1, _K_16, _K_32, _K_63 = _U(_M32), _U(0), _U(1), _U(_XSHIFT), _U(32), _U(63)
_K_INIT_A, _K_MULT_A, _K_INIT_B, _K_MULT_B = _U(_INIT_A), _U(_MULT_A), _U(_INIT_B), _U(_MULT_B)
_K_MIX_L, _K_MIX_R = _U(_MIX_MULT_L), _U(_MIX_MULT_R)
_K_PCG_HI, _K_PCG_LO = _U(_PCG_MULT >> 64), _U(_PCG_MULT & _M64)


@compiled
def _hashmix(value, hash_const):
    """SeedSequence's hashmix: (the mixed value, the next hash constant)."""
    value = value ^ hash_const
    hash_const = (hash_const * _K_MULT_A) & _K_M32
    value = (value * hash_const) & _K_M32
    return value ^ (value >> _K_16), hash_const


@compiled
def _mix(x, y):
    result = (x * _K_MIX_L - y * _K_MIX_R) & _K_M32
    return result ^ (result >> _K_16)


@compiled
def _mix_in(pool, hash_const, words):
    """mix_entropy's loop over the words past the pool's size: each mixed into every pool entry.

    Returns the hash constant it leaves (the pool is updated in place).
    """
    for src in range(words.size):
        for dst in range(_POOL_SIZE):
            hashed, hash_const = _hashmix(words[src], hash_const)
            pool[dst] = _mix(pool[dst], hashed)
    return hash_const


@compiled
def _run_pool_compiled(run):
    """SeedSequence.mix_entropy of the run's words (>= 4 of them): the pool and the hash constant it leaves."""
    pool = np.empty(_POOL_SIZE, dtype=np.uint64)
    hash_const = _K_INIT_A
    for i in range(_POOL_SIZE):
        pool[i], hash_const = _hashmix(run[i], hash_const)
    for src in range(_POOL_SIZE):
        for dst in range(_POOL_SIZE):
            if src != dst:
                hashed, hash_const = _hashmix(pool[src], hash_const)
                pool[dst] = _mix(pool[dst], hashed)
    return pool, _mix_in(pool, hash_const, run[_POOL_SIZE:])


@compiled
def _mul_hi(a, b):
    """The high 64 bits of the 128-bit product of two uint64, on 32-bit halves."""
    a0, a1, b0, b1 = a & _K_M32, a >> _K_32, b & _K_M32, b >> _K_32
    middle = a1 * b0 + ((a0 * b0) >> _K_32)
    middle2 = a0 * b1 + (middle & _K_M32)
    return a1 * b1 + (middle >> _K_32) + (middle2 >> _K_32)


@compiled
def _seed_samples(pool0, hash_const0, samples, key, out):
    """``out[i]``: PCG64 seeded from SeedSequence(run, spawn_key=(samples[i], key)), the run's pool given.

    ``pool0``, ``hash_const0``: mix_entropy's pool and hash constant after the run's words.
    Then, as numpy: the sample's 32-bit words (one, or two from 2**32) and the key's are
    mixed in, ``generate_state(4, uint64)``, and ``pcg64_set_seed``: inc = initseq << 1 | 1;
    state = (inc + initstate) * PCG_DEFAULT_MULTIPLIER_128 + inc, mod 2**128.
    """
    entropy = np.empty(2 + key.size, dtype=np.uint64)
    pool = np.empty(4, dtype=np.uint64)
    words = np.empty(8, dtype=np.uint64)
    for i in range(samples.size):
        sample = np.uint64(samples[i])
        count = 1 if (sample >> _K_32) == _K_0 else 2
        entropy[0] = sample & _K_M32
        entropy[1] = sample >> _K_32
        for k in range(key.size):
            entropy[count + k] = key[k]
        pool[:] = pool0
        _mix_in(pool, hash_const0, entropy[: count + key.size])
        hash_const = _K_INIT_B
        for k in range(8):
            value = pool[k % 4] ^ hash_const
            hash_const = (hash_const * _K_MULT_B) & _K_M32
            value = (value * hash_const) & _K_M32
            words[k] = value ^ (value >> _K_16)
        w0, w1 = words[0] | (words[1] << _K_32), words[2] | (words[3] << _K_32)
        w2, w3 = words[4] | (words[5] << _K_32), words[6] | (words[7] << _K_32)
        # initstate = (w0 << 64) | w1, initseq = (w2 << 64) | w3
        inc_hi, inc_lo = (w2 << _K_1) | (w3 >> _K_63), (w3 << _K_1) | _K_1
        lo = inc_lo + w1
        hi = inc_hi + w0 + (_K_1 if lo < inc_lo else _K_0)
        product_lo = lo * _K_PCG_LO
        product_hi = _mul_hi(lo, _K_PCG_LO) + lo * _K_PCG_HI + hi * _K_PCG_LO
        state_lo = product_lo + inc_lo
        state_hi = product_hi + inc_hi + (_K_1 if state_lo < product_lo else _K_0)
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = state_lo, state_hi, inc_lo, inc_hi
    return out


def pcg64_state_words(seed: int, samples: np.ndarray, stream: int) -> np.ndarray:
    """The states of ``PCG64(SeedSequence(seed, spawn_key=(s, stream)))`` for each s of ``samples``.

    (N, 4) uint64: the 128-bit state's low and high words, then the increment's.

    The run's words come first in the entropy, so the pool they give (and the hash
    constant after them) is the same for every sample: it is computed once per seed;
    then each sample's words and the stream's are mixed in and the generator seeded,
    one sample at a time in a compiled loop (:func:`_seed_samples`).
    """
    samples = np.asarray(samples, dtype=np.int64)
    if samples.size and samples.min() < 0:
        raise ValueError("sample indices must be >= 0")
    key = np.array(_words(int(stream)), dtype=np.uint64)
    pool, hash_const = _run_pool(int(seed))
    out = np.zeros((samples.size, 4), dtype=np.uint64)
    return _seed_samples(pool, np.uint64(hash_const), samples, key, out)


@functools.lru_cache(maxsize=64)
def _run_pool(seed: int) -> tuple[np.ndarray, int]:
    """mix_entropy's pool and hash constant after the run's words (the same for every sample and stream)."""
    run = _words(seed)
    run += [0] * (_POOL_SIZE - len(run))  # SeedSequence pads the run entropy when there is a spawn key
    pool, hash_const = _run_pool_compiled(np.array(run, dtype=np.uint64))
    pool.flags.writeable = False  # shared by every call with this seed
    return pool, int(hash_const)


def pcg64_states(seed: int, samples: np.ndarray, stream: int) -> list[tuple[int, int]]:
    """``(state, inc)`` of ``PCG64(SeedSequence(seed, spawn_key=(s, stream)))`` for each s, as integers."""
    return [(lo | hi << 64, ilo | ihi << 64) for lo, hi, ilo, ihi in pcg64_state_words(seed, samples, stream).tolist()]


@compiled
def _load_stream(words, flags, row):
    """Write a fresh stream's state into the generator: the state words, no buffered 32-bit half."""
    for j in range(4):
        words[j] = row[j]
    flags[0] = 0
    flags[1] = 0


@compiled
def _fill_normals(generator, words, flags, rows, cut, out):
    """Row i of ``out``: standard normals of the stream whose state is ``rows[i]``, in order.

    ``cut`` > 0: a number beyond ``cut`` is drawn again (the next draw of the stream, each
    position in turn, until none is beyond), as ``z[bad] = rng.standard_normal(bad.sum())``
    in a loop does. ``words``/``flags``: the generator's state words and its has_uint32,
    uinteger pair, written in place to load each row's fresh stream.
    """
    for i in range(rows.shape[0]):
        _load_stream(words, flags, rows[i])
        for c in range(out.shape[1]):
            out[i, c] = generator.standard_normal()
        beyond = cut > 0.0
        while beyond:
            beyond = False
            for c in range(out.shape[1]):
                if abs(out[i, c]) > cut:
                    out[i, c] = generator.standard_normal()
                    beyond = beyond or abs(out[i, c]) > cut
    return out


@compiled
def _fill_uniforms(generator, words, flags, rows, low, high, out):
    """Row i of ``out``: uniform numbers in [low, high) of the stream whose state is ``rows[i]``."""
    for i in range(rows.shape[0]):
        _load_stream(words, flags, rows[i])
        for c in range(out.shape[1]):
            out[i, c] = generator.uniform(low, high)
    return out


class StreamDraws:
    """One numpy Generator that takes on, in turn, the stream ``(sample, stream)`` of each sample.

    A state is loaded by writing the PCG64 state words in place (through the bit generator's
    documented ``ctypes`` interface: ~0.3 µs, where the ``state`` property takes ~3 µs) when
    a check at construction shows that this numpy lays them out as expected (128-bit state
    and increment, low word first, then ``has_uint32`` and ``uinteger``); else through the
    ``state`` property.
    """

    def __init__(self) -> None:
        self._bits = np.random.PCG64()
        self.generator = np.random.Generator(self._bits)
        self._words: np.ndarray | None = None
        self._flags: np.ndarray | None = None
        try:
            address = self._bits.ctypes.state_address  # struct {pcg64_random_t *; int has_uint32; uint32 uinteger}
            flags = np.ctypeslib.as_array(ctypes.cast(address, ctypes.POINTER(ctypes.c_uint32)), shape=(4,))
            inner = ctypes.cast(address, ctypes.POINTER(ctypes.c_void_p))[0]
            words = np.ctypeslib.as_array(ctypes.cast(inner, ctypes.POINTER(ctypes.c_uint64)), shape=(4,))
        except (AttributeError, TypeError, ValueError):
            return
        state, inc = (0x0123456789ABCDEF << 64) | 0xFEDCBA9876543210, (0x1111222233334444 << 64) | 0x5555666677778889
        words[:] = state & _M64, state >> 64, inc & _M64, inc >> 64
        flags[2:] = 1, 7
        if self._bits.state == {
            "bit_generator": "PCG64",
            "state": {"state": state, "inc": inc},
            "has_uint32": 1,
            "uinteger": 7,
        }:
            self._words, self._flags = words, flags

    def each(self, seed: int, samples: np.ndarray, stream: int) -> Iterator[np.random.Generator]:
        """The generator, set to each sample's fresh stream in order of ``samples``."""
        if self._words is not None and self._flags is not None:
            rows = np.ascontiguousarray(pcg64_state_words(seed, samples, stream))
            for row in rows:
                _load_stream(self._words, self._flags[2:], row)
                yield self.generator
            return
        for state, inc in pcg64_states(seed, samples, stream):
            self._bits.state = {
                "bit_generator": "PCG64",
                "state": {"state": state, "inc": inc},
                "has_uint32": 0,
                "uinteger": 0,
            }
            yield self.generator

    def normals(self, seed: int, samples: np.ndarray, stream: int, count: int, cut: float = 0.0) -> np.ndarray:
        """(N, count): each sample's stream's first ``count`` standard normals.

        ``cut`` > 0 draws a number beyond ``cut`` again, from the same stream, until none is:
        the numbers ``z = rng.standard_normal(count)`` and ``z[bad] = rng.standard_normal(...)``
        while any is beyond give.
        """
        out = np.empty((len(samples), count))
        if self._words is not None and self._flags is not None and count:
            rows = np.ascontiguousarray(pcg64_state_words(seed, samples, stream))
            return _fill_normals(self.generator, self._words, self._flags[2:], rows, float(cut), out)
        for i, rng in enumerate(self.each(seed, samples, stream)):
            z = rng.standard_normal(count)
            while cut > 0.0 and (np.abs(z) > cut).any():
                bad = np.abs(z) > cut
                z[bad] = rng.standard_normal(int(bad.sum()))
            out[i] = z
        return out

    def uniforms(self, seed: int, samples: np.ndarray, stream: int, count: int, low: float, high: float) -> np.ndarray:
        """(N, count): each sample's stream's first ``count`` numbers of ``rng.uniform(low, high)``."""
        out = np.empty((len(samples), count))
        if self._words is not None and self._flags is not None and count:
            rows = np.ascontiguousarray(pcg64_state_words(seed, samples, stream))
            return _fill_uniforms(self.generator, self._words, self._flags[2:], rows, float(low), float(high), out)
        for i, rng in enumerate(self.each(seed, samples, stream)):
            out[i] = rng.uniform(low, high, count)
        return out
