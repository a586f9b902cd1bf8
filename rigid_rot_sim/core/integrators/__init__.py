"""The integrator registry: every method by name, all with the step API of ``base.py``.

Modules: :mod:`.base` (the step API), :mod:`.explicit` (``euler``, ``rk4``), :mod:`.lie`
(``lie_rk4``), :mod:`.implicit` (``implicit_midpoint``), :mod:`.splitting`, :mod:`.taylor`,
:mod:`.adaptive` (``dop853``), :mod:`.exact_flow` (``exact``, ``exact_split``);
:mod:`.fixed_step`, :mod:`.kernels` and :mod:`.status` (the compiled loop and its kernels'
contract); :mod:`.gyrostat` (the spacecraft with reaction wheels: a state with wheel speeds).

>>> from rigid_rot_sim.core.integrators import get_method
>>> get_method("rk4").orders, get_method("splitting").orders, get_method("splitting").stability
((4,), (2, 4, 6), 'unconditional')
"""

from __future__ import annotations

# kernels imports every fixed-step method's kernel and installs the compiled loop that runs them
from rigid_rot_sim.core.integrators import kernels  # noqa: F401
from rigid_rot_sim.core.integrators.adaptive import DOP853Integrator
from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError
from rigid_rot_sim.core.integrators.exact_flow import ExactFlow, ExactSplit
from rigid_rot_sim.core.integrators.explicit import RK4, Euler
from rigid_rot_sim.core.integrators.implicit import ImplicitMidpoint
from rigid_rot_sim.core.integrators.lie import LieRK4
from rigid_rot_sim.core.integrators.splitting import Splitting
from rigid_rot_sim.core.integrators.taylor import Taylor

METHODS: dict[str, type[Integrator]] = {
    "euler": Euler,
    "rk4": RK4,
    "dop853": DOP853Integrator,
    "implicit_midpoint": ImplicitMidpoint,
    "lie_rk4": LieRK4,
    "splitting": Splitting,
    "taylor": Taylor,
    "exact": ExactFlow,
    "exact_split": ExactSplit,
}


def get_method(name: str) -> type[Integrator]:
    """The integrator class registered as ``name``; ValueError listing the valid names."""
    try:
        return METHODS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown integrator {name!r}; valid methods: {', '.join(sorted(METHODS))}") from None


__all__ = ["METHODS", "Integrator", "NonFiniteStateError", "get_method"]
