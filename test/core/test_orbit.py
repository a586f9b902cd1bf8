"""Orbits: elements <-> state round trips, Kepler's equation, conservation over 100 orbits, J2's secular drift,
the Earth's rotation and the WGS-84 / NED / LVLH frames."""

from __future__ import annotations

import datetime as dt
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigid_rot_sim.core import orbit

MU = orbit.EARTH_MU
angles = st.floats(0.0, 2.0 * math.pi - 1e-9)


def _angle_difference(a: float, b: float) -> float:
    return abs((a - b + math.pi) % (2.0 * math.pi) - math.pi)


@settings(max_examples=300, deadline=None)
@given(
    a=st.floats(6.6e6, 4.3e7),
    e=st.floats(1e-3, 0.9),
    i=st.floats(1e-3, math.pi - 1e-3),
    raan=angles,
    argp=angles,
    nu=angles,
)
def test_elements_round_trip(a: float, e: float, i: float, raan: float, argp: float, nu: float) -> None:
    r, v = orbit.elements_to_rv(MU, a, e, i, raan, argp, nu)
    el = orbit.rv_to_elements(MU, r, v)
    assert el.a == pytest.approx(a, rel=1e-12)
    assert el.e == pytest.approx(e, rel=1e-10, abs=1e-12)
    assert el.i == pytest.approx(i, abs=1e-12)
    assert _angle_difference(el.raan, raan) < 1e-12
    # The argument of periapsis and the anomaly are defined to the eccentricity vector's round-off (~1e-16 / e).
    assert _angle_difference(el.argp, argp) < 1e-12 / e
    assert _angle_difference(el.nu, nu) < 1e-12 / e
    r2, v2 = orbit.elements_to_rv(MU, el.a, el.e, el.i, el.raan, el.argp, el.nu)
    np.testing.assert_allclose(r2, r, rtol=0, atol=1e-12 * np.linalg.norm(r))
    np.testing.assert_allclose(v2, v, rtol=0, atol=1e-12 * np.linalg.norm(v))


def test_elem2rv_conventions_at_periapsis_and_node() -> None:
    """At the ascending node (raan = 90 deg, argp + nu = 0) the body is on +y, moving in the orbit plane."""
    a, e, i = 7.0e6, 0.1, math.radians(30.0)
    r, v = orbit.elements_to_rv(MU, a, e, i, math.pi / 2, 0.0, 0.0)
    np.testing.assert_allclose(r, [0.0, a * (1 - e), 0.0], atol=1e-6)
    speed = math.sqrt(MU * (1 + e) / (a * (1 - e)))  # vis-viva at periapsis
    np.testing.assert_allclose(v, [-speed * math.cos(i), 0.0, speed * math.sin(i)], atol=1e-9)


def test_circular_and_equatorial_conventions() -> None:
    r, v = orbit.elements_to_rv(MU, 7e6, 0.0, 0.0, 0.0, 0.0, 1.0)
    el = orbit.rv_to_elements(MU, r, v)
    assert (el.raan, el.argp) == (0.0, 0.0)
    assert el.nu == pytest.approx(1.0, abs=1e-13)


@pytest.mark.parametrize("e", [0.0, 1e-8, 0.3, 0.7, 0.95, 0.999])
def test_kepler_equation_to_round_off(e: float) -> None:
    for m in np.linspace(-3 * math.pi, 3 * math.pi, 2001):
        ea = orbit.eccentric_anomaly(float(m), e)
        assert _angle_difference(ea - e * math.sin(ea), float(m)) <= 4e-15


def test_true_mean_anomaly_inverse() -> None:
    for e in (0.0, 0.2, 0.9):
        for nu in np.linspace(-3.1, 3.1, 101):
            m = orbit.true_to_mean_anomaly(float(nu), e)
            assert orbit.mean_to_true_anomaly(m, e) == pytest.approx(nu, abs=1e-12)


def test_energy_and_angular_momentum_constant_over_100_orbits() -> None:
    kepler = orbit.kepler_orbit(8.0e6, 0.2, math.radians(51.6), 0.3, 1.1, 0.5)
    times = np.linspace(0.0, 100 * kepler.period, 20001)
    energy, momentum = [], []
    for t in times:
        r, v = kepler.state(float(t))
        energy.append(v @ v / 2 - MU / np.linalg.norm(r))
        momentum.append(np.linalg.norm(np.cross(r, v)))
    energy_0 = -MU / (2 * kepler.a)
    momentum_0 = math.sqrt(MU * kepler.a * (1 - kepler.e**2))
    assert np.max(np.abs(np.array(energy) / energy_0 - 1)) < 1e-13
    assert np.max(np.abs(np.array(momentum) / momentum_0 - 1)) < 1e-13


def test_sun_synchronous_raan_drift() -> None:
    """700 km, e = 0, i = 98.188 deg: the node drifts 0.98565 deg/day (one turn a year)."""
    raan_dot, _, _ = orbit.mean_element_rates(
        orbit.EARTH_MU, orbit.EARTH_J2, orbit.EARTH_RADIUS, 7078.137e3, 0.0, math.radians(98.188)
    )
    assert math.degrees(raan_dot) * 86400.0 == pytest.approx(0.98565, rel=1e-4)


def test_j2_rates_against_the_critical_inclination_and_propagation() -> None:
    _, argp_dot, _ = orbit.mean_element_rates(MU, orbit.EARTH_J2, orbit.EARTH_RADIUS, 7e6, 0.01, math.acos(1 / 5**0.5))
    assert abs(argp_dot) < 1e-20  # the critical inclination: 5 cos^2 i = 1
    kepler = orbit.kepler_orbit(7e6, 0.01, 1.0, 0.2, 0.3, 0.4, j2=orbit.EARTH_J2)
    day = 86400.0
    el = orbit.rv_to_elements(MU, *kepler.state(day))
    assert _angle_difference(el.raan, kepler.raan + kepler.raan_dot * day) < 1e-9


def test_kepler_orbit_refuses_bad_elements() -> None:
    with pytest.raises(ValueError, match="0 <= e < 1"):
        orbit.kepler_orbit(7e6, 1.2, 0.0, 0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="inside the Earth"):
        orbit.kepler_orbit(6.5e6, 0.1, 0.0, 0.0, 0.0, 0.0, j2=orbit.EARTH_J2)


def test_earth_rotation_angle() -> None:
    # At J2000.0 (UT1) the ERA is 2 pi 0.7790572732640; one sidereal day later it is the same.
    assert orbit.earth_rotation_angle(0.0) == pytest.approx(2 * math.pi * 0.7790572732640, abs=1e-15)
    sidereal_day = 86400.0 * 2 * math.pi / (orbit.EARTH_ROTATION_RATE * 86400.0)
    assert orbit.earth_rotation_angle(sidereal_day) == pytest.approx(orbit.earth_rotation_angle(0.0), abs=1e-9)
    # Against GMST (IAU 1982) less the accumulated precession in right ascension (IERS 2010 eq. 5.32), to 0.1".
    for when in (dt.datetime(2025, 1, 1), dt.datetime(2026, 11, 28, 17, 30), dt.datetime(1990, 5, 3, 3, 4, 5)):
        d = orbit.days_since_j2000(when)
        t = d / 36525.0
        gmst = 280.46061837 + 360.98564736629 * d + 0.000387933 * t**2 - t**3 / 38710000.0
        precession = (0.014506 + 4612.156534 * t + 1.3915817 * t**2) / 3600.0
        era = math.degrees(orbit.earth_rotation_angle(d))
        assert abs((gmst - precession - era + 180.0) % 360.0 - 180.0) < 0.1 / 3600.0


def test_decimal_year() -> None:
    assert orbit.decimal_year(dt.datetime(2025, 1, 1)) == 2025.0
    assert orbit.decimal_year(dt.datetime(2024, 7, 2)) == pytest.approx(2024 + 183 / 366)


@settings(max_examples=200, deadline=None)
@given(lat=st.floats(-math.pi / 2, math.pi / 2), lon=st.floats(-math.pi, math.pi), h=st.floats(-5e3, 4e7))
def test_geodetic_round_trip(lat: float, lon: float, h: float) -> None:
    x = orbit.geodetic_to_ecef(lat, lon, h)
    lat2, lon2, h2 = orbit.ecef_to_geodetic(*x)
    assert lat2 == pytest.approx(lat, abs=1e-12)
    if abs(lat) < math.pi / 2 - 1e-9:
        assert _angle_difference(lon2, lon) < 1e-12
    assert h2 == pytest.approx(h, abs=1e-12 * (orbit.EARTH_RADIUS + abs(h)))


def test_geodetic_known_points() -> None:
    np.testing.assert_allclose(orbit.geodetic_to_ecef(0.0, 0.0, 0.0), [orbit.EARTH_RADIUS, 0, 0], atol=1e-9)
    polar = orbit.EARTH_RADIUS * (1 - orbit.WGS84_FLATTENING)
    np.testing.assert_allclose(orbit.geodetic_to_ecef(math.pi / 2, 0.0, 0.0), [0, 0, polar], atol=1e-6)


def test_frames_are_rotations() -> None:
    era = 1.234
    v = np.array([1.0, -2.0, 3.0])
    np.testing.assert_allclose(orbit.ecef_to_eci(era, orbit.eci_to_ecef(era, v)), v, atol=1e-15)
    ned = orbit.ned_matrix(0.3, -1.2)
    np.testing.assert_allclose(ned @ ned.T, np.eye(3), atol=1e-15)
    up = np.array(orbit.geodetic_to_ecef(0.3, -1.2, 1.0)) - np.array(orbit.geodetic_to_ecef(0.3, -1.2, 0.0))
    np.testing.assert_allclose(ned @ up, [0, 0, -1], atol=1e-9)  # down is minus the ellipsoid normal
    r, v = orbit.elements_to_rv(MU, 7e6, 0.0, 0.5, 0.1, 0.0, 0.7)
    lvlh = orbit.lvlh_matrix(r, v)
    np.testing.assert_allclose(lvlh @ lvlh.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(lvlh) == pytest.approx(1.0)
    np.testing.assert_allclose(lvlh @ v / np.linalg.norm(v), [1, 0, 0], atol=1e-12)  # circular: along-track
