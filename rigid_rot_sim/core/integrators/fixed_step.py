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

The loop over the kernels lives in ``integrators/kernels.py``, which imports every method
module (for its kernel), and so this one: it installs itself here when imported
(:func:`install_kernel_loop`; importing ``rigid_rot_sim.core.integrators`` imports it), so
that imports run one way only: method modules -> this module, kernels -> method modules.
The status codes are in ``status.py`` and the torque evaluation (:func:`~rigid_rot_sim.core.torque.torque_at`,
:func:`~rigid_rot_sim.core.torque.float_torque`) in ``core/torque.py``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError
from rigid_rot_sim.core.integrators.status import OK, State
from rigid_rot_sim.core.torque import TORQUE_CALLABLE, TorqueData, torque_data

_NO_SAVES = np.empty((0, 7))


@dataclass(frozen=True)
class KernelLoop:
    """The loop over the kernels: ``ids`` maps a ``kernel_name`` to what the loops dispatch on.

    ``compiled`` and ``interpreted`` are ``advance_steps(method, t_anchor, k0, dt, n, state,
    moments, torque, save_every, saved) -> (state, steps done, status, bad state)``, compiled
    (data torques) and plain Python (callable torques).
    """

    ids: dict[str, int]
    compiled: Callable[..., tuple[Any, ...]]
    interpreted: Callable[..., tuple[Any, ...]]


_LOOP: list[KernelLoop] = []


def install_kernel_loop(loop: KernelLoop) -> None:
    """Run the fixed-step methods with ``loop`` (called once, by ``integrators.kernels``)."""
    _LOOP[:] = [loop]


def _kernel_loop() -> KernelLoop:
    if not _LOOP:
        raise RuntimeError("no kernel loop installed: import rigid_rot_sim.core.integrators (it imports kernels)")
    return _LOOP[0]


class FixedStepIntegrator(Integrator):
    """Base of the fixed-step methods: subclasses set ``kernel_name`` (a key of
    ``integrators.kernels.KERNEL_IDS``) and, optionally, ``error_types`` mapping a kernel
    status to (exception class, message)."""

    kernel_name: str  # per class, or per instance for methods with an ``order`` option
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
        loop = _kernel_loop()
        if self.dt != self._anchor_dt:  # dt changed: time restarts from here
            self._anchor_t, self._anchor_k, self._anchor_dt = self.t, 0, self.dt
        saved = np.empty((n // save_every, 7)) if save_every > 0 else _NO_SAVES
        if n <= 0:
            return saved
        data = self._torque_data()
        method = loop.ids[self.kernel_name]
        start_k = self._anchor_k
        if data.kind != TORQUE_CALLABLE:
            state, done, status, bad = loop.compiled(
                method,
                self._anchor_t,
                start_k,
                self.dt,
                n,
                self._state,
                self._moments,
                self._torque_compiled,
                save_every,
                saved,
            )
        else:
            # interpreted: a step at a time, so that an exception from the callable leaves
            # the state at the last good step
            state, done, status, bad = self._state, 0, OK, self._state
            row = np.empty((1, 7))
            try:
                while done < n and status == OK:
                    state, one, status, bad = loop.interpreted(
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
