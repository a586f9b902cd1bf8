"""What a sweep records of each body at its checkpoints, in one compiled pass over the bodies.

At every checkpoint a sweep updates, per body, the largest ``|omega|``, the range of the
nutation angle (between L and the major principal axis) and the time of the first flip
(the first sign change of the intermediate-axis rate, interpolated linearly between two
checkpoints). On arrays this was a dozen numpy passes per checkpoint, as costly as the
physics of a short run; here it is one loop. The arithmetic is the numpy version's, in
its order (``|v| = sqrt((x*x + y*y) + z*z)``, NaN propagating through the max and min),
so the figures are the same bits. The loop keeps the range of the angle's cosine and
numpy's ``arccos`` (decreasing) turns it into the angle's range at the end.
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["CheckpointTrack", "row_norms", "checkpoint_steps", "checkpoint_time"]

_TINY = float(np.finfo(float).tiny)


@numba.njit(cache=True)
def _row_norms(x, out):
    for i in range(x.shape[0]):
        out[i] = math.sqrt(x[i, 0] * x[i, 0] + x[i, 1] * x[i, 1] + x[i, 2] * x[i, 2])
    return out


def row_norms(x: np.ndarray) -> np.ndarray:
    """(N,) Euclidean norms of the rows of an (N, 3) array: ``np.linalg.norm(x, axis=1)``, the same bits.

    numpy sums each 3-element row in order, ``(x*x + y*y) + z*z``, as this loop does; its
    ``norm`` also copies the array first (``conj``), ~40x the loop's time on a chunk.
    """
    x = np.ascontiguousarray(x, dtype=float)
    return _row_norms(x, np.empty(x.shape[0]))


@numba.njit(cache=True)
def _nan_max(a: float, b: float) -> float:
    """``np.maximum``: NaN if either is."""
    if math.isnan(a) or math.isnan(b):
        return math.nan
    return a if a >= b else b


@numba.njit(cache=True)
def _nan_min(a: float, b: float) -> float:
    """``np.minimum``: NaN if either is."""
    if math.isnan(a) or math.isnan(b):
        return math.nan
    return a if a <= b else b


@numba.njit(cache=True)
def _observe(t, omega, moments, major, intermediate, sign0, max_omega, cos_min, cos_max, first_flip, previous):
    """One checkpoint at time ``t`` (s) of the principal-frame rates ``omega`` (N, 3): updates the trackers in place.

    ``previous``: (N + 1,) the last checkpoint's time, then each body's intermediate rate.
    """
    t0 = previous[0]
    for i in range(omega.shape[0]):
        wx, wy, wz = omega[i, 0], omega[i, 1], omega[i, 2]
        max_omega[i] = _nan_max(max_omega[i], math.sqrt(wx * wx + wy * wy + wz * wz))
        lx, ly, lz = moments[i, 0] * wx, moments[i, 1] * wy, moments[i, 2] * wz
        cos = abs((lx, ly, lz)[major[i]]) / _nan_max(math.sqrt(lx * lx + ly * ly + lz * lz), _TINY)
        if not math.isnan(cos):
            cos = min(max(cos, 0.0), 1.0)
        cos_min[i] = _nan_min(cos_min[i], cos)
        cos_max[i] = _nan_max(cos_max[i], cos)
        w_int = (wx, wy, wz)[intermediate[i]]
        s = sign0[i]
        if math.isnan(first_flip[i]) and s != 0.0 and not math.isnan(w_int) and np.sign(w_int) == -s:
            w0 = previous[i + 1]
            # linear interpolation of the zero crossing between two checkpoints
            frac = w0 / (w0 - w_int)
            first_flip[i] = t0 + frac * (t - t0)
        previous[i + 1] = w_int
    previous[0] = t


class CheckpointTrack:
    """The per-body trackers of a sweep's checkpoints (principal frame, rad/s, rad, s)."""

    def __init__(self, moments: np.ndarray, omega0: np.ndarray) -> None:
        n = moments.shape[0]
        self.moments = np.ascontiguousarray(moments, dtype=float)
        self.major = np.ascontiguousarray(np.argmax(moments, axis=1))
        self.intermediate = np.ascontiguousarray(np.argsort(moments, axis=1)[:, 1])
        self.sign0 = np.sign(omega0[np.arange(n), self.intermediate])
        self.max_omega = np.full(n, -np.inf)
        self._cos_min = np.full(n, np.inf)  # of the nutation angle
        self._cos_max = np.full(n, -np.inf)
        self.first_flip = np.full(n, np.nan)
        self._previous = np.empty(n + 1)
        self._previous[0] = 0.0
        self._previous[1:] = omega0[np.arange(n), self.intermediate]

    def observe(self, t: float, omega: np.ndarray) -> None:
        """Record the checkpoint at ``t`` (s); ``omega`` (N, 3) rad/s, principal frame, NaN for a failed body."""
        _observe(
            float(t),
            np.ascontiguousarray(omega, dtype=float),
            self.moments,
            self.major,
            self.intermediate,
            self.sign0,
            self.max_omega,
            self._cos_min,
            self._cos_max,
            self.first_flip,
            self._previous,
        )

    def nutation_range(self) -> np.ndarray:
        """(N,) rad: the largest minus the smallest nutation angle seen (NaN for a failed body)."""
        return np.arccos(self._cos_min) - np.arccos(self._cos_max)


def checkpoint_steps(n_full: int, checkpoints: int) -> np.ndarray:
    """The step boundaries of a run of ``n_full`` full steps where a sweep takes its ``checkpoints`` (0 included)."""
    return np.unique(np.linspace(0, n_full, checkpoints + 1).round().astype(np.int64))


def checkpoint_time(duration: float, dt: float, n_full: int, last: float, step_end: int) -> float:
    """s: the time at the end of step ``step_end`` (of ``dt`` s; a run of ``n_full`` full steps and a last one of
    ``last`` s, 0 for none, ending on ``duration``): the duration itself at the end, else ``step_end * dt``."""
    return duration if step_end > n_full or (step_end == n_full and last == 0.0) else step_end * dt
