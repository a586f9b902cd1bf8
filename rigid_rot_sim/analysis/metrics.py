"""Errors of a computed final state against a reference state.

All states are in the principal body frame: ``q`` scalar-last, principal -> world;
``omega`` rad/s.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from rigid_rot_sim.core import quaternion as quat


def attitude_error_angle(q_ref: Any, q: Any) -> float:
    """Angle (rad) of the rotation taking attitude ``q_ref`` to ``q``, in [0, pi].

    ``2 atan2(|vec(dq)|, |w(dq)|)`` with ``dq = q_ref^-1 (x) q``: accurate down to
    round-off for tiny angles (where ``2 acos(w)`` loses half the digits) and
    insensitive to the sign of either quaternion.
    """
    dq = quat.multiply(quat.conjugate(quat.normalize(q_ref)), quat.normalize(q))
    return 2.0 * math.atan2(math.sqrt(dq[0] ** 2 + dq[1] ** 2 + dq[2] ** 2), abs(dq[3]))


def omega_error(omega_ref: Any, omega: Any) -> float:
    """Max-norm of the angular velocity error, rad/s."""
    return float(np.max(np.abs(np.asarray(omega, dtype=float) - np.asarray(omega_ref, dtype=float))))


def relative_change(reference: float, value: float) -> float:
    """``|value - reference| / |reference|`` (absolute change if the reference is 0)."""
    scale = abs(reference)
    return abs(value - reference) / scale if scale > 0.0 else abs(value - reference)
