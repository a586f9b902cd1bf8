"""What an identification reads: gyro samples and a piecewise-constant torque, as arrays.

Conventions: times in s (any origin, ascending), angular velocity in rad/s in the body
frame of the measurements, torques in N*m, quaternions scalar-last ``(x, y, z, w)``
rotating body -> world. A torque command acts from its time until the next one (a
zero-order hold, as the node applies commands); torque in the world frame is turned into
the body frame with the measured attitude (:func:`world_torque_in_body`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp


@dataclass(frozen=True)
class PiecewiseTorque:
    """A piecewise-constant body-frame torque: ``values[j]`` (N*m) from ``times[j]`` to ``times[j + 1]``.

    Zero before ``times[0]``; the last value holds to the end. Empty arrays: no torque.
    """

    times: np.ndarray
    values: np.ndarray

    def __post_init__(self) -> None:
        times = np.asarray(self.times, dtype=float).reshape(-1)
        values = np.asarray(self.values, dtype=float).reshape(-1, 3)
        if times.shape[0] != values.shape[0]:
            raise ValueError(f"torque: {times.shape[0]} times but {values.shape[0]} values")
        if not (np.all(np.isfinite(times)) and np.all(np.isfinite(values))):
            raise ValueError("torque: times and values must be finite")
        if np.any(np.diff(times) < 0.0):
            raise ValueError("torque: times must be ascending")
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "values", values)

    @classmethod
    def none(cls) -> PiecewiseTorque:
        """No torque at all."""
        return cls(np.zeros(0), np.zeros((0, 3)))

    def at(self, t: np.ndarray) -> np.ndarray:
        """The torque acting at times ``t`` (n,), N*m, shape (n, 3) (right-continuous)."""
        t = np.asarray(t, dtype=float)
        index = np.searchsorted(self.times, t, side="right") - 1
        out = np.zeros((t.shape[0], 3))
        inside = index >= 0
        out[inside] = self.values[index[inside]]
        return out

    def integral(self, t: np.ndarray) -> np.ndarray:
        """The torque integrated from -inf (zero) to each of ``t``, N*m*s, shape (n, 3)."""
        t = np.asarray(t, dtype=float)
        if self.times.shape[0] == 0:
            return np.zeros((t.shape[0], 3))
        steps = np.diff(self.times)[:, None] * self.values[:-1]
        cumulative = np.concatenate([np.zeros((1, 3)), np.cumsum(steps, axis=0)])
        index = np.searchsorted(self.times, t, side="right") - 1
        out = np.zeros((t.shape[0], 3))
        inside = index >= 0
        i = index[inside]
        out[inside] = cumulative[i] + (t[inside] - self.times[i])[:, None] * self.values[i]
        return out


@dataclass(frozen=True)
class Measurements:
    """Gyro readings, the body-frame torque and (optionally) the attitude of one window.

    :param t: (n,) sample times, s, strictly ascending.
    :param omega: (n, 3) measured angular velocity, rad/s, body frame.
    :param torque: the commanded (or applied) torque, body frame.
    :param orientation: (n, 4) measured attitude (x, y, z, w), body -> world, or None.
    """

    t: np.ndarray
    omega: np.ndarray
    torque: PiecewiseTorque
    orientation: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float).reshape(-1)
        omega = np.asarray(self.omega, dtype=float)
        if omega.shape != (t.shape[0], 3):
            raise ValueError(f"omega: expected shape ({t.shape[0]}, 3), got {omega.shape}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(omega))):
            raise ValueError("samples must be finite")
        if np.any(np.diff(t) <= 0.0):
            raise ValueError("sample times must be strictly ascending")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "omega", omega)
        if self.orientation is not None:
            q = np.asarray(self.orientation, dtype=float)
            if q.shape != (t.shape[0], 4) or not np.all(np.isfinite(q)):
                raise ValueError(f"orientation: expected finite shape ({t.shape[0]}, 4), got {q.shape}")
            object.__setattr__(self, "orientation", q / np.linalg.norm(q, axis=1, keepdims=True))

    def window(self, start: float | None = None, end: float | None = None) -> Measurements:
        """The samples with ``start <= t <= end`` (s, same origin as ``t``); the torque is kept whole."""
        keep = np.ones(self.t.shape[0], dtype=bool)
        if start is not None:
            keep &= self.t >= start
        if end is not None:
            keep &= self.t <= end
        q = None if self.orientation is None else self.orientation[keep]
        return Measurements(self.t[keep], self.omega[keep], self.torque, q)

    def has_torque(self) -> bool:
        """Whether any torque acts inside the window."""
        if self.t.shape[0] == 0:
            return False
        inside = (self.torque.times < self.t[-1]) & (np.append(self.torque.times[1:], np.inf) > self.t[0])
        return bool(np.any(np.abs(self.torque.values[inside]) > 0.0))


def world_torque_in_body(
    times: np.ndarray, world_values: np.ndarray, t: np.ndarray, orientation: np.ndarray, end: float
) -> PiecewiseTorque:
    """A world-frame piecewise-constant torque as a body-frame schedule, with the measured attitude.

    The body sees a world-fixed torque turn as the body turns, so the schedule gets a piece
    per sample interval: the torque in the body frame at the interval's midpoint (attitude
    interpolated by slerp; the mean over the interval to second order in its length).

    :param times: (m,) command times, s; ``world_values``: (m, 3) N*m, world frame.
    :param t: (n,) attitude sample times, s; ``orientation``: (n, 4) (x, y, z, w), body -> world.
    :param end: s, the last time the schedule must cover.
    """
    times = np.asarray(times, dtype=float)
    world = PiecewiseTorque(times, world_values)
    t = np.asarray(t, dtype=float)
    grid = np.union1d(times[times <= end], t[t <= end])
    grid = grid[grid >= min(t[0], times[0] if times.size else t[0])]
    mid = np.append(0.5 * (grid[:-1] + grid[1:]), grid[-1])
    slerp = Slerp(t, Rotation.from_quat(orientation))
    rotation = slerp(np.clip(mid, t[0], t[-1]))
    return PiecewiseTorque(grid, rotation.inv().apply(world.at(mid)))
