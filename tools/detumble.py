"""A 3U CubeSat detumbling with B-dot (duty-cycled) or B-cross in IGRF-14: docs/spacecraft.md's plot.

    .venv/bin/python tools/detumble.py [--law bdot|bcross|both] [--orbits 3] [--out docs/images/detumble.png]

The loop the shipped scene ``cubesat_detumble`` is to run, in the core alone (no scene, no engine yet): a 3U
CubeSat (4 kg, 10 x 10 x 34 cm), 10 deg/s per body axis after separation, three orthogonal rods of 0.2 A*m^2, a
magnetometer at 10 Hz with 100 nT of white noise per reading (:func:`rigid_rot_sim.core.sensors.magnetometer_sample`,
seed 0), on a circular 500 km sun-synchronous orbit (inclination 97.4 deg, J2 secular rates) from
2026-01-01T00:00Z, in IGRF-14 (:mod:`rigid_rot_sim.core.geomagnetic`). The attitude integrator is the core's RK4 at
the magnetometer's period, the dipole held over each period (a zero-order hold, as flight software drives rods).
About 45 s for three orbits on one core.
"""

from __future__ import annotations

import argparse
import datetime as dt
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rigid_rot_sim.core import geomagnetic, magnetic_control, magnetorquer, orbit, sensors
from rigid_rot_sim.core.integrators import get_method

#: The 3U CubeSat: principal moments (kg*m^2) of a 4 kg box of 0.1 x 0.1 x 0.34 m.
CUBESAT_3U = (4.0 * (0.1**2 + 0.34**2) / 12.0, 4.0 * (0.1**2 + 0.34**2) / 12.0, 4.0 * (0.1**2 + 0.1**2) / 12.0)
EPOCH = dt.datetime(2026, 1, 1, tzinfo=dt.timezone.utc)
#: 100 nT per reading at 10 Hz.
MAGNETOMETER = sensors.MagnetometerModel(rate=10.0, noise_density=100e-9 / math.sqrt(10.0))


def orbit_field(altitude: float = 500e3, phase: float = 0.0, epoch: dt.datetime = EPOCH) -> geomagnetic.OrbitField:
    """IGRF-14 along a circular sun-synchronous orbit at ``altitude`` (m), argument of latitude ``phase`` (rad)."""
    kepler = orbit.kepler_orbit(
        orbit.EARTH_RADIUS + altitude, 0.0, math.radians(97.4), 0.3, 0.0, phase, j2=orbit.EARTH_J2
    )
    return geomagnetic.orbit_field("igrf14", kepler, epoch, None)


@dataclass
class HeldDipole:
    """The rods' torque for the integrator: the body dipole held over a step, in the field at (t, q)."""

    field_: geomagnetic.OrbitField
    dipole: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __call__(self, t: float, q: np.ndarray, omega: np.ndarray) -> np.ndarray:
        return np.cross(self.dipole, self.field_.body(t, q))


@dataclass(frozen=True)
class Detumble:
    """One run's record, every ``record_every`` samples: time (s), |omega| (rad/s), each rod's duty in [0, 1]."""

    t: np.ndarray
    rate: np.ndarray
    duty: np.ndarray
    below_at: float | None  # first time |omega| < the threshold, s


def run(
    law: str = "bdot",
    orbits: float = 3.0,
    *,
    omega0_deg: tuple[float, float, float] = (10.0, 10.0, 10.0),
    max_dipole: float = 0.2,
    gain: float = 1e5,
    threshold_deg: float = 0.5,
    stop_below: bool = False,
    record_every: int = 10,
    seed: int = 0,
) -> Detumble:
    """Run the loop; ``gain`` is B-dot's k (A*m^2*s/T; B-cross takes k |b|^2 of a 25 uT field, N*m*s)."""
    field_ = orbit_field()
    step = 1.0 / MAGNETOMETER.rate  # s
    rods = magnetorquer.Magnetorquers(axes=np.eye(3), max_dipoles=[max_dipole] * 3)
    torque = HeldDipole(field_)
    integrator = get_method("rk4")(CUBESAT_3U, step, torque, omega0=np.radians(omega0_deg))
    schedule = magnetic_control.BDotSchedule(gain=gain, sample_period=step, cycle_samples=10, sensing_samples=4)
    state = magnetic_control.BDotState.initial()
    reader = sensors.MagnetometerState()
    t_rec, rate_rec, duty_rec, below_at = [], [], [], None
    duty_sum = np.zeros(3)
    for k in range(int(orbits * field_.kepler.period / step)):
        b_true = field_.body(integrator.t, integrator.q)
        b_measured, reader = sensors.magnetometer_sample(MAGNETOMETER, seed, reader, b_true, integrator.t)
        if law == "bdot":
            state, m_body = magnetic_control.bdot_step(schedule, state, k, b_measured)
        else:
            m_body = magnetic_control.bcross_dipole(integrator.omega, b_measured, gain * (25e-6) ** 2)
        dipoles = magnetorquer.allocate(rods.axes, m_body, rods.max_dipoles)
        torque.dipole = rods.axes @ dipoles
        duty_sum += magnetorquer.rod_duty(dipoles, rods.max_dipoles)
        integrator.step()
        rate = float(np.linalg.norm(integrator.omega))
        if below_at is None and rate < math.radians(threshold_deg):
            below_at = integrator.t
            if stop_below:
                break
        if (k + 1) % record_every == 0:
            t_rec.append(integrator.t)
            rate_rec.append(rate)
            duty_rec.append(duty_sum / record_every)
            duty_sum = np.zeros(3)
    return Detumble(np.array(t_rec), np.array(rate_rec), np.array(duty_rec).reshape(-1, 3), below_at)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--law", choices=("bdot", "bcross", "both"), default="both")
    parser.add_argument("--orbits", type=float, default=3.0)
    parser.add_argument("--out", type=Path, default=Path("docs/images/detumble.png"))
    args = parser.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    laws = ("bdot", "bcross") if args.law == "both" else (args.law,)
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    period = orbit_field().kepler.period
    for law in laws:
        result = run(law, args.orbits)
        when = "not reached" if result.below_at is None else f"{result.below_at / period:.2f} orbits"
        print(f"{law}: |omega| < 0.5 deg/s after {when}; final {math.degrees(result.rate[-1]):.3f} deg/s")
        axes[0].semilogy(result.t / period, np.degrees(result.rate), label=f"{law} (< 0.5 deg/s: {when})")
        # the duty over 60 s windows: B-dot's sensing window caps it at 60 %
        window = 60
        n = len(result.duty) // window * window
        duty = result.duty[:n].reshape(-1, window, 3).mean(axis=1)
        axes[1].plot(result.t[window - 1 : n : window] / period, duty.mean(axis=1), label=f"{law}, mean of 3 rods")
    axes[0].axhline(0.5, color="k", lw=0.8, ls="--")
    axes[0].set_ylabel("|omega|, deg/s")
    axes[0].legend()
    axes[1].set_ylabel("rod duty |m|/m_max (60 s mean)")
    axes[1].set_xlabel("orbits (500 km SSO, 94.5 min)")
    axes[1].legend()
    fig.suptitle("3U CubeSat detumble: rods 0.2 A*m^2, magnetometer 10 Hz (100 nT), IGRF-14, 500 km SSO")
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
