"""The attitude-slew task, body by body: the error to a target attitude, a reward and the hold test.

Compiled (:func:`rigid_rot_sim.core.jit.compiled`, no fastmath) and written one body at a time, so
that a body's numbers have the same bits whatever the number of bodies in the call: the
Gymnasium environments (:mod:`rigid_rot_sim.envs`) run one body and N bodies through it.

Error: ``dq = conj(q_target) (x) q`` (the rotation from the target attitude to the body's,
scalar-last) taken with ``w >= 0`` (the shorter way round); its rotation vector
``e = 2 atan2(|v|, w) v / |v|`` (rad, 0 when v = 0) is the same in the body and the target
frame (a rotation leaves its axis fixed), and ``|e| = angle`` is in [0, pi].

Reward of a control period, with the rates and error at its end and the (normalised) action
held over it::

    r = -(w_attitude * angle + w_rate * |omega| + w_effort * sum(a_i^2))

Hold: a body is *within tolerance* when ``angle < angle_tolerance`` (rad) and ``|omega| <
rate_tolerance`` (rad/s); ``hold`` counts consecutive control periods within tolerance and the
episode terminates once it reaches ``hold_periods``.
"""

from __future__ import annotations

import math

import numpy as np

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.jit import compiled

__all__ = ["slew_update", "attitude_error"]


@compiled
def slew_update(
    q_observed: np.ndarray,
    omega_observed: np.ndarray,
    q: np.ndarray,
    omega: np.ndarray,
    target: np.ndarray,
    action: np.ndarray,
    weights: np.ndarray,
    tolerances: np.ndarray,
    hold: np.ndarray,
    observation: np.ndarray,
    reward: np.ndarray,
    truth: bool,
) -> np.ndarray:
    """Write each body's observation, reward and hold count; returns the terminated flags (N,) bool.

    ``q_observed`` (N, 4), ``omega_observed`` (N, 3): what the body reports (the truth, or a
    sensor's reading); ``q``, ``omega``: the true state (reward and hold use it); ``target``
    (N, 4); ``action`` (N, k) the normalised action held over the period; ``weights`` (3,) =
    (w_attitude, w_rate, w_effort); ``tolerances`` (3,) = (angle_tolerance rad, rate_tolerance
    rad/s, hold_periods). ``hold`` (N,) int64 is updated in place; ``observation`` (N, m >= 10)
    receives ``(q_observed, omega_observed, e_observed)`` in its first 10 columns; ``reward`` (N,).
    ``truth``: the observed state is the true one (its error is computed once).
    """
    n = q.shape[0]
    terminated = np.zeros(n, dtype=np.bool_)
    for b in range(n):
        tx, ty, tz, tw = target[b, 0], target[b, 1], target[b, 2], target[b, 3]
        e1, e2, e3, angle = _error(q[b, 0], q[b, 1], q[b, 2], q[b, 3], tx, ty, tz, tw)
        if not truth:
            e1, e2, e3, _ = _error(
                q_observed[b, 0], q_observed[b, 1], q_observed[b, 2], q_observed[b, 3], tx, ty, tz, tw
            )
        for i in range(4):
            observation[b, i] = q_observed[b, i]
        for i in range(3):
            observation[b, 4 + i] = omega_observed[b, i]
        observation[b, 7], observation[b, 8], observation[b, 9] = e1, e2, e3
        w1, w2, w3 = omega[b, 0], omega[b, 1], omega[b, 2]
        rate = math.sqrt(w1 * w1 + w2 * w2 + w3 * w3)
        effort = 0.0
        for i in range(action.shape[1]):
            effort += action[b, i] * action[b, i]
        reward[b] = -(weights[0] * angle + weights[1] * rate + weights[2] * effort)
        if angle < tolerances[0] and rate < tolerances[1]:
            hold[b] += 1
        else:
            hold[b] = 0
        terminated[b] = hold[b] >= tolerances[2]
    return terminated


@compiled
def _error(
    qx: float, qy: float, qz: float, qw: float, tx: float, ty: float, tz: float, tw: float
) -> tuple[float, float, float, float]:
    """The error rotation vector of q to the target t, and its angle (rad)."""
    dx, dy, dz, dw = quat.multiply(quat.conjugate((tx, ty, tz, tw)), (qx, qy, qz, qw))
    if dw < 0.0:
        dx, dy, dz, dw = -dx, -dy, -dz, -dw
    norm = math.sqrt(dx * dx + dy * dy + dz * dz)
    if norm == 0.0:
        return 0.0, 0.0, 0.0, 0.0
    angle = 2.0 * math.atan2(norm, dw)
    scale = angle / norm
    return scale * dx, scale * dy, scale * dz, angle


def attitude_error(q: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, float]:
    """The error rotation vector (3,) rad and its angle (rad) of attitude ``q`` to ``target`` (both (4,))."""
    e1, e2, e3, angle = _error(*(float(x) for x in q), *(float(x) for x in target))
    return np.array([e1, e2, e3]), float(angle)
