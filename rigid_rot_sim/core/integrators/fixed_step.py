"""Fixed-step methods whose step is a pure function on plain Python floats.

Per-step Python overhead dominates this problem: a step written on floats costs a few
microseconds, the same on 3- and 4-element numpy arrays tens. A method here is a
*kernel*

    kernel(t, state, dt, moments, torque, attitude_torque) -> new_state

with ``state = (qx, qy, qz, qw, w1, w2, w3)`` (principal frame, q principal -> world),
``moments = (I1, I2, I3)``, and ``torque`` either None (free body) or a float torque
function from :func:`float_torque`. ``attitude_torque`` is False when the torque is known
not to depend on the attitude, so kernels may skip computing stage attitudes.
:class:`FixedStepIntegrator` wraps a kernel in the step API of ``base.py`` and runs
:meth:`advance` as a tight loop that converts to numpy only at the end.
"""

from __future__ import annotations

import math
from typing import Any, Callable, ClassVar

import numpy as np

from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError
from rigid_rot_sim.core.quaternion import rotate_inverse
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque, PolynomialTorque

State = tuple[float, float, float, float, float, float, float]
FloatTorque = Callable[[float, tuple, tuple], tuple]


def float_torque(torque: Any) -> tuple[FloatTorque | None, bool]:
    """Adapt a torque model to ``f(t, q, omega) -> (N1, N2, N3)`` on float tuples.

    Returns ``(f, attitude_dependent)``; ``f`` is None for a free body. The structured
    models of ``core/torque.py`` (constant, polynomial in time, gravity) are evaluated on
    floats (no numpy per call); any other callable is called with small numpy arrays, as
    the torque contract says, and counts as depending on the attitude.
    """
    if torque is None:
        return None, False
    if isinstance(torque, ConstantTorque):
        value = tuple(torque.value.tolist())
        if not any(value):
            return None, False
        return (lambda t, q, w: value), False
    if isinstance(torque, PolynomialTorque):
        rows = [tuple(row) for row in torque.coefficients[::-1].tolist()]

        def polynomial(t: float, q: tuple, w: tuple) -> tuple:
            n1, n2, n3 = rows[0]
            for c1, c2, c3 in rows[1:]:  # Horner, highest power first
                n1, n2, n3 = n1 * t + c1, n2 * t + c2, n3 * t + c3
            return n1, n2, n3

        return polynomial, False
    if isinstance(torque, GravityTorque):
        a1, a2, a3 = torque.lever_arm.tolist()
        weight = float(torque.weight)

        def gravity(t: float, q: tuple, w: tuple) -> tuple:
            # lever_arm x (R^T (-weight e_z)), as GravityTorque.__call__ (tests compare the two)
            u1, u2, u3 = rotate_inverse(q, (0.0, 0.0, -weight))
            return a2 * u3 - a3 * u2, a3 * u1 - a1 * u3, a1 * u2 - a2 * u1

        return gravity, True

    def call(t: float, q: tuple, w: tuple) -> tuple:
        n1, n2, n3 = np.asarray(torque(t, np.array(q), np.array(w)), dtype=float).reshape(3).tolist()
        return n1, n2, n3

    return call, True


class FixedStepIntegrator(Integrator):
    """Base of the fixed-step methods: subclasses set ``kernel`` (a staticmethod)."""

    kernel: ClassVar[Callable[..., State]]

    def _on_state_change(self) -> None:
        self._state: State = tuple(self.q.tolist() + self.omega.tolist())
        self._moments = tuple(self.moments.tolist())
        self._torque_source: Any = object()  # forces float_torque() on the next run

    def _float_torque(self) -> tuple[FloatTorque | None, bool]:
        if self.torque is not self._torque_source:
            self._torque_source = self.torque
            self._torque_cache = float_torque(self.torque)
        return self._torque_cache

    def step(self) -> None:
        """Advance the state by one step of ``dt``."""
        self.advance(1)

    def _step_impl(self) -> None:
        self.advance(1)
        self.n_steps -= 1  # base.step() counts this step

    def advance(self, n: int) -> None:
        """Take ``n`` steps of ``dt`` on floats; raise NonFiniteStateError at the first bad step.

        On any error the state is left at the last good step.
        """
        self._run(n, 0)

    def advance_saving(self, n_saves: int, save_every: int) -> tuple[np.ndarray, np.ndarray]:
        """Take ``n_saves * save_every`` steps, saving (q, omega) after every ``save_every``-th."""
        saved = self._run(n_saves * save_every, save_every)
        states = np.array(saved, dtype=float).reshape(n_saves, 7)
        return states[:, :4], states[:, 4:]

    def _run(self, n: int, save_every: int) -> list:
        kernel = self.kernel
        torque, attitude_torque = self._float_torque()
        moments = self._moments
        dt = self.dt
        t0 = self.t
        state = self._state
        isfinite = math.isfinite
        saved = []
        countdown = save_every
        for k in range(n):
            try:
                new = kernel(t0 + k * dt, state, dt, moments, torque, attitude_torque)
            except NonFiniteStateError as error:
                self._commit(state, t0, k)
                raise type(error)(f"{self.name}: step {self.n_steps + 1}, t = {t0 + (k + 1) * dt:.9g} s: {error}") from error
            except BaseException:
                self._commit(state, t0, k)
                raise
            # NaN and inf propagate into the sum; a finite overflow of the sum is re-checked.
            if not isfinite(sum(new)) and not all(map(isfinite, new)):
                self._commit(state, t0, k)
                raise NonFiniteStateError(
                    f"{self.name}: non-finite state at step {self.n_steps + 1}, t = {t0 + (k + 1) * dt:.9g} s "
                    f"(q = {new[:4]}, omega = {new[4:]})"
                )
            state = new
            if save_every:
                countdown -= 1
                if not countdown:
                    saved.append(state)
                    countdown = save_every
        self._commit(state, t0, n)
        return saved

    def _commit(self, state: State, t0: float, steps: int) -> None:
        if steps:
            self._state = state
            self.q = np.array(state[:4])
            self.omega = np.array(state[4:])
            self.t = t0 + steps * self.dt
            self.n_steps += steps
