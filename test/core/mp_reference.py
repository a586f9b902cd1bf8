"""A 40-digit reference of torque-free rigid-body motion in mpmath, independent of core/.

Written from the textbook solution (Landau-Lifshitz section 37; Whittaker section 69), with
mpmath's Jacobi functions and elliptic integrals; :func:`ode_residual` checks it against
Euler's equations and the attitude kinematics by differentiating it numerically, so it does
not rest on the same algebra as ``core/exact.py``.

Conventions as the package: principal moments in any order, omega (rad/s) in the principal
frame, q (x, y, z, w) rotating body -> world. Every float input is taken exactly.
"""

from __future__ import annotations

import mpmath as mp

DIGITS = 40


def _rot_z(a):
    c, s = mp.cos(a), mp.sin(a)
    return mp.matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _rot_x(a):
    c, s = mp.cos(a), mp.sin(a)
    return mp.matrix([[1, 0, 0], [0, c, -s], [0, s, c]])


def quat_to_matrix(q):
    x, y, z, w = q
    return mp.matrix(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_to_quat(r):
    """(x, y, z, w) of a rotation matrix (Shepperd: divide by the largest of the four)."""
    tr = r[0, 0] + r[1, 1] + r[2, 2]
    cands = [1 + tr, 1 + r[0, 0] - r[1, 1] - r[2, 2], 1 - r[0, 0] + r[1, 1] - r[2, 2], 1 - r[0, 0] - r[1, 1] + r[2, 2]]
    k = max(range(4), key=lambda i: cands[i])
    s = 2 * mp.sqrt(cands[k])
    if k == 0:
        return [(r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, s / 4]
    if k == 1:
        return [s / 4, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s]
    if k == 2:
        return [(r[0, 1] + r[1, 0]) / s, s / 4, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s]
    return [(r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, s / 4, (r[1, 0] - r[0, 1]) / s]


def _rotvec_quat(v, t):
    """exp of the rotation vector v t (v in the world frame) as (x, y, z, w)."""
    norm = mp.sqrt(sum(c * c for c in v))
    if norm == 0:
        return [mp.mpf(0)] * 3 + [mp.mpf(1)]
    s = mp.sin(norm * t / 2) / norm
    return [s * v[0], s * v[1], s * v[2], mp.cos(norm * t / 2)]


def _qmul(p, q):
    px, py, pz, pw = p
    qx, qy, qz, qw = q
    return [
        pw * qx + px * qw + py * qz - pz * qy,
        pw * qy - px * qz + py * qw + pz * qx,
        pw * qz + px * qy - py * qx + pz * qw,
        pw * qw - px * qx - py * qy - pz * qz,
    ]


class Reference:
    """omega(t) and q(t) of the torque-free body from (moments, omega0, q0) at t = 0.

    A triaxial body (three distinct moments) off the separatrix, or a spin about a principal
    axis (omega0 along it), which is a uniform rotation.
    """

    def __init__(self, moments, omega0, q0):
        with mp.workdps(DIGITS):
            self.moments = [mp.mpf(float(m)) for m in moments]
            w = [mp.mpf(float(x)) for x in omega0]
            q0 = [mp.mpf(float(x)) for x in q0]
            norm = mp.sqrt(sum(c * c for c in q0))
            self.q0 = [c / norm for c in q0]
            self.omega0 = w
            nonzero = [k for k in range(3) if w[k] != 0]
            if len(nonzero) <= 1:
                self.kind = "uniform"
                self.omega_world = quat_to_matrix(self.q0) * mp.matrix(w)
                return
            self.kind = "elliptic"
            self._elliptic(w)

    def _elliptic(self, w):
        mom = self.moments
        two_e = sum(mom[k] * w[k] ** 2 for k in range(3))
        l2 = sum((mom[k] * w[k]) ** 2 for k in range(3))
        by_moment = sorted(range(3), key=lambda k: mom[k])
        i_mid = mom[by_moment[1]]
        # circulation about the largest axis when L^2 > 2 E I_mid, else about the smallest
        order = by_moment if l2 > two_e * i_mid else by_moment[::-1]
        perm = mp.zeros(3, 3)
        for k, i in enumerate(order):
            perm[k, i] = 1
        if mp.det(perm) < 0:
            for i in range(3):
                perm[1, i] = -perm[1, i]
        self.perm = perm
        wp = perm * mp.matrix(w)
        i1, i2, i3 = (mom[k] for k in order)
        self.i = (i1, i2, i3)
        # amplitudes from the two invariants
        a1 = mp.sqrt((two_e * i3 - l2) / (i1 * (i3 - i1)))
        a2 = mp.sqrt((two_e * i3 - l2) / (i2 * (i3 - i2)))
        a3 = mp.sqrt((l2 - two_e * i1) / (i3 * (i3 - i1)))
        self.lam = mp.sqrt((i3 - i2) * (i3 - i1) * a3**2 / (i1 * i2))
        self.m = i1 * (i2 - i1) * a1**2 / (i3 * (i3 - i2) * a3**2)
        self.n = -i3 * (i2 - i1) / (i1 * (i3 - i2))
        s3 = mp.sign(wp[2])
        self.sigma = mp.sign(i3 - i2) * s3
        self.amp = (a1, self.sigma * a2, s3 * a3)
        self.kk = mp.ellipk(self.m)
        self.u0 = mp.ellipf(mp.atan2(wp[1] / self.amp[1], wp[0] / a1), self.m)
        self.l_norm = mp.sqrt(l2)
        self.pi0 = self._pi_of_am(self.u0)
        m0 = self._zxz_matrix(0, wp)
        self.r_wl = quat_to_matrix(self.q0) * perm.T * m0.T

    def _pi_of_am(self, u):
        """Pi(n; am u | m), continued over every half period."""
        j = mp.floor((u + self.kk) / (2 * self.kk))
        r = u - 2 * j * self.kk
        am = mp.atan2(mp.ellipfun("sn", r, m=self.m), mp.ellipfun("cn", r, m=self.m))
        return mp.ellippi(self.n, am, self.m) + 2 * j * mp.ellippi(self.n, self.m)

    def _zxz_matrix(self, t, wp):
        i1, i2, i3 = self.i
        theta = mp.acos(i3 * wp[2] / self.l_norm)
        psi = mp.atan2(i1 * wp[0], i2 * wp[1])
        if t == 0:
            phi = mp.mpf(0)
        else:
            u = self.lam * t + self.u0
            phi = self.l_norm * t / i3 + self.l_norm * (i3 - i1) / (i1 * i3 * self.lam) * (self._pi_of_am(u) - self.pi0)
        return _rot_z(phi) * _rot_x(theta) * _rot_z(psi)

    def state(self, t):
        """(q, omega) at t (s) as lists of mpf."""
        with mp.workdps(DIGITS):
            t = mp.mpf(t)
            if self.kind == "uniform":
                q = _qmul(_rotvec_quat(self.omega_world, t), self.q0)
                return q, list(self.omega0)
            u = self.lam * t + self.u0
            sn, cn, dn = (mp.ellipfun(k, u, m=self.m) for k in ("sn", "cn", "dn"))
            wp = mp.matrix([self.amp[0] * cn, self.amp[1] * sn, self.amp[2] * dn])
            omega = self.perm.T * wp
            r = self.r_wl * self._zxz_matrix(t, wp) * self.perm
            return matrix_to_quat(r), [omega[k] for k in range(3)]


def ode_residual(ref: Reference, t: float) -> float:
    """Largest residual of Euler's equations and of dq/dt = q (x) (omega, 0) / 2 at t (s),
    with the derivatives from a central difference of the reference (step 1e-10 s: a
    truncation error ~1e-21, a rounding error ~1e-30 at 40 digits)."""
    with mp.workdps(DIGITS):
        i = ref.moments
        h = mp.mpf("1e-10")
        q, w = ref.state(t)
        q_plus, w_plus = ref.state(mp.mpf(t) + h)
        q_minus, w_minus = ref.state(mp.mpf(t) - h)
        dw = [(w_plus[k] - w_minus[k]) / (2 * h) for k in range(3)]
        dq = [(q_plus[k] - q_minus[k]) / (2 * h) for k in range(4)]
        euler = [
            i[0] * dw[0] - (i[1] - i[2]) * w[1] * w[2],
            i[1] * dw[1] - (i[2] - i[0]) * w[2] * w[0],
            i[2] * dw[2] - (i[0] - i[1]) * w[0] * w[1],
        ]
        kinematics = _qmul(q, [w[0] / 2, w[1] / 2, w[2] / 2, 0])
        return float(max(max(abs(e) for e in euler), max(abs(dq[k] - kinematics[k]) for k in range(4))))


class SymmetricReference:
    """omega(t) and q(t) of a symmetric body (I_a = I_b = I_p, distinct axis d) from (moments, omega0, q0):
    the textbook solution, L_body turning about e_d at beta = (1/I_d - 1/I_p) L_d backwards and
    ``q(t) = q0 exp(t L0 / I_p) exp(t beta e_d)`` (Landau-Lifshitz section 33), with the same interface as
    :class:`Reference` (so :func:`ode_residual` checks it)."""

    def __init__(self, moments, omega0, q0, axis):
        with mp.workdps(DIGITS):
            self.moments = [mp.mpf(float(m)) for m in moments]
            self.omega0 = [mp.mpf(float(x)) for x in omega0]
            q0 = [mp.mpf(float(x)) for x in q0]
            norm = mp.sqrt(sum(c * c for c in q0))
            self.q0 = [c / norm for c in q0]
            self.axis = axis
            i_p = self.moments[(axis + 1) % 3]
            self.l0 = [self.moments[k] * self.omega0[k] for k in range(3)]
            self.rate = [c / i_p for c in self.l0]
            self.beta = (1 / self.moments[axis] - 1 / i_p) * self.l0[axis]

    def state(self, t):
        """(q, omega) at t (s) as lists of mpf."""
        with mp.workdps(DIGITS):
            t = mp.mpf(t)
            d = self.axis
            spin = [mp.mpf(0)] * 3
            spin[d] = self.beta
            q = _qmul(_qmul(self.q0, _rotvec_quat(self.rate, t)), _rotvec_quat(spin, t))
            a, b = (d + 1) % 3, (d + 2) % 3
            c, s = mp.cos(self.beta * t), mp.sin(self.beta * t)
            lt = [mp.mpf(0)] * 3
            lt[d] = self.l0[d]
            lt[a] = c * self.l0[a] + s * self.l0[b]
            lt[b] = -s * self.l0[a] + c * self.l0[b]
            return q, [lt[k] / self.moments[k] for k in range(3)]
