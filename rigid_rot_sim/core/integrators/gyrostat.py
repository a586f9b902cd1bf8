"""Integrators of a gyrostat: a body with reaction wheels, under gravity gradient and a body torque.

The state is ``y = (q, omega, Omega, theta)``: q (x, y, z, w) principal -> world, omega (rad/s,
principal frame), the n wheel speeds Omega (rad/s, relative to the body) and the n wheel
angles theta (rad, relative to the body, unwrapped: continuous, never reduced to [-pi, pi]);
the equations are those of :mod:`rigid_rot_sim.core.wheels` (eq. (8): dtheta/dt = Omega). Two methods, both compiled
(:func:`rigid_rot_sim.core.jit.compiled`, no fastmath: the same bits run to run):

* ``rk4``: the classical RK4 on y, the quaternion normalised after each step (order 4);
  step k is taken at ``t_anchor + k dt``, so ``advance(k)`` is k single steps, bit for bit;
* ``dopri5``: Dormand-Prince 5(4) with its error control (``rtol``, ``atol``) and the
  4th-order continuous extension of Dormand and Prince (scipy's RK45 coefficients) to land
  on every multiple of dt. Its own steps do not depend on where it reports: the solver
  (its time, state, next step size and last step's stages) is carried from call to call,
  so ``advance(k)`` equals k calls of ``advance(1)`` bit for bit. It restarts from the
  reported state when the state, the body torque or the wheel commands are replaced. Its
  error control runs over (q, omega, Omega) only: the angles drive nothing, and (as CVODES
  does for quadratures by default) leaving them out keeps the body's steps exactly those
  of a run without them, however large the unwrapped angles grow.

What may change between steps: ``torque`` (None or a :class:`~rigid_rot_sim.core.torque.ConstantTorque`,
principal frame: the commanded body torque) and :meth:`GyrostatIntegrator.set_wheel_commands`
(motor torques, N*m, clamped to each wheel's max_torque by the caller). A step that ends in
a non-finite state, or an adaptive step size that underflows, raises
:class:`~rigid_rot_sim.core.integrators.base.NonFiniteStateError` with the state left at the
last good step.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from rigid_rot_sim.core import validation
from rigid_rot_sim.core.arrays import ArrayLike
from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError
from rigid_rot_sim.core.integrators.status import NON_FINITE, OK
from rigid_rot_sim.core.jit import compiled
from rigid_rot_sim.core.torque import ConstantTorque
from rigid_rot_sim.core.wheels import NO_ORBIT, OrbitModel, WheelModel, gyrostat_rhs, hub_inertia

__all__ = ["GyrostatIntegrator", "GyrostatRK4", "GyrostatDopri5", "GYROSTAT_METHODS", "get_gyrostat_method"]

#: A dopri5 step size that fell below this fraction of |t| (or of dt at t = 0).
STEP_UNDERFLOW = 2
_MAX_STEPS_PER_OUTPUT = 1_000_000


@compiled
def rk4_advance(
    t_anchor: float,
    k0: int,
    dt: float,
    n: int,
    y: np.ndarray,
    moments: np.ndarray,
    wheels: tuple[np.ndarray, ...],
    hub_inverse: np.ndarray,
    external: np.ndarray,
    orbit: np.ndarray,
    commands: np.ndarray,
    applied: np.ndarray,
) -> tuple[int, int]:
    """Steps k0 .. k0 + n - 1 of RK4 from ``y`` (updated in place): (steps done, status).

    ``applied`` receives the motor torques (N*m) that acted at the start of the last step.
    """
    m = y.shape[0]
    k1, k2, k3, k4 = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    stage, new = np.empty(m), np.empty(m)
    scratch = np.empty(applied.shape[0])
    for k in range(n):
        t = t_anchor + (k0 + k) * dt
        h = dt
        gyrostat_rhs(t, y, moments, wheels, hub_inverse, external, orbit, commands, k1, scratch)
        for i in range(m):
            stage[i] = y[i] + 0.5 * h * k1[i]
        gyrostat_rhs(t + 0.5 * h, stage, moments, wheels, hub_inverse, external, orbit, commands, k2, applied)
        for i in range(m):
            stage[i] = y[i] + 0.5 * h * k2[i]
        gyrostat_rhs(t + 0.5 * h, stage, moments, wheels, hub_inverse, external, orbit, commands, k3, applied)
        for i in range(m):
            stage[i] = y[i] + h * k3[i]
        gyrostat_rhs(t + h, stage, moments, wheels, hub_inverse, external, orbit, commands, k4, applied)
        for i in range(m):
            new[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i])
        norm = math.sqrt(new[0] * new[0] + new[1] * new[1] + new[2] * new[2] + new[3] * new[3])
        finite = math.isfinite(norm) and norm > 0.0
        for i in range(4):
            new[i] = new[i] / norm
        for i in range(m):
            finite = finite and math.isfinite(new[i])
        if not finite:
            return k, NON_FINITE
        for i in range(m):
            y[i] = new[i]
        for i in range(applied.shape[0]):
            applied[i] = scratch[i]
    return n, OK


# Dormand-Prince 5(4): nodes, stages, 5th-order weights, error weights and the dense-output
# polynomial of scipy's RK45 (Dormand & Prince 1980; Shampine 1986 continuous extension).
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0])
_A = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0],
        [1 / 5, 0.0, 0.0, 0.0, 0.0],
        [3 / 40, 9 / 40, 0.0, 0.0, 0.0],
        [44 / 45, -56 / 15, 32 / 9, 0.0, 0.0],
        [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0.0],
        [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
    ]
)
_B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84])
_E = np.array([-71 / 57600, 0.0, 71 / 16695, -71 / 1920, 17253 / 339200, -22 / 525, 1 / 40])
_P = np.array(
    [
        [1.0, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
        [0.0, 0.0, 0.0, 0.0],
        [0.0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
        [0.0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
        [0.0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
        [0.0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
        [0.0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
    ]
)

#: The kernels' leading arguments (anchor t, anchor step, dt, steps, state) and trailing ones (moments, wheel
#: data, hub inverse, external torque, orbit data, wheel commands, motor torques out), in their order.
_Grid = tuple[float, int, float, int, np.ndarray]
_Model = tuple[np.ndarray, tuple[np.ndarray, ...], np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]

# solver[...] slots carried between calls
_T, _H, _T_OLD, _H_OLD, _FSAL = range(5)


@compiled
def dopri5_advance(
    t_anchor: float,
    k0: int,
    dt: float,
    n: int,
    y_out: np.ndarray,
    solver: np.ndarray,
    y_int: np.ndarray,
    y_old: np.ndarray,
    stages: np.ndarray,
    rtol: float,
    atol: float,
    moments: np.ndarray,
    wheels: tuple[np.ndarray, ...],
    hub_inverse: np.ndarray,
    external: np.ndarray,
    orbit: np.ndarray,
    commands: np.ndarray,
    applied: np.ndarray,
) -> tuple[int, int]:
    """Report steps k0 + 1 .. k0 + n (times ``t_anchor + k dt``) into ``y_out``: (reports done, status).

    ``solver`` (5,) = (t, h, t_old, h_old, fsal valid), ``y_int`` the solver's state at t,
    ``y_old`` and ``stages`` (7, m) the last accepted step's start and stages (the dense
    output; ``stages[6]`` is f(t, y_int), the next step's first stage); all updated in place.
    On failure y_out holds the last good report.
    """
    m = y_out.shape[0]
    controlled = min(m, 7 + applied.shape[0])  # (q, omega, Omega): the angles are not error-controlled
    stage = np.empty(m)
    new = np.empty(m)
    ks = np.empty((7, m))
    for j in range(n):
        target = t_anchor + (k0 + j + 1) * dt
        count = 0
        while solver[_T] < target:
            count += 1
            t = solver[_T]
            h = solver[_H]
            if count > _MAX_STEPS_PER_OUTPUT or not (h > 1e-12 * max(abs(t), dt)):
                return j, STEP_UNDERFLOW
            if solver[_FSAL] == 0.0:
                gyrostat_rhs(t, y_int, moments, wheels, hub_inverse, external, orbit, commands, stages[6], applied)
                solver[_FSAL] = 1.0
            for i in range(m):
                ks[0, i] = stages[6, i]
            for s in range(1, 6):
                for i in range(m):
                    acc = 0.0
                    for r in range(s):
                        acc += _A[s, r] * ks[r, i]
                    stage[i] = y_int[i] + h * acc
                gyrostat_rhs(
                    t + _C[s] * h, stage, moments, wheels, hub_inverse, external, orbit, commands, ks[s], applied
                )
            for i in range(m):
                acc = 0.0
                for r in range(6):
                    acc += _B[r] * ks[r, i]
                new[i] = y_int[i] + h * acc
            gyrostat_rhs(t + h, new, moments, wheels, hub_inverse, external, orbit, commands, ks[6], applied)
            err = 0.0
            finite = True
            for i in range(m):
                finite = finite and math.isfinite(new[i]) and math.isfinite(ks[6, i])
                if i >= controlled:
                    continue
                e = 0.0
                for r in range(7):
                    e += _E[r] * ks[r, i]
                x = h * e / (atol + rtol * max(abs(y_int[i]), abs(new[i])))
                err += x * x
            err = math.sqrt(err / controlled)
            if not (finite and math.isfinite(err)):
                solver[_H] = 0.2 * h  # retry smaller: a step size underflow ends it
                continue
            if err >= 1.0:
                solver[_H] = h * max(0.2, 0.9 * err**-0.2)
                continue
            for i in range(m):
                y_old[i] = y_int[i]
                y_int[i] = new[i]
                for r in range(7):
                    stages[r, i] = ks[r, i]
            solver[_T_OLD] = t
            solver[_H_OLD] = h
            solver[_T] = t + h
            solver[_H] = h * (10.0 if err == 0.0 else min(10.0, 0.9 * err**-0.2))
        if solver[_T] == target:
            for i in range(m):
                stage[i] = y_int[i]
        else:
            theta = (target - solver[_T_OLD]) / solver[_H_OLD]
            h_old = solver[_H_OLD]
            for i in range(m):
                acc = 0.0
                for r in range(7):
                    horner = _P[r, 0] + theta * (_P[r, 1] + theta * (_P[r, 2] + theta * _P[r, 3]))
                    acc += stages[r, i] * theta * horner
                stage[i] = y_old[i] + h_old * acc
        norm = math.sqrt(stage[0] ** 2 + stage[1] ** 2 + stage[2] ** 2 + stage[3] ** 2)
        ok = math.isfinite(norm) and norm > 0.0
        for i in range(m):
            ok = ok and math.isfinite(stage[i])
        if not ok:
            return j, NON_FINITE
        for i in range(m):
            y_out[i] = stage[i] / norm if i < 4 else stage[i]
    return n, OK


class GyrostatIntegrator(Integrator):
    """Base of the gyrostat methods: the step API of ``base.py`` plus the wheel speeds.

    Parameters (besides those of :class:`~rigid_rot_sim.core.integrators.base.Integrator`)
    ----------
    wheels : WheelModel or None
        The wheels, axes in the principal frame of ``moments`` (None: no wheels).
    orbit : OrbitModel
        The orbit of the gravity-gradient torque (:data:`~rigid_rot_sim.core.wheels.NO_ORBIT`: none).
    wheel_speeds0 : array_like, shape (n,)
        Initial wheel speeds, rad/s relative to the body.
    wheel_angles0 : array_like, shape (n,)
        Initial wheel angles, rad relative to the body (default 0).
    """

    fixed_step: ClassVar[bool] = True
    #: The body torque the method last saw (set by each method before the base initialiser runs).
    _torque_seen: Any

    def __init__(
        self,
        moments: ArrayLike,
        dt: float,
        torque: Any = None,
        *,
        wheels: WheelModel | None = None,
        orbit: OrbitModel = NO_ORBIT,
        wheel_speeds0: ArrayLike | None = None,
        wheel_angles0: ArrayLike | None = None,
        t0: float = 0.0,
        q0: ArrayLike = (0.0, 0.0, 0.0, 1.0),
        omega0: ArrayLike = (0.0, 0.0, 0.0),
        **options: Any,
    ) -> None:
        self.wheels = wheels if wheels is not None else WheelModel((), np.zeros((0, 3)), *([np.zeros(0)] * 6))
        self.orbit = orbit
        n = self.wheels.count
        self.wheel_speeds = np.zeros(n) if wheel_speeds0 is None else np.array(wheel_speeds0, dtype=float).reshape(n)
        self.wheel_angles = np.zeros(n) if wheel_angles0 is None else np.array(wheel_angles0, dtype=float).reshape(n)
        self.wheel_commands = np.zeros(n)
        self._wheel_data = self.wheels.compiled()
        self._orbit_data = orbit.compiled()
        moments_array = np.asarray(moments, dtype=float).reshape(3)
        self._hub_inverse = np.linalg.inv(hub_inertia(moments_array, self.wheels))
        self._check_torque(torque)
        super().__init__(moments, dt, torque, t0=t0, q0=q0, omega0=omega0, **options)

    @staticmethod
    def _check_torque(torque: Any) -> None:
        if torque is not None and not isinstance(torque, ConstantTorque):
            raise ValueError(f"a gyrostat method takes no torque or a ConstantTorque, got {type(torque).__name__}")

    # ------------------------------------------------------------------ state

    def set_state(
        self,
        t: float,
        q: ArrayLike,
        omega: ArrayLike,
        wheel_speeds: ArrayLike | None = None,
        wheel_angles: ArrayLike | None = None,
    ) -> None:
        """Replace the state; ``wheel_speeds`` (rad/s) and ``wheel_angles`` (rad) None keep the wheels' own."""
        values = {}
        for name, given in (("speeds", wheel_speeds), ("angles", wheel_angles)):
            if given is not None:
                values[name] = np.array(given, dtype=float).reshape(self.wheels.count)
                if not np.all(np.isfinite(values[name])):
                    raise ValueError(f"wheel {name} must be finite, got {values[name]}")
        self.wheel_speeds = values.get("speeds", self.wheel_speeds)
        self.wheel_angles = values.get("angles", self.wheel_angles)
        super().set_state(t, q, omega)

    def _on_state_change(self) -> None:
        self._y = np.concatenate((self.q, self.omega, self.wheel_speeds, self.wheel_angles))
        self._anchor_t, self._anchor_k, self._anchor_dt = self.t, 0, self.dt
        self._restart()

    def _restart(self) -> None:
        """Hook: the state or the inputs were replaced."""

    def set_wheel_commands(self, torques: ArrayLike) -> None:
        """Hold the motor torques ``torques`` (N*m, one per wheel, already clamped) from now on."""
        commands = np.array(torques, dtype=float).reshape(self.wheels.count)
        if not np.all(np.isfinite(commands)):
            raise ValueError(f"wheel torques must be finite, got {commands}")
        if not np.array_equal(commands, self.wheel_commands):
            self.wheel_commands = commands
            self._restart()

    def applied_wheel_torques(self) -> np.ndarray:
        """The motor torques (N*m) acting in the current state (after speed saturation)."""
        from rigid_rot_sim.core.wheels import applied_motor_torque

        ramp = self._wheel_data[3]
        return np.array(
            [
                applied_motor_torque(float(u), float(w), float(limit), float(r))
                for u, w, limit, r in zip(
                    self.wheel_commands, self.wheel_speeds, self.wheels.max_speed, ramp, strict=True
                )
            ]
        )

    def _external(self) -> np.ndarray:
        torque = self.torque
        self._check_torque(torque)
        if torque is not self._torque_seen:
            self._torque_seen = torque
            self._restart()
        if torque is None:
            return np.zeros(3)
        assert isinstance(torque, ConstantTorque)  # _check_torque refused anything else
        return np.ascontiguousarray(torque.value, dtype=float)

    def _commit(self, steps: int) -> None:
        if steps:
            y = self._y
            self.q = y[:4].copy()
            self.omega = y[4:7].copy()
            n = self.wheels.count
            self.wheel_speeds = y[7 : 7 + n].copy()
            self.wheel_angles = y[7 + n :].copy()
            self._anchor_k += steps
            self.t = self._anchor_t + self._anchor_k * self.dt
            self.n_steps += steps

    def _start_run(self) -> np.ndarray:
        """Before a run of steps: re-anchor the step grid after a dt change; the external torque (N*m)."""
        if self.dt != self._anchor_dt:
            self._anchor_t, self._anchor_k, self._anchor_dt = self.t, 0, self.dt
        return self._external()

    def advance(self, n: int) -> None:
        """Take ``n`` steps of ``dt`` (NonFiniteStateError at the first bad one, state at the last good one)."""
        n = int(n)
        if n <= 0:
            return
        external = self._start_run()
        grid = (self._anchor_t, self._anchor_k, self.dt, n, self._y)
        applied = np.zeros(self.wheels.count)
        model = (self.moments, self._wheel_data, self._hub_inverse, external, self._orbit_data, self.wheel_commands)
        done, status = self._run(grid, (*model, applied))
        self._commit(done)
        if status != OK:
            self._restart()  # from the last good state
            self._fail(status)

    def _run(self, grid: _Grid, model: _Model) -> tuple[int, int]:
        """The method's compiled loop: (steps done, status).

        ``grid`` (anchor t, anchor step, dt, n steps, state ``self._y``, updated in place) and ``model``
        (moments, wheel data, hub inverse, external torque, orbit data, wheel commands, and the array that
        receives the motor torques acting at the end) are the leading and trailing arguments of the kernels.
        """
        raise NotImplementedError

    def _fail(self, status: int) -> None:
        t_bad = self._anchor_t + (self._anchor_k + 1) * self.dt
        what = "step size underflow" if status == STEP_UNDERFLOW else "non-finite state"
        raise NonFiniteStateError(f"{self.name}: {what} at step {self.n_steps + 1}, t = {t_bad:.9g} s")


class GyrostatRK4(GyrostatIntegrator):
    """Classical RK4 on (q, omega, Omega), compiled; order 4."""

    name = "gyrostat_rk4"
    order = 4

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._torque_seen: Any = None
        super().__init__(*args, **kwargs)

    def _run(self, grid: _Grid, model: _Model) -> tuple[int, int]:
        done, status = rk4_advance(*(*grid, *model))
        return int(done), int(status)


class GyrostatDopri5(GyrostatIntegrator):
    """Dormand-Prince 5(4), compiled, landing on every multiple of dt by its dense output.

    Options
    -------
    rtol, atol : float
        Relative and absolute tolerances of the error control (defaults 1e-10 and 1e-12).
    """

    name = "dopri5"
    order = 5
    fixed_step = False

    def __init__(self, *args: Any, rtol: float = 1e-10, atol: float = 1e-12, **kwargs: Any) -> None:
        self.rtol = validation.positive_scalar("rtol", rtol)
        self.atol = validation.positive_scalar("atol", atol)
        self._torque_seen = None
        self._solver = np.zeros(5)
        super().__init__(*args, **kwargs)

    def _restart(self) -> None:
        m = 7 + 2 * self.wheels.count
        h = self._solver[_H] if self._solver[_H] > 0.0 else self.dt
        self._solver = np.array([self.t, h, self.t, 0.0, 0.0])
        self._y_int = np.concatenate((self.q, self.omega, self.wheel_speeds, self.wheel_angles))
        self._y_old = self._y_int.copy()
        self._stages = np.zeros((7, m))

    def _run(self, grid: _Grid, model: _Model) -> tuple[int, int]:
        """Report ``n`` multiples of dt by the dense output; a failure restarts from the last good report."""
        solver = (self._solver, self._y_int, self._y_old, self._stages, self.rtol, self.atol)
        done, status = dopri5_advance(*(*grid, *solver, *model))
        return int(done), int(status)


#: The methods that can run a scene with wheels or gravity gradient, by name.
GYROSTAT_METHODS: dict[str, type[GyrostatIntegrator]] = {"gyrostat_rk4": GyrostatRK4, "dopri5": GyrostatDopri5}


def get_gyrostat_method(name: str) -> type[GyrostatIntegrator]:
    """The gyrostat method registered as ``name``; ValueError listing the valid names."""
    try:
        return GYROSTAT_METHODS[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"integrator {name!r} cannot run wheels or gravity gradient; "
            f"valid methods: {', '.join(sorted(GYROSTAT_METHODS))}"
        ) from None
