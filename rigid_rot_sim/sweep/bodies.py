"""The bodies of a chunk as a sweep runs them, and what their runs give back.

:class:`Bodies` holds N dispersed bodies' inputs (principal frames as the batch runs them, body
frame as the rows report them); :class:`Outcome` their final states, failures and checkpoint
figures, whichever path ran them (the batch kernels of :mod:`~rigid_rot_sim.sweep.chunks`, or
the run engine per sample, :mod:`~rigid_rot_sim.sweep.engine_runs`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = ["Bodies", "Outcome", "subset", "concat", "split"]


@dataclass
class Bodies:
    """N bodies' inputs, as the batch runs them (principal frames) and as rows report them."""

    moments: np.ndarray  # (N, 3) kg*m^2, principal
    body_from_principal: Rotation  # N rotations (scipy renormalises: the engine's conversions of the initial state)
    body_from_principal_quat: np.ndarray  # (N, 4) the quaternions as given: the engine's frames formulas take these
    q0_body: np.ndarray  # (N, 4)
    omega0_body: np.ndarray  # (N, 3)
    torque_scale: np.ndarray  # (N, 3) multiplies the scheduled body torque
    noise: np.ndarray  # (N, intervals, 3) N*m, body
    misalignment: np.ndarray  # (N,) rad
    attitude0_error: np.ndarray  # (N,) rad
    orbit_phase: np.ndarray  # (N,) rad added to the orbit's true anomaly at t = 0
    epoch_offset: np.ndarray  # (N,) s added to the scene's epoch (whole microseconds)


@dataclass
class Outcome:
    """N runs' ends (body frame; NaN for a failed run, its error in ``errors`` by index) and checkpoint figures.

    ``omega_bound`` (rad/s): what |omega| cannot exceed without a numerical drift (the verdict of a
    run under torque); ``energy_drift`` and ``momentum_drift`` are relative, for torque-free runs;
    ``field_body`` (T, body frame) the true field at the end (NaN: a scene without a field, a failed run).
    """

    q_body: np.ndarray
    omega_body: np.ndarray
    errors: dict[int, str]
    max_omega: np.ndarray
    energy_drift: np.ndarray
    momentum_drift: np.ndarray
    omega_bound: np.ndarray
    first_flip: np.ndarray
    nutation_range: np.ndarray
    field_body: np.ndarray


def subset(bodies: Bodies, mask: np.ndarray) -> Bodies:
    """The bodies selected by ``mask``."""
    return Bodies(**{f.name: getattr(bodies, f.name)[mask] for f in fields(Bodies)})


def concat(a: Bodies, b: Bodies) -> Bodies:
    """The bodies of ``a``, then those of ``b``."""

    def join(x: Any, y: Any) -> Any:
        return Rotation.concatenate([x, y]) if isinstance(x, Rotation) else np.concatenate((x, y))

    return Bodies(**{f.name: join(getattr(a, f.name), getattr(b, f.name)) for f in fields(Bodies)})


def split(outcome: Outcome, n: int) -> tuple[Outcome, Outcome]:
    """The first n bodies' outcome and the rest's."""

    def part(select: slice, offset: int) -> Outcome:
        return Outcome(
            q_body=outcome.q_body[select],
            omega_body=outcome.omega_body[select],
            errors={i - offset: m for i, m in outcome.errors.items() if select.start <= i < (select.stop or 1 << 62)},
            max_omega=outcome.max_omega[select],
            energy_drift=outcome.energy_drift[select],
            momentum_drift=outcome.momentum_drift[select],
            omega_bound=outcome.omega_bound[select],
            first_flip=outcome.first_flip[select],
            nutation_range=outcome.nutation_range[select],
            field_body=outcome.field_body[select],
        )

    return part(slice(0, n), 0), part(slice(n, None), n)
