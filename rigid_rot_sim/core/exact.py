"""Exact torque-free motion of a rigid body (Euler-Poinsot): angular velocity and attitude.

``torque_free_solution(moments, omega0, q0, t0)`` returns a :class:`TorqueFreeSolution`
whose ``omega(t)`` (rad/s, principal body frame) and ``quaternion(t)`` (principal ->
world, scalar-last) are vectorised over t (s).

Derivation (kept here because the tests and the integrators rely on it)
-----------------------------------------------------------------------
Invariants: ``2E = sum I_i w_i^2`` and ``L^2 = sum I_i^2 w_i^2``. Relabel the principal
axes by a proper signed permutation (x' = P x, det P = +1, the middle moment stays
axis 2) so that axis 3 is the one the angular velocity circulates about: the largest
moment when ``D = L^2 - 2 E I2 > 0`` (above the separatrix), the smallest when
``D < 0`` (below). In both orderings (I1 < I2 < I3 or I1 > I2 > I3)

    w1 = A1 cn u,   w2 = sigma A2 sn u,   w3 = s3 A3 dn u,    u = lam (t - t0) + u0,

with s3 = sign w3 (never zero off the separatrix), sigma = eps s3,
eps = sign(I3 - I2), and (every term below is a sum of non-negative terms, so no
cancellation even next to the separatrix)

    A1^2 = w1^2 + I2 (I3 - I2) / (I1 (I3 - I1)) w2^2      = (2 E I3 - L^2) / (I1 (I3 - I1))
    A2^2 = I1 (I3 - I1) / (I2 (I3 - I2)) w1^2 + w2^2      = (2 E I3 - L^2) / (I2 (I3 - I2))
    A3^2 = I2 (I2 - I1) / (I3 (I3 - I1)) w2^2 + w3^2      = (L^2 - 2 E I1) / (I3 (I3 - I1))
    lam^2 = (I3 - I2)(I3 - I1) A3^2 / (I1 I2)
    m  = I1 (I2 - I1) A1^2 / (I3 (I3 - I2) A3^2),   1 - m = D / (I3 (I3 - I2) A3^2)

(substitute into I1 w1' = (I2 - I3) w2 w3 and cyclic, with sn' = cn dn, cn' = -sn dn,
dn' = -m sn cn). On the separatrix (D = 0, m = 1) sn = tanh, cn = dn = sech, and w1 may
have either sign: w1 = s1 A1 sech u with sigma = eps s1 s3.

Attitude: L_world is constant. In a world frame W_L whose z axis is along L, write the
body attitude as z-x-z Euler angles, R = Rz(phi) Rx(theta) Rz(psi). Then
``L_body = |L| (sin th sin psi, sin th cos psi, cos th)`` fixes theta and psi from
w(t), and the body rates give ``phi' = |L| (I1 w1^2 + I2 w2^2) / (L1^2 + L2^2)``.
With ``L1^2 + L2^2 = L^2 - I3^2 w3^2`` and the partial fractions in w3^2,

    phi' = |L| / I3 + |L| (I3 - I1) / (I1 I3) / (1 - n sn^2 u),
    n = -I3 (I2 - I1) / (I1 (I3 - I2))   (< 0 in both orderings),

so ``phi = |L| tau / I3 + |L| (I3 - I1) / (I1 I3 lam) [Pi(n; am u | m) - Pi(n; am u0 | m)]``
with the incomplete integral of the third kind. In Carlson form, for |am u| <= pi/2,
``Pi(n; am u | m) = u + (n/3) sn^3 R_J(cn^2, dn^2, 1, 1 - n sn^2)``; over each half
period 2K it grows by ``2 Pi(n|m) = 2K + (2n/3) R_J(0, 1 - m, 1, 1 - n)``, which is
how large arguments are reduced. On the separatrix
``Pi(n; am u | 1) = (u + a atan(a tanh u)) / (1 - n)`` with a = sqrt(-n).
psi = atan2(L1, L2) is evaluated from the normalised amplitudes so that it stays
continuous through pure spin about axis 3 (L1 = L2 = 0).

The elliptic functions come from the arithmetic-geometric mean with the complementary
parameter 1 - m passed exactly (scipy's ``ellipj`` takes m only, and rounding m near 1
would cost digits next to the separatrix); the quarter period is ``K = pi / (2 a_N)``
from the same AGM, so period reduction and evaluation agree.

Special cases in closed form: a spherical body (omega constant); a symmetric body
(I_a = I_b = I_p, distinct axis d): ``q(t) = exp(tau L_world / I_p) q0 exp(tau beta e_d)``
with ``beta = (1/I_d - 1/I_p) L_d`` (the two flows commute); a stationary spin about
the middle axis (or a body at rest), labelled 'separatrix' because L^2 = 2 E I2 holds.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation
from scipy.special import elliprf, elliprj

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core import validation

CASES = ("spherical", "symmetric", "below_separatrix", "above_separatrix", "separatrix")

_EPS = np.finfo(float).eps
# Moments equal to within this many ulps of the largest are treated as equal.
_EQUAL_MOMENTS_ULPS = 4.0
# |L^2 - 2 E I2| within this many ulps of its two (opposite-sign) terms is the separatrix.
_SEPARATRIX_ULPS = 8.0


@dataclass(frozen=True)
class _RigidRotation:
    """omega constant in the body; q(t) = exp(tau omega_world) q0."""

    omega: np.ndarray
    omega_world: np.ndarray
    q0: np.ndarray

    def evaluate(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rot = Rotation.from_rotvec(tau[:, None] * self.omega_world[None, :]) * Rotation.from_quat(self.q0)
        return rot.as_quat(), np.broadcast_to(self.omega, (tau.size, 3)).copy()


@dataclass(frozen=True)
class _SymmetricFlow:
    """I_a = I_b = i_perp != I_d: commuting rotations about L_world and the body axis d."""

    moments: np.ndarray
    axis: int
    rate_world: np.ndarray  # L_world / i_perp, rad/s
    beta: float  # (1/I_d - 1/i_perp) L_d, rad/s
    l_body0: np.ndarray
    q0: np.ndarray

    def evaluate(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        body_rotvec = np.zeros((tau.size, 3))
        body_rotvec[:, self.axis] = tau * self.beta
        spin = Rotation.from_rotvec(body_rotvec)
        rot = Rotation.from_rotvec(tau[:, None] * self.rate_world[None, :]) * Rotation.from_quat(self.q0) * spin
        l_body = spin.apply(self.l_body0, inverse=True)
        return rot.as_quat(), l_body / self.moments


@dataclass(frozen=True)
class _EllipticFlow:
    """The triaxial body (generic or separatrix) in the relabelled principal frame."""

    perm: np.ndarray  # (3, 3) proper signed permutation, x' = perm @ x
    moments: np.ndarray  # relabelled (I1', I2', I3')
    amplitude: np.ndarray  # (A1, A2, A3), rad/s
    signs: tuple[float, float, float]  # (s1, sigma, s3)
    psi_scale: tuple[float, float]  # (s1 I1 alpha1, sigma I2 alpha2): psi = atan2(c1 cn, c2 sn)
    lam: float
    u0: float
    m1: float  # 1 - m (0 on the separatrix)
    n: float
    l_norm: float
    agm_a: tuple[float, ...]
    agm_c: tuple[float, ...]
    quarter_period: float  # K (inf on the separatrix)
    half_period_pi_excess: float  # 2 (Pi(n|m) - K)
    phase0: tuple[float, float]  # (j0, n/3 sn0^3 R_J(...)) or (atan term) on the separatrix
    compose: np.ndarray  # (4, 4): q_world<-body = compose @ q_zxz

    @property
    def separatrix(self) -> bool:
        return self.m1 == 0.0

    def jacobi(self, r: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """sn, cn, dn of r (|r| <= K) by the descending AGM (Abramowitz & Stegun 16.4)."""
        a, c = self.agm_a, self.agm_c
        levels = len(a) - 1
        phi = (2.0**levels * a[levels]) * r
        for i in range(levels, 0, -1):
            phi = 0.5 * (phi + np.arcsin(c[i] * np.sin(phi) / a[i]))
        sn = np.sin(phi)
        cn = np.cos(phi)
        dn = np.sqrt(cn * cn + self.m1 * sn * sn)
        return sn, cn, dn

    def phase(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """sn, cn, dn at u and the two parts of Pi(n; am u | m) beyond u: (j, g)."""
        if self.separatrix:
            sn = np.tanh(u)
            e = np.exp(-np.abs(u))
            cn = 2.0 * e / (1.0 + e * e)
            a = math.sqrt(-self.n)
            return sn, cn, cn, np.zeros_like(u), a * np.arctan(a * sn)
        k = self.quarter_period
        j = np.floor((u + k) / (2.0 * k))
        r = u - 2.0 * k * j
        sn, cn, dn = self.jacobi(r)
        s2 = sn * sn
        g = (self.n / 3.0) * sn * s2 * elliprj(cn * cn, dn * dn, 1.0, 1.0 - self.n * s2)
        # sn and cn change sign over each half period 2K (dn does not)
        parity = 1.0 - 2.0 * np.mod(j, 2.0)
        return parity * sn, parity * cn, dn, j, g

    def evaluate(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        i1, i2, i3 = self.moments
        a1, a2, a3 = self.amplitude
        s1, sigma, s3 = self.signs
        u = self.lam * tau + self.u0
        sn, cn, dn, j, g = self.phase(u)
        j0, g0 = self.phase0
        coeff = self.l_norm * (i3 - i1) / (i1 * i3 * self.lam)
        if self.separatrix:
            phi = self.l_norm * tau / i3 + coeff * (self.lam * tau + (g - g0)) / (1.0 - self.n)
        else:
            phi = self.l_norm * tau / i1 + coeff * ((j - j0) * self.half_period_pi_excess + (g - g0))
        w = np.stack((s1 * a1 * cn, sigma * a2 * sn, s3 * a3 * dn), axis=-1)
        l1 = i1 * w[:, 0]
        l2 = i2 * w[:, 1]
        theta = np.arctan2(np.hypot(l1, l2), i3 * w[:, 2])
        psi = np.arctan2(self.psi_scale[0] * cn, self.psi_scale[1] * sn)
        q_zxz = zxz_to_quaternion(phi, theta, psi)
        q = q_zxz @ self.compose.T
        return q, w @ self.perm


@dataclass(frozen=True, eq=False)
class TorqueFreeSolution:
    """Exact motion of a torque-free rigid body from (q0, omega0) at t0.

    Attributes
    ----------
    moments : ndarray (3,)
        Principal moments (I1, I2, I3), kg*m^2, in the caller's order.
    omega0 : ndarray (3,)
        Initial angular velocity, rad/s, principal body frame.
    q0 : ndarray (4,)
        Initial attitude, principal -> world, scalar-last, unit.
    t0 : float
        Initial time, s.
    case : str
        One of ``CASES``: 'spherical', 'symmetric', or for a triaxial body
        'above_separatrix' (L^2 > 2 E I2, circulation about the largest-moment axis),
        'below_separatrix' (about the smallest) or 'separatrix' (within rounding).
    """

    moments: np.ndarray
    omega0: np.ndarray
    q0: np.ndarray
    t0: float
    case: str
    _flow: Any = field(repr=False, compare=False)

    def state(self, t: Any) -> tuple[np.ndarray, np.ndarray]:
        """``(quaternion(t), omega(t))`` evaluated together (shapes (..., 4) and (..., 3))."""
        tau = np.asarray(t, dtype=float) - self.t0
        if not np.all(np.isfinite(tau)):
            raise ValueError(f"t must be finite, got {t}")
        q, w = self._flow.evaluate(tau.reshape(-1))
        return q.reshape(tau.shape + (4,)), w.reshape(tau.shape + (3,))

    def omega(self, t: Any) -> np.ndarray:
        """Angular velocity at time(s) t (s), rad/s, principal body frame; shape t.shape + (3,)."""
        return self.state(t)[1]

    def quaternion(self, t: Any) -> np.ndarray:
        """Attitude at time(s) t (s), principal -> world, scalar-last; shape t.shape + (4,)."""
        return self.state(t)[0]

    @property
    def angular_momentum_world(self) -> np.ndarray:
        """The conserved L_world, kg*m^2/s."""
        return Rotation.from_quat(self.q0).apply(self.moments * self.omega0)

    @property
    def energy(self) -> float:
        """The conserved kinetic energy T = 1/2 omega . I omega, J."""
        return 0.5 * float(np.dot(self.moments * self.omega0, self.omega0))


def zxz_to_quaternion(phi: Any, theta: Any, psi: Any) -> np.ndarray:
    """Quaternion (x, y, z, w) of ``Rz(phi) Rx(theta) Rz(psi)`` (intrinsic z-x-z, rad).

    Equals ``Rotation.from_euler('ZXZ', [phi, theta, psi]).as_quat()`` up to sign;
    vectorised over the (broadcast) angle arrays.
    """
    half_sum = 0.5 * (np.asarray(phi) + np.asarray(psi))
    half_diff = 0.5 * (np.asarray(phi) - np.asarray(psi))
    ch = np.cos(0.5 * np.asarray(theta))
    sh = np.sin(0.5 * np.asarray(theta))
    return np.stack(
        (sh * np.cos(half_diff), sh * np.sin(half_diff), ch * np.sin(half_sum), ch * np.cos(half_sum)), axis=-1
    )


def quaternion_to_zxz(q: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """z-x-z Euler angles ``(phi, theta, psi)`` (rad) with ``R(q) = Rz(phi) Rx(theta) Rz(psi)``.

    theta in [0, pi]; phi and psi in (-pi, pi]. Computed from the half-angle form of
    :func:`zxz_to_quaternion` (``phi + psi = 2 atan2(z, w)``, ``phi - psi = 2 atan2(y, x)``),
    so every angle is finite for every unit q: at theta = 0 only phi + psi is defined and
    the split reported is phi = psi; at theta = pi, phi = -psi. For output only: nothing
    divides by sin(theta). q: (..., 4) scalar-last, sign irrelevant.
    """
    q = np.asarray(q, dtype=float)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    theta = 2.0 * np.arctan2(np.hypot(x, y), np.hypot(z, w))
    half_sum = np.arctan2(z, w)
    half_diff = np.arctan2(y, x)
    phi = _wrap_angle(half_sum + half_diff)
    psi = _wrap_angle(half_sum - half_diff)
    return phi, theta, psi


def _wrap_angle(a: np.ndarray) -> np.ndarray:
    """a reduced to (-pi, pi]."""
    return np.pi - np.mod(np.pi - a, 2.0 * np.pi)


def _proper_permutation(order: tuple[int, int, int]) -> np.ndarray:
    perm = np.zeros((3, 3))
    for k, i in enumerate(order):
        perm[k, i] = 1.0
    if np.linalg.det(perm) < 0.0:
        perm[1] *= -1.0  # keep the relabelled frame right-handed
    return perm


def _sign(x: float) -> float:
    return 1.0 if x >= 0.0 else -1.0


def _agm_tables(m: float, m1: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    a = [1.0]
    c = [math.sqrt(m)]
    b = math.sqrt(m1)
    while abs(c[-1]) > _EPS * a[-1] and len(a) < 40:
        a_next = 0.5 * (a[-1] + b)
        # c_{i+1} = (a_i - b_i)/2 = c_i^2 / (4 a_{i+1}) without the subtraction
        c.append(c[-1] * c[-1] / (4.0 * a_next))
        b = math.sqrt(a[-1] * b)
        a.append(a_next)
    return tuple(a), tuple(c)


def _composition_matrix(left: Any, right: Any) -> np.ndarray:
    """4x4 matrix M with ``M @ q = left (x) q (x) right`` (both products are linear in q)."""
    basis = np.eye(4)
    return np.column_stack([quat.multiply(quat.multiply(left, e), right) for e in basis])


def _elliptic_flow(moments: np.ndarray, omega: np.ndarray, q0: np.ndarray, order: tuple[int, int, int]) -> _EllipticFlow:
    perm = _proper_permutation(order)
    i1, i2, i3 = (float(moments[k]) for k in order)
    w1, w2, w3 = (float(x) for x in perm @ omega)
    eps = _sign(i3 - i2)
    d31, d32, d21 = i3 - i1, i3 - i2, i2 - i1
    a1 = math.sqrt(w1 * w1 + i2 * d32 / (i1 * d31) * w2 * w2)
    a2 = math.sqrt(i1 * d31 / (i2 * d32) * w1 * w1 + w2 * w2)
    a3 = math.sqrt(i2 * d21 / (i3 * d31) * w2 * w2 + w3 * w3)
    # D = L^2 - 2 E I2 from its two terms of opposite sign
    t_in, t_out = i3 * d32 * w3 * w3, i1 * d21 * w1 * w1
    big = i3 * d32 * a3 * a3
    separatrix = abs(t_in - t_out) <= _SEPARATRIX_ULPS * _EPS * (abs(t_in) + abs(t_out))
    m1 = 0.0 if separatrix else (t_in - t_out) / big
    m = i1 * d21 * a1 * a1 / big
    lam = math.sqrt(d32 * d31 * a3 * a3 / (i1 * i2))
    n = -i3 * d21 / (i1 * d32)
    s3 = _sign(w3)
    s1 = _sign(w1) if separatrix else 1.0
    sigma = eps * s1 * s3
    l_norm = math.sqrt((i1 * w1) ** 2 + (i2 * w2) ** 2 + (i3 * w3) ** 2)
    alpha1 = 1.0 / math.sqrt(i1 * abs(d31))
    alpha2 = 1.0 / math.sqrt(i2 * abs(d32))
    # phase u0 from sn u0 = sigma w2 / A2, cn u0 = s1 w1 / A1 (normalised against rounding)
    sn0, cn0 = (sigma * w2 / a2, s1 * w1 / a1) if a1 > 0.0 else (0.0, 1.0)
    norm = math.hypot(sn0, cn0)
    sn0, cn0 = sn0 / norm, cn0 / norm
    if separatrix:
        agm_a, agm_c = (1.0,), (1.0,)
        k = math.inf
        excess = 0.0
        u0 = math.asinh(sn0 / cn0)
    else:
        agm_a, agm_c = _agm_tables(m, m1)
        k = math.pi / (2.0 * agm_a[-1])
        excess = (2.0 * n / 3.0) * float(elliprj(0.0, m1, 1.0, 1.0 - n))
        f = sn0 * float(elliprf(cn0 * cn0, cn0 * cn0 + m1 * sn0 * sn0, 1.0))
        u0 = f if cn0 >= 0.0 else math.copysign(2.0 * k, sn0) - f
    flow = _EllipticFlow(
        perm=perm,
        moments=np.array([i1, i2, i3]),
        amplitude=np.array([a1, a2, a3]),
        signs=(s1, sigma, s3),
        psi_scale=(s1 * i1 * alpha1, sigma * i2 * alpha2),
        lam=lam,
        u0=u0,
        m1=m1,
        n=n,
        l_norm=l_norm,
        agm_a=agm_a,
        agm_c=agm_c,
        quarter_period=k,
        half_period_pi_excess=excess,
        phase0=(0.0, 0.0),
        compose=np.eye(4),
    )
    _, _, _, j0, g0 = flow.phase(np.array([u0]))
    flow = dataclasses.replace(flow, phase0=(float(j0[0]), float(g0[0])))
    # theta, psi at tau = 0 from the flow itself so that q(t0) = q0 to rounding
    q_zxz0 = flow.evaluate(np.zeros(1))[0][0]  # compose = identity: q_zxz(0, theta0, psi0)
    q_perm = Rotation.from_matrix(perm).as_quat()
    # q_world<-body = q_WL (x) q_zxz (x) q_perm with q_WL = q0 (x) q_perm^-1 (x) q_zxz(0)^-1
    q_wl = quat.multiply(quat.multiply(q0, quat.conjugate(q_perm)), quat.conjugate(q_zxz0))
    compose = _composition_matrix(q_wl, q_perm)
    return dataclasses.replace(flow, compose=compose)


def torque_free_solution(moments: Any, omega0: Any, q0: Any = (0.0, 0.0, 0.0, 1.0), t0: float = 0.0) -> TorqueFreeSolution:
    """Exact torque-free motion of a rigid body.

    Parameters
    ----------
    moments : array_like (3,)
        Principal moments (I1, I2, I3), kg*m^2, any order.
    omega0 : array_like (3,)
        Angular velocity at t0, rad/s, principal body frame.
    q0 : array_like (4,)
        Attitude at t0, principal -> world, scalar-last (normalised on entry).
    t0 : float
        Initial time, s.

    Returns
    -------
    TorqueFreeSolution
        With ``omega(t)``, ``quaternion(t)``, ``state(t)`` vectorised over t and ``case``.

    Examples
    --------
    >>> sol = torque_free_solution((1.0, 2.0, 3.0), (1.0, 0.1, 0.5))
    >>> sol.case
    'below_separatrix'
    >>> bool(np.allclose(sol.omega(0.0), (1.0, 0.1, 0.5), rtol=0, atol=1e-15))
    True
    """
    moments = validation.principal_moments("moments", moments)
    omega0 = validation.finite_vector("omega0", omega0)
    q0 = validation.quaternion("q0", q0)
    t0 = validation.finite_scalar("t0", t0)
    return _solution(moments, omega0, q0, t0)


def torque_free_flow(moments: np.ndarray, q: Any, omega: Any, tau: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact free flow over tau (s) from (q, omega): ``(q(tau), omega(tau))``.

    The same as ``torque_free_solution(moments, omega, q).state(tau)`` without the input
    checks, for integrators that call it every step with a state they already checked
    (``moments`` a float array (3,), q a unit quaternion).
    """
    solution = _solution(moments, np.asarray(omega, dtype=float), np.asarray(q, dtype=float), 0.0)
    q_new, omega_new = solution._flow.evaluate(np.array([float(tau)]))
    return q_new[0], omega_new[0]


def _solution(moments: np.ndarray, omega0: np.ndarray, q0: np.ndarray, t0: float) -> TorqueFreeSolution:
    idx = [int(i) for i in np.argsort(moments, kind="stable")]
    i_min, i_mid, i_max = idx
    tol = _EQUAL_MOMENTS_ULPS * _EPS * float(moments[i_max])
    low_equal = moments[i_mid] - moments[i_min] <= tol
    high_equal = moments[i_max] - moments[i_mid] <= tol
    l_body = moments * omega0
    if low_equal and high_equal:
        case = "spherical"
        flow: Any = _RigidRotation(omega0.copy(), Rotation.from_quat(q0).apply(omega0), q0)
    elif low_equal or high_equal:
        case = "symmetric"
        axis = i_max if low_equal else i_min
        i_perp = float(moments[i_mid])
        l_world = Rotation.from_quat(q0).apply(l_body)
        beta = (1.0 / moments[axis] - 1.0 / i_perp) * l_body[axis]
        flow = _SymmetricFlow(moments.copy(), axis, l_world / i_perp, float(beta), l_body, q0)
    else:
        d_above = moments[i_max] * (moments[i_max] - moments[i_mid]) * omega0[i_max] ** 2
        d_below = moments[i_min] * (moments[i_mid] - moments[i_min]) * omega0[i_min] ** 2
        scale = d_above + d_below
        if abs(d_above - d_below) <= _SEPARATRIX_ULPS * _EPS * scale:
            case = "separatrix"
        else:
            case = "above_separatrix" if d_above > d_below else "below_separatrix"
        if scale == 0.0:
            # at rest, or a stationary spin about the middle axis
            flow = _RigidRotation(omega0.copy(), Rotation.from_quat(q0).apply(omega0), q0)
        else:
            order = (i_min, i_mid, i_max) if case != "below_separatrix" else (i_max, i_mid, i_min)
            flow = _elliptic_flow(moments, omega0, q0, order)
    return TorqueFreeSolution(moments, omega0, q0, t0, case, flow)
