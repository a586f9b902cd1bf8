"""Fixed-step methods: one compiled kernel per method, run by one compiled loop.

A method here is a *kernel*

    kernel(t, state, dt, moments, torque) -> (new_state, status)

with ``state = (qx, qy, qz, qw, w1, w2, w3)`` (principal frame, q principal -> world),
``moments = (I1, I2, I3)``, ``torque`` the tuple of a :class:`~rigid_rot_sim.core.torque.TorqueData`
(constant, polynomial and gravity torques are data the kernel evaluates) and ``status``
:data:`OK` or the code of a failure the kernel detected (a Newton solve, a torque kick).
Kernels are written on floats and tuples and decorated with ``register_jitable``: numba
compiles them (``@njit(cache=True)``, no fastmath, so bits are reproducible run to run)
into the loop of ``integrators/kernels.py``, and the same source runs interpreted when the
torque is an arbitrary Python callable (the slower path: the callable is called with
small numpy arrays, as the torque contract says). There is no second copy of a formula.

:class:`FixedStepIntegrator` wraps a kernel in the step API of ``base.py``. The time of
step k is ``t_anchor + k * dt`` from the last ``set_state`` (or change of dt), never
accumulated, so advancing k steps in one call gives the same bits as k single steps
(the node steps in chunks whose lengths depend on publish rates and the wall clock).
"""

from __future__ import annotations

from typing import Any, Callable, ClassVar

import numpy as np
from numba.core.extending import overload
from numba.extending import register_jitable

from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError
from rigid_rot_sim.core.torque import (
    TORQUE_CALLABLE,
    TORQUE_GRAVITY,
    TORQUE_NONE,
    TorqueData,
    evaluate_torque_data,
    torque_data,
)

State = tuple[float, float, float, float, float, float, float]
FloatTorque = Callable[[float, tuple, tuple], tuple]

#: Kernel status codes.
OK, NON_FINITE, NEWTON_FAILED, KICK_FAILED = 0, 1, 2, 3


@register_jitable
def has_torque(torque):
    """False for a free body (no torque, or an all-zero constant)."""
    return torque[0] != TORQUE_NONE


@register_jitable
def attitude_dependent(torque):
    """True when the torque may depend on the attitude (gravity, or any callable)."""
    return torque[0] >= TORQUE_GRAVITY


def torque_at(torque: Any, t: float, q: tuple, w: tuple) -> tuple[float, float, float]:
    """The torque (N1, N2, N3) at (t, q, omega) for a kernel: data, or a Python callable.

    Compiled kernels get the data-only version below (numba ``overload``).
    """
    if torque[0] == TORQUE_CALLABLE:
        n1, n2, n3 = np.asarray(torque[3](t, np.array(q), np.array(w)), dtype=float).reshape(3).tolist()
        return n1, n2, n3
    return evaluate_torque_data(torque[0], torque[1], torque[2], t, q, w)


@overload(torque_at)
def _torque_at_compiled(torque, t, q, w):
    def impl(torque, t, q, w):
        return evaluate_torque_data(torque[0], torque[1], torque[2], t, q, w)

    return impl


def float_torque(torque: Any) -> tuple[FloatTorque | None, bool]:
    """Adapt a torque model to ``f(t, q, omega) -> (N1, N2, N3)`` on float tuples.

    Returns ``(f, attitude_dependent)``; ``f`` is None for a free body. The structured
    models of ``core/torque.py`` are evaluated by the kernels' formula
    (:func:`~rigid_rot_sim.core.torque.evaluate_torque_data`); any other callable is
    called with small numpy arrays and counts as depending on the attitude.
    """
    data = torque_data(torque)
    if data.kind == TORQUE_NONE:
        return None, False

    def f(t: float, q: tuple, w: tuple) -> tuple:
        return torque_at(data, t, tuple(q), tuple(w))

    return f, data.kind >= TORQUE_GRAVITY


_NO_SAVES = np.empty((0, 7))
_KERNELS_MODULE: list = []


def _kernels() -> Any:
    """``integrators.kernels`` (imported on first use: it imports every kernel module)."""
    if not _KERNELS_MODULE:
        from rigid_rot_sim.core.integrators import kernels

        _KERNELS_MODULE.append(kernels)
    return _KERNELS_MODULE[0]


class FixedStepIntegrator(Integrator):
    """Base of the fixed-step methods: subclasses set ``kernel_name`` (a key of
    ``integrators.kernels.KERNEL_IDS``) and, optionally, ``error_types`` mapping a kernel
    status to (exception class, message)."""

    kernel_name: ClassVar[str]
    error_types: ClassVar[dict[int, tuple[type, str]]] = {}

    def _on_state_change(self) -> None:
        self._state: State = tuple(self.q.tolist() + self.omega.tolist())
        self._moments = tuple(self.moments.tolist())
        self._torque_source: Any = object()  # forces torque_data() on the next run
        self._anchor_t, self._anchor_k, self._anchor_dt = self.t, 0, self.dt

    def _torque_data(self) -> TorqueData:
        if self.torque is not self._torque_source:
            self._torque_source = self.torque
            self._torque_cache = torque_data(self.torque)
            self._torque_compiled = self._torque_cache.compiled
        return self._torque_cache

    def step(self) -> None:
        """Advance the state by one step of ``dt``."""
        self.advance(1)

    def _step_impl(self) -> None:
        self.advance(1)
        self.n_steps -= 1  # base.step() counts this step

    def advance(self, n: int) -> None:
        """Take ``n`` steps of ``dt``; raise NonFiniteStateError at the first bad step.

        On any error the state is left at the last good step.
        """
        self._run(int(n), 0)

    def advance_saving(self, n_saves: int, save_every: int) -> tuple[np.ndarray, np.ndarray]:
        """Take ``n_saves * save_every`` steps, saving (q, omega) after every ``save_every``-th."""
        saved = self._run(n_saves * save_every, save_every)
        return saved[:, :4], saved[:, 4:]

    def _run(self, n: int, save_every: int) -> np.ndarray:
        kernels = _kernels()
        if self.dt != self._anchor_dt:  # dt changed: time restarts from here
            self._anchor_t, self._anchor_k, self._anchor_dt = self.t, 0, self.dt
        saved = np.empty((n // save_every, 7)) if save_every > 0 else _NO_SAVES
        if n <= 0:
            return saved
        data = self._torque_data()
        method = kernels.KERNEL_IDS[self.kernel_name]
        start_k = self._anchor_k
        if data.kind != TORQUE_CALLABLE:
            state, done, status, bad = kernels.advance_compiled(
                method, self._anchor_t, start_k, self.dt, n, self._state, self._moments, self._torque_compiled, save_every,
                saved,
            )
        else:
            # interpreted: a step at a time, so that an exception from the callable leaves
            # the state at the last good step
            state, done, status, bad = self._state, 0, OK, self._state
            row = np.empty((1, 7))
            try:
                while done < n and status == OK:
                    state, one, status, bad = kernels.advance_steps(
                        method, self._anchor_t, start_k + done, self.dt, 1, state, self._moments, data, 1, row
                    )
                    done += one
                    if one and save_every and done % save_every == 0:
                        saved[done // save_every - 1] = row[0]
            except BaseException:
                self._commit(state, done)
                raise
        self._commit(state, done)
        if status != OK:
            t_bad = self._anchor_t + (self._anchor_k + 1) * self.dt
            where = f"{self.name}: step {self.n_steps + 1}, t = {t_bad:.9g} s"
            if status in self.error_types:
                error, what = self.error_types[status]
                raise error(f"{where}: {what}")
            raise NonFiniteStateError(
                f"{self.name}: non-finite state at step {self.n_steps + 1}, t = {t_bad:.9g} s "
                f"(q = {bad[:4]}, omega = {bad[4:]})"
            )
        return saved

    def _commit(self, state: State, steps: int) -> None:
        if steps:
            self._state = state
            self.q = np.array(state[:4])
            self.omega = np.array(state[4:])
            self._anchor_k += steps
            self.t = self._anchor_t + self._anchor_k * self.dt
            self.n_steps += steps

