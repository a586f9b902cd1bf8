"""Magnetic attitude control laws: B-dot and B-cross detumbling, reaction-wheel momentum unloading.

Plain functions of body-frame vectors (SI: b in T, omega in rad/s, h in N*m*s, dipoles in A*m^2),
the flight-software side of :mod:`rigid_rot_sim.core.magnetorquer`; the rods then make
``tau = m x b``. A rod can only torque perpendicular to the field, so every law below is the
projection of a wanted torque on the plane normal to b.

**B-dot** (Stickler & Alfriend 1974, "Elementary magnetic attitude control system", JSR 13(5);
Markley & Crassidis 2014, *Fundamentals of Spacecraft Attitude Determination and Control*,
sec. 7.5): with the field nearly fixed in inertial space over a control cycle, its body-frame rate
is ``db/dt ~= -omega x b``, and

    m = -k db/dt   ~=  k (omega x b),    tau = -k |b|^2 omega_perp                 (1)

so the rate perpendicular to b decays, from the magnetometer alone (no gyro). ``db/dt`` is a
finite difference of two magnetometer samples. The rods' own field pollutes the magnetometer
(:mod:`.magnetorquer`, eq. (3)), so flight software *duty-cycles*: each control cycle of
``cycle_samples`` magnetometer samples opens with ``sensing_samples`` samples with the rods off
(the first ``settle_samples`` of them skipped while the coils' field decays), the difference is
taken across that window, and the rods then hold ``m`` for the rest of the cycle
(:func:`bdot_step`). ``sensing_samples = 0`` runs the law continuously on consecutive samples.

**B-cross** (the cross-product law of Markley & Crassidis 2014, sec. 7.5; Avanzini & Giulietti
2012, "Magnetic detumbling of a rigid spacecraft", JGCD 35(4), use the same structure), from a
rate measurement:

    m = k (omega x b) / |b|^2,    tau = m x b = -k omega_perp                         (2)

since ``(omega x b) x b = b (omega . b) - omega |b|^2``. On a spherical body (inertia J) in a
fixed field, (2) gives ``omega_par`` constant and ``omega_perp(t) = omega_perp(0) exp(-k t / J)``
exactly (the tests hold the integrators to it). k is in N*m*s.

**Momentum unloading** (Basilisk's ``mtbMomentumManagementSimple`` then ``torque2Dipole``): the
torque wanted from the rods is ``tau_req = -K h_w`` with ``h_w = sum J_i Omega_i g_i`` the wheels'
momentum in the body (relative speeds, :mod:`.wheels` eq. (1)); the dipole that makes its
component normal to b is

    m = (b x tau_req) / |b|^2 = K (h_w x b) / |b|^2,   tau = -K h_w,perp               (3)

and, beyond Basilisk's simple module, :func:`unloading_wheel_torque` gives the wheel motor
torques whose reaction cancels the rods' *achieved* torque (after the split on the rods and
their limits, :func:`rigid_rot_sim.core.magnetorquer.allocate`), so the body's rate is left
alone while the wheels shed momentum (``sum u_i g_i = tau_rods``, least squares). K is in 1/s.

Example
-------
>>> np.round(bcross_dipole([0.0, 0.0, 0.1], [2e-5, 0.0, 0.0], 1e-3), 9).tolist()   # k (w x b) / |b|^2
[0.0, 5.0, 0.0]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from rigid_rot_sim.core import validation
from rigid_rot_sim.core.arrays import ArrayLike, FloatArray


def bcross_dipole(omega: ArrayLike, b_body: ArrayLike, gain: float) -> FloatArray:
    """The B-cross dipole ``m = k (omega x b) / |b|^2`` (eq. (2)), A*m^2, body frame; zero where b = 0."""
    b = np.asarray(b_body, dtype=float)
    b2 = float(b @ b)
    if b2 == 0.0:
        return np.zeros(3)
    result: FloatArray = gain * np.cross(np.asarray(omega, dtype=float), b) / b2
    return result


def bdot_dipole(b_rate: ArrayLike, gain: float) -> FloatArray:
    """The B-dot dipole ``m = -k db/dt`` (eq. (1)), A*m^2, body frame; ``b_rate`` in T/s, k in A*m^2*s/T."""
    result: FloatArray = -gain * np.asarray(b_rate, dtype=float)
    return result


def unloading_dipole(h_wheels: ArrayLike, b_body: ArrayLike, gain: float) -> FloatArray:
    """The unloading dipole ``m = K (h_w x b) / |b|^2`` (eq. (3)), A*m^2, body frame; K in 1/s."""
    return bcross_dipole(h_wheels, b_body, gain)


def unloading_wheel_torque(wheel_axes: ArrayLike, rod_torque: ArrayLike) -> FloatArray:
    """Wheel motor torques u (N*m, one per wheel) with ``sum u_i g_i = tau_rods`` (least squares).

    ``wheel_axes`` (n, 3): the wheels' unit axes as rows (:class:`rigid_rot_sim.core.wheels.WheelModel`'s
    ``axes``); the body feels ``-sum u_i g_i``, which cancels the rods' torque on the body while the
    wheels take it up (:mod:`.wheels` eq. (4)).
    """
    result: FloatArray = np.linalg.pinv(np.asarray(wheel_axes, dtype=float).T) @ np.asarray(rod_torque, dtype=float)
    return result


def wheel_momentum(wheel_axes: ArrayLike, spin_inertias: ArrayLike, speeds: ArrayLike) -> FloatArray:
    """The wheels' momentum ``h_w = sum J_i Omega_i g_i`` in the body, N*m*s (:mod:`.wheels` eq. (1))."""
    result: FloatArray = np.asarray(wheel_axes, dtype=float).T @ (
        np.asarray(spin_inertias, dtype=float) * np.asarray(speeds, dtype=float)
    )
    return result


@dataclass(frozen=True)
class BDotSchedule:
    """The duty cycle of a sampled B-dot controller (module docstring, eq. (1)).

    ``gain`` k (A*m^2*s/T); ``sample_period`` of the magnetometer (s); ``cycle_samples`` per
    control cycle; ``sensing_samples`` at the start of each cycle with the rods off (0: no duty
    cycle, the law runs on consecutive samples); ``settle_samples`` of those skipped before the
    first sample of the difference. The difference spans ``sensing_samples - 1 - settle_samples``
    sample periods, so ``sensing_samples >= settle_samples + 2`` when duty-cycling.
    """

    gain: float
    sample_period: float
    cycle_samples: int = 10
    sensing_samples: int = 3
    settle_samples: int = 1

    def __post_init__(self) -> None:
        validation.positive_scalar("gain", self.gain)
        validation.positive_scalar("sample_period", self.sample_period)
        if self.sensing_samples == 0:
            return
        if not self.settle_samples >= 0 or not self.sensing_samples >= self.settle_samples + 2:
            raise ValueError(
                f"sensing_samples ({self.sensing_samples}) must be 0 or >= settle_samples "
                f"({self.settle_samples}) + 2: the difference needs two samples with the rods settled off"
            )
        if not self.cycle_samples > self.sensing_samples:
            raise ValueError(
                f"cycle_samples ({self.cycle_samples}) must exceed sensing_samples ({self.sensing_samples}):"
                " a cycle with no torquing never detumbles"
            )

    @property
    def duty(self) -> float:
        """The fraction of a cycle with the rods on (1 without duty cycling)."""
        return 1.0 - self.sensing_samples / self.cycle_samples if self.sensing_samples else 1.0


class BDotState(NamedTuple):
    """What a sampled B-dot controller remembers between samples (body frame).

    ``first``: the field at the start of the difference, T (NaN until sampled); ``dipole``: the
    body dipole the rods hold, A*m^2.
    """

    first: np.ndarray
    dipole: np.ndarray

    @classmethod
    def initial(cls) -> BDotState:
        """Nothing sampled yet, rods off."""
        return cls(np.full(3, np.nan), np.zeros(3))


def bdot_step(
    schedule: BDotSchedule, state: BDotState, index: int, b_measured: ArrayLike
) -> tuple[BDotState, FloatArray]:
    """Feed the magnetometer sample ``index`` (0, 1, ...) and get the body dipole to hold until the next one.

    The dipole is A*m^2 in the body frame (zero while sensing); split it on the rods with
    :func:`rigid_rot_sim.core.magnetorquer.allocate`. The first difference needs two samples, so the
    rods stay off until then.
    """
    b = np.asarray(b_measured, dtype=float)
    if schedule.sensing_samples == 0:
        dipole = (
            np.zeros(3)
            if np.isnan(state.first[0])
            else bdot_dipole((b - state.first) / schedule.sample_period, schedule.gain)
        )
        return BDotState(b, dipole), dipole
    phase = index % schedule.cycle_samples
    last = schedule.sensing_samples - 1
    if phase < schedule.sensing_samples:
        # the difference starts afresh each cycle: a missed settle sample leaves no stale start behind
        first = b if phase == schedule.settle_samples else state.first
        if phase < schedule.settle_samples:
            first = np.full(3, np.nan)
        dipole = np.zeros(3)
        if phase == last and not np.isnan(first[0]):
            span = (last - schedule.settle_samples) * schedule.sample_period
            dipole = bdot_dipole((b - first) / span, schedule.gain)
        # the command waits for the window to close: the rods stay off through its last sample
        return BDotState(first, dipole), np.zeros(3)
    return state, state.dipole
