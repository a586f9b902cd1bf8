"""The Earth's main magnetic field: IGRF-14, WMM2025 and a tilted dipole, as spherical harmonics.

Pure numerics; the evaluation (:func:`field_spherical`, :func:`field_ecef_compiled`) is ``register_jitable``,
so the compiled step runs it at the step rate. Inputs: geodetic WGS-84 latitude, longitude (deg) and height
(m) (:func:`field_ned`), or an ECEF position (m) (:func:`field_ecef`); the time a decimal year
(:func:`rigid_rot_sim.core.orbit.decimal_year`). Outputs: nT in NED (north X, east Y, down Z: the NOAA test
values' components) or tesla in ECEF.

Models (:func:`model`; coefficients in :mod:`.geomagnetic_coefficients`, with their provenance)
-----------------------------------------------------------------------------------------------
* ``"igrf14"``: degree 13 (10 before 2000.0), Gauss coefficients linear in time between the 5-year epochs
  1900.0-2025.0, and from 2025.0 to 2030.0 along the predictive secular variation; valid 1900.0-2030.0.
* ``"wmm2025"``: degree 12, ``g(t) = g + (t - 2025.0) g_dot``; valid 2025.0-2030.0.
* ``"dipole"``: IGRF-14's degree-1 terms (g10, g11, h11) at the same time: the centred, tilted dipole.

The potential, on a sphere of reference radius ``a = 6371.2 km`` (geocentric radius r, colatitude theta,
longitude phi; P the Schmidt semi-normalised associated Legendre functions)::

    V = a sum_n (a/r)^(n+1) sum_m (g_nm cos m phi + h_nm sin m phi) P_nm(cos theta),   B = -grad V

computed with the Gauss-normalised recursions of Wertz (1978, appendix H) and the Schmidt factors folded into
the coefficients.

Along an orbit (:class:`OrbitField`, :func:`field_eci_on_orbit`): the body's ECI position from
:mod:`.orbit`, rotated into ECEF by the Earth rotation angle of the scene's epoch plus the sim time, the
field there rotated back to ECI; the decimal year advances by ``t / YEAR_SECONDS`` (a Julian year, 365.25
days: within a calendar year the fraction is off by under a day, 0.3 nT at the largest secular variation
of ~100 nT/yr). Evaluated at every call (the node's outputs, the compiled step): no field-update rate,
no interpolation error. At the geographic poles (sin theta < 1e-12) the colatitude is moved 1e-12 rad off the pole
(6 micrometres) so that the east component stays finite.
"""

from __future__ import annotations

import datetime as _dt
import functools
import math
from dataclasses import dataclass

import numpy as np
from numba.extending import register_jitable

from rigid_rot_sim.core import geomagnetic_coefficients as _coefficients
from rigid_rot_sim.core import orbit
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.jit import compiled
from rigid_rot_sim.core.orbit import KeplerOrbit

__all__ = [
    "MODELS",
    "REFERENCE_RADIUS",
    "FieldModel",
    "model",
    "field_ned",
    "field_ecef",
    "field_spherical",
    "field_ecef_compiled",
    "OrbitField",
    "orbit_field",
    "field_eci_on_orbit",
    "field_eci_on_orbit_compiled",
    "YEAR_SECONDS",
]

#: The models :func:`model` knows.
MODELS = ("igrf14", "wmm2025", "dipole")
#: The geomagnetic reference radius (m) of IGRF and WMM.
REFERENCE_RADIUS = 6371200.0


@dataclass(frozen=True)
class FieldModel:
    """Schmidt-folded Gauss coefficients at epochs, linear in time between them.

    ``epochs`` (K,) decimal years, increasing; ``g``, ``h`` (K, N+1, N+1) nT, already multiplied by the Schmidt
    factors (index ``[k, n, m]``); ``valid`` the (first, last) decimal year the model is defined on.
    """

    name: str
    epochs: np.ndarray
    g: np.ndarray
    h: np.ndarray
    valid: tuple[float, float]

    @property
    def degree(self) -> int:
        return int(self.g.shape[1] - 1)

    def check_time(self, year: float) -> None:
        """Raise ValueError when ``year`` is outside the model's validity."""
        first, last = self.valid
        if not (first <= year <= last):
            raise ValueError(f"the {self.name} field is defined from {first:g} to {last:g}, not at {year:.4f}")


def _schmidt(nmax: int) -> np.ndarray:
    """Gauss -> Schmidt semi-normalisation factors S[n, m] (Wertz H-9)."""
    s = np.zeros((nmax + 1, nmax + 1))
    s[0, 0] = 1.0
    for n in range(1, nmax + 1):
        s[n, 0] = s[n - 1, 0] * (2 * n - 1) / n
        for m in range(1, n + 1):
            s[n, m] = s[n, m - 1] * math.sqrt((n - m + 1) * (2.0 if m == 1 else 1.0) / (n + m))
    return s


def _igrf14() -> FieldModel:
    epochs = np.array(_coefficients.IGRF14_EPOCHS.split(), dtype=float)
    k = epochs.size
    rows = np.array(_coefficients.IGRF14_ROWS.split(), dtype=float).reshape(-1, 2 + k)
    nmax = int(rows[:, 0].max())
    g = np.zeros((k, nmax + 1, nmax + 1))
    h = np.zeros((k, nmax + 1, nmax + 1))
    for row in rows:
        n, m = int(row[0]), int(row[1])
        if m >= 0:
            g[:, n, m] = row[2:]
        else:
            h[:, n, -m] = row[2:]
    s = _schmidt(nmax)
    return FieldModel("igrf14", epochs, g * s, h * s, (float(epochs[0]), float(epochs[-1])))


def _wmm2025() -> FieldModel:
    epoch = float(_coefficients.WMM2025_HEADER.split()[0])
    rows = np.array(_coefficients.WMM2025_ROWS.split(), dtype=float).reshape(-1, 6)
    nmax = int(rows[:, 0].max())
    g = np.zeros((2, nmax + 1, nmax + 1))
    h = np.zeros((2, nmax + 1, nmax + 1))
    span = 5.0
    for n_, m_, gnm, hnm, gdot, hdot in rows:
        n, m = int(n_), int(m_)
        g[:, n, m] = gnm, gnm + span * gdot
        h[:, n, m] = hnm, hnm + span * hdot
    s = _schmidt(nmax)
    return FieldModel("wmm2025", np.array([epoch, epoch + span]), g * s, h * s, (epoch, epoch + span))


def _dipole() -> FieldModel:
    igrf = _igrf14()
    return FieldModel("dipole", igrf.epochs, igrf.g[:, :2, :2].copy(), igrf.h[:, :2, :2].copy(), igrf.valid)


@functools.cache
def model(name: str) -> FieldModel:
    """The field model called ``name`` (one of :data:`MODELS`), built once."""
    builders = {"igrf14": _igrf14, "wmm2025": _wmm2025, "dipole": _dipole}
    if name not in builders:
        raise ValueError(f"unknown field model {name!r}: one of {', '.join(MODELS)}")
    return builders[name]()


# ------------------------------------------------------------- evaluation (compiled into kernels)


@register_jitable
def field_spherical(
    epochs: np.ndarray, g: np.ndarray, h: np.ndarray, year: float, r: float, theta: float, phi: float
) -> tuple[float, float, float]:
    """``(B_r, B_theta, B_phi)`` (nT) at geocentric radius ``r`` (m), colatitude, longitude (rad).

    ``epochs``, ``g``, ``h`` as :class:`FieldModel`; ``year`` decimal; outside the epochs the nearest interval
    is extrapolated (the caller checks validity).
    """
    k = epochs.shape[0]
    j = 0
    while j < k - 2 and year >= epochs[j + 1]:
        j += 1
    w = (year - epochs[j]) / (epochs[j + 1] - epochs[j])
    nmax = g.shape[1] - 1
    ct = math.cos(theta)
    st = math.sin(theta)
    if st < 1e-12:
        st = 1e-12
    ratio = REFERENCE_RADIUS / r
    p = np.zeros((nmax + 1, nmax + 1))
    dp = np.zeros((nmax + 1, nmax + 1))
    p[0, 0] = 1.0
    cos_m = np.empty(nmax + 1)
    sin_m = np.empty(nmax + 1)
    for m in range(nmax + 1):
        cos_m[m] = math.cos(m * phi)
        sin_m[m] = math.sin(m * phi)
    b_r = 0.0
    b_t = 0.0
    b_p = 0.0
    power = ratio * ratio
    for n in range(1, nmax + 1):
        power *= ratio
        sum_r = 0.0
        sum_t = 0.0
        sum_p = 0.0
        for m in range(n + 1):
            if m == n:
                p[n, n] = st * p[n - 1, n - 1]
                dp[n, n] = st * dp[n - 1, n - 1] + ct * p[n - 1, n - 1]
            elif n == 1:
                p[n, m] = ct * p[n - 1, m]
                dp[n, m] = ct * dp[n - 1, m] - st * p[n - 1, m]
            else:
                kk = ((n - 1) * (n - 1) - m * m) / ((2 * n - 1) * (2 * n - 3))
                p[n, m] = ct * p[n - 1, m] - kk * p[n - 2, m]
                dp[n, m] = ct * dp[n - 1, m] - st * p[n - 1, m] - kk * dp[n - 2, m]
            gnm = g[j, n, m] + w * (g[j + 1, n, m] - g[j, n, m])
            hnm = h[j, n, m] + w * (h[j + 1, n, m] - h[j, n, m])
            c = gnm * cos_m[m] + hnm * sin_m[m]
            sum_r += c * p[n, m]
            sum_t += c * dp[n, m]
            sum_p += m * (gnm * sin_m[m] - hnm * cos_m[m]) * p[n, m]
        b_r += (n + 1) * power * sum_r
        b_t -= power * sum_t
        b_p += power * sum_p
    return b_r, b_t, b_p / st


@register_jitable
def field_ecef_compiled(
    epochs: np.ndarray, g: np.ndarray, h: np.ndarray, year: float, x: float, y: float, z: float
) -> tuple[float, float, float]:
    """The field (nT) in ECEF at the ECEF position ``(x, y, z)`` (m)."""
    r = math.sqrt(x * x + y * y + z * z)
    rho = math.hypot(x, y)
    theta = math.atan2(rho, z)
    phi = math.atan2(y, x)
    b_r, b_t, b_p = field_spherical(epochs, g, h, year, r, theta, phi)
    ct, st = math.cos(theta), math.sin(theta)
    cp, sp = math.cos(phi), math.sin(phi)
    b_rho = b_r * st + b_t * ct
    return b_rho * cp - b_p * sp, b_rho * sp + b_p * cp, b_r * ct - b_t * st


def field_ecef(model_name: str, r_ecef_m: np.ndarray, decimal_year: float) -> np.ndarray:
    """The field (T) in ECEF at ECEF position ``r_ecef_m`` (m) at ``decimal_year``."""
    m = model(model_name)
    m.check_time(decimal_year)
    x, y, z = (float(c) for c in np.asarray(r_ecef_m, dtype=float))
    return np.array(field_ecef_compiled(m.epochs, m.g, m.h, float(decimal_year), x, y, z)) * 1e-9


def field_ned(
    model_name: str, latitude_deg: float, longitude_deg: float, altitude_m: float, decimal_year: float
) -> np.ndarray:
    """The field (nT) in north, east, down at a geodetic WGS-84 point (deg, deg, m above the ellipsoid)."""
    latitude = math.radians(latitude_deg)
    longitude = math.radians(longitude_deg)
    r_ecef = np.array(orbit.geodetic_to_ecef(latitude, longitude, float(altitude_m)))
    ned: np.ndarray = orbit.ned_matrix(latitude, longitude) @ field_ecef(model_name, r_ecef, decimal_year)
    return ned * 1e9


#: A Julian year, s: how the field's decimal year advances with sim time along an orbit.
YEAR_SECONDS = 365.25 * 86400.0


@register_jitable
def field_eci_on_orbit(
    kepler: np.ndarray,
    epochs: np.ndarray,
    g: np.ndarray,
    h: np.ndarray,
    epoch_days: float,
    epoch_year: float,
    t: float,
) -> tuple[float, float, float]:
    """The field (nT, ECI) at the body on ``kepler`` (:meth:`KeplerOrbit.compiled`) at sim time ``t`` (s).

    ``epoch_days``: days since J2000.0 (UT1 = UTC) of t = 0; ``epoch_year``: its decimal year.
    """
    x, y, z, _, _, _ = orbit.orbit_state(kepler, t)
    era = orbit.earth_rotation_angle(epoch_days + t / 86400.0)
    c, s = math.cos(era), math.sin(era)
    bx, by, bz = field_ecef_compiled(epochs, g, h, epoch_year + t / YEAR_SECONDS, c * x + s * y, c * y - s * x, z)
    return c * bx - s * by, s * bx + c * by, bz


#: :func:`field_eci_on_orbit` compiled, for Python callers (a call of the pure-Python one costs ~1 ms).
field_eci_on_orbit_compiled = compiled(field_eci_on_orbit)


@dataclass(frozen=True)
class OrbitField:
    """The field a body on ``kepler`` sees: ``model``, and t = 0 at ``epoch_days`` (since J2000.0) and
    ``epoch_year`` (decimal). :func:`orbit_field` builds one with its validity checked."""

    model: FieldModel
    kepler: KeplerOrbit
    epoch_days: float
    epoch_year: float

    def eci(self, t: float) -> np.ndarray:
        """The field (T) in ECI at sim time ``t`` (s)."""
        m = self.model
        b = field_eci_on_orbit_compiled(
            self.kepler.compiled(), m.epochs, m.g, m.h, self.epoch_days, self.epoch_year, float(t)
        )
        return np.array(b) * 1e-9

    def body(self, t: float, orientation: np.ndarray) -> np.ndarray:
        """The field (T) in the body frame at sim time ``t`` (s), attitude ``orientation`` (x, y, z, w) body -> ECI."""
        return np.array(quat.rotate_inverse(orientation, self.eci(t)))


def orbit_field(model_name: str, kepler: KeplerOrbit, epoch: _dt.datetime, duration: float | None) -> OrbitField:
    """The field ``model_name`` along ``kepler`` from ``epoch`` (UTC); ValueError when the run's span
    (``duration`` s; None: the epoch alone) leaves the model's validity."""
    field = model(model_name)
    year = orbit.decimal_year(epoch)
    field.check_time(year)
    if duration is not None:
        field.check_time(year + duration / YEAR_SECONDS)
    return OrbitField(field, kepler, orbit.days_since_j2000(epoch), year)
