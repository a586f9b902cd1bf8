"""Magnetorquers (torque rods): the dipole they make, the torque it feels, the field it adds.

Rod ``i`` is a coil (or a wound ferrite rod) whose magnetic dipole lies along the unit axis
``g_i`` fixed in the body; its commanded dipole ``m_i`` (A*m^2) is clamped to
``|m_i| <= max_i``. The rods' axes are the *columns* of the 3 x n matrix ``G_t`` (Basilisk's
``MtbEffector``, ``GtMatrix_B``: the payload stores it row-major as 3 rows of n, and the effector
reads it as ``Eigen::Matrix3Xd``, one column per rod). The body's dipole and the torque it feels
in the field ``b`` (T, body frame) are

    m_B = G_t clamp(m) + m_res                                                    (1)
    tau = m_B x b                                                                 (2)

with ``m_res`` an optional residual dipole of the spacecraft (A*m^2, body frame; zero by
default). Basilisk writes (2) as ``-[b~] G_t mu`` (``MtbEffector::computeForceTorque``), which is
the same vector. Units: A*m^2 x T = N*m.

The rods also add their own field at the magnetometer (S2E models it; flight teams duty-cycle
rods and magnetometer because of it). Near field of a coil a few centimetres away is not a
dipole's far field, so it is modelled as a measured 3 x n coupling matrix ``C`` (T per A*m^2,
magnetometer frame = body frame here), linear in the clamped dipoles:

    b_measured = b + C clamp(m)                                                   (3)

(zero by default: a magnetometer on a boom, or rods off while it samples).

Example
-------
>>> gt = np.eye(3)
>>> torque(gt, [0.2, 0.0, 0.0], [0.0, 3e-5, 0.0], [0.1, 0.1, 0.1]).tolist()   # 0.1 x 3e-5 along z
[0.0, 0.0, 3e-06]
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rigid_rot_sim.core import validation
from rigid_rot_sim.core.arrays import ArrayLike, FloatArray

#: The shortest rod axis accepted before normalising, so that a typo (an all-zero axis) is refused.
MIN_AXIS_NORM = 1e-9


def clamp_dipoles(dipoles: ArrayLike, max_dipoles: ArrayLike) -> FloatArray:
    """Each rod's dipole clamped to ``[-max_i, max_i]``, A*m^2, shape (n,)."""
    limit = np.asarray(max_dipoles, dtype=float)
    result: FloatArray = np.clip(np.asarray(dipoles, dtype=float), -limit, limit)
    return result


def body_dipole(
    gt_matrix: ArrayLike, dipoles: ArrayLike, max_dipoles: ArrayLike, residual: ArrayLike | None = None
) -> FloatArray:
    """The body's magnetic dipole ``m_B = G_t clamp(m) + m_res`` (eq. (1)), A*m^2, body frame, shape (3,)."""
    m_body: FloatArray = np.asarray(gt_matrix, dtype=float) @ clamp_dipoles(dipoles, max_dipoles)
    if residual is not None:
        m_body = m_body + np.asarray(residual, dtype=float)
    return m_body


def torque(
    gt_matrix: ArrayLike,
    dipoles: ArrayLike,
    b_body: ArrayLike,
    max_dipoles: ArrayLike,
    residual: ArrayLike | None = None,
) -> FloatArray:
    """The rods' torque ``tau = (G_t clamp(m) + m_res) x b`` (eqs. (1)-(2)), N*m, body frame, shape (3,).

    ``gt_matrix`` (3, n): rod axes as columns (unit vectors, body frame); ``dipoles`` (n,):
    commanded dipoles, A*m^2; ``b_body`` (3,): the field, T, body frame; ``max_dipoles`` (n,):
    each rod's limit, A*m^2; ``residual`` (3,), optional: the spacecraft's residual dipole, A*m^2.
    """
    return np.cross(body_dipole(gt_matrix, dipoles, max_dipoles, residual), np.asarray(b_body, dtype=float))


def rod_field(coupling: ArrayLike, dipoles: ArrayLike, max_dipoles: ArrayLike) -> FloatArray:
    """The rods' own field at the magnetometer ``C clamp(m)`` (eq. (3)), T, body frame, shape (3,)."""
    result: FloatArray = np.asarray(coupling, dtype=float) @ clamp_dipoles(dipoles, max_dipoles)
    return result


def allocate(gt_matrix: ArrayLike, m_body: ArrayLike, max_dipoles: ArrayLike) -> FloatArray:
    """Rod dipoles (n,) that make the body dipole ``m_body`` (A*m^2), scaled to respect every limit.

    The least-squares split ``pinv(G_t) m_B`` (exact for three or more independent rods), then one
    common factor ``s <= 1`` so that no rod exceeds its limit: the dipole keeps its direction (a
    per-rod clamp would turn it, and with it the torque), only its size shrinks.
    """
    dipoles = np.linalg.pinv(np.asarray(gt_matrix, dtype=float)) @ np.asarray(m_body, dtype=float)
    limit = np.asarray(max_dipoles, dtype=float)
    over = np.abs(dipoles) / limit
    worst = float(over.max()) if over.size else 0.0
    result: FloatArray = dipoles / worst if worst > 1.0 else dipoles
    return result


@dataclass(frozen=True)
class Magnetorquers:
    """A set of n torque rods fixed in the body (the scene's ``actuators.magnetorquers``).

    ``axes`` (3, n): the rods' unit axes as columns (``G_t``), body frame (normalised here);
    ``max_dipoles`` (n,): each rod's limit, A*m^2 (> 0); ``residual`` (3,): the spacecraft's
    residual dipole, A*m^2, body frame; ``coupling`` (3, n): the rods' field at the magnetometer
    per unit dipole, T/(A*m^2) (eq. (3)); ``names``: one per rod (the command's joint names).
    """

    axes: np.ndarray
    max_dipoles: np.ndarray
    names: tuple[str, ...] = ()
    residual: np.ndarray = field(default_factory=lambda: np.zeros(3))
    coupling: np.ndarray | None = None

    def __post_init__(self) -> None:
        axes = np.array(self.axes, dtype=float)
        if axes.ndim != 2 or axes.shape[0] != 3 or axes.shape[1] < 1:
            raise ValueError(f"axes must have shape (3, n) with n >= 1 (one column per rod), got {axes.shape}")
        n = axes.shape[1]
        axes = validation.finite_array("axes", axes, (3, n))
        norms = np.linalg.norm(axes, axis=0)
        if not np.all(norms > MIN_AXIS_NORM):
            raise ValueError(f"rod {int(np.argmin(norms))}'s axis must not be zero")
        limits = validation.finite_array("max_dipoles", self.max_dipoles, (n,))
        if not np.all(limits > 0.0):
            raise ValueError(f"max_dipoles must be > 0 A*m^2, got {limits.tolist()}")
        names = tuple(self.names) or tuple(f"rod_{i}" for i in range(n))
        if len(names) != n or len(set(names)) != n:
            raise ValueError(f"names must be {n} distinct names, one per rod, got {list(names)}")
        coupling = np.zeros((3, n)) if self.coupling is None else self.coupling
        for name, value in (("axes", axes / norms), ("max_dipoles", limits)):
            object.__setattr__(self, name, _frozen(value))
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "residual", _frozen(validation.finite_vector("residual", self.residual)))
        object.__setattr__(self, "coupling", _frozen(validation.finite_array("coupling", coupling, (3, n))))

    @property
    def count(self) -> int:
        """The number of rods."""
        return int(self.axes.shape[1])

    def torque(self, dipoles: ArrayLike, b_body: ArrayLike) -> FloatArray:
        """The torque (N*m, body frame) of the commanded ``dipoles`` (n,) in the field ``b_body`` (T)."""
        return torque(self.axes, dipoles, b_body, self.max_dipoles, self.residual)

    def clamped(self, dipoles: ArrayLike) -> tuple[FloatArray, list[int]]:
        """The dipoles the rods make, and the indices of the rods the clamp limited (for ``~/sim_events``)."""
        wanted = validation.finite_array("dipoles", dipoles, (self.count,))
        made = clamp_dipoles(wanted, self.max_dipoles)
        return made, [i for i in range(self.count) if made[i] != wanted[i]]

    def measured_field(self, b_body: ArrayLike, dipoles: ArrayLike) -> FloatArray:
        """The field a body-mounted magnetometer sees (eq. (3)): the true field plus the rods' own, T."""
        assert self.coupling is not None  # zeros by default (__post_init__)
        measured: FloatArray = np.asarray(b_body, dtype=float) + rod_field(self.coupling, dipoles, self.max_dipoles)
        return measured


def _frozen(value: np.ndarray) -> np.ndarray:
    array = np.array(value, dtype=float)
    array.setflags(write=False)
    return array


def rod_duty(dipoles: ArrayLike, max_dipoles: ArrayLike) -> FloatArray:
    """Each rod's duty ``|clamp(m_i)| / max_i`` in [0, 1] (the PWM fraction a driver would run)."""
    limit = np.asarray(max_dipoles, dtype=float)
    result: FloatArray = np.abs(clamp_dipoles(dipoles, limit)) / limit
    return result
