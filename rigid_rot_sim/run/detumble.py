"""A B-dot detumble run in the engine, without ROS: the shipped controller's loop, one magnetometer sample a turn.

:func:`run_bdot` drives a :class:`~rigid_rot_sim.run.simulator.Simulator` on a scene with torque rods, a
magnetometer and the Earth's field (``cubesat_detumble``): at each magnetometer sample it reads the magnetometer
(:class:`~rigid_rot_sim.run.sensors.SensorSuite`, the scene's seed: the node's readings, bit for bit), feeds the
duty-cycled B-dot law (:func:`rigid_rot_sim.core.magnetic_control.bdot_step`), splits the body dipole on the rods
(:func:`rigid_rot_sim.core.magnetorquer.allocate`) and submits it as the node's ``~/magnetorquer_command`` would
(:meth:`Simulator.submit_rod_dipoles`), then steps to the next sample. The detumble time is the first sample time
at which |omega| is below the threshold.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rigid_rot_sim.core import magnetic_control, magnetorquer
from rigid_rot_sim.core.steps import whole_steps
from rigid_rot_sim.run.sensors import SensorSuite
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import Scene

__all__ = ["BDOT_GAIN", "DETUMBLED_RATE", "DetumbleRun", "run_bdot"]

#: The shipped B-dot gain, A*m^2*s/T (docs/spacecraft.md: k |b|^2 / J ~ 1/700 s for a 3U CubeSat in 25 uT).
BDOT_GAIN = 1e5
#: Below this |omega| (rad/s) the body counts as detumbled: 0.5 deg/s.
DETUMBLED_RATE = math.radians(0.5)
#: The command source of the rods' dipoles (the node's topic).
SOURCE = "~/magnetorquer_command"


@dataclass(frozen=True)
class DetumbleRun:
    """One run: ``detumble_time`` (s, None if never below ``DETUMBLED_RATE``), and per sample the time ``t``
    (s), ``rate`` |omega| (rad/s) and the rods' ``duty`` (|m_i| / max_i, shape (n, rods))."""

    detumble_time: float | None
    t: np.ndarray
    rate: np.ndarray
    duty: np.ndarray
    digest: int


def run_bdot(
    scene: Scene,
    duration: float | None = None,
    *,
    gain: float = BDOT_GAIN,
    cycle_samples: int = 10,
    sensing_samples: int = 4,
    stop_when_detumbled: bool = False,
) -> DetumbleRun:
    """Run B-dot on ``scene`` for ``duration`` s (default the scene's); the scene's dt must divide the sample period."""
    magnetometer = scene.sensors.magnetometer
    rods = scene.spacecraft.magnetorquers()
    if magnetometer is None or rods is None:
        raise ValueError(f"{scene.name}: B-dot needs sensors.magnetometer and actuators.magnetorquers")
    sim = Simulator(scene)
    sensors = SensorSuite(scene.sensors, field=scene.orbit_field())
    period = 1.0 / magnetometer.rate
    steps = whole_steps(period, sim.clock.dt)
    if steps is None:
        raise ValueError(f"{scene.name}: dt {sim.clock.dt:g} s does not divide the magnetometer's period {period:g} s")
    schedule = magnetic_control.BDotSchedule(gain, period, cycle_samples, sensing_samples)
    state = magnetic_control.BDotState.initial()
    end = scene.duration if duration is None else duration
    if end is None:
        raise ValueError(f"{scene.name}: give a duration (the scene has none)")
    t, rate, duty, detumbled = [], [], [], None
    for k in range(int(end / period + 1e-9)):
        snapshot = sim.snapshot()
        speed = float(np.linalg.norm(snapshot.angular_velocity_body))
        t.append(snapshot.t)
        rate.append(speed)
        if detumbled is None and speed < DETUMBLED_RATE:
            detumbled = snapshot.t
            if stop_when_detumbled:
                break
        state, m_body = magnetic_control.bdot_step(schedule, state, k, sensors.read_magnetometer(snapshot))
        dipoles = magnetorquer.allocate(rods.axes, m_body, rods.max_dipoles)
        duty.append(magnetorquer.rod_duty(dipoles, rods.max_dipoles))
        sim.submit_rod_dipoles(SOURCE, dipoles)
        if sim.advance(steps) != steps:
            raise RuntimeError(f"{scene.name}: the run failed at t = {sim.clock.t:g} s: {sim.failure}")
    return DetumbleRun(
        detumbled, np.array(t), np.array(rate), np.array(duty).reshape(-1, rods.count), sim.snapshot().digest
    )
