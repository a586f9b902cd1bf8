"""The heavy symmetric top: a symmetric body on a fixed pivot under uniform gravity.

Model: the pivot lies on the symmetry axis (body z) at distance ``com_distance`` = l
(m) below the centre of mass (the centre of mass is at ``l e3`` from the pivot); gravity
g acts along -z of the world (z up). The moments about the pivot follow from the
centre-of-mass inertia (I_perp, I_perp, I3) by the parallel-axis theorem:
``(I_perp + m l^2, I_perp + m l^2, I3)``. The top is integrated in singularity-free form
by the ordinary integrators (quaternion + body omega + :class:`GravityTorque`); the z-x-z
Euler angles (theta nutation, phi precession, psi spin) are derived from q for output
only.

Conserved: the energy ``E = 1/2 omega . I_p omega + m g l cos(theta)``, ``p_phi = L . e_z``
(world vertical) and ``p_psi = L . e3 = I3 omega3`` (symmetry axis), L about the pivot.

Exact references (derivations)
------------------------------
With I1 = I_perp + m l^2 (pivot), the Lagrangian gives ``p_psi = I3 (psi' + phi' cos th)``,
``p_phi = I1 phi' sin^2 th + p_psi cos th`` and, for u = cos(theta),

    u'^2 = f(u) = (1 - u^2)(a - b u) - (p_phi - p_psi u)^2 / I1^2,
    a = (2 E - p_psi^2 / I3) / I1,   b = 2 m g l / I1,

a cubic with ``f(+-1) <= 0`` and leading coefficient b > 0: the motion lies between its
roots u1 <= u <= u2 in [-1, 1] (the third root u3 >= 1). Substituting
``u = u1 + (u2 - u1) sn^2(w)`` gives ``w' = nu = sqrt(b (u3 - u1)) / 2`` with parameter
``k^2 = (u2 - u1) / (u3 - u1)`` (:class:`HeavyTopReference`). Then
``phi' = (p_phi - p_psi u) / (I1 (1 - u^2))`` and ``psi' = p_psi / I3 - u phi'`` are
integrated by quadrature over one period of u and the remainder.

The separatrix (:func:`separatrix_state`, :func:`separatrix_solution`): ``f`` has a double
root at u = 1 (the axis creeps up to the vertical in infinite time) when p_phi = p_psi
and ``a = b`` (E' = m g l); then ``f = b (1 - u)^2 (1 + u - beta)``,
``beta = p_psi^2 / (2 I1 m g l)``. Starting at rest in theta at theta0 = pi/3 (u0 = 1/2 a
root) needs beta = 3/2: the matching spin is ``p_psi = sqrt(3 I1 m g l)``
(omega3 = p_psi / I3) with ``phi'(0) = 2 p_psi / (3 I1)``. With s = sech(gamma t),
u = 1 / (1 + s) solves ``u'^2 = b (1 - u)^2 (u - 1/2)`` exactly when
``gamma^2 = b / 2 = m g l / I1``, i.e. ``1 / cos(theta) = 1 + 1 / cosh(gamma t)``. The
angles follow in closed form from ``integral dt / (2 + sech(gamma t))
= t/2 - atan(tanh(gamma t / 2) / sqrt 3) / (gamma sqrt 3)``:

    phi(t) = (p_psi / I1) [t/2 + atan(tanh(gamma t / 2) / sqrt 3) / (gamma sqrt 3)]
    psi(t) = p_psi t / I3 - (p_psi / (2 I1)) [t - 2 atan(tanh(gamma t / 2) / sqrt 3) / (gamma sqrt 3)]
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.integrate import quad
from scipy.special import ellipj, ellipk, ellipkinc

from rigid_rot_sim.core import validation
from rigid_rot_sim.core.arrays import ArrayLike, FloatArray
from rigid_rot_sim.core.dynamics import angular_momentum_world, kinetic_energy, world_to_body
from rigid_rot_sim.core.inertia import parallel_axis_shift
from rigid_rot_sim.core.quaternion import quaternion_to_zxz, zxz_to_quaternion
from rigid_rot_sim.core.simulate import simulate
from rigid_rot_sim.core.torque import GravityTorque

_E_Z = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True, eq=False)
class HeavyTop:
    """A heavy symmetric top.

    Attributes
    ----------
    mass : float
        Mass m, kg (> 0).
    gravity : float
        Gravitational acceleration g, m/s^2 (> 0), acting along -z of the world.
    com_distance : float
        Distance l from the pivot to the centre of mass along the body z axis, m (> 0).
    com_moments : array_like (3,)
        Principal moments about the centre of mass (I_perp, I_perp, I3), kg*m^2;
        the first two must be equal (the body z axis is the symmetry axis).
    """

    mass: float
    gravity: float
    com_distance: float
    com_moments: Any

    def __post_init__(self) -> None:
        object.__setattr__(self, "mass", validation.positive_scalar("mass", self.mass))
        object.__setattr__(self, "gravity", validation.positive_scalar("gravity", self.gravity))
        object.__setattr__(self, "com_distance", validation.positive_scalar("com_distance", self.com_distance))
        moments = validation.principal_moments("com_moments", self.com_moments)
        if abs(moments[0] - moments[1]) > validation.SYMMETRY_RTOL * moments.max():
            raise ValueError(
                f"com_moments[0] and com_moments[1] must be equal for a symmetric top, got {moments.tolist()}"
            )
        object.__setattr__(self, "com_moments", moments)

    @property
    def lever_arm(self) -> np.ndarray:
        """Pivot -> centre of mass, m, body frame: ``(0, 0, l)``."""
        return np.array([0.0, 0.0, self.com_distance])

    @property
    def pivot_moments(self) -> np.ndarray:
        """Principal moments about the pivot (I1, I1, I3), kg*m^2 (parallel-axis theorem)."""
        return np.diag(parallel_axis_shift(np.diag(self.com_moments), self.mass, self.lever_arm)).copy()

    @property
    def torque(self) -> GravityTorque:
        """The gravity torque about the pivot, N*m, body frame."""
        return GravityTorque(self.lever_arm, self.mass * self.gravity)

    def state_from_euler(
        self, theta: float, phi: float, psi: float, theta_dot: float, phi_dot: float, psi_dot: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Attitude q (principal -> world) and body omega (rad/s) from z-x-z angles (rad) and rates (rad/s)."""
        q = zxz_to_quaternion(phi, theta, psi)
        st, ct, sp, cp = math.sin(theta), math.cos(theta), math.sin(psi), math.cos(psi)
        # omega_body = phi' R^T e_z + theta' Rz(-psi) e_x + psi' e_z
        omega = np.array(
            [phi_dot * st * sp + theta_dot * cp, phi_dot * st * cp - theta_dot * sp, phi_dot * ct + psi_dot]
        )
        return q, omega

    def invariants(self, q: ArrayLike, omega: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(E, p_phi, p_psi)``: energy (J) and the momenta about the vertical and the symmetry axis (kg*m^2/s).

        q (..., 4) principal -> world; omega (..., 3) rad/s, body frame.
        """
        moments = self.pivot_moments
        omega = np.asarray(omega, dtype=float)
        cos_theta = world_to_body(q, _E_Z)[..., 2]
        energy = kinetic_energy(moments, omega) + self.mass * self.gravity * self.com_distance * cos_theta
        p_phi = angular_momentum_world(moments, q, omega)[..., 2]
        p_psi = moments[2] * omega[..., 2]
        return energy, p_phi, p_psi

    def simulate(
        self, q0: ArrayLike, omega0: ArrayLike, t_end: float, dt: float, method: str, **options: Any
    ) -> HeavyTopTrajectory:
        """Integrate with a core integrator (``METHODS`` name) and add Euler angles and invariants."""
        traj = simulate(self.pivot_moments, omega0, t_end, dt, method, q0=q0, torque=self.torque, **options)
        phi, theta, psi = quaternion_to_zxz(traj.q)
        energy, p_phi, p_psi = self.invariants(traj.q, traj.omega)
        return HeavyTopTrajectory(traj.t, traj.q, traj.omega, theta, phi, psi, energy, p_phi, p_psi, method)


@dataclass(frozen=True, eq=False)
class HeavyTopTrajectory:
    """A sampled heavy-top run: t (s), q, omega (rad/s, body), z-x-z angles (rad), E (J), p_phi, p_psi."""

    t: np.ndarray
    q: np.ndarray
    omega: np.ndarray
    theta: np.ndarray
    phi: np.ndarray
    psi: np.ndarray
    energy: np.ndarray
    p_phi: np.ndarray
    p_psi: np.ndarray
    method: str


def separatrix_state(top: HeavyTop) -> tuple[np.ndarray, np.ndarray]:
    """(q0, omega0) of the separatrix motion: theta0 = pi/3, theta'0 = 0, phi0 = psi0 = 0 and
    the matching spin ``p_psi = sqrt(3 I1 m g l)``, ``phi'0 = 2 p_psi / (3 I1)``."""
    i1, _, i3 = top.pivot_moments
    p_psi = math.sqrt(3.0 * i1 * top.mass * top.gravity * top.com_distance)
    theta0 = math.pi / 3.0
    phi_dot = 2.0 * p_psi / (3.0 * i1)
    # omega3 = psi' + phi' cos(theta) = p_psi / I3
    psi_dot = p_psi / i3 - phi_dot * math.cos(theta0)
    return top.state_from_euler(theta0, 0.0, 0.0, 0.0, phi_dot, psi_dot)


def separatrix_solution(top: HeavyTop, t: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closed-form ``(theta, phi, psi)`` (rad) at t (s) from :func:`separatrix_state`.

    ``1 / cos(theta) = 1 + 1 / cosh(gamma t)`` with ``gamma = sqrt(m g l / I1)``; phi and psi
    as derived in the module docstring (unwrapped, not reduced to (-pi, pi]).
    """
    i1, _, i3 = top.pivot_moments
    mgl = top.mass * top.gravity * top.com_distance
    gamma = math.sqrt(mgl / i1)
    p_psi = math.sqrt(3.0 * i1 * mgl)
    t = np.asarray(t, dtype=float)
    e = np.exp(-gamma * np.abs(t))
    sech = 2.0 * e / (1.0 + e * e)
    theta = np.arccos(1.0 / (1.0 + sech))
    sqrt3 = math.sqrt(3.0)
    arc = np.arctan(np.tanh(0.5 * gamma * t) / sqrt3) / (gamma * sqrt3)
    phi = (p_psi / i1) * (0.5 * t + arc)
    psi = p_psi * t / i3 - (p_psi / (2.0 * i1)) * (t - 2.0 * arc)
    return theta, phi, psi


@dataclass(frozen=True, eq=False)
class HeavyTopReference:
    """Motion of a heavy top from its invariants: u = cos(theta) by Jacobi functions, phi and psi by quadrature.

    Build with :func:`heavy_top_reference`. ``turning_points`` = (u1, u2) with
    u1 <= cos(theta) <= u2; ``u3`` >= 1 is the third root of f.
    """

    top: HeavyTop
    energy: float
    p_phi: float
    p_psi: float
    turning_points: tuple[float, float]
    u3: float
    nu: float  # rad/s: the Jacobi argument is nu t + w0
    k2: float
    w0: float
    phi0: float
    psi0: float

    @property
    def period(self) -> float:
        """Period of the nutation (theta), s."""
        return 2.0 * float(ellipk(self.k2)) / self.nu

    @property
    def theta_range(self) -> tuple[float, float]:
        """(theta_min, theta_max), rad."""
        u1, u2 = self.turning_points
        return math.acos(min(u2, 1.0)), math.acos(max(u1, -1.0))

    def cos_theta(self, t: ArrayLike) -> np.ndarray:
        """u = cos(theta) at t (s)."""
        u1, u2 = self.turning_points
        sn = ellipj(self.nu * np.asarray(t, dtype=float) + self.w0, self.k2)[0]
        return u1 + (u2 - u1) * sn * sn

    def theta(self, t: ArrayLike) -> np.ndarray:
        """Nutation angle theta(t), rad."""
        theta: FloatArray = np.arccos(np.clip(self.cos_theta(t), -1.0, 1.0))
        return theta

    def _rates(self, s: float) -> tuple[float, float]:
        i1, _, i3 = self.top.pivot_moments
        u = float(self.cos_theta(s))
        # (p_phi - p_psi u) / (1 - u^2) without the 0/0 at u = 1 when p_phi = p_psi
        phi_dot = ((self.p_phi - self.p_psi) / (1.0 - u * u) + self.p_psi / (1.0 + u)) / i1
        return phi_dot, self.p_psi / i3 - u * phi_dot

    def _integral(self, t: float) -> tuple[float, float]:
        """(phi(t) - phi0, psi(t) - psi0) by quadrature over whole periods and the remainder."""
        period = self.period
        periods = math.floor(t / period)
        rest = t - periods * period

        def integrate(a: float, b: float) -> tuple[float, float]:
            return (
                quad(lambda s: self._rates(s)[0], a, b, epsabs=1e-14, epsrel=1e-13, limit=200)[0],
                quad(lambda s: self._rates(s)[1], a, b, epsabs=1e-14, epsrel=1e-13, limit=200)[0],
            )

        one = integrate(0.0, period) if periods else (0.0, 0.0)
        part = integrate(0.0, rest)
        return periods * one[0] + part[0], periods * one[1] + part[1]

    def euler_angles(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(theta, phi, psi)`` at t >= 0 (s), rad; phi and psi unwrapped."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if np.any(t < 0.0) or not np.all(np.isfinite(t)):
            raise ValueError(f"t must be finite and >= 0, got {t}")
        increments = np.array([self._integral(float(s)) for s in t.ravel()]).reshape(t.shape + (2,))
        return self.theta(t), self.phi0 + increments[..., 0], self.psi0 + increments[..., 1]

    def quaternion(self, t: ArrayLike) -> np.ndarray:
        """Attitude (principal -> world, scalar-last) at t >= 0 (s)."""
        theta, phi, psi = self.euler_angles(t)
        return zxz_to_quaternion(phi, theta, psi)


def _polished_roots(coefficients: np.ndarray) -> np.ndarray:
    roots = np.roots(coefficients)
    real = np.sort(roots.real[np.abs(roots.imag) <= 1e-7 * (1.0 + np.abs(roots.real))])
    derivative = np.polyder(coefficients)
    for _ in range(3):  # Newton polishing of the eigenvalue roots
        slope = np.polyval(derivative, real)
        step = np.where(slope != 0.0, np.polyval(coefficients, real) / np.where(slope != 0.0, slope, 1.0), 0.0)
        real = real - step
    return np.sort(real)


def heavy_top_reference(top: HeavyTop, q0: ArrayLike, omega0: ArrayLike) -> HeavyTopReference:
    """The exact heavy-top motion from (q0, omega0) at t = 0 (see the module docstring).

    Raises ValueError when f(u) has no oscillation range in [-1, 1] (a state at a double
    root, such as steady precession or the separatrix, is not covered: use
    :func:`separatrix_solution` for the latter).
    """
    q0 = validation.quaternion("q0", q0)
    omega0 = validation.finite_vector("omega0", omega0)
    i1, _, i3 = top.pivot_moments
    energy, p_phi, p_psi = (float(x) for x in top.invariants(q0, omega0))
    b = 2.0 * top.mass * top.gravity * top.com_distance / i1
    a = (2.0 * energy - p_psi * p_psi / i3) / i1
    # f(u) = (1 - u^2)(a - b u) - (p_phi - p_psi u)^2 / I1^2, highest power first
    coefficients = np.array([b, -a - (p_psi / i1) ** 2, -b + 2.0 * p_phi * p_psi / i1**2, a - (p_phi / i1) ** 2])
    roots = _polished_roots(coefficients)
    u = float(world_to_body(q0, _E_Z)[2])
    if roots.size != 3:
        raise ValueError("heavy_top_reference: f(u) has complex roots (the state is not a bound nutation)")
    u1, u2, u3 = roots
    # the initial u lies between u1 and u2 up to the rounding of the roots
    if not (u1 - 1e-9 <= u <= u2 + 1e-9) or u2 - u1 <= 1e-12:
        raise ValueError(
            f"heavy_top_reference: cos(theta0) = {u} is not inside a nutation range of f (roots {roots.tolist()})"
        )
    k2 = (u2 - u1) / (u3 - u1)
    nu = 0.5 * math.sqrt(b * (u3 - u1))
    s2 = min(max((u - u1) / (u2 - u1), 0.0), 1.0)
    w0 = float(ellipkinc(math.asin(math.sqrt(s2)), k2))
    # u' = up_body . (omega x e3); the Jacobi phase runs backwards when u is decreasing
    up = world_to_body(q0, _E_Z)
    u_dot = float(np.dot(up, np.cross(omega0, _E_Z)))
    if u_dot < 0.0:
        w0 = -w0
    phi0, _, psi0 = (float(x) for x in quaternion_to_zxz(q0))
    return HeavyTopReference(top, energy, p_phi, p_psi, (float(u1), float(u2)), float(u3), nu, k2, w0, phi0, psi0)
