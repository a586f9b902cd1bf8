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

one small matrix product per order (the 7 x 7 table of all pairwise Cauchy products,
contracted with the constant map C). Python overhead per call, not arithmetic, is the
cost at these sizes: this form needs two numpy calls per order. The same recurrence on
plain floats needs fifteen Cauchy products per order (``sum(map(mul, a, b[::-1]))``);
measured at order 24 on this kind of machine: ~1.2 us per order for the numpy form (a
whole internal step, step control and evaluation included, ~40 us), ~7 us per order for
the float form, so the numpy form is kept. The operands of every order are views made
once at construction, so the loop does no slicing.

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

import math
from typing import Any, ClassVar

import numpy as np

from rigid_rot_sim.core.integrators.base import Integrator, NonFiniteStateError, UnsupportedTorqueError
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
    c[_W1, _W2, _W3] = (i2 - i3) / i1
    c[_W2, _W3, _W1] = (i3 - i1) / i2
    c[_W3, _W1, _W2] = (i1 - i2) / i3
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
        if k < n_forcing:
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
    order: ClassVar[int] = 28  # the series order at the default tol; per instance: series_order
    fixed_step: ClassVar[bool] = False

    def __init__(
        self,
        moments: Any,
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
        if not np.all(np.isfinite(self.moments)) or np.any(self.moments <= 0.0):
            raise ValueError(f"taylor: moments must be finite and > 0, got {self.moments}")
        p = self.series_order
        self._coeffs = np.zeros((p + 1, _STATE_SIZE))
        self._weights = np.ones(_STATE_SIZE)
        self._prod = np.zeros((_STATE_SIZE, _STATE_SIZE))
        self._prod_flat = self._prod.reshape(-1)
        self._exponents = np.arange(p + 1, dtype=float)
        self._inverse_orders = 1.0 / np.arange(1, p + 1, dtype=float)
        self._maps = np.zeros((p, _STATE_SIZE, _STATE_SIZE * _STATE_SIZE))
        self._maps_gravity: object = _NOT_BUILT
        # The operands of every order, as views into the persistent buffers, made once:
        # (X_0..k)^T, (X_k..0), the map of order k and the row X_{k+1} it writes.
        coeffs_t = self._coeffs.T
        self._plan = [
            (coeffs_t[:, : k + 1], self._coeffs[k::-1], self._maps[k], self._coeffs[k + 1]) for k in range(p)
        ]
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
            # Commands replace a ConstantTorque every few steps: the maps depend only on
            # the body and gravity, so they are rebuilt only when gravity changes.
            c, b = derivative_map(self.moments, gravity)
            # Map k already carries the 1/(k+1) of the recurrence; filled in place (the
            # plan holds views of it).
            np.multiply(c.reshape(_STATE_SIZE, -1)[None, :, :], self._inverse_orders[:, None, None], out=self._maps)
            self._gravity_forcing = b
            self._maps_gravity = gravity
        b = self._gravity_forcing
        self._const_forcing = b
        self._poly = None
        if isinstance(torque, ConstantTorque):
            self._const_forcing = b + np.concatenate([torque.value / self.moments, np.zeros(4)])
        elif isinstance(torque, PolynomialTorque):
            coeffs = torque.coefficients
            n = coeffs.shape[0]
            j, m = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
            binom = np.array([[math.comb(mm, jj) if mm >= jj else 0 for mm in range(n)] for jj in range(n)], float)
            # coefficients of N(t0 + s) in powers of s: shift[j, m] t0^(m - j) binom(m, j)
            self._poly = (binom, np.maximum(m - j, 0).astype(float), coeffs / self.moments)
        # State-independent forcing that does not move with t0 is computed once.
        if self._poly is None and np.any(self._const_forcing != 0.0):
            self._fixed_forcing = self._const_forcing[None, :].copy()
        else:
            self._fixed_forcing = np.zeros((0, _STATE_SIZE))
        self._torque_seen = torque

    def _forcing(self, t0: float) -> np.ndarray:
        """Coefficients of b(t0 + s) in powers of s, pre-divided by (k + 1): shape (n, 7)."""
        if self._poly is None:
            return self._fixed_forcing  # only an order-0 term, whose 1/(0 + 1) is 1
        binom, powers, scaled = self._poly
        shifted = (binom * np.power(t0, powers)) @ scaled
        forcing = np.zeros((len(shifted), _STATE_SIZE))
        forcing[:, :3] = shifted
        forcing[0] += self._const_forcing
        n = min(len(forcing), self.series_order)
        return forcing[:n] * self._inverse_orders[:n, None]

    # -- stepping -----------------------------------------------------------------------

    def _on_state_change(self) -> None:
        self._rho = None
        self._series = None

    def _step_impl(self) -> None:
        # Dense output: the series of the last internal step covers [t0, t0 + h]; an API
        # step ending inside it is one polynomial evaluation, so short API steps cost
        # little and the internal steps do not depend on dt (as scipy's dense output).
        # When the torque was just replaced (commands arriving at the step rate) or step
        # control is off, the internal steps land on the API step instead.
        target = self.t + self.dt
        landing = self.tol is None
        if self.torque is not self._torque_seen:
            self._configure_torque()
            self._series = None
            landing = True
        series = self._series
        if series is not None and target <= series[0] + series[1]:
            x = self._evaluate(target - series[0], series[2])
        else:
            if series is None:
                t, x = self.t, np.concatenate([self.omega, self.q])
            else:
                t, x = series[0] + series[1], series[3]
            while True:
                remaining = target - t
                land = max(0.0, min(remaining, self.max_step))  # >= 0 despite rounding
                h, p, x_end = self._substep(t, x, land if landing else self.max_step, land)
                self.n_substeps += 1
                if h >= remaining:
                    break
                if t + h == t:
                    raise NonFiniteStateError(
                        f"{self.name}: step size underflow at step {self.n_steps + 1}, t = {t:.9g} s "
                        f"(h = {h:.3g} s; omega = {x_end[:3]})"
                    )
                t += h
                x = x_end
            self._series = (t, h, p, x_end)
            x = x_end if h == remaining else self._evaluate(remaining, p)
        self.t = target
        self.omega = x[:3].copy()
        self.q = x[3:].copy()

    def _evaluate(self, s: float, p: int) -> np.ndarray:
        """The last series (order p) at s from its start, with the quaternion renormalised."""
        x = np.power(s, self._exponents[: p + 1]) @ self._coeffs[: p + 1]
        q = x[3:]
        q *= 1.0 / math.sqrt(float(q @ q))
        return x

    def _substep(self, t0: float, x0: np.ndarray, h_cap: float, h_fallback: float) -> tuple[float, int, np.ndarray]:
        """One Taylor step from (t0, x0) of length <= h_cap; returns (h, order, x(t0 + h)).

        ``h_fallback`` is taken when the series gives no bound (all its last coefficients
        vanish, as for a body at rest) and h_cap is infinite.
        """
        p = self.series_order
        tol = self.tol
        w1, w2, w3 = x0[:3].tolist()
        omega_scale = max(1.0, abs(w1), abs(w2), abs(w3))
        if not math.isfinite(omega_scale):
            raise NonFiniteStateError(f"{self.name}: non-finite state at step {self.n_steps + 1}, t = {t0:.9g} s")
        rho = self._rho
        # rho is infinite after a step whose series vanished (a body at rest): no estimate.
        if tol is not None and rho is not None and math.isfinite(rho) and h_cap < rho:
            # Enough order for the shorter step: (h / rho)^n <= tol.
            needed = math.ceil(math.log(tol) / math.log(h_cap / rho)) + 1 if h_cap > 0.0 else 2
            p = min(p, max(needed, 4))
        coeffs = self._coeffs
        coeffs[0] = x0
        forcing = self._forcing(t0)
        n_forced = min(len(forcing), p)
        # The hot loop: two numpy calls per order (see the module docstring).
        prod = self._prod
        prod_flat = self._prod_flat
        dot = np.dot
        plan = self._plan
        for k in range(n_forced):
            head, tail_reversed, order_map, out = plan[k]
            dot(head, tail_reversed, out=prod)
            dot(order_map, prod_flat, out=out)
            out += forcing[k]
        for head, tail_reversed, order_map, out in plan[n_forced:p]:
            dot(head, tail_reversed, out=prod)
            dot(order_map, prod_flat, out=out)

        h = h_cap
        if tol is not None:
            # omega relative to max(1 rad/s, |omega|), the unit quaternion absolutely
            weights = self._weights
            weights[:3] = 1.0 / omega_scale
            a_prev, a_last = (np.abs(coeffs[p - 1 : p + 1]) * weights).max(axis=1).tolist()
            if not (math.isfinite(a_prev) and math.isfinite(a_last)):
                raise NonFiniteStateError(
                    f"{self.name}: non-finite Taylor coefficients at step {self.n_steps + 1}, t = {t0:.9g} s "
                    f"(omega = {x0[:3]})"
                )
            rho = math.inf
            if a_prev > 0.0:
                rho = (1.0 / a_prev) ** (1.0 / (p - 1))
                h = min(h, rho * tol ** (1.0 / (p - 1)))
            if a_last > 0.0:
                rho_last = (1.0 / a_last) ** (1.0 / p)
                rho = min(rho, rho_last)
                h = min(h, rho_last * tol ** (1.0 / p))
            if p == self.series_order or h < h_cap:
                self._rho = rho
        if math.isinf(h):
            h = h_fallback
        return h, p, self._evaluate(h, p)

