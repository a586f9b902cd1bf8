"""``dop853``: scipy's adaptive explicit Runge-Kutta method of order 8 (Dormand-Prince).

One ``scipy.integrate.DOP853`` solver is carried across steps with an open end
(``t_bound = inf``); it takes its own steps, and every multiple of ``dt`` is read from
its dense output (its interpolant has the method's accuracy), so ``dt`` only sets where
the state is reported. The solver restarts from the current state when the state is
replaced or ``self.torque`` changes.

The state is ``(q, omega)`` with ``dq/dt = 1/2 q (x) (omega, 0)``; the quaternion norm
drifts by about the tolerance inside the solver and the reported q is normalised.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.integrate import DOP853

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core import validation
from rigid_rot_sim.core.dynamics import euler_rhs_components
from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError
from rigid_rot_sim.core.torque import float_torque

_ZERO = (0.0, 0.0, 0.0)


class DOP853Integrator(Integrator):
    """scipy DOP853 landing on every multiple of ``dt`` through its dense output.

    Options
    -------
    rtol, atol : float
        Relative and absolute tolerances passed to scipy (defaults 1e-10 and 1e-12;
        the state mixes a unit quaternion and omega in rad/s).
    max_step : float
        Largest internal step, s (default: unbounded).
    """

    name = "dop853"
    orders = (8,)
    stability = "adaptive"
    fixed_step = False

    def __init__(
        self, *args: Any, rtol: float = 1e-10, atol: float = 1e-12, max_step: float = math.inf, **kwargs: Any
    ) -> None:
        self.rtol = validation.positive_scalar("rtol", rtol)
        self.atol = validation.positive_scalar("atol", atol)
        if not (isinstance(max_step, (int, float)) and max_step > 0):
            raise ValueError(f"max_step must be > 0, got {max_step!r}")
        self.max_step = float(max_step)
        self._solver: DOP853 | None = None
        super().__init__(*args, **kwargs)

    def _on_state_change(self) -> None:
        self._solver = None

    def _rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        qx, qy, qz, qw, w1, w2, w3 = y.tolist()
        n1, n2, n3 = _ZERO if self._torque is None else self._torque(t, (qx, qy, qz, qw), (w1, w2, w3))
        i1, i2, i3 = self._moments
        dq = quat.multiply((qx, qy, qz, qw), (w1, w2, w3, 0.0))
        return np.array(
            (
                0.5 * dq[0],
                0.5 * dq[1],
                0.5 * dq[2],
                0.5 * dq[3],
                *euler_rhs_components(i1, i2, i3, w1, w2, w3, n1, n2, n3),
            )
        )

    def _start(self) -> DOP853:
        self._torque_source = self.torque
        self._torque, _ = float_torque(self.torque)
        self._moments = tuple(self.moments.tolist())
        y0 = np.concatenate((self.q, self.omega))
        return DOP853(self._rhs, self.t, y0, math.inf, rtol=self.rtol, atol=self.atol, max_step=self.max_step)

    def advance(self, n: int) -> None:
        """Take ``n`` steps of ``dt``: one pass of the solver to the last of them."""
        if n > 0:
            self._advance_to(self.t + n * self.dt)
            self.n_steps += n
            if not (np.all(np.isfinite(self.q)) and np.all(np.isfinite(self.omega))):
                raise NonFiniteStateError(
                    f"{self.name}: non-finite state at step {self.n_steps}, t = {self.t:.9g} s "
                    f"(q = {self.q}, omega = {self.omega})"
                )

    def _advance_to(self, target: float) -> None:
        solver = self._solver
        if solver is None or self.torque is not self._torque_source:
            solver = self._solver = self._start()
            self._dense = None
        while solver.t < target:
            message = solver.step()
            if solver.status == "failed" or not np.all(np.isfinite(solver.y)):
                self._solver = None
                step = self.n_steps + max(1, math.ceil((solver.t - self.t) / self.dt))
                raise NonFiniteStateError(
                    f"{self.name}: non-finite state or solver failure at step {step}, t = {solver.t:.9g} s: {message}"
                )
            self._dense = None
        if solver.t == target:
            y = solver.y
        else:
            # one interpolant per solver step, however many multiples of dt it covers
            if self._dense is None:
                self._dense = solver.dense_output()
            y = self._dense(target)
        q = y[:4]
        self.q = q / math.sqrt(float(q @ q))
        self.omega = y[4:].copy()
        self.t = target
