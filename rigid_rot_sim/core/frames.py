"""Principal frame <-> user body frame (and body <-> world): the one home of the conversions' formulas on floats.

The integrators run in the body's *principal* frame; scenes, topics and outputs use the
user's body frame. :attr:`rigid_rot_sim.core.dynamics.RigidBody.body_from_principal`
(``q_bp``) rotates principal coordinates into body coordinates, so

* an attitude principal -> world ``q_p`` is the attitude body -> world ``q_p (x) q_bp^-1``;
* a vector (rate, momentum, torque) has body coordinates ``R(q_bp) v_p``;
* a world-frame vector (a torque command) has body coordinates ``R(q_b)^T v_w`` at the attitude
  body -> world ``q_b`` (:func:`vector_in_body`).

These functions are those formulas on the :mod:`~rigid_rot_sim.core.quaternion` helpers,
so they take plain floats (the run engine, once per step or publication) or equal-length
columns of arrays (the sweep, one body per row: each row gets the bits a per-body call
gives it). :class:`~rigid_rot_sim.core.dynamics.RigidBody`'s ``*_principal`` methods are the
same conversion for whole trajectories, on ``scipy.spatial.transform.Rotation``.

Users: :mod:`rigid_rot_sim.run.observables` (outputs), :mod:`rigid_rot_sim.run.stepper`
(commanded torque), :mod:`rigid_rot_sim.run.gyrostat_stepper` (wheel momentum, gravity gradient),
:func:`rigid_rot_sim.run.timeline.world_in_body` (world torques), :func:`rigid_rot_sim.core.simulate.principal_torque`
(a user's torque callable) and the sweep's chunks.

>>> q_bp = (0.0, 0.0, 0.5**0.5, 0.5**0.5)  # principal axes turned 90 deg about z
>>> [round(c, 12) + 0.0 for c in vector_from_principal(q_bp, (1.0, 0.0, 0.0))]
[0.0, 1.0, 0.0]
>>> [round(c, 12) + 0.0 for c in vector_to_principal(principal_from_body(q_bp), (0.0, 1.0, 0.0))]
[1.0, 0.0, 0.0]
>>> attitude_from_principal((0.0, 0.0, 0.0, 1.0), principal_from_body(q_bp)) == principal_from_body(q_bp)
True
"""

from __future__ import annotations

from typing import Any

from rigid_rot_sim.core import quaternion as quat

__all__ = [
    "attitude_from_principal",
    "attitude_to_principal",
    "principal_from_body",
    "vector_from_principal",
    "vector_in_body",
    "vector_to_principal",
]


def principal_from_body(body_from_principal: Any) -> Any:
    """The inverse rotation ``q_bp^-1`` (x, y, z, w): body coordinates into principal ones."""
    return quat.conjugate(body_from_principal)


def attitude_from_principal(q_principal: Any, principal_from_body: Any) -> Any:
    """Attitude principal -> world (x, y, z, w) -> attitude body -> world: ``q_p (x) q_bp^-1``."""
    return quat.multiply(q_principal, principal_from_body)


def attitude_to_principal(q_body: Any, body_from_principal: Any) -> Any:
    """Attitude body -> world (x, y, z, w) -> attitude principal -> world: ``q_b (x) q_bp``."""
    return quat.multiply(q_body, body_from_principal)


def vector_from_principal(body_from_principal: Any, v_principal: Any) -> Any:
    """Principal-frame coordinates of a vector -> user body-frame ones: ``R(q_bp) v_p``."""
    return quat.rotate(body_from_principal, v_principal)


def vector_to_principal(principal_from_body: Any, v_body: Any) -> Any:
    """User body-frame coordinates of a vector -> principal-frame ones: ``R(q_bp)^T v_b``."""
    return quat.rotate(principal_from_body, v_body)


def vector_in_body(q_body: Any, v_world: Any) -> Any:
    """World coordinates of a vector -> user body-frame ones at the attitude ``q_b`` (body -> world).

    ``R(q_b)^T v_w``.
    """
    return quat.rotate_inverse(q_body, v_world)
