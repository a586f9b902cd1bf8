"""The stepper of a spacecraft scene: reaction wheels and gravity gradient (the gyrostat integrators).

:class:`GyrostatStepper` is the :class:`~rigid_rot_sim.run.stepper.Stepper` of a scene with
``actuators.reaction_wheels`` or ``environment.gravity_gradient``: it runs a method of
:data:`~rigid_rot_sim.core.integrators.gyrostat.GYROSTAT_METHODS` (``auto``: ``dopri5``),
carries the wheel speeds and angles with the body's state, gives the integrator the wheel motor
torques of the :class:`~rigid_rot_sim.run.commands.CommandSchedule` at every boundary, and
reports the total angular momentum (body + wheels), the energy of eq. (6) of
:mod:`rigid_rot_sim.core.wheels` and every torque on the body by source.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core import validation
from rigid_rot_sim.core.integrators.gyrostat import GyrostatIntegrator, get_gyrostat_method
from rigid_rot_sim.core.wheels import (
    NO_ORBIT,
    friction_torque,
    gravity_gradient_torque,
    gyrostat_energy,
    total_momentum_body,
)
from rigid_rot_sim.run.observables import StateSnapshot, _relative_change
from rigid_rot_sim.run.stepper import Stepper, command_torques

__all__ = ["GyrostatStepper", "AUTO_METHOD", "make_stepper"]

#: What ``auto`` picks for a spacecraft scene: the adaptive method (its accuracy does not hang on dt).
AUTO_METHOD = "dopri5"


class GyrostatStepper(Stepper):
    """A :class:`Stepper` for scenes with reaction wheels or gravity gradient."""

    def configure(
        self, method: str, dt: float, options: dict[str, Any], *, first: bool = False, dry_run: bool = False
    ) -> None:
        dt = validation.positive_scalar("dt", dt)
        method = AUTO_METHOD if method == "auto" else method
        cls = get_gyrostat_method(method)
        spacecraft = self.scene.spacecraft
        if not hasattr(self, "_wheels"):
            wheels = spacecraft.wheel_model(self.scene.body.inertia_array)
            self._wheels_body = wheels
            self._wheels = (
                None
                if wheels is None
                else dataclasses.replace(wheels, axes=np.ascontiguousarray(self.body.vector_to_principal(wheels.axes)))
            )
            self._orbit = NO_ORBIT if spacecraft.gravity_gradient is None else spacecraft.gravity_gradient.model()
            self._orbit_data = self._orbit.compiled()  # built once: a Kepler orbit's array costs ~10 us
        if dry_run:
            cls(self.body.principal_moments, dt, wheels=self._wheels, orbit=self._orbit, **options)
            return
        state: tuple[Any, ...]
        if first:
            state = (
                0.0,
                self.body.attitude_to_principal(np.array(self.scene.initial.orientation)),
                np.zeros(3),
                self._initial_speeds(),
                None,
            )
        else:
            assert isinstance(self.integrator, GyrostatIntegrator)
            state = (
                self.integrator.t,
                self.integrator.q,
                self.integrator.omega,
                self.integrator.wheel_speeds,
                self.integrator.wheel_angles,
            )
        integrator = cls(
            self.body.principal_moments,
            dt,
            self.integrator.torque if self.integrator else None,
            wheels=self._wheels,
            orbit=self._orbit,
            t0=state[0],
            q0=state[1],
            omega0=state[2],
            wheel_speeds0=state[3],
            wheel_angles0=state[4],
            **options,
        )
        if self.integrator is not None:
            integrator.set_wheel_commands(self.integrator.wheel_commands)  # type: ignore[attr-defined]
        self.integrator = integrator
        self.method = method
        self.options = dict(options)
        if not first:
            self.clock.change_dt(dt)
            self.commands.reschedule()

    def _initial_speeds(self) -> np.ndarray:
        return np.array([w.initial_speed for w in self.scene.spacecraft.wheels], dtype=float)

    def restart(self) -> None:
        assert isinstance(self.integrator, GyrostatIntegrator)
        self.integrator.set_wheel_commands(np.zeros(len(self.scene.spacecraft.wheels)))
        self.integrator.wheel_speeds = self._initial_speeds()
        self.integrator.wheel_angles = np.zeros(len(self.scene.spacecraft.wheels))  # a reset zeroes the angles
        super().restart()

    def set_command_torque(self) -> None:
        super().set_command_torque()
        assert isinstance(self.integrator, GyrostatIntegrator)
        self.integrator.set_wheel_commands(self.commands.wheel_torques)

    def _saved_state(self) -> tuple[Any, ...]:
        assert isinstance(self.integrator, GyrostatIntegrator)
        return (*super()._saved_state(), self.integrator.wheel_speeds.copy(), self.integrator.wheel_angles.copy())

    def _restore(self, saved: tuple[Any, ...]) -> None:
        assert isinstance(self.integrator, GyrostatIntegrator)
        self.integrator.set_state(saved[0], saved[1], saved[2], wheel_speeds=saved[4], wheel_angles=saved[5])
        self.integrator.n_steps = saved[3]

    def _torque_bound(self) -> float:
        """Commands, plus the wheels' motor and friction torques, plus a bound on the gravity gradient."""
        bound = self.commands.norm_bound()
        for wheel in self.scene.spacecraft.wheels:
            bound += wheel.max_torque + wheel.coulomb + wheel.viscous * wheel.max_speed
        if self._orbit.enabled:
            moments = self.body.principal_moments
            bound += 1.5 * self._orbit_data[0] * float(np.max(moments) - np.min(moments))
        return bound

    def snapshot(self) -> StateSnapshot:
        """The snapshot with the wheels: total momentum and energy, wheel speeds and torques, torques by source."""
        integrator = self.integrator
        assert isinstance(integrator, GyrostatIntegrator)
        base = super().snapshot()
        body_from_principal = tuple(float(v) for v in self.body.body_from_principal)
        q = tuple(float(v) for v in base.orientation)
        momentum_body = base.angular_momentum_body
        energy = base.kinetic_energy
        sources = command_torques(self.commands, base.orientation)
        speeds = integrator.wheel_speeds.copy()
        applied = integrator.applied_wheel_torques()
        wheels = self._wheels_body
        if wheels is not None:
            # eqs. (1) and (6) of core.wheels, in the principal frame the integrator works in
            moments, principal_wheels = self.body.principal_moments, self._wheels
            assert principal_wheels is not None  # built with the body-frame wheels
            momentum = total_momentum_body(moments, principal_wheels, integrator.omega, speeds)
            momentum_body = np.array(quat.rotate(body_from_principal, momentum))
            energy = float(gyrostat_energy(moments, principal_wheels, integrator.omega, speeds))
            net = np.array(
                [
                    u - friction_torque(c, b, s, w)
                    for u, c, b, s, w in zip(
                        applied, wheels.coulomb, wheels.viscous, wheels.stiction_speed, speeds, strict=True
                    )
                ]
            )
            sources.append(("reaction_wheels", -(net @ wheels.axes)))
        if self._orbit.enabled:
            gg = gravity_gradient_torque(
                self._orbit_data, self.body.principal_moments, tuple(integrator.q), integrator.t
            )
            sources.append(("gravity_gradient", np.array(quat.rotate(body_from_principal, gg))))
        total = np.sum([v for _, v in sources], axis=0) if sources else np.zeros(3)
        momentum_world = np.array(quat.rotate(q, momentum_body))
        reference_energy = self.observables._energy_ref
        reference_momentum = self.observables._momentum_ref
        return dataclasses.replace(
            base,
            angular_momentum_body=momentum_body,
            angular_momentum_world=momentum_world,
            kinetic_energy=energy,
            torque_body=total,
            energy_drift=_relative_change(energy, reference_energy),
            angular_momentum_drift=_relative_change(math.hypot(*momentum_world), reference_momentum),
            wheel_names=self.scene.spacecraft.wheel_names,
            wheel_speeds=speeds,
            wheel_angles=integrator.wheel_angles.copy(),
            wheel_torques=applied,
            torque_sources=tuple(sources),
        )

    def set_body_state(self, q: np.ndarray, omega: np.ndarray) -> None:
        super().set_body_state(q, omega)  # the wheels keep their speeds and angles relative to the body


def make_stepper(scene: Any, *args: Any) -> Stepper:
    """The stepper of ``scene``: a :class:`GyrostatStepper` for a spacecraft scene, else a :class:`Stepper`."""
    return (GyrostatStepper if scene.spacecraft else Stepper)(scene, *args)
