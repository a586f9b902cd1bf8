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

D decides the case and sets 1 - m; where its two terms cancel it is evaluated in exact
rational arithmetic from the floats given, so the case and the phase next to the
separatrix are those of the omega0 given (the label 'separatrix' allows 8 ulps, the flow
does not snap to it). Accuracy (against a long-double Taylor reference, t = 1000 s):
~3e-14 relative in omega and ~1e-13 in the attitude away from the separatrix; next to it
the problem itself is ill-conditioned and the error stays below that of a 1-ulp change
of omega0.

Special cases in closed form: a spherical body (omega constant); a symmetric body
(I_a = I_b = I_p, distinct axis d): ``q(t) = exp(tau L_world / I_p) q0 exp(tau beta e_d)``
with ``beta = (1/I_d - 1/I_p) L_d`` (the two flows commute); a stationary spin about
the middle axis (or a body at rest), labelled 'separatrix' because L^2 = 2 E I2 holds.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from fractions import Fraction
from types import SimpleNamespace
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
# Below this fraction of its terms, L^2 - 2 E I2 is evaluated exactly (float subtraction
# would lose more than 7 bits of it).
_EXACT_SEPARATRIX_DISTANCE = 1e-2


# Elementary functions for the two evaluation paths: plain floats (one time, the
# integrators' per-step path, where math is ~10x cheaper than numpy on scalars) and arrays.
_SCALAR_FUNCTIONS = SimpleNamespace(
    sin=math.sin, cos=math.cos, asin=math.asin, atan=math.atan, atan2=math.atan2, sqrt=math.sqrt,
    hypot=math.hypot, tanh=math.tanh, exp=math.exp, abs=abs, floor=math.floor, fmod2=lambda j: j % 2.0,
)
_ARRAY_FUNCTIONS = SimpleNamespace(
    sin=np.sin, cos=np.cos, asin=np.arcsin, atan=np.arctan, atan2=np.arctan2, sqrt=np.sqrt,
    hypot=np.hypot, tanh=np.tanh, exp=np.exp, abs=np.abs, floor=np.floor, fmod2=lambda j: np.mod(j, 2.0),
)


class _RigidRotation:
    """omega constant in the body; q(t) = exp(tau omega_world) q0."""

    def __init__(self, omega: np.ndarray, q0: np.ndarray) -> None:
        self.omega = omega
        self.q0 = q0
        self._omega_tuple = tuple(omega.tolist())
        self._q0_tuple = tuple(q0.tolist())
        self._omega_world_tuple = quat.rotate(self._q0_tuple, self._omega_tuple)
        self.omega_world = np.array(self._omega_world_tuple)

    def evaluate(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rot = Rotation.from_rotvec(tau[:, None] * self.omega_world[None, :]) * Rotation.from_quat(self.q0)
        return rot.as_quat(), np.broadcast_to(self.omega, (tau.size, 3)).copy()

    def evaluate_scalar(self, tau: float) -> tuple[tuple, tuple]:
        wx, wy, wz = self._omega_world_tuple
        return quat.multiply(quat.exp_rotation_vector((tau * wx, tau * wy, tau * wz)), self._q0_tuple), self._omega_tuple


class _SymmetricFlow:
    """I_a = I_b = i_perp != I_d: commuting rotations about L_world and the body axis d."""

    def __init__(self, moments: np.ndarray, axis: int, q0: np.ndarray, omega0: np.ndarray) -> None:
        m = moments.tolist()
        i_perp = m[(axis + 1) % 3]
        l_body = tuple(i * w for i, w in zip(m, omega0.tolist()))
        q0_tuple = tuple(q0.tolist())
        rate_world = tuple(x / i_perp for x in quat.rotate(q0_tuple, l_body))  # rad/s
        self.moments = moments
        self.axis = axis
        self.rate_world = np.array(rate_world)
        self.beta = (1.0 / m[axis] - 1.0 / i_perp) * l_body[axis]  # rad/s
        self.l_body0 = np.array(l_body)
        self.q0 = q0
        self._tuples = (tuple(m), rate_world, l_body, q0_tuple)

    def evaluate(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        body_rotvec = np.zeros((tau.size, 3))
        body_rotvec[:, self.axis] = tau * self.beta
        spin = Rotation.from_rotvec(body_rotvec)
        rot = Rotation.from_rotvec(tau[:, None] * self.rate_world[None, :]) * Rotation.from_quat(self.q0) * spin
        l_body = spin.apply(self.l_body0, inverse=True)
        return rot.as_quat(), l_body / self.moments

    def evaluate_scalar(self, tau: float) -> tuple[tuple, tuple]:
        moments, rate, l_body, q0 = self._tuples
        body_rotvec = [0.0, 0.0, 0.0]
        body_rotvec[self.axis] = tau * self.beta
        spin = quat.exp_rotation_vector(body_rotvec)
        q = quat.multiply(quat.multiply(quat.exp_rotation_vector([tau * r for r in rate]), q0), spin)
        l_now = quat.rotate_inverse(spin, l_body)
        return q, tuple(l / i for l, i in zip(l_now, moments))


class _EllipticFlow:
    """The triaxial body (generic or separatrix) in the relabelled principal frame.

    Attributes (set by :func:`_elliptic_flow`): ``order`` and ``axis_signs`` (the proper
    signed permutation: omega'_k = axis_signs[k] * omega[order[k]]), the relabelled
    ``moments`` (I1', I2', I3'), ``amplitude`` (A1, A2, A3), ``signs`` (s1, sigma, s3),
    ``psi_scale``, ``lam``, ``u0``, ``m1`` (1 - m; 0 on the separatrix), ``n``, ``l_norm``,
    the AGM tables ``agm_a``/``agm_c``, ``quarter_period`` K, ``half_period_pi_excess``
    = 2 (Pi(n|m) - K), ``phase0`` = (j0, g0) and the constant quaternions ``q_wl`` (L frame
    -> world) and ``q_perm`` (body -> relabelled body).
    """

    @property
    def separatrix(self) -> bool:
        return self.m1 == 0.0

    def jacobi(self, r: Any, f: SimpleNamespace = _ARRAY_FUNCTIONS) -> tuple[Any, Any, Any]:
        """sn, cn, dn of r (|r| <= K) by the descending AGM (Abramowitz & Stegun 16.4)."""
        a, c = self.agm_a, self.agm_c
        levels = len(a) - 1
        phi = (2.0**levels * a[levels]) * r
        for i in range(levels, 0, -1):
            phi = 0.5 * (phi + f.asin(c[i] * f.sin(phi) / a[i]))
        sn = f.sin(phi)
        cn = f.cos(phi)
        return sn, cn, f.sqrt(cn * cn + self.m1 * sn * sn)

    def phase(self, u: Any, f: SimpleNamespace = _ARRAY_FUNCTIONS) -> tuple[Any, Any, Any, Any, Any]:
        """sn, cn, dn at u and the two parts of Pi(n; am u | m) beyond u: (j, g)."""
        if self.separatrix:
            sn = f.tanh(u)
            e = f.exp(-f.abs(u))
            cn = 2.0 * e / (1.0 + e * e)
            a = math.sqrt(-self.n)
            return sn, cn, cn, 0.0 * u, a * f.atan(a * sn)
        k = self.quarter_period
        j = f.floor((u + k) / (2.0 * k))
        r = u - 2.0 * k * j
        sn, cn, dn = self.jacobi(r, f)
        s2 = sn * sn
        g = (self.n / 3.0) * sn * s2 * elliprj(cn * cn, dn * dn, 1.0, 1.0 - self.n * s2)
        # sn and cn change sign over each half period 2K (dn does not)
        parity = 1.0 - 2.0 * f.fmod2(j)
        return parity * sn, parity * cn, dn, j, g

    def components(self, tau: Any, f: SimpleNamespace) -> tuple[tuple, list]:
        """Quaternion and omega components at tau (s) (floats or arrays alike)."""
        i1, i2, i3 = self.moments
        a1, a2, a3 = self.amplitude
        s1, sigma, s3 = self.signs
        u = self.lam * tau + self.u0
        sn, cn, dn, j, g = self.phase(u, f)
        j0, g0 = self.phase0
        coeff = self.l_norm * (i3 - i1) / (i1 * i3 * self.lam)
        if self.separatrix:
            phi = self.l_norm * tau / i3 + coeff * (self.lam * tau + (g - g0)) / (1.0 - self.n)
        else:
            phi = self.l_norm * tau / i1 + coeff * ((j - j0) * self.half_period_pi_excess + (g - g0))
        w = (s1 * a1 * cn, sigma * a2 * sn, s3 * a3 * dn)
        theta = f.atan2(f.hypot(i1 * w[0], i2 * w[1]), i3 * w[2])
        psi = f.atan2(self.psi_scale[0] * cn, self.psi_scale[1] * sn)
        q = quat.multiply(quat.multiply(self.q_wl, _zxz_components(phi, theta, psi, f)), self.q_perm)
        omega = [0.0, 0.0, 0.0]
        for k in range(3):
            omega[self.order[k]] = self.axis_signs[k] * w[k]
        return q, omega

    def evaluate(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q, omega = self.components(tau, _ARRAY_FUNCTIONS)
        return np.stack(q, axis=-1), np.stack(omega, axis=-1)

    def evaluate_scalar(self, tau: float) -> tuple[tuple, tuple]:
        q, omega = self.components(tau, _SCALAR_FUNCTIONS)
        return tuple(float(x) for x in q), tuple(float(x) for x in omega)


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
        'below_separatrix' (about the smallest) or 'separatrix' (L^2 = 2 E I2 to within
        8 ulps of its terms). The motion computed is the exact one for the omega0 given
        either way: a state a few ulps off the separatrix leaves the saddle after a while.
    """

    moments: np.ndarray
    omega0: np.ndarray
    q0: np.ndarray
    t0: float
    case: str
    _flow: Any = field(repr=False, compare=False)

    def state(self, t: Any) -> tuple[np.ndarray, np.ndarray]:
        """``(quaternion(t), omega(t))`` evaluated together (shapes (..., 4) and (..., 3))."""
        if isinstance(t, (float, int)) and not isinstance(t, bool):
            # one time: the float path (an order of magnitude cheaper than 1-element arrays)
            if not math.isfinite(t):
                raise ValueError(f"t must be finite, got {t}")
            q, w = self._flow.evaluate_scalar(float(t) - self.t0)
            return np.array(q), np.array(w)
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
    broadcast = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (phi, theta, psi)))
    return np.stack(_zxz_components(*broadcast, _ARRAY_FUNCTIONS), axis=-1)


def _zxz_components(phi: Any, theta: Any, psi: Any, f: SimpleNamespace) -> tuple[Any, Any, Any, Any]:
    half_sum = 0.5 * (phi + psi)
    half_diff = 0.5 * (phi - psi)
    ch = f.cos(0.5 * theta)
    sh = f.sin(0.5 * theta)
    return (sh * f.cos(half_diff), sh * f.sin(half_diff), ch * f.sin(half_sum), ch * f.cos(half_sum))


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


@functools.lru_cache(maxsize=None)
def _relabelling(order: tuple[int, int, int]) -> tuple[tuple[float, float, float], tuple[float, ...]]:
    """Signs and quaternion of the proper signed permutation x'_k = sign_k x[order[k]].

    The quaternion rotates body -> relabelled body coordinates (det = +1 by flipping axis 2).
    """
    perm = np.zeros((3, 3))
    for k, i in enumerate(order):
        perm[k, i] = 1.0
    signs = (1.0, -1.0 if np.linalg.det(perm) < 0.0 else 1.0, 1.0)
    perm[1] *= signs[1]  # keep the relabelled frame right-handed
    return signs, tuple(Rotation.from_matrix(perm).as_quat().tolist())


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


def _elliptic_flow(
    moments: list, omega: list, q0: np.ndarray, order: tuple[int, int, int], d: float
) -> _EllipticFlow:
    """Build the flow; ``d`` = L^2 - 2 E I2 (0 on the separatrix), computed by the caller."""
    flow = _EllipticFlow()
    axis_signs, q_perm = _relabelling(order)
    i1, i2, i3 = (float(moments[k]) for k in order)
    w1, w2, w3 = (axis_signs[k] * float(omega[order[k]]) for k in range(3))
    eps = _sign(i3 - i2)
    d31, d32, d21 = i3 - i1, i3 - i2, i2 - i1
    a1 = math.sqrt(w1 * w1 + i2 * d32 / (i1 * d31) * w2 * w2)
    a2 = math.sqrt(i1 * d31 / (i2 * d32) * w1 * w1 + w2 * w2)
    a3 = math.sqrt(i2 * d21 / (i3 * d31) * w2 * w2 + w3 * w3)
    big = i3 * d32 * a3 * a3
    separatrix = d == 0.0
    m1 = d / big
    m = i1 * d21 * a1 * a1 / big
    lam = math.sqrt(d32 * d31 * a3 * a3 / (i1 * i2))
    n = -i3 * d21 / (i1 * d32)
    s3 = _sign(w3)
    s1 = _sign(w1) if separatrix else 1.0
    sigma = eps * s1 * s3
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
    flow.order, flow.axis_signs = order, axis_signs
    flow.moments = (i1, i2, i3)
    flow.amplitude = (a1, a2, a3)
    flow.signs = (s1, sigma, s3)
    flow.psi_scale = (s1 * i1 * alpha1, sigma * i2 * alpha2)
    flow.lam, flow.u0, flow.m1, flow.n = lam, u0, m1, n
    flow.l_norm = math.sqrt((i1 * w1) ** 2 + (i2 * w2) ** 2 + (i3 * w3) ** 2)
    flow.agm_a, flow.agm_c = agm_a, agm_c
    flow.quarter_period, flow.half_period_pi_excess = k, excess
    _, _, _, j0, g0 = flow.phase(u0, _SCALAR_FUNCTIONS)
    flow.phase0 = (float(j0), float(g0))
    # q_world<-body = q_WL (x) q_zxz(t) (x) q_perm; q_WL from q(t0) = q0, with q_zxz(t0)
    # evaluated by the flow itself so that the two agree to rounding
    flow.q_wl, flow.q_perm = (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 1.0)
    q_zxz0 = flow.evaluate_scalar(0.0)[0]
    flow.q_wl = quat.multiply(quat.multiply(tuple(q0.tolist()), quat.conjugate(q_perm)), quat.conjugate(q_zxz0))
    flow.q_perm = q_perm
    return flow


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


def torque_free_flow(moments: np.ndarray, q: Any, omega: Any, tau: float) -> tuple[tuple, tuple]:
    """Exact free flow over tau (s) from (q, omega): ``(q(tau), omega(tau))`` as float tuples.

    The same as ``torque_free_solution(moments, omega, q).state(tau)`` without the input
    checks, for integrators that call it every step with a state they already checked
    (``moments`` a float array (3,), q a unit quaternion).
    """
    solution = _solution(moments, np.asarray(omega, dtype=float), np.asarray(q, dtype=float), 0.0)
    return solution._flow.evaluate_scalar(float(tau))


def _separatrix_distance(moments: list, omega: list, i_min: int, i_mid: int, i_max: int) -> float:
    """``L^2 - 2 E I2`` from its two terms of opposite sign (exact where they cancel)."""
    d_above = float(moments[i_max] * (moments[i_max] - moments[i_mid]) * omega[i_max] ** 2)
    d_below = float(moments[i_min] * (moments[i_mid] - moments[i_min]) * omega[i_min] ** 2)
    scale = d_above + d_below
    if abs(d_above - d_below) > _EXACT_SEPARATRIX_DISTANCE * scale:
        return d_above - d_below
    # The terms cancel: evaluate exactly in rational arithmetic (a rounded D would decide the
    # case wrongly at the separatrix and cost digits in the phase and precession next to it).
    i1, i2, i3, w1, w3 = (
        Fraction(float(x)) for x in (moments[i_min], moments[i_mid], moments[i_max], omega[i_min], omega[i_max])
    )
    return float(i3 * (i3 - i2) * w3 * w3 - i1 * (i2 - i1) * w1 * w1)


def _solution(moments: np.ndarray, omega0: np.ndarray, q0: np.ndarray, t0: float) -> TorqueFreeSolution:
    m = moments.tolist()
    i_min, i_mid, i_max = sorted(range(3), key=m.__getitem__)
    tol = _EQUAL_MOMENTS_ULPS * _EPS * m[i_max]
    low_equal = m[i_mid] - m[i_min] <= tol
    high_equal = m[i_max] - m[i_mid] <= tol
    if low_equal and high_equal:
        case = "spherical"
        flow: Any = _RigidRotation(omega0.copy(), q0)
    elif low_equal or high_equal:
        case = "symmetric"
        flow = _SymmetricFlow(moments.copy(), i_max if low_equal else i_min, q0, omega0)
    else:
        w = omega0.tolist()
        d = _separatrix_distance(m, w, i_min, i_mid, i_max)
        # The label allows for rounding in the caller's omega0; the flow itself is the exact
        # solution for the omega0 given (the separatrix closed form only when d is exactly 0).
        scale = m[i_max] * (m[i_max] - m[i_mid]) * w[i_max] ** 2 + m[i_min] * (m[i_mid] - m[i_min]) * w[i_min] ** 2
        if abs(d) <= _SEPARATRIX_ULPS * _EPS * scale:
            case = "separatrix"
        else:
            case = "above_separatrix" if d > 0.0 else "below_separatrix"
        if not (w[i_min] or w[i_max]):
            # at rest, or a stationary spin about the middle axis
            flow = _RigidRotation(omega0.copy(), q0)
        else:
            order = (i_max, i_mid, i_min) if d < 0.0 else (i_min, i_mid, i_max)
            flow = _elliptic_flow(m, w, q0, order, d)
    return TorqueFreeSolution(moments, omega0, q0, t0, case, flow)
