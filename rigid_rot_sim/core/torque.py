"""Torque models fed to the integrators.

A torque model is any callable ``torque(t, q, omega) -> ndarray (3,)`` returning the
torque in N*m in the *principal body frame*, given the time t (s), the attitude q
(principal -> world, scalar-last) and the body angular velocity omega (rad/s).
The classes below are such callables that also expose their structure, so that an
integrator may exploit it (a Taylor method expands a constant or polynomial torque
exactly; a splitting method applies a gravity torque as an exact kick).

The compiled integrator kernels evaluate these models as *data* (:func:`torque_data`):
a polynomial in time (a constant is its one row) plus a gravity term, with a kind that
says whether there is a torque at all and whether it depends on the attitude. Any other
callable is :data:`TORQUE_CALLABLE` and runs the kernels' interpreted (slower) path.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple, Protocol

import numpy as np
from numba.core.extending import overload
from numba.extending import register_jitable

from rigid_rot_sim.core.arrays import FloatArray
from rigid_rot_sim.core.quaternion import Floats, Vector
from rigid_rot_sim.core.quaternion import rotate_inverse as _rotate_inverse


class TorqueModel(Protocol):
    def __call__(self, t: float, q: np.ndarray, omega: np.ndarray) -> np.ndarray: ...


TorqueFunction = Callable[[float, np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class ConstantTorque:
    """A torque fixed in the principal body frame, N*m."""

    value: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        value = np.asarray(self.value, dtype=float).reshape(3)
        if not all(map(math.isfinite, value.tolist())):
            raise ValueError(f"torque must be finite, got {value}")
        object.__setattr__(self, "value", value)

    def __call__(self, t: float, q: np.ndarray, omega: np.ndarray) -> np.ndarray:
        return self.value


@dataclass(frozen=True)
class GravityTorque:
    """Torque of uniform gravity about a fixed pivot.

    ``lever_arm`` (m, principal body frame) points from the pivot to the centre of
    mass; ``weight`` = m * g (N) acts along -z of the world. The torque is
    ``lever_arm x (R^T (-weight * e_z))``, quadratic in the quaternion.
    """

    lever_arm: np.ndarray
    weight: float

    def __post_init__(self) -> None:
        arm = np.asarray(self.lever_arm, dtype=float).reshape(3)
        if not np.all(np.isfinite(arm)) or not np.isfinite(self.weight):
            raise ValueError("lever_arm and weight must be finite")
        object.__setattr__(self, "lever_arm", arm)

    def __call__(self, t: float, q: np.ndarray, omega: np.ndarray) -> np.ndarray:
        x, y, z, w = q
        # world z axis expressed in the body frame: third row of R(q)
        up_body = np.array([2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)])
        return np.cross(self.lever_arm, -self.weight * up_body)


@dataclass(frozen=True)
class PolynomialTorque:
    """A torque polynomial in time, fixed in the principal body frame, N*m.

    ``N(t) = sum_k coefficients[k] * t**k`` with t in s, so ``coefficients[k]`` (shape
    (n, 3), n >= 1) is in N*m/s^k. It does not depend on the state, so the Taylor method
    expands it exactly.
    """

    coefficients: np.ndarray

    def __post_init__(self) -> None:
        coefficients = np.array(self.coefficients, dtype=float)
        if coefficients.ndim == 1 and coefficients.shape == (3,):
            coefficients = coefficients.reshape(1, 3)
        if coefficients.ndim != 2 or coefficients.shape[1] != 3 or coefficients.shape[0] < 1:
            raise ValueError(f"coefficients must have shape (n, 3) with n >= 1, got {coefficients.shape}")
        if not np.all(np.isfinite(coefficients)):
            bad = np.argwhere(~np.isfinite(coefficients))[0]
            raise ValueError(f"coefficients[{bad[0]}, {bad[1]}] must be finite, got {coefficients[tuple(bad)]}")
        coefficients.setflags(write=False)
        object.__setattr__(self, "coefficients", coefficients)

    def __call__(self, t: float, q: np.ndarray, omega: np.ndarray) -> np.ndarray:
        value: FloatArray = self.coefficients[-1].copy()
        for c in self.coefficients[-2::-1]:
            value = value * t + c
        return value


#: ``TorqueData.kind``: no torque (free body) / a polynomial in time (constant included) /
#: a gravity term plus an optional polynomial (depends on the attitude) / a Python callable.
TORQUE_NONE, TORQUE_TIME, TORQUE_GRAVITY, TORQUE_CALLABLE = 0, 1, 2, 3


class TorqueData(NamedTuple):
    """A torque model as plain data for the compiled kernels (all N*m, principal frame).

    ``polynomial`` (n, 3): ``N(t) = sum_k polynomial[k] t**k`` (n = 0: no such term);
    ``gravity`` (4,): lever arm (m) and weight (N) of :class:`GravityTorque` (zeros when
    absent); ``function``: the callable for :data:`TORQUE_CALLABLE`, else None.
    """

    kind: int
    polynomial: np.ndarray
    gravity: np.ndarray
    function: Any = None

    @property
    def compiled(self) -> tuple[int, np.ndarray, np.ndarray]:
        """The tuple the compiled kernels take (one numba type for every kind)."""
        return (self.kind, self.polynomial, self.gravity)


_NO_POLYNOMIAL = np.zeros((0, 3))
_NO_GRAVITY = np.zeros(4)


def torque_data(torque: Any) -> TorqueData:
    """The :class:`TorqueData` of a torque model (None or an all-zero constant: no torque)."""
    if torque is None:
        return TorqueData(TORQUE_NONE, _NO_POLYNOMIAL, _NO_GRAVITY)
    if isinstance(torque, ConstantTorque):
        if not any(torque.value.tolist()):  # np.any's truth, without its call overhead
            return TorqueData(TORQUE_NONE, _NO_POLYNOMIAL, _NO_GRAVITY)
        return TorqueData(TORQUE_TIME, np.array(torque.value, dtype=float).reshape(1, 3), _NO_GRAVITY)
    if isinstance(torque, PolynomialTorque):
        # a writable C-contiguous copy: the one array type the compiled kernels were built for
        return TorqueData(TORQUE_TIME, np.array(torque.coefficients, dtype=float, order="C"), _NO_GRAVITY)
    if isinstance(torque, GravityTorque):
        gravity = np.array([*torque.lever_arm.tolist(), float(torque.weight)])
        return TorqueData(TORQUE_GRAVITY, _NO_POLYNOMIAL, gravity)
    if not callable(torque):
        raise TypeError(f"torque must be None or a callable torque(t, q, omega), got {torque!r}")
    return TorqueData(TORQUE_CALLABLE, _NO_POLYNOMIAL, _NO_GRAVITY, torque)


@register_jitable
def evaluate_torque_data(
    kind: int, polynomial: np.ndarray, gravity: np.ndarray, t: float, q: Floats, w: Floats
) -> Vector:
    """The torque (N1, N2, N3) of data-kind torques at time t, attitude q (tuple) and omega.

    Horner's rule on the polynomial rows (highest power first), plus
    ``lever_arm x (R^T (-weight e_z))`` for gravity: compiled into the kernels, and the
    float evaluation :func:`float_torque` uses.
    """
    n1 = n2 = n3 = 0.0
    rows = polynomial.shape[0]
    if rows > 0:
        n1, n2, n3 = polynomial[rows - 1, 0], polynomial[rows - 1, 1], polynomial[rows - 1, 2]
        for k in range(rows - 2, -1, -1):
            n1, n2, n3 = n1 * t + polynomial[k, 0], n2 * t + polynomial[k, 1], n3 * t + polynomial[k, 2]
    if kind == TORQUE_GRAVITY:
        a1, a2, a3, weight = gravity[0], gravity[1], gravity[2], gravity[3]
        u1, u2, u3 = _rotate_inverse(q, (0.0, 0.0, -weight))
        g1, g2, g3 = a2 * u3 - a3 * u2, a3 * u1 - a1 * u3, a1 * u2 - a2 * u1
        if rows > 0:
            return n1 + g1, n2 + g2, n3 + g3
        return g1, g2, g3
    return n1, n2, n3


# -- the torque as the kernels see it: data (compiled) or a Python callable (interpreted) ----

FloatTorque = Callable[[float, Floats, Floats], Vector]


@register_jitable
def has_torque(torque: TorqueData) -> bool:
    """False for a free body (no torque, or an all-zero constant); ``torque`` a TorqueData tuple."""
    return torque[0] != TORQUE_NONE


@register_jitable
def attitude_dependent(torque: TorqueData) -> bool:
    """True when the torque may depend on the attitude (gravity, or any callable)."""
    return torque[0] >= TORQUE_GRAVITY


def torque_at(torque: Any, t: float, q: Floats, w: Floats) -> Vector:
    """The torque (N1, N2, N3) at (t, q, omega) for a kernel: data, or a Python callable.

    Compiled kernels get the data-only version below (numba ``overload``).
    """
    if torque[0] == TORQUE_CALLABLE:
        n1, n2, n3 = np.asarray(torque[3](t, np.array(q), np.array(w)), dtype=float).reshape(3).tolist()
        return n1, n2, n3
    return evaluate_torque_data(torque[0], torque[1], torque[2], t, q, w)


@overload(torque_at)
def _torque_at_compiled(torque: Any, t: Any, q: Any, w: Any) -> Callable[..., Vector]:
    # numba requires the implementation's parameters, annotations included, to equal the typing function's.
    def impl(torque: Any, t: Any, q: Any, w: Any) -> Vector:
        return evaluate_torque_data(torque[0], torque[1], torque[2], t, q, w)

    return impl


def float_torque(torque: Any) -> tuple[FloatTorque | None, bool]:
    """Adapt a torque model to ``f(t, q, omega) -> (N1, N2, N3)`` on float tuples.

    Returns ``(f, attitude_dependent)``; ``f`` is None for a free body. The structured
    models of this module are evaluated by the kernels' formula
    (:func:`evaluate_torque_data`); any other callable is called with small numpy arrays
    and counts as depending on the attitude.
    """
    data = torque_data(torque)
    if data.kind == TORQUE_NONE:
        return None, False

    def f(t: float, q: Floats, w: Floats) -> Vector:
        return torque_at(data, t, tuple(q), tuple(w))

    return f, data.kind >= TORQUE_GRAVITY
