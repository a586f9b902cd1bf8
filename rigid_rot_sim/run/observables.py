"""What a user sees of the integrator's state: the scene's body frame, energies, drifts.

Integrators work in the principal frame of the body (diagonal inertia); a scene's body
frame may be any frame fixed in the body. :class:`Observables` turns a principal-frame
state into a :class:`StateSnapshot` in the user's frames (body -> world quaternion
``(x, y, z, w)``, vectors in the user body and world frames), with the gravity quantities
of a heavy top and the drifts of energy and |L| since a reference state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core import frames
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.dynamics import RigidBody
from rigid_rot_sim.core.torque import GravityTorque
from rigid_rot_sim.scene.scene import Scene

__all__ = ["Observables", "StateSnapshot"]

#: A drift reference (J, kg*m^2/s) below this counts as zero (drift 0, as for a body at rest):
#: relative to it, any real change would overflow a float.
_TINY_REFERENCE = 1e-250


@dataclass(frozen=True)
class StateSnapshot:
    """The state at one step boundary, in the scene's frames (user body frame, world frame).

    Units: s, rad/s, kg*m^2/s, N*m, J. ``orientation`` is the unit quaternion (x, y, z, w)
    rotating body -> world. ``torque_body`` is the total torque over the step that ended
    here (gravity at this state for a top). The drifts are ``(E - E_ref) / |E_ref|`` and
    ``(|L| - |L_ref|) / |L_ref|`` since the last reset or set_state (0 when the reference
    is 0, i.e. a body at rest). ``euler_zxz`` (rad: precession, nutation, spin of the
    symmetry axis pivot -> centre of mass), ``p_phi`` and ``p_psi`` (kg*m^2/s) are set for
    gravity scenes only.
    """

    t: float
    step: int
    orientation: np.ndarray
    angular_velocity_body: np.ndarray
    angular_velocity_world: np.ndarray
    angular_momentum_body: np.ndarray
    angular_momentum_world: np.ndarray
    torque_body: np.ndarray
    kinetic_energy: float
    potential_energy: float
    energy_drift: float
    angular_momentum_drift: float
    euler_zxz: np.ndarray | None = None
    p_phi: float | None = None
    p_psi: float | None = None
    #: Reaction wheels (scene order): speeds relative to the body (rad/s) and the motor torques acting (N*m).
    wheel_names: tuple[str, ...] | None = None
    wheel_speeds: np.ndarray | None = None
    #: Reaction wheel angles relative to the body (rad, unwrapped: continuous, 0 at the start and after a reset).
    wheel_angles: np.ndarray | None = None
    wheel_torques: np.ndarray | None = None
    #: Every torque acting on the body at this state, by source, N*m, user body frame (their sum is ``torque_body``).
    torque_sources: tuple[tuple[str, np.ndarray], ...] | None = None
    #: The run digest up to this step (:mod:`~rigid_rot_sim.run.digest`), an unsigned 64-bit integer.
    digest: int = 0

    @property
    def energy(self) -> float:
        """Total energy, J."""
        return self.kinetic_energy + self.potential_energy


class Observables:
    """The user-frame view of ``body`` in ``scene``: frames, gravity (a heavy top) and drift references.

    ``gravity`` is the gravity torque model (principal frame) of a gravity scene, else None;
    ``weight`` (N) and ``com_body`` (m, user body frame) describe it.
    """

    def __init__(self, scene: Scene, body: RigidBody) -> None:
        self.body = body
        self.gravity: GravityTorque | None = None
        self.com_body = np.zeros(3)  # m; no gravity: no weight, so no torque from it
        self.weight = 0.0
        if scene.gravity is not None:
            assert scene.body.mass is not None and scene.body.center_of_mass is not None
            self.com_body = np.array(scene.body.center_of_mass, dtype=float)
            self.weight = scene.body.mass * scene.gravity.acceleration
            self.gravity = GravityTorque(body.vector_to_principal(self.com_body), self.weight)
            self._symmetry_axis = self.com_body / np.linalg.norm(self.com_body)
            # frame whose z is the symmetry axis, for the heavy top's Euler angles
            align, _ = Rotation.align_vectors([self._symmetry_axis], [[0.0, 0.0, 1.0]])
            self._body_from_top = tuple(float(v) for v in align.as_quat())
        self._body_from_principal = tuple(float(v) for v in body.body_from_principal)
        #: Rotation from the user body frame to the principal frame (x, y, z, w).
        self.principal_from_body = frames.principal_from_body(self._body_from_principal)
        self._energy_ref = 0.0
        self._momentum_ref = 0.0

    def set_reference(self, reference: StateSnapshot) -> None:
        """Measure the drifts from ``reference`` on (its energy and |L|)."""
        self._energy_ref = reference.energy
        self._momentum_ref = math.hypot(*reference.angular_momentum_world)

    def gravity_torque_bound(self) -> float:
        """The largest gravity torque (N*m) on the body: weight times the centre-of-mass distance."""
        return self.weight * float(np.linalg.norm(self.com_body))

    def snapshot(
        self, t: float, step: int, q_principal: Any, omega_principal: Any, torque_body: Any, digest: int = 0
    ) -> StateSnapshot:
        """The snapshot of the principal-frame state (``q``, ``ω``) under ``torque_body`` (N*m, user body frame);
        ``digest``: the run digest up to this step."""
        # plain floats and the quaternion helpers: this runs at every publication
        i1, i2, i3 = (float(v) for v in self.body.principal_moments)
        q_principal = tuple(float(v) for v in q_principal)
        w1, w2, w3 = (float(v) for v in omega_principal)
        body_from_principal = self._body_from_principal
        q = frames.attitude_from_principal(q_principal, self.principal_from_body)
        if q[3] < 0.0:
            q = (-q[0], -q[1], -q[2], -q[3])  # same rotation; w >= 0 keeps outputs continuous near identity
        omega_body = frames.vector_from_principal(body_from_principal, (w1, w2, w3))
        momentum_body = frames.vector_from_principal(body_from_principal, (i1 * w1, i2 * w2, i3 * w3))
        momentum_world = quat.rotate(q, momentum_body)
        kinetic = 0.5 * (i1 * w1 * w1 + i2 * w2 * w2 + i3 * w3 * w3)
        potential = 0.0
        euler = p_phi = p_psi = None
        if self.gravity is not None:
            potential = self.weight * quat.rotate(q, self.com_body)[2]
            gravity_principal = self.gravity(0.0, np.array(q_principal), np.array((w1, w2, w3)))
            gravity = frames.vector_from_principal(body_from_principal, gravity_principal)
            torque_body = tuple(a + b for a, b in zip(torque_body, gravity, strict=True))
            euler = np.array(quat.quaternion_to_zxz(quat.multiply(q, self._body_from_top)))
            p_phi = momentum_world[2]
            p_psi = float(np.dot(momentum_body, self._symmetry_axis))
        energy = kinetic + potential
        momentum = math.hypot(*momentum_world)
        return StateSnapshot(
            t=t,
            step=step,
            orientation=np.array(q),
            angular_velocity_body=np.array(omega_body),
            angular_velocity_world=np.array(quat.rotate(q, omega_body)),
            angular_momentum_body=np.array(momentum_body),
            angular_momentum_world=np.array(momentum_world),
            torque_body=np.array(torque_body, dtype=float),
            kinetic_energy=kinetic,
            potential_energy=potential,
            energy_drift=_relative_change(energy, self._energy_ref),
            angular_momentum_drift=_relative_change(momentum, self._momentum_ref),
            euler_zxz=euler,
            p_phi=p_phi,
            p_psi=p_psi,
            digest=digest,
        )


def _relative_change(value: float, reference: float) -> float:
    if abs(reference) < _TINY_REFERENCE:
        return 0.0
    return (value - reference) / abs(reference)
