"""Rigid-body rotational dynamics: the body, Euler's equations, invariants, frames.

Frames: the *user body frame* is the one the inertia tensor was given in; the
*principal frame* is the body frame whose axes are the principal axes, where the
tensor is ``diag(I1, I2, I3)``. The integrators work in the principal frame;
:class:`RigidBody` keeps the rotation between the two so that every output is
reported in the user body frame.

Physics (derived from dL/dt = N in the world frame with L_world = R L_body and
dR/dt = R [omega]x): in the principal frame

    I1 dw1/dt = (I2 - I3) w2 w3 + N1     (and cyclic: 1 -> 2 -> 3 -> 1)
    dq/dt = 1/2 q (x) (omega, 0)         (q scalar-last, body -> world)

with T = 1/2 omega . L and L_body = I omega, L_world = R(q) L_body.
Units: kg*m^2, rad/s, N*m, J.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numba.extending import register_jitable
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core import frames, validation
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.inertia import principal_frame, principal_orientation
from rigid_rot_sim.core.validation import FloatArray


@register_jitable
def euler_rhs_components(
    i1: float, i2: float, i3: float, w1: float, w2: float, w3: float, n1: float, n2: float, n3: float
) -> tuple[float, float, float]:
    """Angular acceleration d(omega)/dt (rad/s^2) from Euler's equations, component-wise.

    Principal moments ``i1..i3`` (kg*m^2), body rates ``w1..w3`` (rad/s) and torque
    ``n1..n3`` (N*m) in the principal frame. Works on floats (the integrators' hot
    loops, compiled into the numba kernels) and elementwise on arrays alike; this is the
    one place the formula lives.
    """
    return (
        ((i2 - i3) * w2 * w3 + n1) / i1,
        ((i3 - i1) * w3 * w1 + n2) / i2,
        ((i1 - i2) * w1 * w2 + n3) / i3,
    )


@register_jitable
def axes_by_moment(i1: float, i2: float, i3: float) -> tuple[int, int, int]:
    """The principal axes (0, 1, 2) sorted by moment, smallest first (ties: axis order)."""
    if i2 < i1:
        lo, hi = 1, 0
    else:
        lo, hi = 0, 1
    i_lo = i2 if lo == 1 else i1
    i_hi = i1 if lo == 1 else i2
    if i3 < i_lo:
        return 2, lo, hi
    if i3 < i_hi:
        return lo, 2, hi
    return lo, hi, 2


def euler_rhs(moments: Any, omega: Any, torque: Any = None) -> np.ndarray:
    """Angular acceleration d(omega)/dt, rad/s^2, principal frame.

    Parameters
    ----------
    moments : array_like, shape (3,)
        Principal moments (I1, I2, I3), kg*m^2.
    omega : array_like, shape (..., 3)
        Angular velocity, rad/s, principal frame.
    torque : array_like, shape (..., 3), optional
        Torque about the centre of mass (or the pivot), N*m, principal frame.
    """
    i1, i2, i3 = np.asarray(moments, dtype=float)
    omega = np.asarray(omega, dtype=float)
    torque = np.zeros_like(omega) if torque is None else np.broadcast_to(np.asarray(torque, dtype=float), omega.shape)
    alpha = euler_rhs_components(
        i1, i2, i3, omega[..., 0], omega[..., 1], omega[..., 2], torque[..., 0], torque[..., 1], torque[..., 2]
    )
    return np.stack(alpha, axis=-1)


def angular_momentum_body(moments: Any, omega: Any) -> FloatArray:
    """Body-frame angular momentum ``L = I omega``, kg*m^2/s (principal frame; shape (..., 3))."""
    moments_array: FloatArray = np.asarray(moments, dtype=float)
    omega_array: FloatArray = np.asarray(omega, dtype=float)
    return moments_array * omega_array


def kinetic_energy(moments: Any, omega: Any) -> FloatArray | float:
    """Rotational kinetic energy ``T = 1/2 omega . L``, J (principal frame; shape (...))."""
    omega_array: FloatArray = np.asarray(omega, dtype=float)
    energy: FloatArray | float = 0.5 * np.sum(omega_array * angular_momentum_body(moments, omega_array), axis=-1)
    return energy


def body_to_world(q: Any, v_body: Any) -> np.ndarray:
    """Rotate body-frame vectors to the world frame, ``R(q) v`` (q: (..., 4) scalar-last)."""
    q = np.asarray(q, dtype=float)
    v_body = np.asarray(v_body, dtype=float)
    rotated = Rotation.from_quat(q.reshape(-1, 4)).apply(v_body.reshape(-1, 3))
    return rotated.reshape(np.broadcast_shapes(q.shape[:-1] + (3,), v_body.shape))


def world_to_body(q: Any, v_world: Any) -> np.ndarray:
    """Rotate world-frame vectors into the body frame, ``R(q)^T v`` (q: (..., 4) scalar-last)."""
    q = np.asarray(q, dtype=float)
    v_world = np.asarray(v_world, dtype=float)
    rotated = Rotation.from_quat(q.reshape(-1, 4)).apply(v_world.reshape(-1, 3), inverse=True)
    return rotated.reshape(np.broadcast_shapes(q.shape[:-1] + (3,), v_world.shape))


def angular_momentum_world(moments: Any, q: Any, omega: Any) -> np.ndarray:
    """World-frame angular momentum ``R(q) I omega``, kg*m^2/s (principal-frame q and omega)."""
    return body_to_world(q, angular_momentum_body(moments, omega))


def quaternion_derivative(q: Any, omega: Any) -> np.ndarray:
    """``dq/dt = 1/2 q (x) (omega, 0)``, 1/s, for body-frame omega (rad/s); shape (..., 4)."""
    q = np.asarray(q, dtype=float)
    omega = np.asarray(omega, dtype=float)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    wx, wy, wz = omega[..., 0], omega[..., 1], omega[..., 2]
    return 0.5 * np.stack(
        (
            w * wx + y * wz - z * wy,
            w * wy + z * wx - x * wz,
            w * wz + x * wy - y * wx,
            -x * wx - y * wy - z * wz,
        ),
        axis=-1,
    )


@dataclass(frozen=True)
class RigidBody:
    """A rigid body's inertia, with its principal axes.

    Attributes
    ----------
    principal_moments : ndarray, shape (3,)
        (I1, I2, I3), kg*m^2, the eigenvalues of the inertia tensor.
    body_from_principal : ndarray, shape (4,)
        Unit quaternion (x, y, z, w) rotating principal-frame coordinates into user
        body-frame coordinates: ``v_body = R(body_from_principal) v_principal``.
        The identity when the inertia was given as principal moments or a diagonal tensor.
    inertia_tensor : ndarray, shape (3, 3)
        The tensor in the user body frame, kg*m^2.
    """

    principal_moments: np.ndarray
    body_from_principal: np.ndarray
    inertia_tensor: np.ndarray

    @classmethod
    def from_inertia(cls, inertia: Any, name: str = "inertia") -> RigidBody:
        """Build from three principal moments (kg*m^2) or a symmetric 3x3 tensor.

        A diagonal tensor keeps the user's axes (no rotation). Otherwise the principal
        axes are the tensor's eigenvectors, made right-handed, so that
        ``tensor = R diag(I) R^T`` with ``R = R(body_from_principal)``.
        ValueError (naming ``name``) for non-finite values, non-positive moments, an
        asymmetric tensor or moments violating the triangle inequality.
        """
        shape = np.shape(inertia)
        if shape == (3,):
            moments = validation.principal_moments(name, inertia)
            return cls(moments, np.array(quat.IDENTITY), np.diag(moments))
        if shape != (3, 3):
            raise ValueError(f"{name} must be 3 principal moments or a 3x3 tensor, got shape {shape}")
        tensor = validation.inertia_tensor(name, inertia)
        if not np.any(tensor - np.diag(np.diag(tensor))):
            moments = validation.principal_moments(f"diag({name})", np.diag(tensor))
            return cls(moments, np.array(quat.IDENTITY), tensor)
        eigenvalues, axes = principal_frame(tensor)
        moments = validation.principal_moments(f"eigenvalues of {name}", eigenvalues)
        return cls(moments, principal_orientation(axes), tensor)

    @property
    def is_principal(self) -> bool:
        """True when the user body frame is the principal frame."""
        return bool(np.array_equal(self.body_from_principal, quat.IDENTITY))

    def vector_to_principal(self, v_body: Any) -> np.ndarray:
        """User body-frame vectors (..., 3) -> principal-frame coordinates."""
        return world_to_body(np.broadcast_to(self.body_from_principal, np.shape(v_body)[:-1] + (4,)), v_body)

    def vector_from_principal(self, v_principal: Any) -> np.ndarray:
        """Principal-frame vectors (..., 3) -> user body-frame coordinates.

        The formula of :func:`rigid_rot_sim.core.frames.vector_from_principal` on each row, the run engine's.
        """
        rows = np.reshape(np.asarray(v_principal, dtype=float), (-1, 3))
        v = frames.vector_from_principal(tuple(float(c) for c in self.body_from_principal), tuple(rows.T))
        return np.stack(v, axis=-1).reshape(np.shape(v_principal))

    def attitude_to_principal(self, q_body: Any) -> np.ndarray:
        """Attitude body -> world (..., 4) -> attitude principal -> world, ``q (x) q_bp``."""
        r = quat.compose_rotations(
            Rotation.from_quat(np.reshape(q_body, (-1, 4))), Rotation.from_quat(self.body_from_principal)
        )
        return r.as_quat(canonical=False).reshape(np.shape(q_body))

    def attitude_from_principal(self, q_principal: Any) -> np.ndarray:
        """Attitude principal -> world (..., 4) -> attitude body -> world, ``q (x) q_bp^-1``.

        The formula of :func:`rigid_rot_sim.core.frames.attitude_from_principal` on each row, the run
        engine's: an attitude the engine and :func:`~rigid_rot_sim.core.simulate.simulate` report has the same bits.
        """
        rows = np.reshape(np.asarray(q_principal, dtype=float), (-1, 4))
        principal_from_body = frames.principal_from_body(tuple(float(v) for v in self.body_from_principal))
        q = frames.attitude_from_principal(tuple(rows.T), principal_from_body)
        return np.stack(q, axis=-1).reshape(np.shape(q_principal))
