"""Euler's equations and their parameter sensitivities, integrated over the samples (compiled).

The model of an identification: a rigid body with inertia tensor ``J`` (kg*m^2, body frame)
under a known piecewise-constant body-frame torque ``tau`` plus a constant bias ``tau_b``::

    J dw/dt + w x (J w) = tau(t) + tau_b

The tensor is affine in the fitted parameters, ``J = J0 + sum_i theta_i E_i`` (``E_i``
symmetric; ``rigid_rot_sim.identify.fit`` chooses the basis: the six entries, or five
with the trace fixed). With ``S = dw/dp`` for ``p = (theta, tau_b, w0)`` the forward
sensitivities obey ``dS/dt = A(w) S + B(w)``, ``A = -J^-1 ([w]x J - [J w]x)``,
``B_theta_i = -J^-1 (E_i f + w x E_i w)`` and ``B_tau_b = J^-1``. Both are advanced by the
classical fourth-order Runge-Kutta method on the same stages, so ``S`` is the exact
derivative of the discrete solution (Gauss-Newton steps and the covariance use the Jacobian
of what is fitted, not an approximation of it).

The grid (``node_t``) holds every sample time and every torque change, each step never
longer than the caller's largest step: the torque is constant within a step, so the fourth
order holds across torque changes. The attitude (``q``, scalar-last, body -> world) is advanced
beside ``w`` for replays (``dq/dt = q (x) (w, 0) / 2``, renormalised each step).
"""

from __future__ import annotations

import numpy as np

from rigid_rot_sim.core.jit import compiled


@compiled
def _rates(
    w: np.ndarray,
    S: np.ndarray,
    J: np.ndarray,
    Jinv: np.ndarray,
    E: np.ndarray,
    torque: np.ndarray,
    with_sens: bool,
    f: np.ndarray,
    dS: np.ndarray,
    C: np.ndarray,
    M: np.ndarray,
) -> None:
    """(dw/dt, dS/dt) at one stage, into ``f`` (3,) and ``dS`` (3, k + 6); ``C``, ``M``: (3, 3) scratch."""
    Jw0 = J[0, 0] * w[0] + J[0, 1] * w[1] + J[0, 2] * w[2]
    Jw1 = J[1, 0] * w[0] + J[1, 1] * w[1] + J[1, 2] * w[2]
    Jw2 = J[2, 0] * w[0] + J[2, 1] * w[1] + J[2, 2] * w[2]
    g0 = torque[0] - (w[1] * Jw2 - w[2] * Jw1)
    g1 = torque[1] - (w[2] * Jw0 - w[0] * Jw2)
    g2 = torque[2] - (w[0] * Jw1 - w[1] * Jw0)
    for r in range(3):
        f[r] = Jinv[r, 0] * g0 + Jinv[r, 1] * g1 + Jinv[r, 2] * g2
    if not with_sens:
        return
    k = E.shape[0]
    n_par = S.shape[1]
    # d(w x J w)/dw = [w]x J - [J w]x ; its negative times S, then J^-1
    for c in range(3):
        C[0, c] = w[1] * J[2, c] - w[2] * J[1, c]
        C[1, c] = w[2] * J[0, c] - w[0] * J[2, c]
        C[2, c] = w[0] * J[1, c] - w[1] * J[0, c]
    C[0, 1] -= -Jw2
    C[0, 2] -= Jw1
    C[1, 0] -= Jw2
    C[1, 2] -= -Jw0
    C[2, 0] -= -Jw1
    C[2, 1] -= Jw0
    # M = -J^-1 C
    for r in range(3):
        for c in range(3):
            M[r, c] = -(Jinv[r, 0] * C[0, c] + Jinv[r, 1] * C[1, c] + Jinv[r, 2] * C[2, c])
    for r in range(3):
        for c in range(n_par):
            dS[r, c] = M[r, 0] * S[0, c] + M[r, 1] * S[1, c] + M[r, 2] * S[2, c]
    for i in range(k):
        Ef0 = E[i, 0, 0] * f[0] + E[i, 0, 1] * f[1] + E[i, 0, 2] * f[2]
        Ef1 = E[i, 1, 0] * f[0] + E[i, 1, 1] * f[1] + E[i, 1, 2] * f[2]
        Ef2 = E[i, 2, 0] * f[0] + E[i, 2, 1] * f[1] + E[i, 2, 2] * f[2]
        Ew0 = E[i, 0, 0] * w[0] + E[i, 0, 1] * w[1] + E[i, 0, 2] * w[2]
        Ew1 = E[i, 1, 0] * w[0] + E[i, 1, 1] * w[1] + E[i, 1, 2] * w[2]
        Ew2 = E[i, 2, 0] * w[0] + E[i, 2, 1] * w[1] + E[i, 2, 2] * w[2]
        h0 = Ef0 + w[1] * Ew2 - w[2] * Ew1
        h1 = Ef1 + w[2] * Ew0 - w[0] * Ew2
        h2 = Ef2 + w[0] * Ew1 - w[1] * Ew0
        for r in range(3):
            dS[r, i] -= Jinv[r, 0] * h0 + Jinv[r, 1] * h1 + Jinv[r, 2] * h2
    for r in range(3):
        for j in range(3):
            dS[r, k + j] += Jinv[r, j]


@compiled
def _stage(
    w: np.ndarray,
    S: np.ndarray,
    a: float,
    f: np.ndarray,
    K: np.ndarray,
    ws: np.ndarray,
    Ss: np.ndarray,
    with_sens: bool,
) -> None:
    """The next stage's point ``(w + a f, S + a K)`` into ``ws``, ``Ss``."""
    for r in range(3):
        ws[r] = w[r] + a * f[r]
    if with_sens:
        for r in range(3):
            for c in range(S.shape[1]):
                Ss[r, c] = S[r, c] + a * K[r, c]


@compiled
def _qdot(q: np.ndarray, w: np.ndarray) -> np.ndarray:
    # q (x) (w, 0) / 2, Hamilton product, scalar last
    out = np.empty(4)
    out[0] = 0.5 * (q[3] * w[0] + q[1] * w[2] - q[2] * w[1])
    out[1] = 0.5 * (q[3] * w[1] + q[2] * w[0] - q[0] * w[2])
    out[2] = 0.5 * (q[3] * w[2] + q[0] * w[1] - q[1] * w[0])
    out[3] = -0.5 * (q[0] * w[0] + q[1] * w[1] + q[2] * w[2])
    return out


@compiled
def integrate_segments(
    node_t: np.ndarray,
    node_torque: np.ndarray,
    node_sample: np.ndarray,
    segment_nodes: np.ndarray,
    J: np.ndarray,
    E: np.ndarray,
    tau_b: np.ndarray,
    omega0: np.ndarray,
    q0: np.ndarray,
    n_samples: int,
    with_sens: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Angular velocity (and sensitivities, attitude) at every sample, segment by segment.

    :param node_t: (m,) grid times, s, ascending.
    :param node_torque: (m, 3) body-frame torque, N*m, acting from ``node_t[j]`` to ``node_t[j + 1]``.
    :param node_sample: (m,) the sample index at each node, or -1.
    :param segment_nodes: (S + 1,) first node of each segment; the last entry is the node after the end.
    :param J: (3, 3) inertia tensor, kg*m^2; ``E``: (k, 3, 3) its derivatives by the parameters.
    :param tau_b: (3,) torque bias, N*m, body frame.
    :param omega0: (S, 3) angular velocity at each segment's first node, rad/s.
    :param q0: (S, 4) attitude at each segment's first node (x, y, z, w).
    :return: omega (n, 3) rad/s; sens (n, 3, k + 6) d omega / d (theta, tau_b, omega0 of its
        segment) (zeros when ``with_sens`` is false); q (n, 4).
    """
    k = E.shape[0]
    n_par = k + 6
    Jinv = np.linalg.inv(J)
    omega = np.zeros((n_samples, 3))
    q_out = np.zeros((n_samples, 4))
    sens = np.zeros((n_samples, 3, n_par)) if with_sens else np.zeros((1, 3, n_par))
    f1, f2, f3, f4 = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    K1, K2, K3, K4 = np.empty((3, n_par)), np.empty((3, n_par)), np.empty((3, n_par)), np.empty((3, n_par))
    ws, Ss = np.empty(3), np.empty((3, n_par))
    C, M = np.empty((3, 3)), np.empty((3, 3))
    for s in range(segment_nodes.shape[0] - 1):
        first = segment_nodes[s]
        last = segment_nodes[s + 1] - 1
        w = omega0[s].copy()
        q = q0[s].copy()
        S = np.zeros((3, n_par))
        for j in range(3):
            S[j, k + 3 + j] = 1.0
        for node in range(first, last + 1):
            idx = node_sample[node]
            if idx >= 0:
                omega[idx] = w
                q_out[idx] = q
                if with_sens:
                    sens[idx] = S
            if node == last:
                break
            h = node_t[node + 1] - node_t[node]
            torque = node_torque[node] + tau_b
            _rates(w, S, J, Jinv, E, torque, with_sens, f1, K1, C, M)
            _stage(w, S, 0.5 * h, f1, K1, ws, Ss, with_sens)
            _rates(ws, Ss, J, Jinv, E, torque, with_sens, f2, K2, C, M)
            w2 = ws.copy()
            _stage(w, S, 0.5 * h, f2, K2, ws, Ss, with_sens)
            _rates(ws, Ss, J, Jinv, E, torque, with_sens, f3, K3, C, M)
            w3 = ws.copy()
            _stage(w, S, h, f3, K3, ws, Ss, with_sens)
            _rates(ws, Ss, J, Jinv, E, torque, with_sens, f4, K4, C, M)
            w4 = ws.copy()
            qk1 = _qdot(q, w)
            qk2 = _qdot(q + 0.5 * h * qk1, w2)
            qk3 = _qdot(q + 0.5 * h * qk2, w3)
            qk4 = _qdot(q + h * qk3, w4)
            q = q + (h / 6.0) * (qk1 + 2.0 * qk2 + 2.0 * qk3 + qk4)
            q = q / np.sqrt(q @ q)
            w = w + (h / 6.0) * (f1 + 2.0 * f2 + 2.0 * f3 + f4)
            if with_sens:
                for r in range(3):
                    for c in range(n_par):
                        S[r, c] += (h / 6.0) * (K1[r, c] + 2.0 * K2[r, c] + 2.0 * K3[r, c] + K4[r, c])
    return omega, sens, q_out
