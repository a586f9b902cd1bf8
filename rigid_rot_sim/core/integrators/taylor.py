"""High-order Taylor series method for the rigid body with a polynomial-structured torque.

State ``x = (omega_1, omega_2, omega_3, q_x, q_y, q_z, q_w)`` in the principal body frame.
Euler's equations ``I1 w1' = (I2 - I3) w2 w3 + N1`` (cyclic) and the kinematics
``q' = 1/2 q (x) (omega, 0)`` are quadratic polynomials in x, and so is the torque of
uniform gravity about a pivot (:class:`~rigid_rot_sim.core.torque.GravityTorque` is
bilinear in q). Every right-hand side therefore has the form

    f_o(x) = sum_ij C[o, i, j] x_i x_j + b_o(t),

with ``b`` polynomial in time (a constant or :class:`PolynomialTorque`, and the constant
part of the gravity torque). Writing ``x(t0 + s) = sum_k X_k s^k``, the Taylor
coefficient of a product is the Cauchy product ``(x_i x_j)_k = sum_m X_m,i X_k-m,j``, so

    X_{k+1} = ( C : (X_0..k)^T (X_k..0)  +  b_k ) / (k + 1),

one contraction per order. Only the Cauchy products that C uses are formed. Without gravity
(the common case: free body, constant or polynomial torque) the recurrence is written out
(:func:`rigid_body_series`): the fifteen products of Euler's equations and the kinematics
share one pass over the coefficients with seven independent accumulators, about 2.5x faster
than running them through tables. With gravity (up to ten more products) it runs the list
of C's non-zero entries (:func:`general_series`), built once per body and gravity term and
cached (:func:`recurrence_tables`); the recurrence, the step control and the dense
output are compiled numba kernels (``register_jitable``, run by one cached loop over API
steps), so an internal step costs a few microseconds and a 1 kHz node step that ends
inside the last series one polynomial evaluation.

Order and step (Jorba & Zou, "A software package for the numerical integration of ODEs
by means of high-order Taylor methods", Experimental Mathematics 14 (2005) 99-117):
the coefficients of an analytic solution decay like ``|X_k| ~ s * rho^-k`` with rho the
distance to the nearest complex singularity. The step is the largest h for which the
last two terms of the series stay below the tolerance,
``h = min_{k in {p-1, p}} (tol / |W X_k|_inf)^(1/k)``, hence h ~ rho * tol^(1/p), where the
weights W take omega relative to ``max(1 rad/s, |omega|_inf)`` and the unit quaternion
absolutely (a fast spin must not loosen the attitude tolerance).
Per unit time the cost is ~ p / h (constant cost per order), minimised at
``p = -ln(tol)`` with h ~ rho / e; Jorba and Zou's ``p = -ln(tol) / 2`` (h ~ rho / e^2)
minimises arithmetic ~ p^2 / h instead, which is not our cost model. The default is
``p = ceil(-ln(tol))`` clamped to 10..30; benchmarks/taylor_vs_scipy.py measures both.
When the step is cut short (landing on a multiple of dt, or ``max_step``), the order is
lowered to the one the previous radius estimate says is enough for that shorter step,
and the same last-two-terms test still decides: if that order was too low the step is
shortened, never accepted above tolerance.

The method is adaptive inside each API step of length ``dt`` and reports the state
exactly at its end: ``simulate(..., dt=T, method='taylor')`` is one API step made of
large internal steps. The series of the last internal step is a dense output: an API
step that ends inside it costs one polynomial evaluation, so the internal steps do not
depend on dt (a 1 kHz node step costs ~10 us). When the torque object was replaced
before a step (commands at the step rate) the internal steps land on the end of the API
step instead (the last one shortened, with the lowered order described above), since a
series computed for the old torque is of no further use.

The quaternion is renormalised after every internal step: the exact flow keeps |q| = 1,
but the truncated series keeps it only to the truncation error, and the drift would
accumulate over many steps (and slowly scale the gravity torque, which is quadratic
in q). The projection is smaller than the local error and does not lower the order.

Torques: None, ConstantTorque, PolynomialTorque and GravityTorque are expanded exactly.
Any other callable is refused with a ValueError: the recurrence needs the torque's
Taylor coefficients, which a black-box ``torque(t, q, omega)`` does not provide, and
freezing it over a step would silently drop the method to first order.
"""

from __future__ import annotations

import functools
import math
from typing import Any, ClassVar

import numpy as np
from numba.extending import register_jitable

from rigid_rot_sim.core.arrays import ArrayLike, FloatArray, IntArray
from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError, UnsupportedTorqueError
from rigid_rot_sim.core.jit import compiled
from rigid_rot_sim.core.torque import ConstantTorque, GravityTorque, PolynomialTorque, TorqueFunction

SUPPORTED_TORQUES = "None (free body), ConstantTorque, PolynomialTorque, GravityTorque"

MIN_AUTO_ORDER = 10
MAX_AUTO_ORDER = 30
MAX_ORDER = 60
DEFAULT_TOL = 1e-12

_NOT_BUILT = object()  # marks maps not yet built for any torque

# State layout: omega (rad/s) first, then the quaternion (x, y, z, w).
_W1, _W2, _W3, _QX, _QY, _QZ, _QW = range(7)
_STATE_SIZE = 7


def order_for_tolerance(tol: float) -> int:
    """Series order used for the local error tolerance ``tol``: ceil(-ln tol) in 10..30."""
    return int(min(MAX_AUTO_ORDER, max(MIN_AUTO_ORDER, math.ceil(-math.log(tol)))))


def euler_coefficients(i1: float, i2: float, i3: float) -> tuple[float, float, float]:
    """``((I2 - I3) / I1, (I3 - I1) / I2, (I1 - I2) / I3)``: Euler's equations as ``w1' = c1 w2 w3 + N1 / I1``
    (cyclic), the coefficients of the recurrence's quadratic terms (moments in kg*m^2)."""
    return (i2 - i3) / i1, (i3 - i1) / i2, (i1 - i2) / i3


#: The kernels' coefficient buffer and recurrence tables as one argument: (coeffs, pairs, terms,
#: term_values, inverse_orders, forcing, binom, poly, const_forcing).
Recurrence = tuple[
    FloatArray, IntArray, IntArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray
]


@functools.lru_cache(maxsize=256)
def recurrence_tables(key: tuple[Any, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(pairs, terms, term_values, b) for the compiled recurrence, cached per body (and gravity).

    ``key`` is ``(I1, I2, I3)`` or ``(I1, I2, I3, lever_arm, weight)`` with gravity. Without gravity
    the recurrence is :func:`rigid_body_series` (no tables: ``pairs`` is empty and ``term_values``
    holds Euler's three coefficients); with gravity :func:`general_series` runs the non-zero
    entries of :func:`derivative_map`'s C: the pairs (i, j) of the Cauchy products it needs, each
    once, and the terms (output, pair) with their values. The arrays are read-only (shared).
    """
    moments = np.array(key[:3], dtype=float)
    if len(key) == 3:
        pairs = np.zeros((0, 2), dtype=np.int64)
        terms = np.zeros((0, 2), dtype=np.int64)
        values = np.array(euler_coefficients(*key))
        b = np.zeros(_STATE_SIZE)
    else:
        c, b = derivative_map(moments, GravityTorque(np.array(key[3]), key[4]))
        entries = np.argwhere(c != 0.0)
        pair_list = sorted({(int(i), int(j)) for _, i, j in entries})
        index = {pair: k for k, pair in enumerate(pair_list)}
        pairs = np.array(pair_list, dtype=np.int64).reshape(-1, 2)
        terms = np.array([[o, index[(i, j)]] for o, i, j in entries], dtype=np.int64).reshape(-1, 2)
        values = np.array([c[o, i, j] for o, i, j in entries], dtype=float)
    for array in (pairs, terms, values, b):
        array.setflags(write=False)
    return pairs, terms, values, b


@functools.cache
def _inverse_orders(p: int) -> np.ndarray:
    """1 / (1, 2, ..., p), read-only (shared by every instance of order p)."""
    inverse = 1.0 / np.arange(1, p + 1, dtype=float)
    inverse.setflags(write=False)
    return inverse


def derivative_map(moments: np.ndarray, gravity: GravityTorque | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The quadratic form ``C`` (7, 7, 7) and constant ``b`` (7,) with ``x' = C:x x + b``.

    Parameters
    ----------
    moments : ndarray, shape (3,)
        Principal moments (I1, I2, I3), kg*m^2.
    gravity : GravityTorque or None
        Gravity about a pivot, whose torque is quadratic in q (plus a constant part).

    Returns
    -------
    C : ndarray, shape (7, 7, 7)
        ``x'_o = sum_ij C[o, i, j] x_i x_j + b_o`` for the state (omega, q).
    b : ndarray, shape (7,)
        The state-independent part (gravity's constant part; add other torques / I).
    """
    i1, i2, i3 = (float(v) for v in moments)
    c = np.zeros((_STATE_SIZE, _STATE_SIZE, _STATE_SIZE))
    b = np.zeros(_STATE_SIZE)
    # Euler's equations, principal frame.
    c[_W1, _W2, _W3], c[_W2, _W3, _W1], c[_W3, _W1, _W2] = euler_coefficients(i1, i2, i3)
    # q' = 1/2 q (x) (omega, 0), Hamilton product, scalar-last.
    c[_QX, _QW, _W1], c[_QX, _QY, _W3], c[_QX, _QZ, _W2] = 0.5, 0.5, -0.5
    c[_QY, _QW, _W2], c[_QY, _QZ, _W1], c[_QY, _QX, _W3] = 0.5, 0.5, -0.5
    c[_QZ, _QW, _W3], c[_QZ, _QX, _W2], c[_QZ, _QY, _W1] = 0.5, 0.5, -0.5
    c[_QW, _QX, _W1], c[_QW, _QY, _W2], c[_QW, _QZ, _W3] = -0.5, -0.5, -0.5
    if gravity is not None:
        # The world z axis in body coordinates (GravityTorque's formula, third row of
        # R(q)) as a quadratic form in q plus the constant e_z.
        up = np.zeros((3, _STATE_SIZE, _STATE_SIZE))
        up[0, _QX, _QZ], up[0, _QW, _QY] = 2.0, -2.0
        up[1, _QY, _QZ], up[1, _QW, _QX] = 2.0, 2.0
        up[2, _QX, _QX], up[2, _QY, _QY] = -2.0, -2.0
        up_const = np.array([0.0, 0.0, 1.0])
        rx, ry, rz = gravity.lever_arm
        # torque = lever_arm x (-weight * up) = M @ up
        m = -float(gravity.weight) * np.array([[0.0, -rz, ry], [rz, 0.0, -rx], [-ry, rx, 0.0]])
        inv_i = np.array([1.0 / i1, 1.0 / i2, 1.0 / i3])
        c[:3] += np.einsum("c,cd,dij->cij", inv_i, m, up)
        b[:3] += inv_i * (m @ up_const)
    return c, b


def taylor_coefficients(x0: np.ndarray, order: int, c: np.ndarray, forcing: np.ndarray | None = None) -> np.ndarray:
    """Taylor coefficients ``X[k]`` (order + 1, 7) of the solution of ``x' = C:x x + b(s)``.

    ``x(s) = sum_k X[k] s^k`` near s = 0 with ``x(0) = x0``; ``forcing[j]`` (n, 7) is the
    coefficient of ``s^j`` in b(s) (None: b = 0). A plain reference form of the
    recurrence that :class:`Taylor` runs in place.
    """
    x = np.zeros((order + 1, _STATE_SIZE))
    x[0] = x0
    c_flat = c.reshape(_STATE_SIZE, _STATE_SIZE * _STATE_SIZE)
    n_forcing = 0 if forcing is None else len(forcing)
    for k in range(order):
        products = x[: k + 1].T @ x[k::-1]
        f = c_flat @ products.ravel()
        if forcing is not None and k < n_forcing:
            f = f + forcing[k]
        x[k + 1] = f / (k + 1)
    return x


class Taylor(Integrator):
    """Adaptive high-order Taylor series method (see the module docstring).

    Options
    -------
    tol : float or None
        Local error tolerance per internal step: absolute on the unit quaternion, on omega
        relative to ``max(1 rad/s, |omega|_inf)``; default 1e-12. Sets the order
        (ceil(-ln tol) in 10..30) and the step. ``None`` switches step control off: one
        internal step of the given ``order`` per ``min(dt, max_step)`` (for convergence
        studies).
    order : int or None
        Series order (2..60) overriding the one derived from ``tol``.
    max_step : float
        Upper bound on the internal step, s (default: unbounded).
    """

    name: ClassVar[str] = "taylor"
    orders: ClassVar[tuple[int, ...]] = (28,)  # the series order at the default tol; per instance: series_order
    stability = "adaptive"
    fixed_step: ClassVar[bool] = False

    def __init__(
        self,
        moments: ArrayLike,
        dt: float,
        torque: TorqueFunction | None = None,
        *,
        tol: float | None = DEFAULT_TOL,
        order: int | None = None,
        max_step: float = math.inf,
        **kwargs: Any,
    ) -> None:
        if tol is not None:
            tol = float(tol)
            if not (math.isfinite(tol) and 0.0 < tol < 1.0):
                raise ValueError(f"taylor: tol must be in (0, 1), got {tol}")
        if order is None:
            if tol is None:
                raise ValueError("taylor: tol=None (no step control) needs an explicit order")
            order = order_for_tolerance(tol)
        elif isinstance(order, bool) or int(order) != order or not 2 <= int(order) <= MAX_ORDER:
            raise ValueError(f"taylor: order must be an integer in 2..{MAX_ORDER}, got {order}")
        max_step = float(max_step)
        if not max_step > 0.0:
            raise ValueError(f"taylor: max_step must be > 0, got {max_step}")
        self.tol = tol
        self.series_order = int(order)
        self.max_step = max_step
        self._rho: float | None = None
        self.n_substeps = 0  # internal Taylor steps taken so far (for reports and tests)
        super().__init__(moments, dt, torque, **kwargs)
        if not all(math.isfinite(v) and v > 0.0 for v in self.moments.tolist()):
            raise ValueError(f"taylor: moments must be finite and > 0, got {self.moments}")
        p = self.series_order
        self._coeffs = np.zeros((p + 1, _STATE_SIZE))
        self._inverse_orders = _inverse_orders(p)
        self._forcing_buffer = np.zeros((p, _STATE_SIZE))
        self._x_end = np.zeros(_STATE_SIZE)
        self._series_buffer = np.zeros(4)
        self._state_buffer = np.zeros(10)
        self._counters = np.zeros(3, dtype=np.int64)
        self._maps_gravity: object = _NOT_BUILT
        self._configure_torque()

    # -- torque -------------------------------------------------------------------------

    def _configure_torque(self) -> None:
        """Derive the recurrence's constant map and forcing from ``self.torque``."""
        self._rho = None  # the convergence radius estimated under the old torque no longer holds
        torque = self.torque
        gravity = torque if isinstance(torque, GravityTorque) else None
        if not (torque is None or gravity is not None or isinstance(torque, (ConstantTorque, PolynomialTorque))):
            raise UnsupportedTorqueError(
                f"taylor: unsupported torque {torque!r}. The Taylor method expands the torque in "
                f"its recurrence and supports only {SUPPORTED_TORQUES} (from "
                "rigid_rot_sim.core.torque); for an arbitrary callable torque use method "
                "'dop853' (adaptive) or 'rk4'."
            )
        if self._maps_gravity is _NOT_BUILT or gravity is not self._maps_gravity:
            # Commands replace a ConstantTorque every few steps: the map depends only on
            # the body and gravity, so it is rebuilt only when gravity changes.
            key = tuple(self.moments.tolist())
            if gravity is not None:
                key += (tuple(np.asarray(gravity.lever_arm, dtype=float).tolist()), float(gravity.weight))
            self._pairs, self._terms, self._term_values, self._gravity_forcing = recurrence_tables(key)
            self._maps_gravity = gravity
        b = self._gravity_forcing
        self._const_forcing = b.copy()
        poly = np.zeros((0, 3))
        if isinstance(torque, ConstantTorque):
            self._const_forcing[:3] += torque.value / self.moments
        elif isinstance(torque, PolynomialTorque):
            poly = torque.coefficients / self.moments
        n = poly.shape[0]
        # coefficients of N(t0 + s) in powers of s: sum_m binom(m, j) t0^(m - j) poly[m]
        self._binom = np.array([[math.comb(m, j) if m >= j else 0 for m in range(n)] for j in range(n)], float)
        self._binom = self._binom.reshape(n, n)
        self._poly = np.ascontiguousarray(poly)
        self._torque_seen = torque

    def _forcing(self, t0: float) -> np.ndarray:
        """Coefficients of b(t0 + s) in powers of s, pre-divided by (k + 1): shape (n, 7)."""
        rows = taylor_forcing(
            t0,
            self._binom,
            self._poly,
            self._const_forcing,
            self._inverse_orders,
            self.series_order,
            self._forcing_buffer,
        )
        return self._forcing_buffer[:rows].copy()

    # -- stepping -----------------------------------------------------------------------

    def _on_state_change(self) -> None:
        self._rho = None
        self._series: bool | None = None

    def advance(self, n: int) -> None:
        """Take ``n`` API steps of ``dt`` in one compiled loop (the same bits as n calls of
        :meth:`step`: each API step is the same computation either way)."""
        if n > 0:
            self._advance_steps(int(n))

    def _advance_steps(self, n: int) -> None:
        # Dense output: the series of the last internal step covers [t0, t0 + h]; an API
        # step ending inside it is one polynomial evaluation, so short API steps cost
        # little and the internal steps do not depend on dt (as scipy's dense output).
        # When the torque was just replaced (commands arriving at the step rate) or step
        # control is off, the internal steps land on the API step instead.
        landing_first = False
        if self.torque is not self._torque_seen:
            self._configure_torque()
            self._series = None
            landing_first = True
        series = self._series_buffer  # t, h, order, valid
        if self._series is None:
            series[3] = 0.0
        state = self._state_buffer  # omega, q, t, rho (< 0: none), t of a failure
        state[:3] = self.omega
        state[3:7] = self.q
        state[7] = self.t
        state[8] = -1.0 if self._rho is None else self._rho
        counters = self._counters  # API steps done, internal steps, status
        counters[:] = 0
        taylor_advance(
            n,
            self.dt,
            state,
            series,
            self._x_end,
            landing_first,
            self.tol is not None,
            -1.0 if self.tol is None else self.tol,
            self.max_step,
            self.series_order,
            self._recurrence,
            counters,
        )
        done, substeps, status = (int(v) for v in counters)
        self.n_substeps += substeps
        if done:
            self.t = float(state[7])
            self.omega = state[:3].copy()
            self.q = state[3:7].copy()
            self.n_steps += done
        self._rho = None if state[8] < 0.0 else float(state[8])
        self._series = True if series[3] else None  # the series itself stays in the buffers
        if status == _OK:
            return
        t = float(state[9])
        if status == _NON_FINITE_STATE:
            raise NonFiniteStateError(f"{self.name}: non-finite state at step {self.n_steps + 1}, t = {t:.9g} s")
        if status == _NON_FINITE_SERIES:
            raise NonFiniteStateError(
                f"{self.name}: non-finite Taylor coefficients at step {self.n_steps + 1}, t = {t:.9g} s "
                f"(omega = {self.omega})"
            )
        raise NonFiniteStateError(
            f"{self.name}: step size underflow at step {self.n_steps + 1}, t = {t:.9g} s (omega = {self.omega})"
        )

    @property
    def _recurrence(self) -> Recurrence:
        """The kernels' coefficient buffer and recurrence tables, in their order (coeffs ... const_forcing)."""
        return (
            self._coeffs,
            self._pairs,
            self._terms,
            self._term_values,
            self._inverse_orders,
            self._forcing_buffer,
            self._binom,
            self._poly,
            self._const_forcing,
        )

    def _substep(self, t0: float, x0: np.ndarray, h_cap: float, h_fallback: float) -> tuple[float, int, np.ndarray]:
        """One Taylor step from (t0, x0) of length <= h_cap; returns (h, order, x(t0 + h)).

        ``h_fallback`` is taken when the series gives no bound (all its last coefficients
        vanish, as for a body at rest) and h_cap is infinite.
        """
        rho = np.array([-1.0 if self._rho is None else self._rho])
        x_end = np.zeros(_STATE_SIZE)
        self._series = None  # the coefficient buffer is reused here
        h, p, status = taylor_substep(
            t0,
            np.asarray(x0, dtype=float),
            h_cap,
            h_fallback,
            self.tol is not None,
            -1.0 if self.tol is None else self.tol,
            self.series_order,
            rho,
            self._recurrence,
            x_end,
        )
        if status != _OK:
            raise NonFiniteStateError(f"{self.name}: non-finite state or Taylor coefficients at t = {t0:.9g} s")
        self._rho = None if rho[0] < 0.0 else float(rho[0])
        return h, p, x_end


# -- the compiled kernels (numba: register_jitable, run by taylor_advance) ----------------

_OK, _NON_FINITE_STATE, _NON_FINITE_SERIES, _UNDERFLOW = 0, 1, 2, 3


@register_jitable
def taylor_forcing(
    t0: float,
    binom: FloatArray,
    poly: FloatArray,
    const_forcing: FloatArray,
    inverse_orders: FloatArray,
    series_order: int,
    out: FloatArray,
) -> int:
    """Fill out[:n] with the coefficients of b(t0 + s), pre-divided by (k + 1); returns n."""
    n: int = poly.shape[0]
    if n == 0:
        for c in range(_STATE_SIZE):
            if const_forcing[c] != 0.0:
                out[0, :] = const_forcing
                return 1
        return 0
    rows = min(n, series_order)
    for j in range(rows):
        for c in range(_STATE_SIZE):
            out[j, c] = 0.0
        for c in range(3):
            total = 0.0
            for m in range(j, n):
                total += binom[j, m] * t0 ** (m - j) * poly[m, c]
            out[j, c] = total
    for c in range(_STATE_SIZE):
        out[0, c] += const_forcing[c]
    for j in range(rows):
        for c in range(_STATE_SIZE):
            out[j, c] *= inverse_orders[j]
    return rows


@register_jitable
def taylor_evaluate(coeffs: FloatArray, p: int, s: float, out: FloatArray) -> None:
    """The series (order p) at s (Horner), quaternion renormalised, into out."""
    for c in range(_STATE_SIZE):
        value = coeffs[p, c]
        for k in range(p - 1, -1, -1):
            value = value * s + coeffs[k, c]
        out[c] = value
    norm = 1.0 / math.sqrt(out[3] * out[3] + out[4] * out[4] + out[5] * out[5] + out[6] * out[6])
    for c in range(3, _STATE_SIZE):
        out[c] *= norm


@register_jitable
def taylor_substep(
    t0: float,
    x0: FloatArray,
    h_cap: float,
    h_fallback: float,
    controlled: bool,
    tol: float,
    series_order: int,
    rho_box: FloatArray,
    recurrence: Recurrence,
    x_end: FloatArray,
) -> tuple[float, int, int]:
    """One Taylor step of length <= h_cap from (t0, x0): (h, order, status); x(t0 + h) into x_end.

    ``rho_box[0]`` holds the convergence radius estimate (< 0: none) and is updated.
    """
    coeffs, pairs, terms, term_values, inverse_orders, forcing, binom, poly, const_forcing = recurrence
    p = series_order
    omega_scale = max(1.0, abs(x0[0]), abs(x0[1]), abs(x0[2]))
    if not math.isfinite(omega_scale):
        return 0.0, p, _NON_FINITE_STATE
    rho = rho_box[0]
    # rho is infinite after a step whose series vanished (a body at rest): no estimate.
    if controlled and rho >= 0.0 and math.isfinite(rho) and h_cap < rho:
        # Enough order for the shorter step: (h / rho)^n <= tol.
        needed = math.ceil(math.log(tol) / math.log(h_cap / rho)) + 1 if h_cap > 0.0 else 2
        p = min(p, max(needed, 4))
    for c in range(_STATE_SIZE):
        coeffs[0, c] = x0[c]
    n_forced = min(taylor_forcing(t0, binom, poly, const_forcing, inverse_orders, series_order, forcing), p)
    if pairs.shape[0] == 0:
        rigid_body_series(coeffs, p, term_values, forcing, n_forced, inverse_orders)
    else:
        general_series(coeffs, p, pairs, terms, term_values, forcing, n_forced, inverse_orders)
    return _step_from_series(h_cap, h_fallback, controlled, tol, series_order, p, omega_scale, rho_box, coeffs, x_end)


@register_jitable
def rigid_body_series(
    coeffs: FloatArray, p: int, euler: FloatArray, forcing: FloatArray, n_forced: int, inverse_orders: FloatArray
) -> None:
    """coeffs[1..p] from coeffs[0] for Euler's equations and q' = 1/2 q (x) (omega, 0), written out.

    ``euler = ((I2 - I3) / I1, (I3 - I1) / I2, (I1 - I2) / I3)``; ``forcing`` (torque / I, pre-divided
    by k + 1) acts on omega only. The fifteen Cauchy products share one pass over m, with one
    accumulator per state component: seven independent chains the CPU overlaps (the generic form
    below runs fifteen dependent chains, one after another, through index tables).
    """
    a1, a2, a3 = euler[0], euler[1], euler[2]
    for k in range(p):
        e1 = 0.0  # (w2 w3)_k
        e2 = 0.0  # (w3 w1)_k
        e3 = 0.0  # (w1 w2)_k
        dx = 0.0  # (qw w1 + qy w3 - qz w2)_k
        dy = 0.0  # (qw w2 + qz w1 - qx w3)_k
        dz = 0.0  # (qw w3 + qx w2 - qy w1)_k
        dw = 0.0  # (qx w1 + qy w2 + qz w3)_k
        for m in range(k + 1):
            n = k - m
            u1 = coeffs[n, 0]
            u2 = coeffs[n, 1]
            u3 = coeffs[n, 2]
            qx = coeffs[m, 3]
            qy = coeffs[m, 4]
            qz = coeffs[m, 5]
            qw = coeffs[m, 6]
            e1 += coeffs[m, 1] * u3
            e2 += coeffs[m, 2] * u1
            e3 += coeffs[m, 0] * u2
            dx += qw * u1 + qy * u3 - qz * u2
            dy += qw * u2 + qz * u1 - qx * u3
            dz += qw * u3 + qx * u2 - qy * u1
            dw += qx * u1 + qy * u2 + qz * u3
        scale = inverse_orders[k]
        half = 0.5 * scale
        coeffs[k + 1, 0] = (a1 * scale) * e1
        coeffs[k + 1, 1] = (a2 * scale) * e2
        coeffs[k + 1, 2] = (a3 * scale) * e3
        coeffs[k + 1, 3] = half * dx
        coeffs[k + 1, 4] = half * dy
        coeffs[k + 1, 5] = half * dz
        coeffs[k + 1, 6] = -half * dw
        if k < n_forced:
            for c in range(3):
                coeffs[k + 1, c] += forcing[k, c]


@register_jitable
def general_series(
    coeffs: FloatArray,
    p: int,
    pairs: IntArray,
    terms: IntArray,
    term_values: FloatArray,
    forcing: FloatArray,
    n_forced: int,
    inverse_orders: FloatArray,
) -> None:
    """coeffs[1..p] from coeffs[0] for any ``x' = C:x x + b`` given by its non-zero entries (gravity)."""
    n_pairs = pairs.shape[0]
    products = np.empty(n_pairs)
    for k in range(p):
        # the Cauchy products (x_i x_j)_k = sum_m X_m,i X_k-m,j that C uses
        for a in range(n_pairs):
            i, j = pairs[a, 0], pairs[a, 1]
            total = 0.0
            for m in range(k + 1):
                total += coeffs[m, i] * coeffs[k - m, j]
            products[a] = total
        for c in range(_STATE_SIZE):
            coeffs[k + 1, c] = 0.0
        scale = inverse_orders[k]
        for e in range(terms.shape[0]):
            coeffs[k + 1, terms[e, 0]] += (term_values[e] * scale) * products[terms[e, 1]]
        if k < n_forced:
            for c in range(_STATE_SIZE):
                coeffs[k + 1, c] += forcing[k, c]


@register_jitable
def _step_from_series(
    h_cap: float,
    h_fallback: float,
    controlled: bool,
    tol: float,
    series_order: int,
    p: int,
    omega_scale: float,
    rho_box: FloatArray,
    coeffs: FloatArray,
    x_end: FloatArray,
) -> tuple[float, int, int]:
    """The step from the series' last two terms (see the module docstring); x(t0 + h) into x_end."""
    h = h_cap
    if controlled:
        # omega relative to max(1 rad/s, |omega|), the unit quaternion absolutely
        a_prev = 0.0
        a_last = 0.0
        for c in range(_STATE_SIZE):
            weight = 1.0 / omega_scale if c < 3 else 1.0
            a_prev = max(a_prev, abs(coeffs[p - 1, c]) * weight)
            a_last = max(a_last, abs(coeffs[p, c]) * weight)
        if not (math.isfinite(a_prev) and math.isfinite(a_last)):
            return 0.0, p, _NON_FINITE_SERIES
        rho = math.inf
        if a_prev > 0.0:
            rho = (1.0 / a_prev) ** (1.0 / (p - 1))
            h = min(h, rho * tol ** (1.0 / (p - 1)))
        if a_last > 0.0:
            rho_last = (1.0 / a_last) ** (1.0 / p)
            rho = min(rho, rho_last)
            h = min(h, rho_last * tol ** (1.0 / p))
        if p == series_order or h < h_cap:
            rho_box[0] = rho
    if math.isinf(h):
        h = h_fallback
    taylor_evaluate(coeffs, p, h, x_end)
    return h, p, _OK


@register_jitable
def _taylor_advance(
    n: int,
    dt: float,
    state: FloatArray,
    series: FloatArray,
    x_end: FloatArray,
    landing_first: bool,
    controlled: bool,
    tol: float,
    max_step: float,
    series_order: int,
    recurrence: Recurrence,
    counters: IntArray,
) -> None:
    """n API steps: state = (omega, q, t, rho, t of a failure) updated in place; series = (t, h, order, valid)
    of the last internal step, whose end state is x_end; counters = (done, substeps, status)."""
    coeffs = recurrence[0]
    rho_box = np.empty(1)
    rho_box[0] = state[8]
    x = np.empty(_STATE_SIZE)
    out = np.empty(_STATE_SIZE)
    for step in range(n):
        landing = (not controlled) or (landing_first and step == 0)
        target = state[7] + dt
        if series[3] != 0.0 and target <= series[0] + series[1]:
            taylor_evaluate(coeffs, int(series[2]), target - series[0], out)
        else:
            if series[3] == 0.0:
                t = state[7]
                for c in range(_STATE_SIZE):
                    x[c] = state[c]
            else:
                t = series[0] + series[1]
                for c in range(_STATE_SIZE):
                    x[c] = x_end[c]
            while True:
                remaining = target - t
                land = max(0.0, min(remaining, max_step))  # >= 0 despite rounding
                h, p, status = taylor_substep(
                    t,
                    x,
                    land if landing else max_step,
                    land,
                    controlled,
                    tol,
                    series_order,
                    rho_box,
                    recurrence,
                    x_end,
                )
                if status != _OK:
                    state[8], state[9] = rho_box[0], t
                    counters[2] = status
                    return
                counters[1] += 1
                if h >= remaining:
                    break
                if t + h == t:
                    state[8], state[9] = rho_box[0], t
                    counters[2] = _UNDERFLOW
                    return
                t += h
                for c in range(_STATE_SIZE):
                    x[c] = x_end[c]
            series[0], series[1], series[2], series[3] = t, h, p, 1.0
            if h == remaining:
                for c in range(_STATE_SIZE):
                    out[c] = x_end[c]
            else:
                taylor_evaluate(coeffs, p, remaining, out)
        finite = True
        for c in range(_STATE_SIZE):
            finite = finite and math.isfinite(out[c])
        if not finite:
            state[8], state[9] = rho_box[0], target
            counters[2] = _NON_FINITE_STATE
            return
        for c in range(_STATE_SIZE):
            state[c] = out[c]
        state[7] = target
        counters[0] += 1
    state[8] = rho_box[0]


taylor_advance = compiled(_taylor_advance)
