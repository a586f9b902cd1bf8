"""The numerical core of rigid_rot_sim: numpy, scipy and numba, nothing else (no ROS, no files).

Conventions everywhere: SI units; quaternions scalar-last ``(x, y, z, w)`` rotating
body -> world (as ``scipy.spatial.transform.Rotation`` and geometry_msgs do);
angular velocity and torque in the body frame unless a name says ``_world``.

The public façade, as ``scipy.integrate`` re-exports its solvers (loaded on first use, so that
importing :mod:`rigid_rot_sim.core.limits` does not load numba)::

    from rigid_rot_sim.core import simulate, get_method, METHODS, torque_free_solution

Modules, one job each:

* :mod:`.dynamics` - the body (principal axes), Euler's equations, invariants; :mod:`.frames` -
  the principal <-> user body frame conversion on floats; :mod:`.inertia` - mass properties;
* :mod:`.integrators` - one step API, the registry ``METHODS``; :mod:`.simulate` - one body over
  [0, t_end]; :mod:`.simulate_wheels` - its wheel inputs; :mod:`.batch` - N bodies at once;
  :mod:`.batch_gyrostat` - N spacecraft with wheels at once; :mod:`.slew` - the slew task's
  observation, reward and hold test, compiled (the Gymnasium environments');
* :mod:`.exact` - the closed-form torque-free motion, on :mod:`.elliptic`; :mod:`.heavy_top` -
  the heavy symmetric top; :mod:`.wheels` - a spacecraft with reaction wheels (a gyrostat);
* :mod:`.torque` - torque models; :mod:`.sensors` - a rate gyro and a star tracker;
  :mod:`.magnetorquer` - torque rods (dipole, torque, their field at the magnetometer);
  :mod:`.magnetic_control` - B-dot and B-cross detumbling, momentum unloading with the rods;
* :mod:`.orbit` - Keplerian orbits with J2, the Earth's rotation, WGS-84, NED and LVLH;
  :mod:`.geomagnetic` - IGRF-14, WMM2025 and the dipole field, on the coefficients of
  :mod:`.geomagnetic_coefficients`;
  :mod:`.sensitivities` - Euler's equations with parameter sensitivities (``rigid-rot identify``'s model);
* :mod:`.quaternion` - quaternion helpers on floats; :mod:`.steps` - which step a time lands on
  and how many steps a duration takes;
* :mod:`.jit` - numba with an on-disk cache; :mod:`.precompile` - fills that cache;
  :mod:`.limits` - every documented input limit; :mod:`.validation` - argument checks.

The rooms above it: :mod:`rigid_rot_sim.scene` reads scene files into frozen dataclasses (PyYAML,
jsonschema); :mod:`rigid_rot_sim.run` is the run engine (commands, clock, pacing) over these
numerics. Neither is imported from here (``test/test_structure.py`` checks the layer order).
"""

from __future__ import annotations

import importlib
from typing import Any

#: Public name -> the module of this package that defines it.
_FACADE = {
    "simulate": "simulate",
    "Trajectory": "simulate",
    "METHODS": "integrators",
    "get_method": "integrators",
    "Integrator": "integrators",
    "NonFiniteStateError": "integrators",
    "torque_free_solution": "exact",
    "TorqueFreeSolution": "exact",
    "mass_properties": "inertia",
    "MassProperties": "inertia",
    "RigidBody": "dynamics",
    "ConstantTorque": "torque",
    "GravityTorque": "torque",
    "PolynomialTorque": "torque",
}

__all__ = sorted(_FACADE)


def __getattr__(name: str) -> Any:
    """Load a façade name from its module on first use (PEP 562)."""
    module = _FACADE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
