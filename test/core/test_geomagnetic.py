"""The geomagnetic field: NOAA's WMM2025 test values, IGRF-14 against NOAA's geomaglib, the dipole in closed form."""

from __future__ import annotations

import math
from importlib.resources import files

import numpy as np
import pytest

from rigid_rot_sim.core import geomagnetic, orbit

#: NOAA's WMM2025_TEST_VALUES.txt: year, height (km), geodetic latitude, longitude (deg), X, Y, Z (nT).
WMM2025_TEST_VALUES = [
    (2025.0, 0.0, 80.0, 0.0, 6521.6, 145.9, 54791.5),
    (2025.0, 0.0, 0.0, 120.0, 39677.8, -109.6, -10580.2),
    (2025.0, 0.0, -80.0, 240.0, 6117.5, 15751.9, -52022.5),
    (2025.0, 100.0, 80.0, 0.0, 6216.0, 92.4, 52598.8),
    (2025.0, 100.0, 0.0, 120.0, 37688.6, -96.2, -10152.1),
    (2025.0, 100.0, -80.0, 240.0, 5907.6, 14780.3, -49540.7),
    (2027.5, 0.0, 80.0, 0.0, 6500.8, 294.5, 54869.4),
    (2027.5, 0.0, 0.0, 120.0, 39701.6, -167.4, -10381.8),
    (2027.5, 0.0, -80.0, 240.0, 6200.7, 15730.3, -51783.7),
    (2027.5, 100.0, 80.0, 0.0, 6196.7, 233.8, 52670.5),
    (2027.5, 100.0, 0.0, 120.0, 37711.5, -148.7, -9969.8),
    (2027.5, 100.0, -80.0, 240.0, 5984.0, 14760.1, -49317.7),
]


@pytest.mark.parametrize("year, height_km, lat, lon, x, y, z", WMM2025_TEST_VALUES)
def test_wmm2025_noaa_test_values(year: float, height_km: float, lat: float, lon: float, x: float, y: float, z: float):
    b = geomagnetic.field_ned("wmm2025", lat, lon, height_km * 1e3, year)
    np.testing.assert_allclose(b, [x, y, z], rtol=0, atol=0.1)


def _geomaglib_igrf14(lat: float, lon: float, height_km: float, year: float) -> np.ndarray:
    """X, Y, Z (nT) from NOAA/CIRES geomaglib's IGRF-14 (its own coefficient file and summation)."""
    from geomaglib import legendre, magmath, sh_loader, sh_vars, util

    cof = str(files("geomaglib.cof") / "IGRF14_sv.COF")
    coef, nmax = sh_loader.load_igrf_coef(cof, skip_two_columns=True, load_year=min(5 * int(year // 5), 2025))
    coef = sh_loader.timely_modify_magnetic_model(coef, year)
    r, geoc_lat = util.geod_to_geoc_lat(lat, height_km)
    sph = sh_vars.comp_sh_vars(lon, r, geoc_lat, nmax)
    leg = legendre.Flattened_Chaos_Legendre1(nmax, [90.0 - geoc_lat])
    bt, bp, br = magmath.mag_SPH_summation(nmax, sph, coef["g"], coef["h"], leg, [geoc_lat])
    bx, by, bz = magmath.rotate_magvec(bt, bp, br, geoc_lat, lat)
    return np.array([bx[0], by[0], bz[0]])


def test_igrf14_against_geomaglib_over_60_points() -> None:
    """At the 26 epochs 1900-2025 and in the predictive span 2025-2030, where geomaglib's file is IGRF-14's.

    (Between two epochs geomaglib moves each coefficient along its secular variation rounded to 0.01 nT/yr,
    and leaves out degrees 11-13 from 1995 to 2000; IGRF-14 interpolates the coefficients linearly, as we do:
    ``test_igrf14_is_linear_between_epochs``.)
    """
    rng = np.random.default_rng(37)
    years = [*np.arange(1900.0, 2026.0, 5.0), *rng.uniform(2025.0, 2030.0, 34)]
    worst = 0.0
    for year in years:
        lat, lon = rng.uniform(-89.0, 89.0), rng.uniform(-180.0, 180.0)
        height_km = rng.uniform(0.0, 1000.0)
        ours = geomagnetic.field_ned("igrf14", lat, lon, height_km * 1e3, year)
        worst = max(worst, float(np.max(np.abs(ours - _geomaglib_igrf14(lat, lon, height_km, year)))))
    assert worst < 0.3


def test_igrf14_is_linear_between_epochs() -> None:
    """The field is linear in the coefficients: between two epochs it is the epochs' fields interpolated."""
    rng = np.random.default_rng(2)
    for start in np.arange(1900.0, 2025.0, 5.0):
        w = rng.uniform()
        point = (rng.uniform(-89.0, 89.0), rng.uniform(-180.0, 180.0), rng.uniform(0.0, 1e6))
        before, after = (geomagnetic.field_ned("igrf14", *point, year) for year in (start, start + 5.0))
        between = geomagnetic.field_ned("igrf14", *point, start + 5.0 * w)
        np.testing.assert_allclose(between, before + w * (after - before), rtol=0, atol=1e-8)


def test_dipole_is_igrf_degree_one_in_closed_form() -> None:
    """B = (a/r)^3 [3 (m . r_hat) r_hat - m] with m = a^3 (g11, h11, g10) nT (the degree-1 potential's gradient)."""
    igrf = geomagnetic.model("igrf14")
    schmidt_free = igrf.g[:, 1, :2], igrf.h[:, 1, 1]
    rng = np.random.default_rng(1)
    for _ in range(50):
        year = rng.uniform(1900.0, 2030.0)
        k = min(int(np.searchsorted(igrf.epochs, year, side="right")) - 1, len(igrf.epochs) - 2)
        w = (year - igrf.epochs[k]) / (igrf.epochs[k + 1] - igrf.epochs[k])
        g10, g11 = schmidt_free[0][k] + w * (schmidt_free[0][k + 1] - schmidt_free[0][k])
        h11 = schmidt_free[1][k] + w * (schmidt_free[1][k + 1] - schmidt_free[1][k])
        r = rng.normal(size=3)
        r *= rng.uniform(6.4e6, 4.2e7) / np.linalg.norm(r)
        r_hat = r / np.linalg.norm(r)
        m = np.array([g11, h11, g10])
        expected = (geomagnetic.REFERENCE_RADIUS / np.linalg.norm(r)) ** 3 * (3 * (m @ r_hat) * r_hat - m)
        np.testing.assert_allclose(geomagnetic.field_ecef("dipole", r, year) * 1e9, expected, rtol=0, atol=0.5)


def test_ned_and_ecef_agree_and_units() -> None:
    lat, lon, h = 45.0, 7.0, 500e3
    ned = geomagnetic.field_ned("igrf14", lat, lon, h, 2026.0)
    r = np.array(orbit.geodetic_to_ecef(math.radians(lat), math.radians(lon), h))
    ecef = geomagnetic.field_ecef("igrf14", r, 2026.0)
    np.testing.assert_allclose(orbit.ned_matrix(math.radians(lat), math.radians(lon)) @ ecef * 1e9, ned, atol=1e-9)
    assert 1e-5 < np.linalg.norm(ecef) < 6e-5  # tens of microtesla in LEO


def test_pole_is_finite_and_continuous() -> None:
    at_pole = geomagnetic.field_ned("igrf14", 90.0, 0.0, 0.0, 2025.0)
    near = geomagnetic.field_ned("igrf14", 90.0 - 1e-7, 0.0, 0.0, 2025.0)
    assert np.all(np.isfinite(at_pole))
    np.testing.assert_allclose(at_pole, near, atol=0.01)


def test_validity_and_unknown_model_refused() -> None:
    with pytest.raises(ValueError, match="wmm2025 field is defined from 2025 to 2030"):
        geomagnetic.field_ned("wmm2025", 0.0, 0.0, 0.0, 2024.5)
    with pytest.raises(ValueError, match="igrf14 field is defined from 1900 to 2030"):
        geomagnetic.field_ned("igrf14", 0.0, 0.0, 0.0, 2031.0)
    with pytest.raises(ValueError, match="unknown field model 'chaos'"):
        geomagnetic.field_ned("chaos", 0.0, 0.0, 0.0, 2025.0)


def test_field_along_an_orbit_is_the_ecef_field_turned_by_the_earth_rotation_angle() -> None:
    import datetime as dt

    kepler = orbit.kepler_orbit(6.9e6, 0.01, math.radians(97.5), 0.3, 0.2, 0.1, j2=orbit.EARTH_J2)
    epoch = dt.datetime(2026, 3, 1, 6, 0, 0)
    along = geomagnetic.orbit_field("igrf14", kepler, epoch, 86400.0)
    for t in (0.0, 1234.5, 80000.0):
        r_eci, _ = kepler.state(t)
        era = orbit.earth_rotation_angle(orbit.days_since_j2000(epoch) + t / 86400.0)
        year = orbit.decimal_year(epoch) + t / geomagnetic.YEAR_SECONDS
        expected = orbit.ecef_to_eci(era, geomagnetic.field_ecef("igrf14", orbit.eci_to_ecef(era, r_eci), year))
        np.testing.assert_allclose(along.eci(t), expected, rtol=1e-12, atol=1e-18)
    q = np.array([0.1, 0.2, -0.3, 0.9]) / np.linalg.norm([0.1, 0.2, -0.3, 0.9])
    assert np.linalg.norm(along.body(5.0, q)) == pytest.approx(np.linalg.norm(along.eci(5.0)), rel=1e-14)
    with pytest.raises(ValueError, match="wmm2025 field is defined from 2025 to 2030"):
        geomagnetic.orbit_field("wmm2025", kepler, dt.datetime(2029, 12, 1), 86400.0 * 60)
