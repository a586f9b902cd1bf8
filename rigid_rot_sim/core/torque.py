"""Torque models fed to the integrators.

A torque model is any callable ``torque(t, q, omega) -> ndarray (3,)`` returning the
torque in N*m in the *principal body frame*, given the time t (s), the attitude q
(principal -> world, scalar-last) and the body angular velocity omega (rad/s).
The classes below are such callables that also expose their structure, so that an
integrator may exploit it (a Taylor method expands a constant or polynomial torque
exactly; a splitting method applies a gravity torque as an exact kick).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Protocol

import numpy as np


class TorqueModel(Protocol):
    def __call__(self, t: float, q: np.ndarray, omega: np.ndarray) -> np.ndarray: ...


TorqueFunction = Callable[[float, np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class ConstantTorque:
    """A torque fixed in the principal body frame, N*m."""

    value: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        value = np.asarray(self.value, dtype=float).reshape(3)
        if not np.all(np.isfinite(value)):
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
        value = self.coefficients[-1].copy()
        for c in self.coefficients[-2::-1]:
            value = value * t + c
        return value
