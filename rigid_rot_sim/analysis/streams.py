"""numpy's per-sample streams ``PCG64(SeedSequence(seed, spawn_key=(sample, stream)))``, many samples at once.

Building one such generator costs numpy 10-30 µs (a SeedSequence, then a PCG64 seeded from
it), more than a short run's physics in the batch core. The same generator states are
computed here for a whole chunk of samples: numpy's SeedSequence hash (its ``mix_entropy``
and ``generate_state``, 32-bit words) and PCG64's seeding (``pcg_setseq_128_srandom_r``,
128-bit arithmetic on 32-bit limbs), vectorised over the samples. :class:`StreamDraws` loads each state into
one generator in turn, so every draw is numpy's own, bit for bit
(``test/analysis/test_streams.py`` compares the states and draws with numpy's).
"""

from __future__ import annotations

import ctypes
from collections.abc import Iterator

import numpy as np

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


def _pool(entropy: list[np.ndarray]) -> list[np.ndarray]:
    """SeedSequence.mix_entropy on columns of 32-bit words (uint64 arrays, values < 2**32).

    Array arithmetic wraps modulo 2**64 without warnings; masking keeps the low 32 bits,
    which is numpy's uint32 arithmetic.
    """
    hash_const = _INIT_A
    zero = np.zeros_like(entropy[0])

    def hashmix(value: np.ndarray) -> np.ndarray:
        nonlocal hash_const
        value = value ^ np.uint64(hash_const)
        hash_const = (hash_const * _MULT_A) & _M32
        value = (value * np.uint64(hash_const)) & np.uint64(_M32)
        return value ^ (value >> np.uint64(_XSHIFT))

    def mix(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        difference = np.asarray(x * np.uint64(_MIX_MULT_L) - y * np.uint64(_MIX_MULT_R), dtype=np.uint64)
        result = difference & np.uint64(_M32)
        return result ^ (result >> np.uint64(_XSHIFT))

    pool = [hashmix(entropy[i] if i < len(entropy) else zero) for i in range(_POOL_SIZE)]
    for src in range(_POOL_SIZE):
        for dst in range(_POOL_SIZE):
            if src != dst:
                pool[dst] = mix(pool[dst], hashmix(pool[src]))
    for src in range(_POOL_SIZE, len(entropy)):
        for dst in range(_POOL_SIZE):
            pool[dst] = mix(pool[dst], hashmix(entropy[src]))
    return pool


def _seed_words(pool: list[np.ndarray]) -> list[np.ndarray]:
    """SeedSequence.generate_state(4, np.uint64) from the pools: four uint64 columns."""
    hash_const = _INIT_B
    state = []
    for i in range(8):
        value = pool[i % _POOL_SIZE] ^ np.uint64(hash_const)
        hash_const = (hash_const * _MULT_B) & _M32
        value = (value * np.uint64(hash_const)) & np.uint64(_M32)
        state.append(value ^ (value >> np.uint64(_XSHIFT)))
    return [state[2 * i] | (state[2 * i + 1] << np.uint64(32)) for i in range(4)]


def _limbs(high: np.ndarray, low: np.ndarray) -> list[np.ndarray]:
    """A 128-bit number from its two 64-bit words, as four 32-bit limbs (uint64 arrays), low first."""
    m32 = np.uint64(_M32)
    return [low & m32, low >> np.uint64(32), high & m32, high >> np.uint64(32)]


def _normalised(limbs: list[np.ndarray]) -> list[np.ndarray]:
    """Carry each limb's excess over 32 bits into the next (mod 2**128)."""
    out = []
    carry: np.ndarray | np.uint64 = np.uint64(0)
    for limb in limbs:
        total = limb + carry
        out.append(total & np.uint64(_M32))
        carry = total >> np.uint64(32)
    return out


def _add(a: list[np.ndarray], b: list[np.ndarray]) -> list[np.ndarray]:
    return _normalised([x + y for x, y in zip(a, b, strict=True)])


def _times_multiplier(a: list[np.ndarray]) -> list[np.ndarray]:
    """``a * PCG_DEFAULT_MULTIPLIER_128 mod 2**128`` on limbs: partial products split into 32-bit halves."""
    m = [(_PCG_MULT >> (32 * j)) & _M32 for j in range(4)]
    acc = [np.zeros_like(a[0]) for _ in range(4)]
    for i in range(4):
        for j in range(4 - i):
            product = a[i] * np.uint64(m[j])  # < 2**64
            acc[i + j] += product & np.uint64(_M32)
            if i + j + 1 < 4:
                acc[i + j + 1] += product >> np.uint64(32)
    return _normalised(acc)


def pcg64_state_words(seed: int, samples: np.ndarray, stream: int) -> np.ndarray:
    """The states of ``PCG64(SeedSequence(seed, spawn_key=(s, stream)))`` for each s of ``samples``.

    (N, 4) uint64: the 128-bit state's low and high words, then the increment's.
    """
    samples = np.asarray(samples, dtype=np.int64)
    if samples.size and samples.min() < 0:
        raise ValueError("sample indices must be >= 0")
    run = _words(int(seed))
    run += [0] * (_POOL_SIZE - len(run))  # SeedSequence pads the run entropy when there is a spawn key
    key = _words(int(stream))
    out = np.zeros((samples.size, 4), dtype=np.uint64)
    # SeedSequence coerces each sample index to as many words as it needs: group by that count
    n_words = np.where(samples >> 32 == 0, 1, 2)
    for count in np.unique(n_words):
        where = np.flatnonzero(n_words == count)
        s = samples[where].astype(np.uint64)
        columns = [(s >> np.uint64(32 * j)) & np.uint64(_M32) for j in range(int(count))]
        entropy = [np.full(s.size, word, dtype=np.uint64) for word in run] + columns
        entropy += [np.full(s.size, word, dtype=np.uint64) for word in key]
        w0, w1, w2, w3 = _seed_words(_pool(entropy))
        # pcg64_set_seed: initstate = (w0, w1), initseq = (w2, w3) as (high, low) words;
        # srandom_r: inc = initseq << 1 | 1; state = 0; step; state += initstate; step
        init_state, init_seq = _limbs(w0, w1), _limbs(w2, w3)
        inc = [(limb << np.uint64(1)) & np.uint64(_M32) for limb in init_seq]
        inc = [inc[0] | np.uint64(1)] + [inc[k] | (init_seq[k - 1] >> np.uint64(31)) for k in range(1, 4)]
        state = _add(_times_multiplier(_add(inc, init_state)), inc)
        for column, limbs in ((0, state[:2]), (1, state[2:]), (2, inc[:2]), (3, inc[2:])):
            out[where, column] = limbs[0] | (limbs[1] << np.uint64(32))
    return out


def pcg64_states(seed: int, samples: np.ndarray, stream: int) -> list[tuple[int, int]]:
    """``(state, inc)`` of ``PCG64(SeedSequence(seed, spawn_key=(s, stream)))`` for each s, as integers."""
    return [(lo | hi << 64, ilo | ihi << 64) for lo, hi, ilo, ihi in pcg64_state_words(seed, samples, stream).tolist()]


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
            "bit_generator": "PCG64", "state": {"state": state, "inc": inc}, "has_uint32": 1, "uinteger": 7,
        }:
            self._words, self._flags = words, flags

    def each(self, seed: int, samples: np.ndarray, stream: int) -> Iterator[np.random.Generator]:
        """The generator, set to each sample's fresh stream in order of ``samples``."""
        if self._words is not None and self._flags is not None:
            words = np.ascontiguousarray(pcg64_state_words(seed, samples, stream))
            clear = np.zeros(2, dtype=np.uint32)
            state_at, flags_at = self._words.ctypes.data, self._flags[2:].ctypes.data
            row_at, clear_at = words.ctypes.data, clear.ctypes.data
            for i in range(words.shape[0]):
                ctypes.memmove(state_at, row_at + 32 * i, 32)  # state, inc: the row's four words
                ctypes.memmove(flags_at, clear_at, 8)  # has_uint32, uinteger: a fresh stream's
                yield self.generator
            return
        for state, inc in pcg64_states(seed, samples, stream):
            self._bits.state = {
                "bit_generator": "PCG64", "state": {"state": state, "inc": inc}, "has_uint32": 0, "uinteger": 0,
            }
            yield self.generator
