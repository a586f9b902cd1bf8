"""The step API shared by every integrator (modelled on scipy.integrate's OdeSolver).

Rules for whoever implements a method:

* Subclass :class:`Integrator`, set the class attributes ``name`` (the registry key),
  ``orders`` (the nominal orders of accuracy it can be built with, its default first; a
  method with several takes an ``order`` option and sets ``self._order``), ``stability``
  (:data:`Stability`) and ``fixed_step`` (False for adaptive methods, which still land
  exactly on every multiple of ``dt``). An instance's :attr:`~Integrator.order` is its own.
* Implement one of two things. Either ``_step_impl(self) -> None``: advance ``self.t``,
  ``self.q`` and ``self.omega`` by ``self.dt`` (the base class's :meth:`advance` loops
  it, counts the steps in ``n_steps``, checks each new state and restores the last good
  one on failure); or :meth:`advance` itself, a faster loop that keeps the same
  per-step semantics: it counts the steps it takes, stops at the first bad one with the
  state left at the last good step, and raises. :meth:`step` is ``advance(1)``. State lives
  in the *principal* body frame: ``q`` is a unit quaternion (x, y, z, w) rotating
  principal -> world, ``omega`` (rad/s) and the torque (N*m, from ``self.torque(t, q, omega)``
  or ``None`` for a free body) are in principal coordinates. ``self.moments`` holds (I1, I2, I3) in kg*m^2.
* Accept method-specific options as keyword arguments in ``__init__`` and reject
  unknown ones with a ValueError naming them.
* Never return NaN: a step whose new state is not finite raises
  :class:`NonFiniteStateError` naming the step number and the time.
* Every failure of a step is a :class:`NonFiniteStateError`, whatever the method: an
  ArithmeticError or ValueError raised on the way (``math domain error`` from ``sin(inf)``,
  OverflowError, ZeroDivisionError) is re-raised as one, chained to the original. This is
  done here, for :meth:`step`, :meth:`advance` and :meth:`advance_saving` of every
  subclass (:meth:`Integrator.__init_subclass__` wraps its overrides), so it holds for
  compiled kernels too.
* ``self.torque`` may be replaced between steps (the node holds topic commands
  piecewise constant); methods that cache anything about it must re-read it each step.
  Likewise ``self.dt`` may be changed between steps (``simulate`` shortens the last one).
* Change the state only through :meth:`set_state` (methods may keep it in a faster form).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Any, ClassVar, Literal

import numpy as np

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.arrays import ArrayLike
from rigid_rot_sim.core.torque import TorqueFunction


class NonFiniteStateError(FloatingPointError):
    """Raised when a step produced a non-finite state, or failed on the way to one."""


class UnsupportedTorqueError(ValueError):
    """The torque set on the integrator is one the method cannot take: a usage error, raised as is."""


#: What a failing step may raise besides NonFiniteStateError (math domain error, overflow).
_STEP_ERRORS = (ArithmeticError, ValueError)


def _failing_as_non_finite(method: Callable[..., Any]) -> Callable[..., Any]:
    """``method`` with every step error turned into NonFiniteStateError (the documented failure)."""

    @functools.wraps(method)
    def wrapper(self: Any, *args: Any, **kwargs: Any) -> Any:
        try:
            return method(self, *args, **kwargs)
        except (NonFiniteStateError, UnsupportedTorqueError):
            raise
        except _STEP_ERRORS as exc:
            raise NonFiniteStateError(
                f"{self.name or type(self).__name__}: step {self.n_steps + 1}, t = {self.t:.9g} s failed: "
                f"{type(exc).__name__}: {exc}"
            ) from exc

    wrapper.fails_as_non_finite = True  # type: ignore[attr-defined]
    return wrapper


_STEPPING_METHODS = ("step", "advance", "advance_saving")


#: How a method's step is bounded on a free body: ``explicit`` (stable only below a limit of
#: the gyroscopic frequency times dt), ``unconditional`` (bounded at any dt), ``adaptive``
#: (error control picks its own substeps within dt), ``exact`` (the exact flow).
Stability = Literal["explicit", "unconditional", "adaptive", "exact"]


class Integrator:
    """Advance the attitude and angular velocity of a rigid body by steps of ``dt``.

    Parameters
    ----------
    moments : array_like, shape (3,)
        Principal moments of inertia (I1, I2, I3), kg*m^2.
    dt : float
        Step length, s (> 0).
    torque : callable or None
        ``torque(t, q, omega) -> (3,)`` in N*m, principal body frame; None for a free body.
    t0 : float
        Initial time, s.
    q0 : array_like, shape (4,)
        Initial attitude, principal -> world, scalar-last; normalised on entry.
    omega0 : array_like, shape (3,)
        Initial angular velocity, rad/s, principal body frame.
    """

    name: ClassVar[str] = ""
    #: Nominal orders of accuracy the method can be built with, the default first (0: exact).
    orders: ClassVar[tuple[int, ...]] = (0,)
    stability: ClassVar[Stability]
    fixed_step: ClassVar[bool] = True
    #: This instance's order when the method takes an ``order`` option (else ``orders[0]``).
    _order: int | None = None

    @property
    def order(self) -> int:
        """Nominal order of accuracy of this instance (0: no truncation error)."""
        return self.orders[0] if self._order is None else self._order

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        for attribute in _STEPPING_METHODS:
            method = cls.__dict__.get(attribute)
            if callable(method) and not getattr(method, "fails_as_non_finite", False):
                setattr(cls, attribute, _failing_as_non_finite(method))

    def __init__(
        self,
        moments: ArrayLike,
        dt: float,
        torque: TorqueFunction | None = None,
        *,
        t0: float = 0.0,
        q0: ArrayLike = (0.0, 0.0, 0.0, 1.0),
        omega0: ArrayLike = (0.0, 0.0, 0.0),
        **options: Any,
    ) -> None:
        if options:
            raise ValueError(f"{self.name or type(self).__name__}: unknown option(s) {sorted(options)}")
        self.moments = np.asarray(moments, dtype=float).reshape(3)
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be finite and > 0, got {dt}")
        self.dt = float(dt)
        self.torque = torque
        self.n_steps = 0
        self.set_state(t0, q0, omega0)

    def set_state(self, t: float, q: ArrayLike, omega: ArrayLike) -> None:
        """Replace the state (q is normalised; a zero or non-finite q is a ValueError)."""
        q = np.asarray(q, dtype=float).reshape(4)
        omega = np.asarray(omega, dtype=float).reshape(3)
        x, y, z, w = q.tolist()
        norm_squared = x * x + y * y + z * z + w * w  # |q|^2 as quat.normalize forms it
        if not (math.isfinite(norm_squared) and norm_squared > 0.0):
            raise ValueError(f"q must be a finite non-zero quaternion, got {q}")
        if not all(map(math.isfinite, omega.tolist())):
            raise ValueError(f"omega must be finite, got {omega}")
        if not math.isfinite(t):
            raise ValueError(f"t must be finite, got {t}")
        self.t = float(t)
        # the kernels' normalisation (the batch core normalises its bodies the same way)
        self.q = np.array(quat.normalize((x, y, z, w)))
        self.omega = omega
        self._on_state_change()

    def _on_state_change(self) -> None:
        """Hook for methods that cache quantities derived from the state."""

    def step(self) -> None:
        """Advance the state by one step of ``dt`` (on failure the state is the one before it)."""
        self.advance(1)

    def advance(self, n: int) -> None:
        """Take ``n`` steps of ``dt``: the state of n calls of :meth:`step` (for adaptive
        methods, up to their tolerance, as they may step past the intermediate outputs)."""
        for _ in range(n):
            self._checked_step()

    def _checked_step(self) -> None:
        """One step of :meth:`_step_impl`, counted and checked; the state before it on failure."""
        before = (self.t, self.q.copy(), self.omega.copy())
        try:
            self._step_impl()
        except _STEP_ERRORS:
            self.set_state(*before)  # also for UnsupportedTorqueError: nothing was stepped
            raise
        self.n_steps += 1
        if not (np.all(np.isfinite(self.q)) and np.all(np.isfinite(self.omega))):
            raise NonFiniteStateError(
                f"{self.name}: non-finite state at step {self.n_steps}, t = {self.t:.9g} s "
                f"(q = {self.q}, omega = {self.omega})"
            )

    def advance_saving(self, n_saves: int, save_every: int) -> tuple[np.ndarray, np.ndarray]:
        """Take ``n_saves * save_every`` steps; return q (n_saves, 4) and omega (n_saves, 3)
        after every ``save_every``-th step (principal frame). Methods may override it."""
        q = np.empty((n_saves, 4))
        omega = np.empty((n_saves, 3))
        for k in range(n_saves):
            self.advance(save_every)
            q[k] = self.q
            omega[k] = self.omega
        return q, omega

    def _step_impl(self) -> None:
        raise NotImplementedError


for _attribute in _STEPPING_METHODS:
    setattr(Integrator, _attribute, _failing_as_non_finite(getattr(Integrator, _attribute)))
