"""The torque rods' torque on the engine's step, from the dipoles the commands hold and the Earth's field.

``(G_t clamp(m) + m_res) x b`` (:func:`rigid_rot_sim.core.magnetorquer.torque`) with the field at the step's
start, in the body at its attitude then, held over the step: a zero-order hold, as for a world-frame torque
(first order in dt while the body turns the field within the step). :attr:`RodTorque.field` is the scene's
:class:`~rigid_rot_sim.core.geomagnetic.OrbitField` (``environment.magnetic_field`` on its ``orbit``; the world
frame is its ECI): a scene with rods must have one (scene validation).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rigid_rot_sim.core.magnetorquer import Magnetorquers
from rigid_rot_sim.run.timeline import world_in_body
from rigid_rot_sim.scene.scene import Scene

__all__ = ["RodTorque"]

Vector3 = tuple[float, float, float]


@dataclass
class RodTorque:
    """The rods of a scene (None without) and the field they act on (None until the engine has one)."""

    rods: Magnetorquers | None
    principal_from_body: Any
    field: Any = None

    @classmethod
    def of(cls, scene: Scene, principal_from_body: Any) -> RodTorque:
        """The rods of ``scene`` in its field along its orbit (a scene with rods has one: scene validation)."""
        rods = scene.spacecraft.magnetorquers()
        return cls(rods, principal_from_body, scene.orbit_field() if rods is not None else None)

    @property
    def present(self) -> bool:
        """The scene has rods (its steps take a torque that may change at every boundary)."""
        return self.rods is not None

    @property
    def active(self) -> bool:
        """The rods act: the scene has them and the field is known."""
        return self.rods is not None and self.field is not None

    def torque(self, t: float, q_principal: Any, dipoles: Any) -> Vector3 | None:
        """The rods' torque (N*m, user body frame) at time ``t`` (s) and attitude ``q_principal``; None if inactive."""
        if self.rods is None or self.field is None:
            return None
        b = world_in_body(tuple(q_principal), self.principal_from_body, self.field.eci(t))
        x, y, z = self.rods.torque(dipoles, b).tolist()
        return x, y, z

    def add(self, body: Vector3, t: float, q_principal: Any, dipoles: Any) -> Vector3:
        """``body`` (N*m) plus the rods' torque."""
        rods = self.torque(t, q_principal, dipoles)
        return body if rods is None else (body[0] + rods[0], body[1] + rods[1], body[2] + rods[2])

    def named(self, t: float, q_principal: Any, dipoles: Any) -> list[tuple[str, np.ndarray]]:
        """The rods' torque as a snapshot's torque source (none while inactive)."""
        rods = self.torque(t, q_principal, dipoles)
        return [] if rods is None else [("magnetorquers", np.array(rods))]

    def bound(self, t: float) -> float:
        """A bound (N*m) on the rods' torque at time ``t`` (s), any attitude and command: (sum of the limits +
        |m_res|) |b| (the step re-expresses the torque at every boundary, so the field's change is small)."""
        if self.rods is None or self.field is None:
            return 0.0
        dipole = float(np.sum(self.rods.max_dipoles)) + float(np.linalg.norm(self.rods.residual))
        return dipole * float(np.linalg.norm(self.field.eci(t)))
