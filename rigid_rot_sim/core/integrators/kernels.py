"""The compiled loop over the fixed-step kernels (see ``fixed_step.py`` for the contract).

One entry point, :func:`advance_compiled` (:func:`rigid_rot_sim.core.jit.compiled`), runs any
registered kernel for n steps: time of step k ``t_anchor + k * dt``, a non-finite check
after every step, the state saved after every ``save_every``-th. It is compiled once per
machine (``make setup`` does it; see ``core/jit.py`` for where the cache lives) and
reused by every later process. :func:`advance_steps` is
the same loop uncompiled, for torques given as Python callables. Importing this module
installs both in ``fixed_step.py`` (:func:`~.fixed_step.install_kernel_loop`), which runs them.
"""

from __future__ import annotations

import math
from typing import Any

from numba.extending import register_jitable

from rigid_rot_sim.core.arrays import FloatArray
from rigid_rot_sim.core.integrators.exact_flow import exact_split_step
from rigid_rot_sim.core.integrators.explicit import euler_step, rk4_step
from rigid_rot_sim.core.integrators.fixed_step import KernelLoop, install_kernel_loop
from rigid_rot_sim.core.integrators.implicit import implicit_midpoint_step
from rigid_rot_sim.core.integrators.lie import cf4_step
from rigid_rot_sim.core.integrators.splitting import COMPOSITIONS, splitting_step
from rigid_rot_sim.core.integrators.status import NON_FINITE, OK, State, StepResult
from rigid_rot_sim.core.jit import compiled
from rigid_rot_sim.core.quaternion import Vector

EULER, RK4, LIE_RK4, IMPLICIT_MIDPOINT, SPLITTING2, SPLITTING4, SPLITTING6, EXACT_SPLIT2, EXACT_SPLIT4 = range(9)

#: ``FixedStepIntegrator.kernel_name`` -> the id the compiled loop dispatches on.
KERNEL_IDS = {
    "euler": EULER,
    "rk4": RK4,
    "lie_rk4": LIE_RK4,
    "implicit_midpoint": IMPLICIT_MIDPOINT,
    "splitting2": SPLITTING2,
    "splitting4": SPLITTING4,
    "splitting6": SPLITTING6,
    "exact_split2": EXACT_SPLIT2,
    "exact_split4": EXACT_SPLIT4,
}

_SPLITTING2 = COMPOSITIONS[2]
_SPLITTING4 = COMPOSITIONS[4]
_SPLITTING6 = COMPOSITIONS[6]


@register_jitable
def step_kernel(method: int, t: float, state: State, dt: float, moments: Vector, torque: Any) -> StepResult:
    """One step of the kernel ``method`` (an id of KERNEL_IDS): (new_state, status).

    ``torque`` is a :class:`~rigid_rot_sim.core.torque.TorqueData` when run by Python and its plain
    tuple ``TorqueData.compiled`` when compiled (the kernels index it, so both work).
    """
    if method == RK4:
        return rk4_step(t, state, dt, moments, torque)
    if method == LIE_RK4:
        return cf4_step(t, state, dt, moments, torque)
    if method == IMPLICIT_MIDPOINT:
        return implicit_midpoint_step(t, state, dt, moments, torque)
    if method == SPLITTING2:
        return splitting_step(t, state, dt, moments, torque, _SPLITTING2)
    if method == SPLITTING4:
        return splitting_step(t, state, dt, moments, torque, _SPLITTING4)
    if method == SPLITTING6:
        return splitting_step(t, state, dt, moments, torque, _SPLITTING6)
    if method == EXACT_SPLIT2:
        return exact_split_step(t, state, dt, moments, torque, _SPLITTING2)
    if method == EXACT_SPLIT4:
        return exact_split_step(t, state, dt, moments, torque, _SPLITTING4)
    return euler_step(t, state, dt, moments, torque)


@register_jitable
def advance_steps(
    method: int,
    t_anchor: float,
    k0: int,
    dt: float,
    n: int,
    state: State,
    moments: Vector,
    torque: Any,
    save_every: int,
    saved: FloatArray,
) -> tuple[State, int, int, State]:
    """Steps k0 .. k0 + n - 1 from ``state``: returns (state, steps done, status, bad state).

    Stops at the first step whose kernel reports a failure or whose state is not finite,
    leaving ``state`` at the last good step and that step's result in ``bad state``.
    """
    countdown = save_every
    row = 0
    for k in range(n):
        new, status = step_kernel(method, t_anchor + (k0 + k) * dt, state, dt, moments, torque)
        if status != OK:
            return state, k, status, new
        finite = True
        for x in new:
            finite = finite and math.isfinite(x)
        if not finite:
            return state, k, NON_FINITE, new
        state = new
        if save_every > 0:
            countdown -= 1
            if countdown == 0:
                for i in range(7):
                    saved[row, i] = state[i]
                row += 1
                countdown = save_every
    return state, n, OK, state


advance_compiled = compiled(advance_steps)

install_kernel_loop(KernelLoop(KERNEL_IDS, advance_compiled, advance_steps))
