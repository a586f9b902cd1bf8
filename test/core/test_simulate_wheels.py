"""``simulate`` with reaction wheels and the gravity gradient: closed forms, conservation laws, the engine's bits."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core.integrators.gyrostat import GYROSTAT_METHODS
from rigid_rot_sim.core.simulate import simulate
from rigid_rot_sim.core.wheels import orbit_model, wheel_model
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.scene import load_scene

SCENES = Path(__file__).resolve().parents[2] / "config" / "scenes"
MOMENTS = np.array([10.0, 12.0, 15.0])
METHODS = sorted(GYROSTAT_METHODS)
# a user body frame that is not the principal one: the inertia tensor and the wheel axis are rotated alike
TILT = Rotation.from_rotvec([0.3, -0.5, 0.7]).as_matrix()


def three_wheels():
    return wheel_model(
        np.diag(MOMENTS), ["a", "b", "c"], [[1, 0, 0], [0, 1, 0], [1, 1, 1]], [0.1, 0.2, 0.15], [0.2] * 3, [600.0] * 3
    )


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("tilted", [False, True])
def test_single_wheel_on_a_principal_axis_follows_the_closed_form(method, tilted):
    """Wheel and spin on principal axis 3, constant motor torque u (test_wheels.py's derivation):
    (I3 - J) dw3/dt = -u and J (dw3/dt + dOmega/dt) = u, so w3 and Omega are linear in t and the
    attitude is a rotation about axis 3 by w0 t - u t^2 / (2 (I3 - J)). t_end is off the grid of dt:
    the last, shorter step lands on it."""
    spin, u, w0, speed0, t_end = 0.5, 0.05, 0.2, 10.0, 10.004
    frame = TILT if tilted else np.eye(3)
    inertia = frame @ np.diag(MOMENTS) @ frame.T
    axis = frame[:, 2]
    wheels = wheel_model(inertia, ["z"], [axis], [spin], [0.1], [1000.0])
    traj = simulate(
        inertia, 0.0 * axis + w0 * axis, t_end, 0.01, method, wheels=wheels, wheel_speeds0=[speed0], wheel_torque=[u]
    )
    assert traj.wheel_speeds.shape == (1002, 1) and traj.t[-1] == t_end
    t = traj.t
    i3 = MOMENTS[2]
    rate = w0 - u * t / (i3 - spin)
    np.testing.assert_allclose(traj.omega @ axis, rate, rtol=1e-11, atol=0)
    np.testing.assert_allclose(traj.omega - np.outer(traj.omega @ axis, axis), 0.0, atol=1e-12)
    np.testing.assert_allclose(traj.wheel_speeds[:, 0], speed0 + u * i3 / (spin * (i3 - spin)) * t, rtol=1e-11)
    angle = w0 * t - 0.5 * u * t * t / (i3 - spin)
    expected = Rotation.from_rotvec(angle[:, None] * axis)
    error = (Rotation.from_quat(traj.q) * expected.inv()).magnitude()
    assert np.max(error) < 1e-9
    # internal torque: the total momentum (body + wheel) stays I3 w0 + J Omega0 along the axis
    np.testing.assert_allclose(traj.L_world, np.outer(np.ones(len(t)), (i3 * w0 + spin * speed0) * axis), atol=1e-11)


@pytest.mark.parametrize("method", METHODS)
def test_total_world_momentum_and_energy_are_conserved_with_free_frictionless_wheels(method):
    """No motor, no friction, no external torque: R(q) H and T are invariants (to the method's accuracy);
    and the body alone does exchange momentum with the wheels, so the test sees the wheels' part."""
    wheels = three_wheels()
    traj = simulate(MOMENTS, (0.1, 0.3, -0.2), 20.0, 0.02, method, wheels=wheels, wheel_speeds0=(50.0, -20.0, 30.0))
    h = traj.L_world
    momentum_drift = np.max(np.linalg.norm(h - h[0], axis=1)) / np.linalg.norm(h[0])
    energy_drift = np.max(np.abs(traj.energy - traj.energy[0])) / traj.energy[0]
    # dopri5 at rtol 1e-10 drifts ~4e-11, rk4 at dt = 20 ms ~2e-10 (its order is test_wheels.py's business)
    limit = 1e-9 if method == "dopri5" else 1e-8
    assert momentum_drift < limit and energy_drift < limit, (momentum_drift, energy_drift)
    body_only = np.einsum("nij,nj->ni", Rotation.from_quat(traj.q).as_matrix(), MOMENTS * traj.omega)
    assert np.max(np.linalg.norm(body_only - body_only[0], axis=1)) > 1e3 * limit * np.linalg.norm(h[0])


@pytest.mark.parametrize("method", METHODS)
def test_motor_torques_are_internal_the_world_momentum_stays(method):
    """A schedule of motor torques moves momentum between body and wheels, never out of the system."""
    schedule = [(0.0, [0.2, -0.1, 0.05]), (3.005, [-0.2, 0.0, 0.1]), (7.0, [0.0, 0.0, 0.0])]
    traj = simulate(
        MOMENTS,
        (0.1, 0.3, -0.2),
        10.0,
        0.01,
        method,
        wheels=three_wheels(),
        wheel_speeds0=(5.0, -2.0, 3.0),
        wheel_torque=schedule,
        save_every=10,
    )
    h = traj.L_world
    assert np.max(np.linalg.norm(h - h[0], axis=1)) < 1e-9 * np.linalg.norm(h[0])
    assert abs(traj.wheel_speeds[-1, 0] - traj.wheel_speeds[0, 0]) > 1.0  # the wheels did turn


@pytest.mark.parametrize("method", METHODS)
def test_simulate_equals_the_simulator_on_the_shipped_wheel_slew_bit_for_bit(method):
    scene = load_scene(SCENES / "wheel_slew.yaml")
    spacecraft = scene.spacecraft
    traj = simulate(
        scene.body.inertia_array,
        scene.initial.angular_velocity,
        scene.duration,
        scene.integrator.dt,
        method,
        scene.initial.orientation,
        wheels=spacecraft.wheel_model(scene.body.inertia_array),
        wheel_speeds0=[w.initial_speed for w in spacecraft.wheels],
        wheel_torque=spacecraft.wheel_schedule.segments,
        save_every=250,
    )
    sim = Simulator(scene, method=method)
    assert len(traj.t) == 25
    for row in range(1, len(traj.t)):
        sim.advance(250)
        snap = sim.snapshot()
        assert snap.orientation.tobytes() == traj.q[row].tobytes(), row
        assert snap.angular_velocity_body.tobytes() == traj.omega[row].tobytes(), row
        assert np.asarray(snap.wheel_speeds).tobytes() == traj.wheel_speeds[row].tobytes(), row
    np.testing.assert_allclose(traj.L_world[-1], snap.angular_momentum_world, rtol=0, atol=1e-15)
    assert traj.energy[-1] == pytest.approx(snap.kinetic_energy, rel=1e-14)
    assert abs(traj.omega[-1, 2]) < 2e-4 < np.max(np.abs(traj.omega[:, 2]))  # a slew: it turned and nearly stopped


def test_schedule_starts_take_effect_at_the_next_boundary_and_torques_are_clamped():
    wheels = three_wheels()
    kwargs = dict(wheels=wheels, wheel_speeds0=(5.0, -2.0, 3.0))

    def run(start, torques):
        schedule = [(0.0, [0.1, 0, 0]), (start, torques)]
        return simulate(MOMENTS, (0.1, 0.3, -0.2), 2.0, 0.01, "gyrostat_rk4", wheel_torque=schedule, **kwargs)

    a = run(1.0031, [5.0, -9.0, 0.0])  # clamped to +-0.2 N*m, from boundary 101
    b = run(1.01, [0.2, -0.2, 0.0])
    c = run(1.0, [0.2, -0.2, 0.0])
    assert a.q.tobytes() == b.q.tobytes() and a.wheel_speeds.tobytes() == b.wheel_speeds.tobytes()
    # 1.0 s is boundary 100, 1.0031 s comes to boundary 101: up to step 100 the same, then c's change acts first
    assert a.wheel_speeds[:101].tobytes() == c.wheel_speeds[:101].tobytes()
    assert a.wheel_speeds[101].tobytes() != c.wheel_speeds[101].tobytes()


def test_gravity_gradient_pitch_libration_through_simulate():
    """Equatorial orbit, axes radial / along-track / normal: pitch librates at n sqrt(3 (I2 - I1) / I3)."""
    moments = np.array([100.0, 200.0, 150.0])
    orbit = orbit_model(3.986004418e14, 6778137.0, 0.0)
    n = orbit.mean_motion
    expected = n * math.sqrt(3 * (moments[1] - moments[0]) / moments[2])
    theta0 = 1e-3
    t_end = 4 * 2 * math.pi / expected
    traj = simulate(
        moments,
        (0.0, 0.0, n),
        t_end,
        2.0,
        "gyrostat_rk4",
        (0.0, 0.0, math.sin(theta0 / 2), math.cos(theta0 / 2)),
        orbit=orbit,
    )
    assert traj.wheel_speeds is None
    pitch = np.unwrap(2 * np.arctan2(traj.q[:, 2], traj.q[:, 3])) - n * traj.t
    sign = np.signbit(pitch)
    k = np.flatnonzero(sign[1:] != sign[:-1])
    crossings = traj.t[k] + (traj.t[k + 1] - traj.t[k]) * pitch[k] / (pitch[k] - pitch[k + 1])
    assert len(crossings) >= 6
    period = 2 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    assert 2 * math.pi / period == pytest.approx(expected, rel=1e-3)
    # without the orbit there is no restoring torque: the pitch offset stays put
    free = simulate(moments, (0.0, 0.0, n), t_end, 2.0, "rk4", traj.q[0])
    assert np.all(np.abs(np.unwrap(2 * np.arctan2(free.q[:, 2], free.q[:, 3])) - n * free.t - theta0) < 1e-9)


def test_wheels_with_a_method_that_cannot_run_them_name_those_that_can():
    for method in ("taylor", "exact", "splitting", "dop853"):
        with pytest.raises(ValueError, match="cannot run wheels.*dopri5, gyrostat_rk4"):
            simulate(MOMENTS, (0.1, 0.2, 0.3), 1.0, 0.1, method, wheels=three_wheels())


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(wheel_speeds0=[1.0]), "need wheels"),
        (dict(wheels=three_wheels(), wheel_speeds0=[1.0, 2.0]), "2 value"),
        (dict(wheels=three_wheels(), wheel_speeds0=[1.0, 2.0, 700.0]), r"wheel_speeds0\[2\].*max_speed"),
        (dict(wheels=three_wheels(), wheel_torque=[0.1, 0.1]), "2 torque"),
        (dict(wheels=three_wheels(), wheel_torque=[0.1, math.nan, 0.1]), "finite"),
        (dict(wheels=three_wheels(), wheel_torque=[(1.0, [0, 0, 0]), (1.0, [0, 0, 0])]), "later"),
        (dict(wheels=three_wheels(), torque=lambda t, q, w: (0.0, 0.0, 0.0)), "ConstantTorque"),
        (dict(wheels="rw"), "WheelModel"),
        (dict(orbit=(1.0, 2.0)), "OrbitModel"),
    ],
)
def test_bad_wheel_inputs_are_value_errors_naming_them(kwargs, match):
    with pytest.raises(ValueError, match=match):
        simulate(MOMENTS, (0.1, 0.2, 0.3), 1.0, 0.1, "gyrostat_rk4", **kwargs)


def test_wheels_that_leave_no_body_for_this_inertia_are_refused():
    wheels = wheel_model(np.diag(MOMENTS), ["big"], [[1, 0, 0]], [9.0], [0.1], [100.0])
    with pytest.raises(ValueError, match="positive definite"):
        simulate((5.0, 12.0, 15.0), (0.1, 0.2, 0.3), 1.0, 0.1, "gyrostat_rk4", wheels=wheels)


def test_the_documented_examples_run():
    """docs/spacecraft.md's `simulate()` section, as written (simulate_gyrostat's docstring example runs in
    test_simulate.py's doctest of the module)."""
    import doctest

    docs = doctest.testfile(str(Path(__file__).resolve().parents[2] / "docs" / "spacecraft.md"), module_relative=False)
    assert docs.attempted >= 10 and docs.failed == 0


SPACECRAFT = """
body: {inertia_tensor: [[120, 2, -1.5], [2, 95, 3], [-1.5, 3, 140]]}
initial: {angular_velocity: [0.001, -0.002, 0.0011], orientation: [0.1, -0.2, 0.3, 0.927]}
actuators:
  reaction_wheels:
    - {name: a, axis: [1, 0, 0], inertia: 0.159, max_torque: 0.2, max_speed: 628.3, initial_speed: 10.47,
       friction: {coulomb: 0.0005, viscous: 1.0e-6}}
    - {name: b, axis: [0, 1, 0], inertia: 0.159, max_torque: 0.2, max_speed: 628.3}
    - {name: c, axis: [0.577, 0.577, 0.577], inertia: 0.159, max_torque: 0.2, max_speed: 628.3, initial_speed: -5}
  wheel_torque_schedule: {segments: [{start: 0.0, torques: [0.1, -0.3, 0.05]}, {start: 3.333, torques: [0, 0.1, 0]}]}
environment:
  gravity_gradient: {mu: 3.986004418e+14, orbit: {radius: 6778137.0, inclination: 0.9}}
integrator: {method: %s, dt: 0.05}
"""


@pytest.mark.parametrize("method", METHODS)
def test_simulate_steps_like_the_simulator_with_a_tensor_friction_and_gravity_gradient(method):
    """A user frame that is not principal, friction, gravity gradient, a clamped schedule: the integrator states
    (principal frame, where both integrate) are the Simulator's bit for bit. (Body-frame outputs may differ in
    the last bit of the frame rotation, and the snapshot reports the quaternion with w >= 0.)"""
    from rigid_rot_sim.scene.scene import parse_scene_text

    scene = parse_scene_text(SPACECRAFT % method)
    spacecraft = scene.spacecraft
    traj = simulate(
        scene.body.inertia_array,
        scene.initial.angular_velocity,
        10.0,
        scene.integrator.dt,
        method,
        scene.initial.orientation,
        wheels=spacecraft.wheel_model(scene.body.inertia_array),
        wheel_speeds0=[w.initial_speed for w in spacecraft.wheels],
        wheel_torque=spacecraft.wheel_schedule.segments,
        orbit=spacecraft.gravity_gradient.model(),
        save_every=7,
    )
    sim = Simulator(scene)
    assert not sim.stepper.body.is_principal
    for row in range(1, len(traj.t) - 1):
        sim.advance(7)
        integrator = sim.stepper.integrator
        assert integrator.q.tobytes() == traj.q_principal[row].tobytes(), row
        assert integrator.omega.tobytes() == traj.omega_principal[row].tobytes(), row
        assert integrator.wheel_speeds.tobytes() == traj.wheel_speeds[row].tobytes(), row
    snap = sim.snapshot()
    np.testing.assert_allclose(traj.omega[-2], snap.angular_velocity_body, rtol=0, atol=1e-17)
    np.testing.assert_allclose(traj.L_world[-2], snap.angular_momentum_world, rtol=1e-14)
