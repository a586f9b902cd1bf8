"""Argument checks: each takes a value and returns it cleaned, or raises ValueError.

The message names the argument (and the index of a bad component) and says what is
wrong, e.g. ``omega0[1] must be finite, got nan``. Modelled on scipy.integrate's
``validate_tol`` / ``validate_max_step``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from rigid_rot_sim.core.arrays import FloatArray

# Moments from an eigen-decomposition or a CAD export satisfy the triangle inequality
# only up to rounding (a thin plate has I3 = I1 + I2 exactly in theory).
TRIANGLE_RTOL = 1e-12
# Relative asymmetry tolerated in a user-supplied inertia tensor.
SYMMETRY_RTOL = 1e-9


def finite_scalar(name: str, value: Any) -> float:
    """Return ``float(value)``; ValueError unless it is a finite real number."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{name} must be finite, got {x}")
    return x


def positive_scalar(name: str, value: Any) -> float:
    """Return ``float(value)``; ValueError unless it is finite and > 0."""
    x = finite_scalar(name, value)
    if not x > 0.0:
        raise ValueError(f"{name} must be > 0, got {x}")
    return x


def nonnegative_scalar(name: str, value: Any) -> float:
    """Return ``float(value)``; ValueError unless it is finite and >= 0."""
    x = finite_scalar(name, value)
    if x < 0.0:
        raise ValueError(f"{name} must be >= 0, got {x}")
    return x


def finite_array(name: str, value: Any, shape: tuple[int, ...]) -> FloatArray:
    """Return ``value`` as a float array of the given shape with every entry finite."""
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real array of shape {shape}, got {value!r}") from None
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got shape {a.shape}")
    if math.isfinite(sum(a.ravel().tolist())):  # all finite (a sum with inf or nan is not): the cheap check
        return a
    bad = np.argwhere(~np.isfinite(a))
    if bad.size:
        index = tuple(int(i) for i in bad[0])
        where = index[0] if len(index) == 1 else list(index)
        raise ValueError(f"{name}[{where}] must be finite, got {a[tuple(bad[0])]}")
    return a


def finite_vector(name: str, value: Any, size: int = 3) -> FloatArray:
    """Return a finite float vector of length ``size``."""
    return finite_array(name, value, (size,))


def quaternion(name: str, value: Any) -> FloatArray:
    """Return the finite, non-zero quaternion (x, y, z, w) normalised to unit length."""
    q = finite_vector(name, value, 4)
    scale = float(np.max(np.abs(q)))  # first to O(1): |q| of components near 1e308 overflows
    if not scale > 0.0:
        raise ValueError(f"{name} must be a non-zero quaternion (x, y, z, w), got {q}")
    q = q / scale
    return q / float(np.linalg.norm(q))


def principal_moments(name: str, value: Any) -> FloatArray:
    """Return principal moments (I1, I2, I3), kg*m^2: finite, > 0, and a physical body.

    A rigid body's moments satisfy ``Ii + Ij >= Ik`` for every permutation (equality
    for a plane lamina); violations within ``TRIANGLE_RTOL`` of the sum are rounding.
    """
    moments = finite_vector(name, value, 3)
    for i in range(3):
        if not moments[i] > 0.0:
            raise ValueError(f"{name}[{i}] must be > 0 kg*m^2, got {moments[i]}")
    total = float(moments.sum())
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        if moments[i] + moments[j] < moments[k] - TRIANGLE_RTOL * total:
            raise ValueError(
                f"{name} = {moments.tolist()} violates the triangle inequality "
                f"{name}[{i}] + {name}[{j}] >= {name}[{k}] of a rigid body"
            )
    return moments


def inertia_tensor(name: str, value: Any) -> FloatArray:
    """Return a finite, symmetric 3x3 inertia tensor (kg*m^2), symmetrised exactly.

    Positivity and the triangle inequality are checked on its eigenvalues by
    :func:`principal_moments` where the principal axes are computed.
    """
    tensor = finite_array(name, value, (3, 3))
    scale = float(np.max(np.abs(tensor)))
    asym = np.abs(tensor - tensor.T)
    if float(np.max(asym)) > SYMMETRY_RTOL * scale:
        i, j = np.unravel_index(int(np.argmax(asym)), asym.shape)
        raise ValueError(
            f"{name} must be symmetric: {name}[{i}][{j}] = {tensor[i, j]} != {name}[{j}][{i}] = {tensor[j, i]}"
        )
    return 0.5 * (tensor + tensor.T)
