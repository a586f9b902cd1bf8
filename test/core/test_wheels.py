"""Reaction wheels and gravity gradient: tests from physics (conservation laws, closed forms, classical frequencies)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rigid_rot_sim.core.dynamics import body_to_world
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.integrators.gyrostat import GYROSTAT_METHODS, GyrostatDopri5, GyrostatRK4
from rigid_rot_sim.core.torque import ConstantTorque
from rigid_rot_sim.core.wheels import (
    SPEED_RAMP_FRACTION,
    gyrostat_energy,
    orbit_model,
    total_momentum_body,
    wheel_model,
)

MOMENTS = np.array([10.0, 12.0, 15.0])


def three_wheels(**kwargs):
    return wheel_model(
        np.diag(MOMENTS),
        ["a", "b", "c"],
        [[1, 0, 0], [0, 1, 0], [1, 1, 1]],
        [0.1, 0.2, 0.15],
        [0.2] * 3,
        [600.0] * 3,
        **kwargs,
    )


def invariants(g, wheels):
    momentum = body_to_world(g.q, total_momentum_body(MOMENTS, wheels, g.omega, g.wheel_speeds))
    return momentum, float(gyrostat_energy(MOMENTS, wheels, g.omega, g.wheel_speeds))


def drift(cls, dt, duration=20.0, **options):
    wheels = three_wheels()
    g = cls(MOMENTS, dt, wheels=wheels, omega0=(0.1, 0.3, -0.2), wheel_speeds0=(50.0, -20.0, 30.0), **options)
    h0, e0 = invariants(g, wheels)
    g.advance(round(duration / dt))
    h1, e1 = invariants(g, wheels)
    return float(np.linalg.norm(h1 - h0) / np.linalg.norm(h0)), abs(e1 - e0) / e0


def test_rk4_conserves_world_momentum_and_energy_to_fourth_order():
    """Frictionless wheels, no motor or external torque: R(q) H and T are invariants; RK4's error falls as dt^4."""
    coarse = drift(GyrostatRK4, 0.1)
    fine = drift(GyrostatRK4, 0.05)
    for a, b in zip(coarse, fine, strict=True):
        assert a > 1e-11  # measurable, so that the ratio means something
        # halving dt divides the drift by 2^4 or more (the energy's leading error term is O(dt^5) here)
        assert 0.85 * 2**4 < a / b < 1.3 * 2**5, (a, b)


def test_dopri5_conserves_to_its_tolerance():
    momentum, energy = drift(GyrostatDopri5, 0.05, rtol=1e-11, atol=1e-13)
    assert momentum < 1e-9 and energy < 1e-9
    loose = drift(GyrostatDopri5, 0.05, rtol=1e-6, atol=1e-8)
    assert max(loose) > max(momentum, energy)  # the tolerance controls the error


@pytest.mark.parametrize("cls", list(GYROSTAT_METHODS.values()))
def test_single_wheel_on_a_principal_axis_matches_the_closed_form(cls):
    """Wheel on axis 3, body spinning about 3, constant motor torque u:
    (I3 - J) dw3/dt = -u and J (dw3/dt + dOmega/dt) = u, so both are linear in t."""
    spin, u, w0, speed0 = 0.5, 0.05, 0.2, 10.0
    wheels = wheel_model(np.diag(MOMENTS), ["z"], [[0, 0, 1]], [spin], [0.1], [1000.0])
    g = cls(MOMENTS, 0.01, wheels=wheels, omega0=(0.0, 0.0, w0), wheel_speeds0=(speed0,))
    g.set_wheel_commands([u])
    g.advance(1000)
    t = g.t
    i3 = MOMENTS[2]
    assert g.omega[2] == pytest.approx(w0 - u * t / (i3 - spin), rel=1e-12)
    assert g.wheel_speeds[0] == pytest.approx(speed0 + u * i3 / (spin * (i3 - spin)) * t, rel=1e-12)
    # the attitude: a rotation about z by the integral of w3
    angle = w0 * t - 0.5 * u * t * t / (i3 - spin)
    assert g.q[2] == pytest.approx(math.sin(angle / 2), abs=1e-10)
    assert g.q[3] == pytest.approx(math.cos(angle / 2), abs=1e-10)
    np.testing.assert_allclose(g.applied_wheel_torques(), [u])


@pytest.mark.parametrize("cls", list(GYROSTAT_METHODS.values()))
def test_speed_saturation_stops_the_wheel_at_max_speed(cls):
    """A wheel driven hard towards max_speed approaches it and never passes it; the reverse torque acts in full."""
    spin, max_speed = 0.5, 100.0
    wheels = wheel_model(np.diag(MOMENTS), ["z"], [[0, 0, 1]], [spin], [0.1], [max_speed])
    g = cls(MOMENTS, 0.01, wheels=wheels, wheel_speeds0=(90.0,))
    g.set_wheel_commands([0.1])
    top = 0.0
    for _ in range(200):
        g.advance(50)
        top = max(top, g.wheel_speeds[0])
    assert top <= max_speed
    assert g.wheel_speeds[0] > max_speed * (1 - SPEED_RAMP_FRACTION)  # it got there
    assert g.applied_wheel_torques()[0] < 0.1 * 0.01  # and the motor has (almost) let go
    # total momentum is the body's plus the wheel's: with the motor stopped, the body rate stops changing
    w_before = g.omega[2]
    g.set_wheel_commands([-0.1])  # slowing down: full torque
    np.testing.assert_allclose(g.applied_wheel_torques(), [-0.1])
    g.advance(100)
    assert g.omega[2] > w_before


@pytest.mark.parametrize("cls", list(GYROSTAT_METHODS.values()))
def test_coulomb_and_viscous_friction_as_documented(cls):
    """Single wheel on a principal axis, no motor torque: the friction torque f slows the wheel at
    dOmega/dt = -f I3 / (J (I3 - J)) and the body takes up the momentum (H conserved)."""
    spin, c, b, stiction = 0.5, 0.05, 0.002, 0.01
    i3 = MOMENTS[2]
    gain = i3 / (spin * (i3 - spin))
    wheels = wheel_model(
        np.diag(MOMENTS), ["z"], [[0, 0, 1]], [spin], [0.1], [1000.0], coulomb=[c], stiction_speed=[stiction]
    )
    g = cls(MOMENTS, 0.01, wheels=wheels, wheel_speeds0=(10.0,))
    g.advance(100)
    assert g.wheel_speeds[0] == pytest.approx(10.0 - c * gain * g.t, rel=1e-10)
    assert i3 * g.omega[2] + spin * g.wheel_speeds[0] == pytest.approx(spin * 10.0, rel=1e-12)
    g.advance(15000)  # long after it would have stopped (97 s): it rests, decaying within the stiction speed
    assert abs(g.wheel_speeds[0]) <= 1e-3 * stiction

    wheels = wheel_model(np.diag(MOMENTS), ["z"], [[0, 0, 1]], [spin], [0.1], [1000.0], viscous=[b])
    g = cls(MOMENTS, 0.01, wheels=wheels, wheel_speeds0=(10.0,))
    g.advance(500)
    assert g.wheel_speeds[0] == pytest.approx(10.0 * math.exp(-b * gain * g.t), rel=1e-9)


@pytest.mark.parametrize("cls", list(GYROSTAT_METHODS.values()))
def test_gravity_gradient_pitch_libration_has_the_classical_frequency(cls):
    """Equatorial circular orbit; body axes 1 radial, 2 along-track, 3 orbit normal (pitch). Small pitch
    librations about the rotating radial direction have frequency n sqrt(3 (I2 - I1) / I3)."""
    moments = np.array([100.0, 200.0, 150.0])
    orbit = orbit_model(3.986004418e14, 6778137.0, 0.0)
    n = orbit.mean_motion
    theta0 = 1e-3
    q0 = (0.0, 0.0, math.sin(theta0 / 2), math.cos(theta0 / 2))
    expected = n * math.sqrt(3 * (moments[1] - moments[0]) / moments[2])
    g = cls(moments, 2.0, orbit=orbit, q0=q0, omega0=(0.0, 0.0, n))
    times, pitch = [], []
    for _ in range(int(4 * 2 * math.pi / expected / 2.0)):
        g.advance(1)
        times.append(g.t)
        pitch.append(2 * math.atan2(g.q[2], g.q[3]) - n * g.t)
    pitch = np.unwrap(np.array(pitch))
    times = np.array(times)
    crossings = []
    for k in range(1, len(pitch)):
        if pitch[k - 1] > 0.0 >= pitch[k] or pitch[k - 1] < 0.0 <= pitch[k]:
            crossings.append(times[k - 1] + (times[k] - times[k - 1]) * pitch[k - 1] / (pitch[k - 1] - pitch[k]))
    assert len(crossings) >= 6
    period = 2 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    assert 2 * math.pi / period == pytest.approx(expected, rel=1e-3)
    assert np.max(np.abs(pitch)) == pytest.approx(theta0, rel=1e-2)  # a libration, not a tumble
    assert np.max(np.abs(g.omega[:2])) < 1e-12  # planar


@pytest.mark.parametrize("cls", list(GYROSTAT_METHODS.values()))
def test_advance_k_equals_k_single_steps_bit_for_bit(cls):
    wheels = three_wheels(coulomb=[1e-3, 0.0, 2e-3], viscous=[1e-5, 0.0, 0.0])
    orbit = orbit_model(3.986004418e14, 6778137.0, 0.5)
    kwargs = dict(wheels=wheels, orbit=orbit, omega0=(0.01, 0.02, -0.03), wheel_speeds0=(5.0, -3.0, 0.0))
    a = cls(MOMENTS, 0.1, ConstantTorque(np.array([1e-3, 0.0, -2e-3])), **kwargs)
    b = cls(MOMENTS, 0.1, ConstantTorque(np.array([1e-3, 0.0, -2e-3])), **kwargs)
    for g in (a, b):
        g.set_wheel_commands([0.05, -0.2, 0.1])
    a.advance(137)
    for k in (1, 7, 29, 100):
        b.advance(k) if k != 100 else b.advance(137 - 37)
    assert a.t == b.t
    assert a.q.tobytes() == b.q.tobytes()
    assert a.omega.tobytes() == b.omega.tobytes()
    assert a.wheel_speeds.tobytes() == b.wheel_speeds.tobytes()
    assert a.wheel_angles.tobytes() == b.wheel_angles.tobytes()


@pytest.mark.parametrize("cls", list(GYROSTAT_METHODS.values()))
def test_a_blow_up_raises_non_finite_and_keeps_the_last_good_state(cls):
    wheels = three_wheels()
    g = cls(MOMENTS, 1.0, wheels=wheels, omega0=(1e153, 1e153, -1e153))
    with pytest.raises(NonFiniteStateError):
        g.advance(50)
    assert np.all(np.isfinite(g.omega)) and np.all(np.isfinite(g.q)) and np.all(np.isfinite(g.wheel_speeds))


def test_a_wheel_set_that_leaves_no_body_is_refused():
    with pytest.raises(ValueError, match="positive definite"):
        wheel_model(np.diag(MOMENTS), ["big"], [[1, 0, 0]], [10.0], [0.1], [100.0])
    with pytest.raises(ValueError, match="axis"):
        wheel_model(np.diag(MOMENTS), ["zero"], [[0, 0, 0]], [0.1], [0.1], [100.0])


# ------------------------------------------------------------------ wheel angles (eq. (8))


@pytest.mark.parametrize("cls", list(GYROSTAT_METHODS.values()))
def test_wheel_angle_of_a_single_wheel_follows_the_closed_form_and_is_never_wrapped(cls):
    # body at rest, one wheel on the z principal axis, constant motor torque u:
    # dOmega/dt = u I3 / (J (I3 - J)) = a, so theta(t) = Omega0 t + a t^2 / 2 (rad, relative to the body)
    spin, u, speed0 = 0.5, 0.1, 3.0
    wheels = wheel_model(np.diag(MOMENTS), ["z"], [[0, 0, 1]], [spin], [0.2], [1000.0])
    g = cls(MOMENTS, 0.01, wheels=wheels, wheel_speeds0=[speed0])
    g.set_wheel_commands([u])
    a = u * MOMENTS[2] / (spin * (MOMENTS[2] - spin))
    angles = []
    for _ in range(40):
        g.advance(50)
        angles.append(float(g.wheel_angles[0]))
    t = g.t
    assert t == pytest.approx(20.0)
    assert g.wheel_angles[0] == pytest.approx(speed0 * t + 0.5 * a * t * t, rel=1e-12)
    assert g.wheel_angles[0] > 20 * math.pi  # many turns: unwrapped, never reduced to [-pi, pi]
    assert np.all(np.diff(angles) > 0.0)  # continuous and increasing with a positive speed


@pytest.mark.parametrize("cls", list(GYROSTAT_METHODS.values()))
def test_wheel_angles_drive_nothing_and_do_not_change_the_steps(cls):
    # the angles feed back into nothing and (dopri5) stay out of the error control, so a huge
    # initial angle leaves every other state bit for bit as it was
    wheels = three_wheels()
    common = dict(wheels=wheels, omega0=(0.1, 0.3, -0.2), wheel_speeds0=(50.0, -20.0, 30.0))
    small = cls(MOMENTS, 0.05, ConstantTorque(np.array([0.01, 0.0, -0.02])), **common)
    large = cls(MOMENTS, 0.05, ConstantTorque(np.array([0.01, 0.0, -0.02])), wheel_angles0=[1e7, -3.0, 0.5], **common)
    for g in (small, large):
        g.set_wheel_commands([0.05, -0.1, 0.02])
        g.advance(200)
    assert np.array_equal(small.q, large.q) and np.array_equal(small.omega, large.omega)
    assert np.array_equal(small.wheel_speeds, large.wheel_speeds)
    moved = small.wheel_angles
    assert large.wheel_angles == pytest.approx(moved + [1e7, -3.0, 0.5], rel=1e-12, abs=1e-6)


@pytest.mark.parametrize("cls", list(GYROSTAT_METHODS.values()))
def test_set_state_replaces_or_keeps_the_wheel_angles(cls):
    wheels = three_wheels()
    g = cls(MOMENTS, 0.05, wheels=wheels, wheel_speeds0=(1.0, 2.0, 3.0))
    g.advance(10)
    kept = g.wheel_angles.copy()
    assert np.all(kept != 0.0)
    g.set_state(g.t, g.q, g.omega)
    assert np.array_equal(g.wheel_angles, kept)
    g.set_state(g.t, g.q, g.omega, wheel_angles=[0.0, 1.0, 2.0])
    assert g.wheel_angles.tolist() == [0.0, 1.0, 2.0]
    with pytest.raises(ValueError, match="wheel angles must be finite"):
        g.set_state(g.t, g.q, g.omega, wheel_angles=[0.0, math.inf, 2.0])


# ------------------------------------------------------------------ gravity gradient on any orbit


def test_a_circular_kepler_orbit_is_the_circular_orbit_of_the_torque() -> None:
    """raan = argp = nu = 0: the Kepler orbit's node is world x, as the circular model's: the same torque."""
    from rigid_rot_sim.core.orbit import kepler_orbit
    from rigid_rot_sim.core.wheels import gravity_gradient_torque, kepler_orbit_model

    circular = orbit_model(3.986004418e14, 7.0e6, 0.7)
    kepler = kepler_orbit_model(kepler_orbit(7.0e6, 0.0, 0.7, 0.0, 0.0, 0.0))
    q = tuple(np.array([0.1, -0.3, 0.2, 0.9]) / np.linalg.norm([0.1, -0.3, 0.2, 0.9]))
    for t in (0.0, 100.0, 2345.6):
        np.testing.assert_allclose(kepler.position_world(t), circular.position_world(t), atol=1e-12)
        a = gravity_gradient_torque(kepler.compiled(), MOMENTS, q, t)
        b = gravity_gradient_torque(circular.compiled(), MOMENTS, q, t)
        np.testing.assert_allclose(a, b, rtol=1e-11, atol=1e-20)


@pytest.mark.parametrize("cls", list(GYROSTAT_METHODS.values()))
def test_gravity_gradient_pitch_on_an_inclined_eccentric_orbit(cls) -> None:
    """e = 0.1, i = 50 deg: body axis 3 along the orbit normal, so the motion stays in the orbit plane and the
    pitch alpha (axis 1 from periapsis, about the normal) obeys I3 alpha'' = 3 mu / R^3 (I2 - I1) sin phi cos phi,
    phi = nu - alpha: the scalar equation, integrated by scipy to 1e-12, against the 3-D gyrostat."""
    from scipy.integrate import solve_ivp
    from scipy.spatial.transform import Rotation

    from rigid_rot_sim.core.orbit import EARTH_MU, kepler_orbit, mean_to_true_anomaly
    from rigid_rot_sim.core.wheels import kepler_orbit_model

    moments = np.array([100.0, 200.0, 150.0])
    kepler = kepler_orbit(7.5e6, 0.1, math.radians(50.0), 0.5, 0.7, 0.0)
    r0, v0 = kepler.state(0.0)
    p_hat = r0 / np.linalg.norm(r0)
    h = np.cross(r0, v0)
    h_hat = h / np.linalg.norm(h)
    alpha0 = 0.02
    axes = Rotation.from_rotvec(alpha0 * h_hat).as_matrix() @ np.column_stack((p_hat, np.cross(h_hat, p_hat), h_hat))
    q0 = Rotation.from_matrix(axes).as_quat()
    nu_dot0 = np.linalg.norm(h) / np.linalg.norm(r0) ** 2
    g = cls(moments, 1.0, orbit=kepler_orbit_model(kepler), q0=q0, omega0=(0.0, 0.0, nu_dot0))

    def pitch_rhs(t: float, y: np.ndarray) -> list[float]:
        r, _ = kepler.state(t)
        nu = mean_to_true_anomaly(kepler.mean_anomaly + kepler.mean_anomaly_dot * t, kepler.e)
        phi = nu - y[0]
        k = 3 * EARTH_MU / np.linalg.norm(r) ** 3 * (moments[1] - moments[0]) / moments[2]
        return [y[1], k * math.sin(phi) * math.cos(phi)]

    period = kepler.period
    samples = np.round(np.arange(1, 41) * (2 * period / 40))  # whole steps of 1 s
    reference = solve_ivp(pitch_rhs, (0, samples[-1]), [alpha0, nu_dot0], t_eval=samples, rtol=1e-12, atol=1e-14)
    errors = []
    for t, alpha_ref in zip(samples, reference.y[0], strict=True):
        g.advance(round(t - g.t))
        axis1 = Rotation.from_quat(g.q).as_matrix()[:, 0]
        alpha = math.atan2(np.cross(p_hat, axis1) @ h_hat, axis1 @ p_hat)
        errors.append(abs((alpha - alpha_ref + math.pi) % (2 * math.pi) - math.pi))
        assert abs(Rotation.from_quat(g.q).as_matrix()[:, 2] @ h_hat - 1.0) < 1e-9  # stays in the orbit plane
    assert max(errors) < 1e-6
    assert (
        np.ptp(reference.y[0] - np.unwrap([mean_to_true_anomaly(kepler.mean_anomaly_dot * t, 0.1) for t in samples]))
        > 0.05
    )
