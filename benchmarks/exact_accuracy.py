"""Accuracy of core/exact.py against an extended-precision Taylor-series reference.

The reference runs in x87 long double (eps ~1.1e-19) with a fixed step of 1/32 s.

Euler's equations and dq/dt = 1/2 q (x) (omega, 0) are quadratic, so the Taylor
coefficients follow from Cauchy products; long double keeps the reference ~1e5 times
more accurate than the float64 solution it checks.

Run: .venv/bin/python benchmarks/exact_accuracy.py [T_SECONDS]   (default 1000)
"""

import sys
import time

import numpy as np
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.exact import torque_free_solution

LD = np.longdouble
#: The reference's step (s): 1/32 in long double.
REFERENCE_STEP = LD(1) / 32


def taylor_reference(moments, omega0, q0, t_end, h=REFERENCE_STEP, order=28):
    i1, i2, i3 = (LD(m) for m in moments)
    c = np.array([(i2 - i3) / i1, (i3 - i1) / i2, (i1 - i2) / i3], dtype=LD)
    w = np.array([LD(x) for x in omega0], dtype=LD)
    q = np.array([LD(x) for x in q0], dtype=LD)
    q /= np.sqrt(np.sum(q * q))
    n_steps = int(round(float(LD(t_end) / h)))
    assert abs(n_steps * h - LD(t_end)) == 0, "t_end must be a multiple of h"
    N = order
    W = np.zeros((N + 1, 3), dtype=LD)
    Q = np.zeros((N + 1, 4), dtype=LD)
    powers = h ** np.arange(N + 1, dtype=LD)
    for _ in range(n_steps):
        W[0] = w
        Q[0] = q
        for k in range(N):
            Wk = W[: k + 1]
            Wr = W[k::-1]
            Qr = Q[k::-1]
            # [w2 w3]_k, [w3 w1]_k, [w1 w2]_k
            p23 = np.dot(Wk[:, 1], Wr[:, 2])
            p31 = np.dot(Wk[:, 2], Wr[:, 0])
            p12 = np.dot(Wk[:, 0], Wr[:, 1])
            W[k + 1] = c * np.array([p23, p31, p12], dtype=LD) / (k + 1)
            x, y, z, s = Qr[:, 0], Qr[:, 1], Qr[:, 2], Qr[:, 3]
            a, b, d = Wk[:, 0], Wk[:, 1], Wk[:, 2]
            Q[k + 1] = (
                LD(0.5)
                * np.array(
                    [
                        np.dot(s, a) + np.dot(y, d) - np.dot(z, b),
                        np.dot(s, b) + np.dot(z, a) - np.dot(x, d),
                        np.dot(s, d) + np.dot(x, b) - np.dot(y, a),
                        -np.dot(x, a) - np.dot(y, b) - np.dot(z, d),
                    ],
                    dtype=LD,
                )
                / (k + 1)
            )
        w = powers @ W
        q = powers @ Q
    return q, w


def main() -> None:
    T = float(sys.argv[1]) if len(sys.argv) > 1 else 1000.0
    Q0 = Rotation.from_rotvec([0.3, -0.7, 1.1]).as_quat()
    CASES = [
        ((1.0, 2.0, 3.0), (1.0, 0.1, 0.5)),
        ((1.0, 2.0, 3.0), (0.1, 0.2, 1.0)),
        ((3.0, 1.0, 2.0), (1.0, 0.1, 0.2)),
        ((3.0, 4.0, 6.0), (1.0, 0.3, 0.5 * (1 + 1e-6))),
        ((3.0, 4.0, 6.0), (1.0, 0.3, 0.5 * (1 + 1e-10))),
        ((2.0, 2.0, 3.0), (0.3, 0.4, 0.5)),
    ]
    for moments, omega0 in CASES:
        sol = torque_free_solution(moments, omega0, Q0)
        t0 = time.time()
        q_ref, w_ref = taylor_reference(moments, omega0, Q0, T)
        el = time.time() - t0
        q, w = sol.state(T)
        werr = float(np.max(np.abs(w.astype(np.longdouble) - w_ref)) / np.linalg.norm(omega0))
        qr = (q_ref / np.sqrt(np.sum(q_ref * q_ref))).astype(float)
        qerr = float(min(np.linalg.norm(q - qr), np.linalg.norm(q + qr)))
        print(
            f"{str(moments):18s} {str(omega0):32s} {sol.case:17s} T={T:g} s  "
            f"|dw|/|w0| = {werr:.2e}  |dq| = {qerr:.2e}  (ref {el:.1f} s)"
        )


if __name__ == "__main__":
    main()
