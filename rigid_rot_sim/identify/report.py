"""Validation replays and the outputs of an identification: the summary, the JSON object, the body YAML.

A replay re-simulates the whole window from one initial state (the rate the fit found at the
window's start, the measured attitude there) with a given tensor, and reads it as the gyro
would (plus the gyro bias of that model). Its residuals against the measurements, RMS over the
samples and axes (rad/s) and the attitude angle RMS (rad, when the bag has an attitude), say
how well the model replays the bag.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.sensitivities import integrate_segments
from rigid_rot_sim.identify.data import Measurements
from rigid_rot_sim.identify.fit import Identification, build_grid


@dataclass(frozen=True)
class SimulatedWindow:
    """One model replayed over the window: the gyro it predicts (n, 3) rad/s, its attitude (n, 4) or None."""

    label: str
    inertia: np.ndarray
    omega: np.ndarray
    orientation: np.ndarray | None
    omega_rms: float
    attitude_rms: float | None


@dataclass(frozen=True)
class Validation:
    """The bag replayed with the nominal tensor (None when there is none) and with the identified one."""

    nominal: SimulatedWindow | None
    identified: SimulatedWindow


def simulate_window(
    measurements: Measurements,
    inertia: np.ndarray,
    omega0: np.ndarray,
    label: str,
    torque_bias: np.ndarray | None = None,
    gyro_bias: np.ndarray | None = None,
    max_step: float = 0.005,
) -> SimulatedWindow:
    """Re-simulate the window from ``omega0`` (rad/s, true rate at the first sample) with ``inertia`` (kg*m^2)."""
    grid = build_grid(measurements, math.inf, max_step)
    q0 = measurements.orientation[0] if measurements.orientation is not None else np.array([0.0, 0.0, 0.0, 1.0])
    omega, _, q = integrate_segments(
        grid.node_t, grid.node_torque, grid.node_sample, grid.segment_nodes, np.asarray(inertia, dtype=float),
        np.zeros((0, 3, 3)), np.zeros(3) if torque_bias is None else torque_bias,
        np.asarray(omega0, dtype=float).reshape(1, 3), q0.reshape(1, 4), measurements.t.shape[0], False,
    )  # fmt: skip
    reading = omega + (0.0 if gyro_bias is None else gyro_bias)
    omega_rms = float(np.sqrt(np.mean((reading - measurements.omega) ** 2)))
    attitude_rms = None
    if measurements.orientation is not None:
        angles = (Rotation.from_quat(measurements.orientation).inv() * Rotation.from_quat(q)).magnitude()
        attitude_rms = float(np.sqrt(np.mean(angles**2)))
    orientation = q if measurements.orientation is not None else None
    return SimulatedWindow(label, np.asarray(inertia, dtype=float), reading, orientation, omega_rms, attitude_rms)


def validate(measurements: Measurements, result: Identification, nominal: np.ndarray | None) -> Validation:
    """Replays with the nominal tensor (if given) and the identified model, from the fitted initial rate."""
    omega0 = result.segment_omega0[0]
    identified = simulate_window(
        measurements, result.inertia, omega0, "identified", result.torque_bias, result.gyro_bias
    )
    nominal_replay = None
    if nominal is not None:
        tensor = np.asarray(nominal, dtype=float)
        if result.identifiable == "ratios":
            tensor = tensor / np.trace(tensor)  # no torque: only the ratios matter, compare like with like
        nominal_replay = simulate_window(measurements, tensor, omega0, "nominal")
    return Validation(nominal_replay, identified)


def _matrix(a: np.ndarray | None) -> Any:
    return None if a is None else np.asarray(a, dtype=float).tolist()


def as_json(result: Identification, validation: Validation | None, sources: dict[str, str]) -> dict[str, Any]:
    """The JSON object of ``rigid-rot identify --json`` (SI units, body frame of the measurements)."""

    def rms(r: SimulatedWindow | None) -> Any:
        return None if r is None else {"omega": r.omega_rms, "attitude": r.attitude_rms}

    return {
        "inertia": _matrix(result.inertia),
        "inertia_sigma": _matrix(result.inertia_sigma),
        "inertia_covariance": _matrix(result.inertia_covariance),
        "principal_moments": _matrix(result.principal_moments),
        "principal_moments_sigma": _matrix(result.principal_moments_sigma),
        "principal_axes": _matrix(result.principal_axes),
        "identifiable": result.identifiable,
        "torque_bias": _matrix(result.torque_bias),
        "torque_bias_sigma": _matrix(result.torque_bias_sigma),
        "gyro_bias": _matrix(result.gyro_bias),
        "gyro_bias_sigma": _matrix(result.gyro_bias_sigma),
        "residual_rms": result.residual_rms,
        "noise_sigma": _matrix(result.noise_sigma),
        "unobservable": list(result.unobservable),
        "warnings": list(result.warnings),
        "samples": result.n_samples,
        "validation": None
        if validation is None
        else {"nominal_rms": rms(validation.nominal), "identified_rms": rms(validation.identified)},
        "sources": sources,
    }


def body_yaml(result: Identification) -> str:
    """A scene's ``body`` section with the identified tensor (``inertia_tensor``, kg*m^2)."""
    if result.identifiable != "full":
        raise ValueError("the bag has no torque, so only the ratios of the inertia are known: no body to write")
    rows = "\n".join(f"    - [{', '.join(repr(float(v)) for v in row)}]" for row in result.inertia)
    sigma = ", ".join(f"{v:.3g}" for v in result.principal_moments_sigma)
    return (
        "# identified by rigid-rot identify: kg*m^2, body frame of the measurements\n"
        f"# principal moments {', '.join(f'{v:.6g}' for v in result.principal_moments)} +- {sigma} (1 sigma)\n"
        f"body:\n  inertia_tensor:\n{rows}\n"
    )


def summary(result: Identification, validation: Validation | None) -> str:
    """The human summary."""
    unit = "kg*m^2" if result.identifiable == "full" else "(unit trace: ratios only)"
    lines = [f"inertia tensor {unit}, body frame, +- 1 sigma:"]
    for row, sig in zip(result.inertia, result.inertia_sigma, strict=True):
        lines.append("  [" + ", ".join(f"{v: .6g} +- {s:.2g}" for v, s in zip(row, sig, strict=True)) + "]")
    lines.append(
        "principal moments: "
        + ", ".join(
            f"{v:.6g} +- {s:.2g}" for v, s in zip(result.principal_moments, result.principal_moments_sigma, strict=True)
        )
    )
    if result.torque_bias is not None and result.torque_bias_sigma is not None:
        lines.append(f"torque bias (N*m, body): {_pm(result.torque_bias, result.torque_bias_sigma)}")
    if result.gyro_bias is not None and result.gyro_bias_sigma is not None:
        lines.append(f"gyro bias (rad/s, body): {_pm(result.gyro_bias, result.gyro_bias_sigma)}")
    lines.append(
        f"identifiable: {result.identifiable}; {result.n_samples} samples; "
        f"residual RMS {result.residual_rms:.3g} rad/s "
        f"(per axis {', '.join(f'{v:.3g}' for v in result.noise_sigma)})"
    )
    lines += [f"warning: {w}" for w in result.warnings]
    lines += list(result.unobservable)
    if validation is not None:
        for r in (validation.nominal, validation.identified):
            if r is not None:
                att = "" if r.attitude_rms is None else f", attitude RMS {r.attitude_rms:.3g} rad"
                lines.append(f"replay with the {r.label} inertia: rate RMS {r.omega_rms:.3g} rad/s{att}")
    return "\n".join(lines)


def _pm(values: np.ndarray, sigma: np.ndarray) -> str:
    return "[" + ", ".join(f"{v:.4g} +- {s:.2g}" for v, s in zip(values, sigma, strict=True)) + "]"
