"""The torque rods in the run engine's parts: dipole commands held with the wheels' rule (clamped and said, refused
with a reason), and the rods' torque on the step, ``(G_t clamp(m) + m_res) x b`` with IGRF's field at the step's
start, held over the step.

A scene with rods needs the Earth's field (``environment.magnetic_field`` on its ``orbit``); the stepper takes it
from the scene."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rigid_rot_sim.core import magnetorquer
from rigid_rot_sim.core.dynamics import RigidBody
from rigid_rot_sim.core.quaternion import rotate_inverse
from rigid_rot_sim.run.clock import StepClock
from rigid_rot_sim.run.commands import CommandRejected, CommandSchedule
from rigid_rot_sim.run.gyrostat_stepper import make_stepper
from rigid_rot_sim.run.observables import Observables
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.features import refuse_unhonoured
from rigid_rot_sim.scene.scene import SceneError, parse_scene_text

J = 0.02  # kg*m^2: a sphere, so a torque held over a step changes omega by exactly tau dt / J
SCENE = f"""
body: {{principal_moments: [{J}, {J}, {J}]}}
initial: {{angular_velocity: [0.1, -0.05, 0.08]}}
integrator: {{method: rk4, dt: 0.1}}
epoch: "2026-01-01T00:00:00Z"
orbit:
  elements: {{semi_major_axis: 6878137.0, eccentricity: 0.0, inclination_deg: 97.4, raan_deg: 17.0,
             argument_of_periapsis_deg: 0.0, true_anomaly_deg: 0.0}}
environment:
  magnetic_field: {{model: igrf14}}
actuators:
  magnetorquers:
    residual_dipole: [0.0, 0.0, 0.001]
    rods:
      - {{name: mtq_x, axis: [1, 0, 0], max_dipole: 0.2}}
      - {{name: mtq_y, axis: [0.6, 0.8, 0], max_dipole: 0.2}}
      - {{name: mtq_z, axis: [0, 0, 1], max_dipole: 0.1}}
"""


def parts(scene_text: str = SCENE):
    scene = parse_scene_text(scene_text)
    body = RigidBody.from_inertia(scene.body.inertia_array)
    clock = StepClock(scene.integrator.dt)
    commands = CommandSchedule(scene, clock)
    stepper = make_stepper(scene, body, Observables(scene, body), clock, commands, "rk4", {})
    return scene, clock, commands, stepper


def test_dipoles_are_held_from_their_step_clamped_and_refused_with_a_reason():
    _, clock, commands, _ = parts()
    assert commands.rod_dipoles == (0.0, 0.0, 0.0)
    step, clamped, which = commands.submit_rods("cli", [0.5, -0.1, -0.3], 0.25)
    assert (step, clamped, which) == (3, (0.2, -0.1, -0.1), (0, 2))  # t = 0.25 s lands on the boundary at 0.3 s
    commands.process_due()
    assert commands.rod_dipoles == (0.0, 0.0, 0.0)  # not yet
    clock.k = 3
    commands.process_due()
    assert commands.rod_dipoles == (0.2, -0.1, -0.1)
    clock.k = 300
    commands.process_due()
    assert commands.rod_dipoles == (0.2, -0.1, -0.1)  # held until the next command: no timeout
    for dipoles, reason in (
        ([0.1, 0.1], r"2 dipole\(s\) for 3 rod\(s\) \[mtq_x, mtq_y, mtq_z\]"),
        ([0.1, math.nan, 0.0], "non-finite dipole for rod 'mtq_y'"),
    ):
        with pytest.raises(CommandRejected, match=reason):
            commands.submit_rods("cli", dipoles, clock.t)
    _, _, plain, _ = parts(SCENE.split("actuators:")[0])
    with pytest.raises(CommandRejected, match="this scene has no torque rods"):
        plain.submit_rods("cli", [0.1], 0.0)


def test_rods_need_the_field_and_paths_that_do_not_run_them_refuse_them():
    no_field = SCENE.replace("environment:\n  magnetic_field: {model: igrf14}\n", "")
    with pytest.raises(SceneError, match="actuators.magnetorquers: the rods act on the Earth's field"):
        parse_scene_text(no_field)
    scene = parse_scene_text(SCENE)
    Simulator(scene)  # the engine runs them
    refuse_unhonoured(scene, "resim")  # resim replays the recorded rod commands
    for path in ("sweep", "simulate"):
        with pytest.raises(ValueError, match=f"^spacecraft.magnetorquers: not run by the {path} path"):
            refuse_unhonoured(scene, path)
    coupled = SCENE.replace("max_dipole: 0.1}", "max_dipole: 0.1, magnetometer_coupling: [0.0, 0.0, 1.0e-6]}")
    with pytest.raises(ValueError, match="^spacecraft.magnetorquers.coupling: not run by the engine path"):
        Simulator(parse_scene_text(coupled))


def test_the_rods_torque_acts_on_the_step_as_the_cores_law_in_igrf():
    scene, clock, commands, stepper = parts()
    assert stepper.rods.active
    commands.submit_rods("cli", [0.5, -0.1, 0.05], 0.0)
    stepper.set_command_torque()
    t0, q0, w0 = stepper.integrator.t, stepper.integrator.q.copy(), stepper.integrator.omega.copy()
    done, reason = stepper.advance(1)
    assert (done, reason) == (1, None)
    rods = scene.spacecraft.magnetorquers()
    b_body = np.array(rotate_inverse(q0, stepper.rods.field.eci(t0)))  # principal = body frame here (a sphere)
    tau = magnetorquer.torque(rods.axes, [0.5, -0.1, 0.05], b_body, rods.max_dipoles, rods.residual)
    assert abs(tau @ b_body) <= 1e-12 * np.linalg.norm(tau) * np.linalg.norm(b_body)
    np.testing.assert_allclose(stepper.integrator.omega, w0 + tau * clock.dt / J, rtol=0, atol=1e-16)
    sources = dict(stepper.snapshot().torque_sources)
    at_end = stepper.rods.torque(stepper.integrator.t, stepper.integrator.q, commands.rod_dipoles)
    np.testing.assert_allclose(sources["magnetorquers"], at_end, rtol=0, atol=0)
    # the rotation limit's bound holds the torque at any attitude: (sum of the limits + |m_res|) |b|
    assert np.linalg.norm(tau) <= stepper.rods.bound(t0) and stepper.rods.bound(t0) < 0.6 * np.linalg.norm(b_body)


def test_rods_off_leave_the_residual_dipole_acting():
    _, _, _, stepper = parts()
    stepper.set_command_torque()
    b_body = np.array(rotate_inverse(stepper.integrator.q, stepper.rods.field.eci(0.0)))
    residual = stepper.rods.torque(0.0, stepper.integrator.q, (0.0, 0.0, 0.0))
    np.testing.assert_allclose(residual, np.cross([0.0, 0.0, 0.001], b_body), rtol=1e-15, atol=1e-24)
