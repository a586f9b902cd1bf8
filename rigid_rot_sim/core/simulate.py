"""``simulate``: integrate one rigid body over [0, t_end] and return its trajectory.

Frames: everything in and out is in the *user body frame* (the frame the inertia was
given in) and the world frame; the integration itself runs in the principal frame
(see :class:`rigid_rot_sim.core.dynamics.RigidBody`).

Time grid: ``n = floor(t_end / dt)`` full steps (a ratio within 1e-9 of an integer
counts as that integer), then, if ``t_end`` is not a multiple of ``dt``, one last
shorter step that lands on ``t_end`` exactly. Samples are taken at ``t = 0`` and after
every ``save_every``-th full step, ``t = k * save_every * dt``, and always at ``t_end``.

Example
-------
>>> traj = simulate((1.0, 2.0, 3.0), (1.0, 0.1, 0.5), t_end=1.0, dt=0.01, method="rk4")
>>> float(traj.t[-1]), traj.q.shape
(1.0, (101, 4))

Reaction wheels and the gravity gradient (``wheels=``, ``orbit=``) are run by the gyrostat
methods (:func:`simulate_gyrostat`, inputs checked by :mod:`rigid_rot_sim.core.simulate_wheels`); the
trajectory then carries the wheel speeds. Example: ``docs/spacecraft.md``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rigid_rot_sim.core import frames, validation
from rigid_rot_sim.core.dynamics import RigidBody, angular_momentum_world, kinetic_energy
from rigid_rot_sim.core.integrators import get_method
from rigid_rot_sim.core.steps import step_grid
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque, PolynomialTorque


@dataclass(frozen=True)
class Trajectory:
    """Sampled solution of :func:`simulate` (user body frame).

    Attributes
    ----------
    t : ndarray, shape (n,)
        Sample times, s.
    q : ndarray, shape (n, 4)
        Attitude, unit quaternion (x, y, z, w) rotating body -> world.
    omega : ndarray, shape (n, 3)
        Angular velocity, rad/s, body frame.
    method : str
        Integrator name.
    energy : ndarray, shape (n,)
        Rotational kinetic energy T = 1/2 omega . L, J (computed on first access); with wheels,
        body and wheels (eq. (6) of :mod:`rigid_rot_sim.core.wheels`).
    L_world : ndarray, shape (n, 3)
        Angular momentum in the world frame, kg*m^2/s (computed on first access); with wheels,
        the total ``R(q) (I omega + sum J Omega g)`` (eq. (1) of :mod:`rigid_rot_sim.core.wheels`).
    wheel_speeds : ndarray, shape (n, n_wheels), or None
        Wheel speeds Omega, rad/s relative to the body, in the order of the wheels (None without wheels;
        with wheels the trajectory is a :class:`GyrostatTrajectory`).
    """

    t: np.ndarray
    q: np.ndarray
    omega: np.ndarray
    method: str
    # the principal-frame samples and moments the invariants are computed from (on demand:
    # a caller in a loop that never reads them does not pay for them)
    principal_moments: np.ndarray = field(repr=False, compare=False)
    q_principal: np.ndarray = field(repr=False, compare=False)
    omega_principal: np.ndarray = field(repr=False, compare=False)
    # not a field: a plain trajectory pays nothing for it (GyrostatTrajectory's is one)
    wheel_speeds = None

    @functools.cached_property
    def energy(self) -> np.ndarray:
        """Rotational kinetic energy T = 1/2 omega . L, J, shape (n,)."""
        return np.asarray(kinetic_energy(self.principal_moments, self.omega_principal))

    @functools.cached_property
    def L_world(self) -> np.ndarray:
        """Angular momentum in the world frame, kg*m^2/s, shape (n, 3)."""
        return angular_momentum_world(self.principal_moments, self.q_principal, self.omega_principal)


@dataclass(frozen=True)
class GyrostatTrajectory(Trajectory):
    """A :class:`Trajectory` with reaction wheels: their speeds, and invariants of body + wheels.

    ``wheel_speeds`` (n, n_wheels): rad/s relative to the body, in the order of the wheels.
    """

    wheel_speeds: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # type: ignore[assignment]
    # the wheels (a core.wheels.WheelModel, axes in the principal frame) the invariants include
    wheels_principal: Any = field(default=None, repr=False, compare=False)

    @functools.cached_property
    def energy(self) -> np.ndarray:
        """Kinetic energy of body and wheels (eq. (6) of :mod:`rigid_rot_sim.core.wheels`), J, shape (n,)."""
        from rigid_rot_sim.core.wheels import gyrostat_energy

        return gyrostat_energy(self.principal_moments, self.wheels_principal, self.omega_principal, self.wheel_speeds)

    @functools.cached_property
    def L_world(self) -> np.ndarray:
        """Total angular momentum ``R(q) (I omega + sum J Omega g)`` (eq. (1) of core.wheels), world, kg*m^2/s."""
        from rigid_rot_sim.core.dynamics import body_to_world
        from rigid_rot_sim.core.wheels import total_momentum_body

        momentum = total_momentum_body(
            self.principal_moments, self.wheels_principal, self.omega_principal, self.wheel_speeds
        )
        return body_to_world(self.q_principal, momentum)


def principal_torque(body: RigidBody, torque: Any, is_principal: bool | None = None) -> Any:
    """A user body-frame torque (None, vector, torque model or callable) as a principal-frame model."""
    if torque is None:
        return None
    if not callable(torque):
        torque = ConstantTorque(validation.finite_vector("torque", torque))
    if body.is_principal if is_principal is None else is_principal:
        return torque
    to_principal = body.vector_to_principal
    if isinstance(torque, ConstantTorque):
        return ConstantTorque(to_principal(torque.value))
    if isinstance(torque, PolynomialTorque):
        return PolynomialTorque(to_principal(torque.coefficients))
    if isinstance(torque, GravityTorque):
        # the gravity torque is covariant: rotating the lever arm rotates the torque
        return GravityTorque(to_principal(torque.lever_arm), torque.weight)
    return _UserFrameTorque(torque, tuple(body.body_from_principal.tolist()))


@dataclass(frozen=True)
class _UserFrameTorque:
    """Calls a user body-frame ``torque(t, q_body, omega_body)`` from the principal frame."""

    torque: Any
    body_from_principal: tuple[float, float, float, float]

    def __call__(self, t: float, q: np.ndarray, omega: np.ndarray) -> np.ndarray:
        bp = self.body_from_principal
        pb = frames.principal_from_body(bp)
        q_body = frames.attitude_from_principal(q, pb)
        omega_body = frames.vector_from_principal(bp, omega)
        n_body = np.asarray(self.torque(t, np.array(q_body), np.array(omega_body)), dtype=float).reshape(3)
        return np.array(frames.vector_to_principal(pb, n_body.tolist()))


def simulate(
    inertia: Any,
    omega0: Any,
    t_end: float,
    dt: float,
    method: str,
    q0: Any = (0.0, 0.0, 0.0, 1.0),
    torque: Any = None,
    *,
    save_every: int = 1,
    wheels: Any = None,
    wheel_speeds0: Any = None,
    wheel_torque: Any = None,
    orbit: Any = None,
    **options: Any,
) -> Trajectory:
    """Integrate a rigid body's rotation from t = 0 to ``t_end``.

    Parameters
    ----------
    inertia : array_like, shape (3,) or (3, 3)
        Principal moments (I1, I2, I3) or the inertia tensor, kg*m^2, body frame.
    omega0 : array_like, shape (3,)
        Initial angular velocity, rad/s, body frame.
    t_end : float
        Final time, s (>= 0).
    dt : float
        Step, s (> 0); for adaptive methods, the output interval.
    method : str
        A name in ``rigid_rot_sim.core.integrators.METHODS``.
    q0 : array_like, shape (4,)
        Initial attitude (x, y, z, w), body -> world; normalised.
    torque : None, array_like (3,), or callable
        None (free body), a constant body-frame torque (N*m), or
        ``torque(t, q, omega) -> (3,)`` in N*m with q, omega and the result in the body frame.
    save_every : int
        Keep every ``save_every``-th step (>= 1).
    wheels : WheelModel, optional
        Reaction wheels (:func:`rigid_rot_sim.core.wheels.wheel_model`, axes in the body frame; the
        inertia includes them). Only the gyrostat methods (``gyrostat_rk4``, ``dopri5``) run them; ``torque``
        is then None or constant.
    wheel_speeds0 : array_like, shape (n_wheels,), optional
        Initial wheel speeds, rad/s relative to the body (default 0).
    wheel_torque : array_like (n_wheels,) or a schedule, optional
        Motor torques on the wheels (N*m, clamped to each wheel's max_torque as the run engine
        does): constant, or a schedule of ``(start_s, torques)`` pairs (or segments with ``start``
        and ``torques``, e.g. a scene's ``wheel_torque_schedule.segments``), each acting from the
        first step boundary at or after its start; zero before the first.
    orbit : OrbitModel, optional
        The circular orbit of the gravity-gradient torque (:func:`rigid_rot_sim.core.wheels.orbit_model`).
    **options
        Method options (e.g. ``order`` for ``splitting``, ``rtol``/``atol`` for ``dop853``).

    Raises
    ------
    ValueError
        Naming the argument: non-finite inputs, non-positive moments or moments breaking the
        triangle inequality, dt <= 0, t_end < 0, an unknown method or option.
    NonFiniteStateError
        A step produced a non-finite state (names the step and the time).
    """
    if wheels is not None or orbit is not None or wheel_speeds0 is not None or wheel_torque is not None:
        return simulate_gyrostat(
            inertia,
            omega0,
            t_end,
            dt,
            method,
            q0,
            torque,
            save_every=save_every,
            wheels=wheels,
            wheel_speeds0=wheel_speeds0,
            wheel_torque=wheel_torque,
            orbit=orbit,
            **options,
        )
    body, is_principal = rigid_body(inertia)
    omega0 = validation.finite_vector("omega0", omega0)
    q0 = attitude(q0)
    t_end = validation.nonnegative_scalar("t_end", t_end)
    dt = validation.positive_scalar("dt", dt)
    if type(save_every) is not int or save_every < 1:  # the common case skips the call
        save_every = checked_save_every(save_every)
    integrator_class = get_method(method)

    # the run engine's conversion of the attitude even for a principal body (scipy's composition renormalises: an
    # ulp), so both start from the same bits; w = 1 (the identity, the default) and a principal body's rates convert
    # exactly, without building Rotation objects
    q0_p = q0 if is_principal and q0[3] == 1.0 else body.attitude_to_principal(q0)
    omega0_p = omega0 if is_principal else body.vector_to_principal(omega0)
    integrator = integrator_class(
        body.principal_moments,
        dt,
        principal_torque(body, torque, is_principal),
        q0=q0_p,
        omega0=omega0_p,
        **options,
    )

    n_full, last = step_grid(t_end, dt)
    n_saves = n_full // save_every
    rest = n_full - n_saves * save_every
    tail = bool(rest) or last > 0.0
    n_rows = n_saves + 1 + tail
    t = np.arange(n_rows) * (save_every * dt)
    q_p = np.empty((n_rows, 4))
    omega_p = np.empty((n_rows, 3))
    q_p[0] = q0_p
    omega_p[0] = omega0_p
    if n_saves:
        q_p[1 : n_saves + 1], omega_p[1 : n_saves + 1] = integrator.advance_saving(n_saves, save_every)
    if rest:
        integrator.advance(rest)
    if last > 0.0:
        integrator.dt = last
        integrator.step()
    if tail:
        q_p[-1] = integrator.q
        omega_p[-1] = integrator.omega
    if n_full or tail:
        t[-1] = t_end  # the grid's last point is t_end up to rounding; report it exactly

    if is_principal:
        q_body, omega_body = q_p, omega_p
    else:
        q_body = body.attitude_from_principal(q_p)
        omega_body = body.vector_from_principal(omega_p)
    return Trajectory(
        t=t,
        q=q_body,
        omega=omega_body,
        method=method,
        principal_moments=body.principal_moments,
        q_principal=q_p,
        omega_principal=omega_p,
    )


def simulate_gyrostat(
    inertia: Any,
    omega0: Any,
    t_end: float,
    dt: float,
    method: str,
    q0: Any = (0.0, 0.0, 0.0, 1.0),
    torque: Any = None,
    *,
    save_every: int = 1,
    wheels: Any = None,
    wheel_speeds0: Any = None,
    wheel_torque: Any = None,
    orbit: Any = None,
    **options: Any,
) -> Trajectory:
    """:func:`~rigid_rot_sim.core.simulate.simulate` with reaction wheels and the gravity gradient.

    Parameters as :func:`~rigid_rot_sim.core.simulate.simulate`'s; ``method`` is ``rk4`` or
    ``dopri5`` (ValueError naming them otherwise), ``torque`` None or a constant body-frame
    vector (N*m). ``wheel_speeds0`` or ``wheel_torque`` need ``wheels``; a wheel speed beyond its
    max_speed is refused. Time grid and sampling as ``simulate``'s.

    Example: a wheel on the body's z axis driven by 0.05 N*m for 10 s; body and wheel trade momentum.

    >>> from rigid_rot_sim.core.wheels import wheel_model
    >>> rw = wheel_model(np.diag([10.0, 12.0, 15.0]), ["rw_z"], [[0, 0, 1]], [0.5], [0.1], [1000.0])
    >>> traj = simulate((10.0, 12.0, 15.0), (0.0, 0.0, 0.2), 10.0, 0.01, "gyrostat_rk4", wheels=rw,
    ...                 wheel_speeds0=[10.0], wheel_torque=[0.05])
    >>> traj.wheel_speeds.shape, round(float(traj.omega[-1, 2]), 9)    # (I3 - J) dw/dt = -u
    ((1001, 1), 0.165517241)
    >>> bool(np.allclose(traj.L_world, [0.0, 0.0, 15.0 * 0.2 + 0.5 * 10.0], rtol=0, atol=1e-12))
    True
    """
    # imported here: a caller of the plain path does not pay the gyrostat kernels' import (~20 ms)
    from rigid_rot_sim.core.integrators.gyrostat import get_gyrostat_method
    from rigid_rot_sim.core.simulate_wheels import checked_wheel_speeds, checked_wheels, wheel_torque_events
    from rigid_rot_sim.core.wheels import NO_ORBIT, OrbitModel

    body, is_principal = rigid_body(inertia)
    omega0 = validation.finite_vector("omega0", omega0)
    q0 = attitude(q0)
    t_end = validation.nonnegative_scalar("t_end", t_end)
    dt = validation.positive_scalar("dt", dt)
    save_every = checked_save_every(save_every)
    integrator_class = get_gyrostat_method(method)
    if orbit is not None and not isinstance(orbit, OrbitModel):
        raise ValueError(
            f"orbit must be an OrbitModel (rigid_rot_sim.core.wheels.orbit_model), got {type(orbit).__name__}"
        )
    if wheels is None and (wheel_speeds0 is not None or wheel_torque is not None):
        raise ValueError("wheel_speeds0 and wheel_torque need wheels")
    moments = body.principal_moments
    wheels_p = checked_wheels(wheels, moments, body)
    n_wheels = 0 if wheels is None else wheels.count
    speeds0 = checked_wheel_speeds(wheels, wheel_speeds0)
    events = [] if wheels is None else wheel_torque_events(wheels, wheel_torque, dt)

    # the run engine's conversion of the attitude even for a principal body (scipy's composition renormalises: an
    # ulp), so both start from the same bits; w = 1 (the identity, the default) and a principal body's rates convert
    # exactly, without building Rotation objects
    q0_p = q0 if is_principal and q0[3] == 1.0 else body.attitude_to_principal(q0)
    omega0_p = omega0 if is_principal else body.vector_to_principal(omega0)
    integrator = integrator_class(
        moments,
        dt,
        principal_torque(body, torque, is_principal),
        wheels=wheels_p,
        orbit=NO_ORBIT if orbit is None else orbit,
        q0=q0_p,
        omega0=omega0_p,
        wheel_speeds0=speeds0,
        **options,
    )

    n_full, last = step_grid(t_end, dt)
    n_saves = n_full // save_every
    tail = n_full > n_saves * save_every or last > 0.0
    n_rows = n_saves + 1 + tail
    t = np.arange(n_rows) * (save_every * dt)
    q_p = np.empty((n_rows, 4))
    omega_p = np.empty((n_rows, 3))
    speeds = np.empty((n_rows, n_wheels))
    q_p[0], omega_p[0], speeds[0] = q0_p, omega0_p, speeds0

    k, row, pending = 0, 1, 0
    while True:
        while pending < len(events) and events[pending][0] <= k:  # the commands due at this boundary
            integrator.set_wheel_commands(events[pending][1])
            pending += 1
        if k >= n_full:
            break
        stop = min(
            n_full,
            row * save_every if row <= n_saves else n_full,
            events[pending][0] if pending < len(events) else n_full,
        )
        integrator.advance(stop - k)
        k = stop
        if row <= n_saves and k == row * save_every:
            q_p[row], omega_p[row], speeds[row] = integrator.q, integrator.omega, integrator.wheel_speeds
            row += 1
    if last > 0.0:
        integrator.dt = last
        integrator.advance(1)
    if tail:
        q_p[-1], omega_p[-1], speeds[-1] = integrator.q, integrator.omega, integrator.wheel_speeds
    if n_full or tail:
        t[-1] = t_end

    if is_principal:
        q_body, omega_body = q_p, omega_p
    else:
        q_body = body.attitude_from_principal(q_p)
        omega_body = body.vector_from_principal(omega_p)
    if wheels_p is None:  # gravity gradient only: a rigid body's trajectory
        return Trajectory(
            t=t,
            q=q_body,
            omega=omega_body,
            method=method,
            principal_moments=moments,
            q_principal=q_p,
            omega_principal=omega_p,
        )
    return GyrostatTrajectory(
        t=t,
        q=q_body,
        omega=omega_body,
        method=method,
        principal_moments=moments,
        q_principal=q_p,
        omega_principal=omega_p,
        wheel_speeds=speeds,
        wheels_principal=wheels_p,
    )


def checked_save_every(save_every: Any) -> int:
    """``save_every`` as an int >= 1 (ValueError otherwise)."""
    if isinstance(save_every, bool) or not isinstance(save_every, (int, np.integer)) or save_every < 1:
        raise ValueError(f"save_every must be an integer >= 1, got {save_every!r}")
    return int(save_every)


def rigid_body(inertia: Any) -> tuple[RigidBody, bool]:
    """``(RigidBody.from_inertia(inertia), body.is_principal)``, cached per inertia value (arrays read-only)."""
    try:
        values = np.asarray(inertia, dtype=float)
    except (TypeError, ValueError):
        values = None
    if values is None or values.shape not in ((3,), (3, 3)):
        body = RigidBody.from_inertia(inertia, "inertia")  # raises the documented error
        return body, body.is_principal
    return _cached_body(values.shape, values.tobytes())


@functools.lru_cache(maxsize=256)
def _cached_body(shape: tuple[int, ...], data: bytes) -> tuple[RigidBody, bool]:
    body = RigidBody.from_inertia(np.frombuffer(data).reshape(shape), "inertia")
    for array in (body.principal_moments, body.body_from_principal, body.inertia_tensor):
        array.setflags(write=False)
    return body, body.is_principal


_IDENTITY_ATTITUDE = (0.0, 0.0, 0.0, 1.0)


def attitude(q0: Any) -> np.ndarray:
    """``validation.quaternion("q0", q0)``, with the identity (the default) looked up.

    A q0 already of unit length to rounding (|q|^2 within 4 eps of 1: a scene's, normalised when it was read) is
    kept as given, as the run engine keeps a scene's: the conversion to the principal frame normalises it once more
    (scipy's rounding) in both, so they start from the same bits (normalising twice may move an ulp).
    """
    if type(q0) is tuple and q0 == _IDENTITY_ATTITUDE:
        return np.array(_IDENTITY_ATTITUDE)
    q = validation.quaternion("q0", q0)
    given = np.asarray(q0, dtype=float)
    return given if abs(float(given @ given) - 1.0) <= _UNIT_TOLERANCE else q


#: |q|^2 of a quaternion normalised in double is 1 to within a few ulps.
_UNIT_TOLERANCE = 4.0 * float(np.finfo(float).eps)
