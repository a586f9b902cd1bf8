"""``exact`` and ``exact_split``: the exact torque-free flow as an integrator.

``exact`` advances the state by the elliptic-function solution of ``core/exact.py``: no
truncation error at any dt, so its error is rounding only (its ``order`` is 0: the error
does not depend on the step). It is for torque-free bodies; a torque is refused with a
ValueError pointing to ``exact_split``. The solution object built from a state is reused
for every later step (evaluated at the absolute time) until the state is replaced through
``set_state``, so a step costs one evaluation, and n steps taken by :meth:`advance` cost
one evaluation too.

``exact_split`` is the splitting of Celledoni, Fasso, Safstrom and Zanna (BIT 48, 2008):
the Hamiltonian is split into the free rigid body, flowed exactly, and the torque, applied
as kicks of omega with the attitude held. The basic step is the symmetric product

    kick(h/2) o free(h) o adjoint kick(h/2)           (Strang, order 2)

with the same kick pair as ``splitting`` (explicit kick, then the adjoint kick solved by
fixed-point iteration; both exact for torques that do not depend on omega, e.g. gravity
and constant body torques, which are then exact kicks). Order 4 is Yoshida's triple jump
of it (option ``order``). Time advances in the free flow, so time-dependent torques keep
the symmetry.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba.extending import register_jitable

from rigid_rot_sim.core.arrays import ArrayLike
from rigid_rot_sim.core.exact import TorqueFreeSolution, free_flow, solution_from_state
from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError, UnsupportedTorqueError
from rigid_rot_sim.core.integrators.fixed_step import FixedStepIntegrator
from rigid_rot_sim.core.integrators.splitting import KICK_ERROR, State7, Vector, adjoint_kick, kick
from rigid_rot_sim.core.integrators.status import KICK_FAILED, OK
from rigid_rot_sim.core.torque import float_torque, has_torque, torque_at

EXACT_SPLIT_ORDERS = (2, 4)


def _refuse_torque(torque: Any) -> None:
    if float_torque(torque)[0] is not None:
        raise UnsupportedTorqueError(
            "exact: torque must be None or zero (the exact flow is torque-free); "
            "use exact_split for a body under torque"
        )


class ExactFlow(Integrator):
    """The exact torque-free flow (Jacobi elliptic functions and Carlson's R_J); no options."""

    name = "exact"
    orders = (0,)  # no truncation error: exact up to rounding at any dt
    stability = "exact"
    fixed_step = True

    def __init__(self, moments: ArrayLike, dt: float, torque: Any = None, **kwargs: Any) -> None:
        _refuse_torque(torque)
        super().__init__(moments, dt, torque, **kwargs)

    def _on_state_change(self) -> None:
        self._solution: TorqueFreeSolution | None = None

    def _anchor(self) -> TorqueFreeSolution:
        # Re-read the torque every step: the node may replace it between steps.
        _refuse_torque(self.torque)
        if self._solution is None:
            self._solution = solution_from_state(self.moments, self.omega, self.q, self.t)
            self._anchor_t, self._anchor_dt, self._anchor_k = self.t, self.dt, 0
        elif self.dt != self._anchor_dt:
            self._anchor_t, self._anchor_dt, self._anchor_k = self.t, self.dt, 0
        return self._solution

    def _advance_by(self, steps: int) -> None:
        """One evaluation, on floats, at ``steps`` steps past the current state."""
        solution = self._anchor()
        k = self._anchor_k + steps
        t = self._anchor_t + k * self._anchor_dt
        q, omega = solution.state_floats(t)
        if not math.isfinite(sum(q) + sum(omega)):
            raise NonFiniteStateError(
                f"{self.name}: non-finite state at step {self.n_steps + steps}, t = {t:.9g} s "
                f"(q = {q}, omega = {omega})"
            )
        self.q, self.omega, self.t, self._anchor_k = np.array(q), np.array(omega), t, k
        self.n_steps += steps

    def _advance_saving(self, n_saves: int, save_every: int) -> tuple[np.ndarray, np.ndarray]:
        """Evaluate the solution after every save_every-th of n_saves * save_every steps at once."""
        solution = self._anchor()
        k = self._anchor_k + save_every * np.arange(1, n_saves + 1)
        q, omega = solution.state(self._anchor_t + k * self._anchor_dt)
        good = np.isfinite(q).all(axis=1) & np.isfinite(omega).all(axis=1)
        if not good.all():
            first = int(np.argmin(good))
            raise NonFiniteStateError(
                f"{self.name}: non-finite state at step {self.n_steps + (first + 1) * save_every}, "
                f"t = {self._anchor_t + k[first] * self._anchor_dt:.9g} s (q = {q[first]}, omega = {omega[first]})"
            )
        self.q, self.omega = q[-1], omega[-1]
        self.t = self._anchor_t + int(k[-1]) * self._anchor_dt
        self._anchor_k = int(k[-1])
        self.n_steps += n_saves * save_every
        return q, omega

    def advance(self, n: int) -> None:
        """Take n steps in one evaluation (the same state as n calls of :meth:`step`)."""
        if n > 0:
            self._advance_by(n)

    def advance_saving(self, n_saves: int, save_every: int) -> tuple[np.ndarray, np.ndarray]:
        """The states after every save_every-th step, all evaluated in one vectorised call."""
        if n_saves <= 0:
            return np.empty((0, 4)), np.empty((0, 3))
        return self._advance_saving(n_saves, save_every)


@register_jitable
def exact_split_step(
    t: float, state: State7, h: float, moments: Vector, torque: Any, coefficients: tuple[float, ...]
) -> tuple[State7, int]:
    """One step of the composition ``coefficients`` of kick(h/2) o free(h) o adjoint kick(h/2)."""
    qx, qy, qz, qw, w1, w2, w3 = state
    q = (qx, qy, qz, qw)
    i1, i2, i3 = moments
    if not has_torque(torque):
        q, w = free_flow(moments, q, (w1, w2, w3), h)
        return (q[0], q[1], q[2], q[3], w[0], w[1], w[2]), OK
    n1, n2, n3 = torque_at(torque, t, q, (w1, w2, w3))
    for gamma in coefficients:
        tau = gamma * h
        hk = 0.5 * tau
        w1, w2, w3 = kick(w1, w2, w3, hk, n1, n2, n3, i1, i2, i3)
        if not math.isfinite(w1 + w2 + w3):
            # a non-finite torque: hand the bad state back for the step's NaN check
            return (q[0], q[1], q[2], q[3], w1, w2, w3), OK
        q, w = free_flow(moments, q, (w1, w2, w3), tau)
        w1, w2, w3 = w
        t += tau
        w1, w2, w3, n1, n2, n3, converged = adjoint_kick(torque, t, q, w1, w2, w3, hk, i1, i2, i3)
        if not converged:
            return state, KICK_FAILED
    qx, qy, qz, qw = q
    inv = 1.0 / math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    return (qx * inv, qy * inv, qz * inv, qw * inv, w1, w2, w3), OK


class ExactSplit(FixedStepIntegrator):
    """Exact free flow with torque kicks (Celledoni et al. 2008), order 2 or 4.

    Options
    -------
    order : {2, 4}
        2: Strang kick-flow-kick; 4: Yoshida's triple jump of it (default 2).
    """

    name = "exact_split"
    orders = EXACT_SPLIT_ORDERS
    stability = "unconditional"
    error_types = {KICK_FAILED: (NonFiniteStateError, KICK_ERROR)}

    def __init__(self, *args: Any, order: int = 2, **kwargs: Any) -> None:
        if order not in self.orders:
            raise ValueError(f"exact_split: order must be one of {list(self.orders)}, got {order!r}")
        self._order = order
        self.kernel_name = f"exact_split{order}"
        super().__init__(*args, **kwargs)
