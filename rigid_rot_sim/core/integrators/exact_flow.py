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

from rigid_rot_sim.core.exact import TorqueFreeSolution, _solution, torque_free_flow
from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError, UnsupportedTorqueError
from rigid_rot_sim.core.integrators.fixed_step import FixedStepIntegrator, float_torque
from rigid_rot_sim.core.integrators.splitting import COMPOSITIONS, _adjoint_kick

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
    order = 0  # no truncation error: exact up to rounding at any dt
    fixed_step = True

    def __init__(self, moments: Any, dt: float, torque: Any = None, **kwargs: Any) -> None:
        _refuse_torque(torque)
        super().__init__(moments, dt, torque, **kwargs)

    def _on_state_change(self) -> None:
        self._solution: TorqueFreeSolution | None = None

    def _anchor(self) -> TorqueFreeSolution:
        # Re-read the torque every step: the node may replace it between steps.
        _refuse_torque(self.torque)
        if self._solution is None:
            self._solution = _solution(self.moments, self.omega, self.q, self.t)
            self._anchor_t, self._anchor_dt, self._anchor_k = self.t, self.dt, 0
        elif self.dt != self._anchor_dt:
            self._anchor_t, self._anchor_dt, self._anchor_k = self.t, self.dt, 0
        return self._solution

    def step(self) -> None:
        """Advance the state by one step of ``dt``."""
        self.advance(1)

    def _step_impl(self) -> None:
        self._advance_by(1)
        self.n_steps -= 1  # base.step() counts this step

    def _advance_by(self, steps: int) -> None:
        """One evaluation, on floats, at ``steps`` steps past the current state."""
        solution = self._anchor()
        k = self._anchor_k + steps
        t = self._anchor_t + k * self._anchor_dt
        q, omega = solution._flow.evaluate_scalar(t - solution.t0)
        if not math.isfinite(sum(q) + sum(omega)):
            raise NonFiniteStateError(
                f"{self.name}: non-finite state at step {self.n_steps + steps}, t = {t:.9g} s (q = {q}, omega = {omega})"
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


def _make_kernel(coefficients: tuple[float, ...]):
    def kernel(t, state, h, moments, torque, attitude_torque):
        q = state[:4]
        w1, w2, w3 = state[4:]
        i1, i2, i3 = moments
        moments_array = np.array(moments)
        if torque is None:
            q_new, w_new = torque_free_flow(moments_array, q, (w1, w2, w3), h)
            return (*q_new, *w_new)
        n1, n2, n3 = torque(t, q, (w1, w2, w3))
        for gamma in coefficients:
            tau = gamma * h
            hk = 0.5 * tau
            w1 += hk * n1 / i1
            w2 += hk * n2 / i2
            w3 += hk * n3 / i3
            if not math.isfinite(w1 + w2 + w3):
                # a non-finite torque: hand the bad state back for the step's NaN check
                return (*q, w1, w2, w3)
            q, (w1, w2, w3) = torque_free_flow(moments_array, q, (w1, w2, w3), tau)
            t += tau
            w1, w2, w3, n1, n2, n3 = _adjoint_kick(torque, t, q, w1, w2, w3, hk, i1, i2, i3)
        qx, qy, qz, qw = q
        inv = 1.0 / math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        return qx * inv, qy * inv, qz * inv, qw * inv, w1, w2, w3

    return kernel


_KERNELS = {order: _make_kernel(COMPOSITIONS[order]) for order in EXACT_SPLIT_ORDERS}


class ExactSplit(FixedStepIntegrator):
    """Exact free flow with torque kicks (Celledoni et al. 2008), order 2 or 4.

    Options
    -------
    order : {2, 4}
        2: Strang kick-flow-kick; 4: Yoshida's triple jump of it (default 2).
    """

    name = "exact_split"
    order = 2

    def __init__(self, *args: Any, order: int = 2, **kwargs: Any) -> None:
        if order not in EXACT_SPLIT_ORDERS:
            raise ValueError(f"exact_split: order must be one of {list(EXACT_SPLIT_ORDERS)}, got {order!r}")
        self.order = order
        self.kernel = _KERNELS[order]
        super().__init__(*args, **kwargs)
