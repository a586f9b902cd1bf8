"""A spacecraft with balanced reaction wheels (a gyrostat) and the gravity-gradient torque.

Conventions (those of Basilisk's ``reactionWheelStateEffector``, so that results compare):

* the body inertia ``I`` (kg*m^2, about the centre of mass) *includes* the wheels, as if
  they were locked to the body;
* wheel i spins about the unit axis ``g_i`` fixed in the body, with spin inertia ``J_i``
  (kg*m^2) about it; it is balanced (its centre of mass on its axis, the axis a principal
  axis of the wheel, transverse moments equal);
* ``Omega_i`` (rad/s) is the wheel's speed *relative to the body* about ``g_i``;
* ``u_i`` (N*m) is the motor torque on wheel i about ``g_i``; the body feels ``-u_i g_i``.

Equations, derived from first principles (body frame, omega the body rate in rad/s).
The wheel's absolute angular velocity is ``omega + Omega_i g_i``; with ``g_i`` a principal
axis of the wheel, its momentum is ``I_wheel,i omega + J_i Omega_i g_i``, so the total
angular momentum about the centre of mass is

    H = I omega + h_w,        h_w = sum_i J_i Omega_i g_i                        (1)

(``I`` already holds every wheel's inertia as if locked). Newton-Euler for the whole,
torque-free but for the external torque tau, in the rotating body frame:

    dH/dt|body + omega x H = tau                                                  (2)

The axial momentum of a symmetric wheel, ``J_i (g_i . omega + Omega_i)``, changes only by
the axial torque on it (the gyroscopic term ``(omega x g_i) . I_wheel (omega + Omega_i g_i)``
vanishes for equal transverse moments):

    J_i (g_i . domega/dt + dOmega_i/dt) = u_i - f_i(Omega_i)                      (3)

with ``f_i`` the friction torque. Eliminating dOmega_i/dt from (2) with (3):

    (I - sum_i J_i g_i g_i^T) domega/dt = tau - omega x H - sum_i (u_i - f_i) g_i    (4)
    dOmega_i/dt = (u_i - f_i) / J_i - g_i . domega/dt                               (5)

so the matrix that multiplies domega/dt is ``I_s = I - sum J_i g_i g_i^T``, the inertia
without the wheels' spin inertia (it must be positive definite: :func:`wheel_model`
refuses a wheel set that leaves no body). The kinetic energy is

    T = 1/2 omega^T I_s omega + sum_i 1/2 J_i (g_i . omega + Omega_i)^2              (6)

and (4), (5) give ``dT/dt = omega . tau + sum_i Omega_i (u_i - f_i)``: with frictionless
wheels, no motor torque and no external torque, T and the world-frame momentum
``R(q) H`` are conserved (the tests check both to the method's order); the attitude
obeys ``dq/dt = 1/2 q (x) (omega, 0)`` as for the bare body. Each wheel's angle theta_i
(rad, about g_i, relative to the body) is the integral of its relative speed,

    dtheta_i/dt = Omega_i                                                          (8)

unwrapped (continuous, never reduced to [-pi, pi]: a joint position a controller differentiates
must not jump); it drives nothing, so the integrators carry it without error control.

Limits, as documented in the scene schema:

* torque saturation: a motor command is clamped to ``|u_i| <= max_torque_i`` (the run
  engine clamps it, and says so);
* speed saturation: the motor never drives a wheel past ``max_speed_i``: a torque that
  speeds the wheel up (``u_i Omega_i > 0``) is scaled by ``clip((max_speed_i - |Omega_i|) /
  ramp_i, 0, 1)`` with ``ramp_i = max_speed_i / 100``, so it fades to zero over the last
  1 % below max_speed (continuous in the state: every method keeps its order, and a wheel
  driven against its limit approaches it without passing it); a torque that slows the
  wheel always acts;
* friction: ``f_i = coulomb_i * s(Omega_i) + viscous_i * Omega_i`` (N*m, opposing the
  relative speed), with ``s`` the sign of Omega_i, made linear below
  ``stiction_speed_i`` (``s = Omega_i / stiction_speed_i`` for ``|Omega_i| <
  stiction_speed_i``; Basilisk's ``omegaLimitCycle``), so a wheel left alone comes to rest
  instead of chattering about zero.

Gravity gradient, on a circular orbit of radius ``R`` (m) about a body of gravitational
parameter ``mu`` (m^3/s^2): the centre of mass is at world position
``R (cos u, cos i sin u, sin i sin u)`` from the planet's centre, ``u = n t`` the argument
of latitude, ``n = sqrt(mu / R^3)`` the mean motion (rad/s), ``i`` the inclination: the
orbit's node line is the world x axis, the ascending node on +x, the orbit normal
``(0, -sin i, cos i)``, and at t = 0 the body is at the ascending node. With ``r`` the
unit vector from the planet to the body expressed in the body frame (the world position
rotated into the body frame by ``R(q)^T``), the torque about the centre of mass is

    tau_gg = 3 mu / R^5  R_b x (I R_b) = 3 n^2 r x (I r)                           (7)

(the first term of the expansion of the gravity of a point mass over the body). On any
orbit of :mod:`rigid_rot_sim.core.orbit` (:func:`kepler_orbit_model`: eccentric, inclined, with
J2's drift) the same torque with the body's position from that orbit, ``3 mu / |R|^3 r x (I r)``,
the world frame then being the orbit's inertial frame. A
satellite with principal axes along radial (I_r), along-track (I_t) and orbit normal
(I_n) librates in pitch, relative to the rotating radial frame, at
``n sqrt(3 (I_t - I_r) / I_n)`` (stable for I_t > I_r): in the common LVLH axes (x
along-track, y minus orbit normal, z nadir) this is ``n sqrt(3 (I_x - I_z) / I_y)``.

Everything here is in the frame the caller gives (the integrators use the principal
frame: :meth:`WheelModel.in_frame` rotates the axes). Units: SI throughout.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba.extending import register_jitable

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.orbit import KeplerOrbit, orbit_state

__all__ = [
    "WheelModel",
    "OrbitModel",
    "wheel_model",
    "orbit_model",
    "kepler_orbit_model",
    "NO_ORBIT",
    "gyrostat_rhs",
    "applied_motor_torque",
    "friction_torque",
    "gravity_gradient_torque",
    "total_momentum_body",
    "gyrostat_energy",
    "mean_motion",
]

#: Fraction of max_speed over which a motor torque that speeds the wheel up fades to zero.
SPEED_RAMP_FRACTION = 0.01
#: Default speed (rad/s) below which Coulomb friction is linear in the speed (Basilisk's omegaLimitCycle).
DEFAULT_STICTION_SPEED = 1e-4


@dataclass(frozen=True)
class WheelModel:
    """Reaction wheels as arrays (n wheels), in one body frame.

    ``axes`` (n, 3) unit spin axes; ``spin_inertia`` (n,) kg*m^2; ``max_torque`` (n,) N*m;
    ``max_speed`` (n,) rad/s; ``coulomb`` (n,) N*m; ``viscous`` (n,) N*m*s/rad;
    ``stiction_speed`` (n,) rad/s; ``names`` the wheels' names.
    """

    names: tuple[str, ...]
    axes: np.ndarray
    spin_inertia: np.ndarray
    max_torque: np.ndarray
    max_speed: np.ndarray
    coulomb: np.ndarray
    viscous: np.ndarray
    stiction_speed: np.ndarray

    @property
    def count(self) -> int:
        return len(self.names)

    def in_frame(self, rotation: np.ndarray) -> WheelModel:
        """The same wheels with axes ``rotation @ g`` (rotation: (3, 3), e.g. user body -> principal)."""
        axes = np.ascontiguousarray(self.axes @ np.asarray(rotation, dtype=float).T)
        return WheelModel(
            self.names,
            axes,
            self.spin_inertia,
            self.max_torque,
            self.max_speed,
            self.coulomb,
            self.viscous,
            self.stiction_speed,
        )

    def compiled(self) -> tuple[np.ndarray, ...]:
        """The tuple the kernels take: (axes, J, max_speed, ramp, coulomb, viscous, stiction_speed)."""
        return (
            np.ascontiguousarray(self.axes, dtype=float),
            self.spin_inertia,
            self.max_speed,
            self.max_speed * SPEED_RAMP_FRACTION,
            self.coulomb,
            self.viscous,
            self.stiction_speed,
        )


def _array(values: Any, n: int, name: str, minimum: float, strict: bool) -> np.ndarray:
    a = np.array(values, dtype=float).reshape(n)
    bad = ~np.isfinite(a) | ((a <= minimum) if strict else (a < minimum))
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{name}[{i}] must be finite and {'>' if strict else '>='} {minimum:g}, got {a[i]}")
    return a


def wheel_model(
    inertia: Any,
    names: Any,
    axes: Any,
    spin_inertia: Any,
    max_torque: Any,
    max_speed: Any,
    coulomb: Any = None,
    viscous: Any = None,
    stiction_speed: Any = None,
) -> WheelModel:
    """Validated :class:`WheelModel` for a body of inertia ``inertia`` (3x3, kg*m^2, wheels included).

    Axes are normalised; ValueError when an axis is zero, a value is out of range, or the
    inertia less the wheels' spin inertias (``I - sum J g g^T``, eq. (4)) is not positive definite.
    """
    names = tuple(str(n) for n in names)
    n = len(names)
    axes = np.array(axes, dtype=float).reshape(n, 3)
    norms = np.linalg.norm(axes, axis=1)
    for i in range(n):
        if not (math.isfinite(norms[i]) and norms[i] > 0.0):
            raise ValueError(f"wheel {names[i]!r}: axis must be a finite non-zero vector, got {axes[i].tolist()}")
    axes = np.ascontiguousarray(axes / norms[:, None])
    zeros = np.zeros(n)
    model = WheelModel(
        names,
        axes,
        _array(spin_inertia, n, "spin_inertia", 0.0, True),
        _array(max_torque, n, "max_torque", 0.0, True),
        _array(max_speed, n, "max_speed", 0.0, True),
        _array(zeros if coulomb is None else coulomb, n, "coulomb", 0.0, False),
        _array(zeros if viscous is None else viscous, n, "viscous", 0.0, False),
        _array(
            np.full(n, DEFAULT_STICTION_SPEED) if stiction_speed is None else stiction_speed,
            n,
            "stiction_speed",
            0.0,
            True,
        ),
    )
    hub = np.asarray(inertia, dtype=float).reshape(3, 3) - (
        model.spin_inertia[:, None, None] * axes[:, :, None] * axes[:, None, :]
    ).sum(axis=0)
    smallest = float(np.linalg.eigvalsh(0.5 * (hub + hub.T))[0])
    if not smallest > 0.0:
        raise ValueError(
            f"the body inertia less the wheels' spin inertias (I - sum J g g^T) must be positive definite "
            f"(smallest eigenvalue {smallest:.6g} kg*m^2): the body inertia includes the wheels"
        )
    return model


@dataclass(frozen=True)
class OrbitModel:
    """The orbit of the gravity-gradient torque: circular, ``mu`` (m^3/s^2), ``radius`` (m), ``inclination``
    (rad) in the world frame, or any :class:`~rigid_rot_sim.core.orbit.KeplerOrbit` (``kepler``; then the world
    frame is its inertial frame and ``radius``, ``inclination`` are unused).

    ``mu = 0`` means no gravity gradient (:data:`NO_ORBIT`).
    """

    mu: float = 0.0
    radius: float = 1.0
    inclination: float = 0.0
    kepler: KeplerOrbit | None = None

    @property
    def enabled(self) -> bool:
        return self.mu > 0.0

    @property
    def mean_motion(self) -> float:
        """n = sqrt(mu / R^3), or the Kepler orbit's mean anomaly rate, rad/s (0 without an orbit)."""
        if self.kepler is not None:
            return self.kepler.mean_anomaly_dot
        return mean_motion(self.mu, self.radius)

    def compiled(self) -> np.ndarray:
        """For the kernels: ``(k, n, cos i, sin i)`` then :meth:`KeplerOrbit.compiled` (zeros when circular).

        ``k`` bounds ``3 mu / R^3`` over the orbit: ``3 n^2`` when circular, ``3 mu / r_p^3`` (at periapsis)
        on a Kepler orbit; 0 without an orbit.
        """
        if self.kepler is None:
            n = self.mean_motion
            head = [3.0 * n * n, n, math.cos(self.inclination), math.sin(self.inclination)]
            return np.array(head + [0.0] * _KEPLER_SIZE)
        kepler = self.kepler
        periapsis = kepler.a * (1.0 - kepler.e)
        head = [3.0 * kepler.mu / periapsis**3, kepler.mean_anomaly_dot, math.cos(kepler.i), math.sin(kepler.i)]
        return np.concatenate((np.array(head), kepler.compiled()))

    def position_world(self, t: float) -> np.ndarray:
        """The unit vector from the planet to the body at time t (s), world frame."""
        _, x, y, z = _orbit_direction(self.compiled(), t)
        return np.array((x, y, z))


NO_ORBIT = OrbitModel()
_KEPLER_SIZE = 10  # the length of KeplerOrbit.compiled()


def mean_motion(mu: float, radius: float) -> float:
    """Mean motion sqrt(mu / R^3) (rad/s) of a circular orbit of radius R (m)."""
    return math.sqrt(mu / radius**3) if mu > 0.0 else 0.0


def kepler_orbit_model(kepler: KeplerOrbit) -> OrbitModel:
    """The gravity gradient on ``kepler`` (:func:`rigid_rot_sim.core.orbit.kepler_orbit` validates it)."""
    return OrbitModel(kepler.mu, kepler.a, kepler.i, kepler)


def orbit_model(mu: float, radius: float, inclination: float = 0.0) -> OrbitModel:
    """Validated :class:`OrbitModel` (mu > 0, radius > 0, inclination in [0, pi] rad)."""
    if not (math.isfinite(mu) and mu > 0.0):
        raise ValueError(f"mu must be finite and > 0 m^3/s^2, got {mu}")
    if not (math.isfinite(radius) and radius > 0.0):
        raise ValueError(f"orbit radius must be finite and > 0 m, got {radius}")
    if not (math.isfinite(inclination) and 0.0 <= inclination <= math.pi):
        raise ValueError(f"inclination must be in [0, pi] rad, got {inclination}")
    return OrbitModel(float(mu), float(radius), float(inclination))


# ------------------------------------------------------------- formulas (compiled into kernels)


@register_jitable
def _orbit_direction(orbit: np.ndarray, t: float) -> tuple[float, float, float, float]:
    """``(3 mu / R^3, unit vector from the planet to the body)`` at ``t`` of :meth:`OrbitModel.compiled`."""
    if orbit[5] > 0.0:  # a Kepler orbit: its semi-major axis
        x, y, z, _, _, _ = orbit_state(orbit[4:], t)
        r = math.sqrt(x * x + y * y + z * z)
        return 3.0 * orbit[4] / (r * r * r), x / r, y / r, z / r
    u = orbit[1] * t
    su = math.sin(u)
    return orbit[0], math.cos(u), orbit[2] * su, orbit[3] * su


@register_jitable
def gravity_gradient_torque(
    orbit: np.ndarray, moments: np.ndarray, q: tuple[float, float, float, float], t: float
) -> tuple[float, float, float]:
    """Eq. (7): ``3 mu / R^3 r x (I r)`` (N*m) in the principal frame of ``moments``; q principal -> world.

    ``orbit`` is :meth:`OrbitModel.compiled`; zero torque when 3 n^2 is 0.
    """
    if orbit[0] == 0.0:
        return 0.0, 0.0, 0.0
    k, x, y, z = _orbit_direction(orbit, t)
    r1, r2, r3 = quat.rotate_inverse(q, (x, y, z))
    i1, i2, i3 = moments[0], moments[1], moments[2]
    return k * (i3 - i2) * r2 * r3, k * (i1 - i3) * r3 * r1, k * (i2 - i1) * r1 * r2


@register_jitable
def friction_torque(coulomb: float, viscous: float, stiction_speed: float, speed: float) -> float:
    """Friction torque (N*m) opposing a relative wheel speed (rad/s).

    Coulomb (linear below stiction_speed) + viscous.
    """
    if speed > stiction_speed:
        s = 1.0
    elif speed < -stiction_speed:
        s = -1.0
    else:
        s = speed / stiction_speed
    return coulomb * s + viscous * speed


@register_jitable
def applied_motor_torque(command: float, speed: float, max_speed: float, ramp: float) -> float:
    """The motor torque (N*m) that acts for a (clamped) command at wheel speed ``speed`` (rad/s).

    A torque that speeds the wheel up fades linearly to zero over the last ``ramp`` rad/s
    below ``max_speed`` (and is zero beyond it); one that slows it down acts in full.
    """
    if command * speed <= 0.0:
        return command
    margin = (max_speed - abs(speed)) / ramp
    if margin >= 1.0:
        return command
    if margin <= 0.0:
        return 0.0
    return command * margin


@register_jitable
def gyrostat_rhs(
    t: float,
    y: np.ndarray,
    moments: np.ndarray,
    wheels: tuple[np.ndarray, ...],
    hub_inverse: np.ndarray,
    external: np.ndarray,
    orbit: np.ndarray,
    commands: np.ndarray,
    dy: np.ndarray,
    applied: np.ndarray,
) -> None:
    """d/dt of ``y = (q, omega, Omega[, theta])`` into ``dy`` (eqs. (4), (5), dq/dt = 1/2 q (x) omega).

    When ``y`` also carries the n wheel angles ``theta`` (rad, relative to the body: length 7 + 2n),
    ``dtheta_i/dt = Omega_i`` (eq. (8)); the angles feed back into nothing.
    ``moments`` (3,) principal moments (wheels included); ``wheels`` :meth:`WheelModel.compiled`
    in the principal frame; ``hub_inverse`` (3, 3) the inverse of ``I - sum J g g^T``;
    ``external`` (3,) a constant external torque (N*m); ``orbit`` :meth:`OrbitModel.compiled`;
    ``commands`` (n,) clamped motor torques; ``applied`` (n,) receives the motor torques that act.
    """
    axes, spin, max_speed, ramp, coulomb, viscous, stiction = wheels
    qx, qy, qz, qw = y[0], y[1], y[2], y[3]
    w1, w2, w3 = y[4], y[5], y[6]
    i1, i2, i3 = moments[0], moments[1], moments[2]
    h1, h2, h3 = i1 * w1, i2 * w2, i3 * w3
    r1, r2, r3 = external[0], external[1], external[2]
    g1, g2, g3 = gravity_gradient_torque(orbit, moments, (qx, qy, qz, qw), t)
    r1 += g1
    r2 += g2
    r3 += g3
    n = spin.shape[0]
    for i in range(n):
        speed = y[7 + i]
        u = applied_motor_torque(commands[i], speed, max_speed[i], ramp[i])
        applied[i] = u
        net = u - friction_torque(coulomb[i], viscous[i], stiction[i], speed)
        dy[7 + i] = net  # the axial torque on the wheel, finished below
        h = spin[i] * speed
        h1 += h * axes[i, 0]
        h2 += h * axes[i, 1]
        h3 += h * axes[i, 2]
        r1 -= net * axes[i, 0]
        r2 -= net * axes[i, 1]
        r3 -= net * axes[i, 2]
    r1 -= w2 * h3 - w3 * h2
    r2 -= w3 * h1 - w1 * h3
    r3 -= w1 * h2 - w2 * h1
    a1 = hub_inverse[0, 0] * r1 + hub_inverse[0, 1] * r2 + hub_inverse[0, 2] * r3
    a2 = hub_inverse[1, 0] * r1 + hub_inverse[1, 1] * r2 + hub_inverse[1, 2] * r3
    a3 = hub_inverse[2, 0] * r1 + hub_inverse[2, 1] * r2 + hub_inverse[2, 2] * r3
    dq = quat.multiply((qx, qy, qz, qw), (w1, w2, w3, 0.0))
    dy[0], dy[1], dy[2], dy[3] = 0.5 * dq[0], 0.5 * dq[1], 0.5 * dq[2], 0.5 * dq[3]
    dy[4], dy[5], dy[6] = a1, a2, a3
    for i in range(n):
        dy[7 + i] = dy[7 + i] / spin[i] - (axes[i, 0] * a1 + axes[i, 1] * a2 + axes[i, 2] * a3)
    if y.shape[0] >= 7 + 2 * n:
        for i in range(n):
            dy[7 + n + i] = y[7 + i]


# ---------------------------------------------------------------------- invariants (numpy)


def hub_inertia(moments: Any, wheels: WheelModel) -> np.ndarray:
    """``I - sum J g g^T`` (3, 3), kg*m^2, with ``moments`` the principal moments of the wheels' frame."""
    spin = np.einsum("i,ij,ik->jk", wheels.spin_inertia, wheels.axes, wheels.axes)
    hub: np.ndarray = np.diag(np.asarray(moments, dtype=float)) - spin
    return hub


def total_momentum_body(moments: Any, wheels: WheelModel, omega: Any, speeds: Any) -> np.ndarray:
    """Eq. (1): ``I omega + sum J Omega g`` (kg*m^2/s), body frame; omega (..., 3), speeds (..., n)."""
    omega = np.asarray(omega, dtype=float)
    speeds = np.asarray(speeds, dtype=float)
    momentum: np.ndarray = np.asarray(moments, dtype=float) * omega + (speeds * wheels.spin_inertia) @ wheels.axes
    return momentum


def gyrostat_energy(moments: Any, wheels: WheelModel, omega: Any, speeds: Any) -> np.ndarray:
    """Eq. (6): kinetic energy (J) of body and wheels; omega (..., 3), speeds (..., n)."""
    omega = np.asarray(omega, dtype=float)
    speeds = np.asarray(speeds, dtype=float)
    hub = hub_inertia(moments, wheels)
    axial = omega @ wheels.axes.T + speeds
    body = 0.5 * np.einsum("...j,jk,...k->...", omega, hub, omega)
    energy: np.ndarray = body + 0.5 * np.sum(wheels.spin_inertia * axial**2, axis=-1)
    return energy
