"""The run digest: one 64-bit number that changes with any bit of any step's state.

Definition (what :func:`fold_steps` computes; pinned by ``test/run/test_digest.py``)::

    h = 0xcbf29ce484222325                      # FNV-1a 64 offset basis, before the first step
    for every step, in order:                   # the state at the boundary the step ends on
        for w in bits(t), bits(qx), bits(qy), bits(qz), bits(qw), bits(wx), bits(wy), bits(wz):
            h = ((h XOR w) * 0x100000001b3) mod 2**64   # FNV-1a 64 prime, a 64-bit word at a time

``bits(x)`` is the IEEE-754 binary64 pattern of ``x`` as an unsigned 64-bit integer; ``t`` is
the sim time of the boundary (s, the step clock's exact time), ``q`` the integrator's
attitude quaternion (x, y, z, w) and ``w`` its angular velocity (rad/s), both in the
principal frame, as the integrator holds them (no rounding of a conversion in between).
Each update is a bijection of ``h`` for a given word, so two runs that differ in one word
of one step never share a digest. The digest runs over the whole run: resets, set_state
and integrator changes are part of it, as the recorded event log replays them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["DIGEST_SEED", "FNV_PRIME", "fold_steps", "format_digest"]

#: FNV-1a 64 offset basis: the digest of a run before its first step.
DIGEST_SEED = 0xCBF29CE484222325
#: FNV-1a 64 prime.
FNV_PRIME = 0x100000001B3
_MASK = (1 << 64) - 1


def fold_steps(digest: int, t: Any, q: Any, omega: Any) -> int:
    """``digest`` with the steps (t[i], q[i], omega[i]) folded in, in order.

    ``t`` (n,) s; ``q`` (n, 4) x, y, z, w; ``omega`` (n, 3) rad/s; float64.
    """
    words = np.empty((len(t), 8), dtype=np.float64)
    words[:, 0] = t
    words[:, 1:5] = q
    words[:, 5:8] = omega
    h = digest
    for w in words.view(np.uint64).ravel().tolist():
        h = ((h ^ w) * FNV_PRIME) & _MASK
    return h


def format_digest(digest: int) -> str:
    """The digest as 16 hex digits (how the CLI and the logs show it)."""
    return f"{digest:016x}"
