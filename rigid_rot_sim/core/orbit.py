"""Keplerian orbits with first-order secular J2, the Earth's rotation, and the Earth-fixed frames.

Pure numerics (numpy, numba's ``register_jitable`` so that the kernels compile the same formulas). SI units,
angles in radians, times in seconds.

Frames
------
* ECI: the inertial frame of the orbit (x to the vernal equinox, z to the celestial pole; the scene's world
  frame when it has an ``orbit:``). Taken as the GCRF of the epoch with neither precession nor nutation: the
  Earth's rotation is a rotation by the Earth rotation angle about z.
* ECEF: Earth-fixed, ``r_ecef = R_z(-theta) r_eci`` with ``theta`` the Earth rotation angle (ERA, IERS 2010
  eq. 5.15) of UT1, taken equal to UTC (|UT1 - UTC| < 0.9 s, a 3.7e-4 deg rotation at most), without polar
  motion (< 0.5 arcsec), precession and nutation (these move the pole some 0.35 deg between 2000 and 2025 in
  the GCRF: a field model evaluated with this ECEF is off by that tilt, the price of an orbit frame that needs
  no Earth orientation data).
* geodetic: WGS-84 latitude, longitude (rad) and height above the ellipsoid (m).
* NED: north, east, down at a geodetic point; LVLH: x along-track (completing the triad), y minus the orbit
  normal, z nadir (to the Earth's centre).

Elements
--------
The classical elements ``(a, e, i, raan, argp, nu)`` as Basilisk's ``orbitalMotion.elem2rv``: semi-major axis
(m), eccentricity, inclination, right ascension of the ascending node, argument of periapsis, true anomaly.
Kepler's equation ``M = E - e sin E`` is solved by Newton's method to round-off for 0 <= e < 1.

J2 (:func:`mean_element_rates`): the first-order secular rates of the mean elements (Vallado, eqs. 9-41):
``raan_dot = -3/2 n J2 (R/p)^2 cos i``, ``argp_dot = 3/4 n J2 (R/p)^2 (5 cos^2 i - 1)``,
``M_dot = n (1 + 3/4 J2 (R/p)^2 sqrt(1 - e^2) (3 cos^2 i - 1))``, ``p = a (1 - e^2)``. A :class:`KeplerOrbit`
with J2 places the body on the osculating ellipse of the drifting mean elements: it leaves out J2's
short-period terms (a few km in LEO), not its secular drift.
"""

from __future__ import annotations

import datetime as _dt
import math
from dataclasses import dataclass

import numpy as np
from numba.extending import register_jitable

__all__ = [
    "EARTH_MU",
    "EARTH_J2",
    "EARTH_RADIUS",
    "WGS84_FLATTENING",
    "EARTH_ROTATION_RATE",
    "Elements",
    "KeplerOrbit",
    "eccentric_anomaly",
    "true_to_mean_anomaly",
    "mean_to_true_anomaly",
    "elements_to_rv",
    "rv_to_elements",
    "mean_element_rates",
    "kepler_orbit",
    "days_since_j2000",
    "decimal_year",
    "earth_rotation_angle",
    "eci_to_ecef",
    "ecef_to_eci",
    "geodetic_to_ecef",
    "ecef_to_geodetic",
    "ned_matrix",
    "lvlh_matrix",
]

#: The Earth's gravitational parameter (m^3/s^2), WGS-84 / EGM2008.
EARTH_MU = 3.986004418e14
#: The Earth's J2, EGM2008 (-sqrt(5) C20-bar), unnormalised.
EARTH_J2 = 1.082626925638815e-3
#: WGS-84 equatorial radius (m), the reference radius of J2.
EARTH_RADIUS = 6378137.0
#: WGS-84 flattening.
WGS84_FLATTENING = 1.0 / 298.257223563
#: d(ERA)/dt (rad/s of UT1): 2 pi 1.00273781191135448 per day.
EARTH_ROTATION_RATE = 2.0 * math.pi * 1.00273781191135448 / 86400.0

_J2000 = _dt.datetime(2000, 1, 1, 12, 0, 0, tzinfo=_dt.timezone.utc)
_WGS84_E2 = WGS84_FLATTENING * (2.0 - WGS84_FLATTENING)
_TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class Elements:
    """Classical elements: ``a`` (m), ``e``, ``i``, ``raan``, ``argp``, ``nu`` (rad)."""

    a: float
    e: float
    i: float
    raan: float
    argp: float
    nu: float


# ------------------------------------------------------------- anomalies


@register_jitable
def eccentric_anomaly(mean_anomaly: float, e: float) -> float:
    """E with ``E - e sin E = M`` (rad), 0 <= e < 1, to round-off (Newton from ``M + e sin M``, or pi)."""
    m = float(np.fmod(mean_anomaly, 2.0 * math.pi))
    if m > math.pi:
        m -= 2.0 * math.pi
    elif m < -math.pi:
        m += 2.0 * math.pi
    big = e > 0.8
    ea = (math.pi if m >= 0.0 else -math.pi) if big else m + e * math.sin(m)
    for _ in range(60):
        step = (ea - e * math.sin(ea) - m) / (1.0 - e * math.cos(ea))
        ea -= step
        if abs(step) <= 4e-16 * max(1.0, abs(ea)):
            break
    return ea


@register_jitable
def mean_to_true_anomaly(mean_anomaly: float, e: float) -> float:
    """The true anomaly (rad, in (-pi, pi]) at mean anomaly ``M`` (rad), 0 <= e < 1."""
    ea = eccentric_anomaly(mean_anomaly, e)
    return 2.0 * math.atan2(math.sqrt(1.0 + e) * math.sin(0.5 * ea), math.sqrt(1.0 - e) * math.cos(0.5 * ea))


def true_to_mean_anomaly(nu: float, e: float) -> float:
    """The mean anomaly (rad, in (-pi, pi]) at true anomaly ``nu`` (rad), 0 <= e < 1."""
    ea = 2.0 * math.atan2(math.sqrt(1.0 - e) * math.sin(0.5 * nu), math.sqrt(1.0 + e) * math.cos(0.5 * nu))
    return ea - e * math.sin(ea)


# ------------------------------------------------------------- elements <-> state


@register_jitable
def _rv(
    mu: float, a: float, e: float, i: float, raan: float, argp: float, nu: float
) -> tuple[float, float, float, float, float, float]:
    p = a * (1.0 - e * e)
    r = p / (1.0 + e * math.cos(nu))
    theta = argp + nu
    co, so = math.cos(raan), math.sin(raan)
    ci, si = math.cos(i), math.sin(i)
    ct, st = math.cos(theta), math.sin(theta)
    cw, sw = math.cos(argp), math.sin(argp)
    k = -math.sqrt(mu / p)
    s1 = st + e * sw
    c1 = ct + e * cw
    return (
        r * (co * ct - so * st * ci),
        r * (so * ct + co * st * ci),
        r * st * si,
        k * (co * s1 + so * c1 * ci),
        k * (so * s1 - co * c1 * ci),
        -k * c1 * si,
    )


def elements_to_rv(
    mu: float, a: float, e: float, i: float, raan: float, argp: float, nu: float
) -> tuple[np.ndarray, np.ndarray]:
    """Position (m) and velocity (m/s) in the inertial frame of the elements (Basilisk's ``elem2rv``).

    ``mu`` m^3/s^2, ``a`` m (> 0, 0 <= e < 1), angles rad.
    """
    if not (a > 0.0 and 0.0 <= e < 1.0):
        raise ValueError(f"elements_to_rv takes an ellipse: a > 0 m and 0 <= e < 1, got a={a!r}, e={e!r}")
    x = _rv(mu, a, e, i, raan, argp, nu)
    return np.array(x[:3]), np.array(x[3:])


def rv_to_elements(mu: float, r: np.ndarray, v: np.ndarray) -> Elements:
    """The classical elements of the state ``r`` (m), ``v`` (m/s) on an ellipse.

    Where an angle is undefined the convention is Basilisk's: on a circular orbit ``argp = 0`` and ``nu`` is the
    argument of latitude; on an equatorial one ``raan = 0`` and the node is the x axis.
    """
    r = np.asarray(r, dtype=float)
    v = np.asarray(v, dtype=float)
    rn = float(np.linalg.norm(r))
    h = np.cross(r, v)
    hn = float(np.linalg.norm(h))
    energy = float(v @ v) / 2.0 - mu / rn
    if not energy < 0.0:
        raise ValueError(f"rv_to_elements takes an ellipse (negative energy), got {energy:g} J/kg")
    a = -mu / (2.0 * energy)
    e_vec = np.cross(v, h) / mu - r / rn
    e = float(np.linalg.norm(e_vec))
    i = math.acos(max(-1.0, min(1.0, h[2] / hn)))
    node = np.array([-h[1], h[0], 0.0])
    nn = float(np.linalg.norm(node))
    tiny = 1e-11
    if nn > tiny * hn:
        raan = math.atan2(node[1], node[0]) % _TWO_PI
        n_hat = node / nn
    else:
        raan, n_hat = 0.0, np.array([1.0, 0.0, 0.0])
    m_hat = np.cross(h / hn, n_hat)  # 90 deg ahead of the node in the orbit plane
    if e > tiny:
        argp = math.atan2(float(e_vec @ m_hat), float(e_vec @ n_hat)) % _TWO_PI
        p_hat = e_vec / e
        q_hat = np.cross(h / hn, p_hat)
        nu = math.atan2(float(r @ q_hat), float(r @ p_hat)) % _TWO_PI
    else:
        argp = 0.0
        nu = math.atan2(float(r @ m_hat), float(r @ n_hat)) % _TWO_PI
    return Elements(a, e, i, raan, argp, nu)


def mean_element_rates(mu: float, j2: float, r_eq: float, a: float, e: float, i: float) -> tuple[float, float, float]:
    """First-order secular J2 rates (rad/s) of the mean elements: ``(raan_dot, argp_dot, mean_anomaly_dot)``.

    ``mu`` m^3/s^2, ``r_eq`` the reference radius of ``j2`` (m), ``a`` m, ``i`` rad; the mean anomaly's rate
    includes the mean motion ``n = sqrt(mu / a^3)``.
    """
    n = math.sqrt(mu / a**3)
    p = a * (1.0 - e * e)
    k = n * j2 * (r_eq / p) ** 2
    c = math.cos(i)
    return (
        -1.5 * k * c,
        0.75 * k * (5.0 * c * c - 1.0),
        n + 0.75 * k * math.sqrt(1.0 - e * e) * (3.0 * c * c - 1.0),
    )


# ------------------------------------------------------------- a propagated orbit


@dataclass(frozen=True)
class KeplerOrbit:
    """An orbit of the Earth's centre: elements at t = 0 and their secular rates (zero without J2).

    ``a`` m, ``e``, ``i``, ``raan``, ``argp``, ``mean_anomaly`` rad at t = 0; ``mu`` m^3/s^2; ``j2`` the J2 used
    for the rates (0 for a Keplerian orbit); rates rad/s (:func:`mean_element_rates`).
    """

    mu: float
    a: float
    e: float
    i: float
    raan: float
    argp: float
    mean_anomaly: float
    j2: float = 0.0
    raan_dot: float = 0.0
    argp_dot: float = 0.0
    mean_anomaly_dot: float = 0.0

    @property
    def period(self) -> float:
        """The anomalistic period 2 pi / M_dot (s)."""
        return _TWO_PI / self.mean_anomaly_dot

    def compiled(self) -> np.ndarray:
        """``(mu, a, e, i, raan, argp, M, raan_dot, argp_dot, M_dot)`` for :func:`orbit_state`."""
        return np.array(
            [
                self.mu,
                self.a,
                self.e,
                self.i,
                self.raan,
                self.argp,
                self.mean_anomaly,
                self.raan_dot,
                self.argp_dot,
                self.mean_anomaly_dot,
            ]
        )

    def state(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Position (m) and velocity (m/s) in ECI at time ``t`` (s after the epoch)."""
        x = orbit_state(self.compiled(), t)
        return np.array(x[:3]), np.array(x[3:])


@register_jitable
def orbit_state(orbit: np.ndarray, t: float) -> tuple[float, float, float, float, float, float]:
    """``(x, y, z, vx, vy, vz)`` (m, m/s, ECI) of :meth:`KeplerOrbit.compiled` at ``t`` (s)."""
    mean_anomaly = float(np.fmod(orbit[6] + orbit[9] * t, 2.0 * math.pi))
    nu = mean_to_true_anomaly(mean_anomaly, orbit[2])
    return _rv(orbit[0], orbit[1], orbit[2], orbit[3], orbit[4] + orbit[7] * t, orbit[5] + orbit[8] * t, nu)


def kepler_orbit(
    a: float,
    e: float,
    i: float,
    raan: float,
    argp: float,
    nu: float,
    *,
    mu: float = EARTH_MU,
    j2: float = 0.0,
    r_eq: float = EARTH_RADIUS,
) -> KeplerOrbit:
    """A validated :class:`KeplerOrbit` from elements at t = 0 (true anomaly ``nu``); ``j2 = 0``: Keplerian."""
    values = {"a": a, "e": e, "i": i, "raan": raan, "argp": argp, "nu": nu, "mu": mu, "j2": j2}
    for name, value in values.items():
        if not math.isfinite(value):
            raise ValueError(f"orbit {name} must be finite, got {value!r}")
    if not (mu > 0.0 and a > 0.0 and 0.0 <= e < 1.0 and 0.0 <= i <= math.pi and j2 >= 0.0):
        raise ValueError(
            f"an orbit needs mu > 0, a > 0 m, 0 <= e < 1, 0 <= i <= pi and j2 >= 0, got mu={mu!r}, a={a!r}, "
            f"e={e!r}, i={i!r}, j2={j2!r}"
        )
    if a * (1.0 - e) <= r_eq and j2 > 0.0:
        raise ValueError(f"the periapsis a (1 - e) = {a * (1.0 - e):g} m is inside the Earth (radius {r_eq:g} m)")
    rates = mean_element_rates(mu, j2, r_eq, a, e, i)
    return KeplerOrbit(mu, a, e, i, raan, argp, true_to_mean_anomaly(nu, e), j2, *rates)


# ------------------------------------------------------------- time and the Earth's rotation


def days_since_j2000(when: _dt.datetime) -> float:
    """Days (of 86400 s) from 2000-01-01T12:00:00 UTC to ``when`` (naive = UTC), leap seconds left out."""
    if when.tzinfo is None:
        when = when.replace(tzinfo=_dt.timezone.utc)
    return (when - _J2000).total_seconds() / 86400.0


def decimal_year(when: _dt.datetime) -> float:
    """``when`` (naive = UTC) as a decimal year: the year plus the fraction of its length (the field models')."""
    if when.tzinfo is None:
        when = when.replace(tzinfo=_dt.timezone.utc)
    start = _dt.datetime(when.year, 1, 1, tzinfo=_dt.timezone.utc)
    end = _dt.datetime(when.year + 1, 1, 1, tzinfo=_dt.timezone.utc)
    return when.year + (when - start).total_seconds() / (end - start).total_seconds()


@register_jitable
def earth_rotation_angle(days: float) -> float:
    """ERA (rad, in [0, 2 pi)) at ``days`` of UT1 since J2000.0 (IERS 2010 eq. 5.15; UT1 taken as UTC)."""
    whole = math.floor(days)
    turns = 0.7790572732640 + 0.00273781191135448 * days + (days - whole)
    return 2.0 * math.pi * (turns - math.floor(turns))


@register_jitable
def _rotate_z(angle: float, x: float, y: float, z: float) -> tuple[float, float, float]:
    c, s = math.cos(angle), math.sin(angle)
    return c * x - s * y, s * x + c * y, z


def eci_to_ecef(era: float, vector_eci: np.ndarray) -> np.ndarray:
    """A vector from ECI to ECEF at Earth rotation angle ``era`` (rad): ``R_z(-era) v``."""
    return np.array(_rotate_z(-era, *np.asarray(vector_eci, dtype=float)))


def ecef_to_eci(era: float, vector_ecef: np.ndarray) -> np.ndarray:
    """A vector from ECEF to ECI at Earth rotation angle ``era`` (rad): ``R_z(era) v``."""
    return np.array(_rotate_z(era, *np.asarray(vector_ecef, dtype=float)))


# ------------------------------------------------------------- WGS-84


@register_jitable
def geodetic_to_ecef(latitude: float, longitude: float, height: float) -> tuple[float, float, float]:
    """ECEF position (m) of WGS-84 geodetic latitude, longitude (rad) and height (m)."""
    sl, cl = math.sin(latitude), math.cos(latitude)
    n = EARTH_RADIUS / math.sqrt(1.0 - _WGS84_E2 * sl * sl)
    return (
        (n + height) * cl * math.cos(longitude),
        (n + height) * cl * math.sin(longitude),
        (n * (1.0 - _WGS84_E2) + height) * sl,
    )


@register_jitable
def ecef_to_geodetic(x: float, y: float, z: float) -> tuple[float, float, float]:
    """WGS-84 geodetic latitude, longitude (rad) and height (m) of an ECEF position (m), to round-off.

    Fixed-point iteration on the latitude from the geocentric one (converges to 1e-15 rad in a few passes above
    the Earth's centre region; 30 passes at most).
    """
    p = math.hypot(x, y)
    longitude = math.atan2(y, x)
    latitude = math.atan2(z, p * (1.0 - _WGS84_E2))
    height = 0.0
    for _ in range(30):
        sl = math.sin(latitude)
        n = EARTH_RADIUS / math.sqrt(1.0 - _WGS84_E2 * sl * sl)
        previous = latitude
        latitude = math.atan2(z + _WGS84_E2 * n * sl, p)
        if abs(latitude - previous) < 1e-15:
            break
    sl, cl = math.sin(latitude), math.cos(latitude)
    n = EARTH_RADIUS / math.sqrt(1.0 - _WGS84_E2 * sl * sl)
    # The height along the normal, well conditioned at any latitude.
    height = p * cl + z * sl - n * (1.0 - _WGS84_E2 * sl * sl)
    return latitude, longitude, height


def ned_matrix(latitude: float, longitude: float) -> np.ndarray:
    """Rows: north, east, down at a geodetic point, in ECEF: ``v_ned = ned_matrix @ v_ecef``."""
    sl, cl = math.sin(latitude), math.cos(latitude)
    so, co = math.sin(longitude), math.cos(longitude)
    return np.array([[-sl * co, -sl * so, cl], [-so, co, 0.0], [-cl * co, -cl * so, -sl]])


def lvlh_matrix(r: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rows: LVLH x (along-track), y (minus the orbit normal), z (nadir) in the frame of ``r``, ``v``.

    ``v_lvlh = lvlh_matrix(r, v) @ v_frame``.
    """
    r = np.asarray(r, dtype=float)
    h = np.cross(r, np.asarray(v, dtype=float))
    z = -r / np.linalg.norm(r)
    y = -h / np.linalg.norm(h)
    return np.array([np.cross(y, z), y, z])
