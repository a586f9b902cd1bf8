"""Integrator choice and step-size warnings, derived from linear stability theory.

The numbers here come from two sources and are cross-checked by the stability
suite (``rigid-rot stability``, :mod:`rigid_rot_sim.analysis.stability`), whose
bisection for the largest stable step of each explicit method is compared with
:func:`max_stable_dt` in ``test/analysis/test_stability.py``.

Theory used
-----------
*Gyroscopic frequency.* Linearising Euler's equations ``I1 w1' = (I2 - I3) w2 w3``
(cyclic) about a steady spin of rate ``W`` about principal axis i gives small
oscillations (about the major and minor axes) or exponential growth (about the
intermediate axis) with rate::

    nu_i = W * sqrt(|(Ii - Ij)(Ii - Ik)| / (Ij Ik))

By the triangle inequality on the moments, ``nu_i <= W``: the free rigid body is
never stiffer than its spin rate. :func:`gyroscopic_frequency` bounds the rate by
``omega_max * max_i sqrt(...)``.

*Explicit methods.* A method is stable on an oscillation of frequency ``nu`` when
``i nu dt`` lies in its stability region. Classical RK4 contains the imaginary axis
up to ``|z| = 2 sqrt(2)``; explicit Euler contains no part of it, so it amplifies
every gyroscopic oscillation by ``sqrt(1 + (nu dt)^2)`` per step at any dt (the
amplitude grows by a factor e in about ``2 / (nu^2 dt)`` seconds).

*Structure-preserving methods.* The implicit midpoint rule conserves T and |L|
exactly for the free body; the splittings compose exact rotations, so |L| is exact
and |omega| <= |L| / I_min: neither can blow up at any dt. Their accuracy limit is
the rotation per step ``|omega| dt``: beyond about pi rad per step the sampled motion
aliases and splitting resonances appear (bounded but wrong).

*Adaptive methods* (dop853, taylor) subdivide the step themselves and need no bound.

Measured by the stability suite's bisection (``rigid-rot stability``; 1000 steps, growth of
energy or |L| at most 1 %), on cases from thin rods (1e-6 ratio) and MuJoCo's rod to
symmetric and generic triaxial bodies:

* rk4 and lie_rk4: the largest stable step is 0.99 to 1.2 times ``2 sqrt(2) / nu``
  (the bound here is for the worst axis at |omega0|, hence never optimistic);
* implicit_midpoint: bounded at any step, but its Newton solve (core/integrators/implicit.py,
  started from omega_n) fails from about ``nu dt = 4`` on a generic triaxial body
  (measured 4.15 for I = (1, 2, 3), omega0 = (10, 1, 5)); ``MIDPOINT_SOLVER_LIMIT``;
* splitting (order 2): |L| exact at any step, but the energy error passes 1 % at about
  2.5 rad of rotation per step on the same body; hence ``ROTATION_PER_STEP_LIMIT = 2``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.integrators import METHODS

if TYPE_CHECKING:
    from rigid_rot_sim.core.dynamics import RigidBody
    from rigid_rot_sim.scene.scene import Scene

#: Extent of classical RK4's stability region along the imaginary axis.
RK4_IMAGINARY_LIMIT = 2.0 * math.sqrt(2.0)

#: Rotation per step (rad) above which the fixed-step methods lose accuracy (still bounded
#: for the structure-preserving ones): below pi, where the sampled attitude aliases, with the
#: margin the stability suite measured (splitting's energy error reaches 1 % at ~2.5 rad/step).
ROTATION_PER_STEP_LIMIT = 2.0

#: ``nu * dt`` from which implicit_midpoint's Newton solve may fail (measured, see above).
MIDPOINT_SOLVER_LIMIT = 4.0

#: ``nu * dt`` above which a 4th-order explicit method's local error (~(nu dt)^5 / 120)
#: exceeds about 3e-4 per step; reported as an accuracy warning, not instability.
EXPLICIT_ACCURACY_LIMIT = 0.5


def _methods_with_stability(*kinds: str) -> tuple[str, ...]:
    """The registered methods whose ``stability`` class is one of ``kinds``, in registry order."""
    return tuple(name for name, cls in METHODS.items() if cls.stability in kinds)


#: Methods bounded for any dt on a free body.
UNCONDITIONALLY_STABLE = _methods_with_stability("unconditional", "exact")
ADAPTIVE = _methods_with_stability("adaptive")
EXPLICIT_FIXED_STEP = _methods_with_stability("explicit")
#: Methods bounded at any dt whose :func:`practical_step_limit` was measured by the stability
#: suite (implicit_midpoint's Newton solve, splitting's accuracy per rotation).
MEASURED_STEP_LIMITS = ("implicit_midpoint", "splitting")

TORQUE_KINDS = ("none", "constant", "schedule", "topic", "gravity")


def _validated_moments(principal_moments: Any) -> np.ndarray:
    moments = np.asarray(principal_moments, dtype=float)
    if moments.shape != (3,):
        raise ValueError(f"principal_moments must have shape (3,), got {moments.shape}")
    for i, value in enumerate(moments):
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"principal_moments[{i}] must be finite and > 0, got {value}")
    return moments


def _validated_positive(name: str, value: float, allow_zero: bool = False) -> float:
    value = float(value)
    if not math.isfinite(value) or value < 0.0 or (value == 0.0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must be finite and {bound}, got {value}")
    return value


def gyroscopic_factor(principal_moments: Any) -> float:
    """Dimensionless ``max_i sqrt(|(Ii - Ij)(Ii - Ik)| / (Ij Ik))`` (0 for a sphere, <= 1)."""
    i1, i2, i3 = _validated_moments(principal_moments)
    factors = (
        abs((i1 - i2) * (i1 - i3)) / (i2 * i3),
        abs((i2 - i3) * (i2 - i1)) / (i3 * i1),
        abs((i3 - i1) * (i3 - i2)) / (i1 * i2),
    )
    return math.sqrt(max(factors))


def gyroscopic_frequency(principal_moments: Any, omega_max: float) -> float:
    """Bound on the linearised gyroscopic frequency (rad/s) for ``|omega| <= omega_max`` (rad/s)."""
    omega_max = _validated_positive("omega_max", omega_max, allow_zero=True)
    return omega_max * gyroscopic_factor(principal_moments)


def max_stable_dt(method: str, principal_moments: Any, omega_max: float) -> float:
    """Largest step (s) for which ``method`` is linearly stable at spin rates up to ``omega_max``.

    ``math.inf`` for methods bounded at any step (structure-preserving, adaptive, or a
    spherical body); 0.0 for explicit Euler on a non-spherical spinning body (unstable
    at every step; see :func:`euler_growth_time` for how fast).
    """
    nu = gyroscopic_frequency(principal_moments, omega_max)
    if method in UNCONDITIONALLY_STABLE or method in ADAPTIVE or nu == 0.0:
        return math.inf
    if method == "euler":
        return 0.0
    if method in ("rk4", "lie_rk4"):
        return RK4_IMAGINARY_LIMIT / nu
    raise ValueError(f"method: no stability bound known for {method!r}")


def practical_step_limit(method: str, principal_moments: Any, omega_max: float) -> float:
    """Step (s) beyond which ``method`` is unstable *or* fails the suite's 1 % criterion.

    The linear bound of :func:`max_stable_dt` for the explicit methods; the measured
    solver and accuracy limits for implicit_midpoint and splitting; inf for the rest.
    """
    nu = gyroscopic_frequency(principal_moments, omega_max)
    if method == "implicit_midpoint":
        return MIDPOINT_SOLVER_LIMIT / nu if nu > 0 else math.inf
    if method == "splitting":
        return ROTATION_PER_STEP_LIMIT / omega_max if omega_max > 0 else math.inf
    return max_stable_dt(method, principal_moments, omega_max)


def euler_growth_time(principal_moments: Any, omega_max: float, dt: float) -> float:
    """Time (s) in which explicit Euler multiplies a gyroscopic oscillation by e."""
    nu = gyroscopic_frequency(principal_moments, omega_max)
    dt = _validated_positive("dt", dt)
    if nu == 0.0:
        return math.inf
    # amplitude factor per step sqrt(1 + (nu dt)^2) -> rate ln(1 + (nu dt)^2) / (2 dt)
    return 2.0 * dt / math.log1p((nu * dt) ** 2)


def step_warnings(method: str, principal_moments: Any, omega_max: float, dt: float) -> list[str]:
    """Human-readable warnings for running ``method`` at step ``dt`` (s) up to ``omega_max`` (rad/s).

    Empty when the combination is stable and accurate by the criteria of this module.
    """
    moments = _validated_moments(principal_moments)
    omega_max = _validated_positive("omega_max", omega_max, allow_zero=True)
    dt = _validated_positive("dt", dt)
    nu = gyroscopic_frequency(moments, omega_max)
    rotation = omega_max * dt
    warnings: list[str] = []
    if method == "euler":
        if nu > 0.0:
            warnings.append(
                f"euler is unstable on gyroscopic oscillations at any dt: at {omega_max:.3g} rad/s "
                f"the nutation amplitude and energy grow by a factor e every "
                f"{euler_growth_time(moments, omega_max, dt):.3g} s; use rk4 "
                f"(dt < {RK4_IMAGINARY_LIMIT / nu:.3g} s), implicit_midpoint or exact_split"
            )
    elif method in ("rk4", "lie_rk4"):
        limit = max_stable_dt(method, moments, omega_max)
        if dt > limit:
            warnings.append(
                f"dt too large for this spin rate with {method}: max stable dt ≈ {limit:.3g} s "
                f"(gyroscopic frequency {nu:.3g} rad/s, RK4 stable for nu*dt < 2*sqrt(2)); "
                "use implicit_midpoint or exact_split"
            )
        elif nu * dt > EXPLICIT_ACCURACY_LIMIT:
            warnings.append(
                f"{method} at nu*dt = {nu * dt:.3g} is stable but inaccurate (local error ~ "
                f"(nu*dt)^5/120 ≈ {(nu * dt) ** 5 / 120:.2g} per step); use dt < "
                f"{EXPLICIT_ACCURACY_LIMIT / nu:.3g} s or exact_split"
            )
    elif method == "implicit_midpoint" and nu * dt > MIDPOINT_SOLVER_LIMIT:
        warnings.append(
            f"implicit_midpoint at nu*dt = {nu * dt:.3g}: its Newton solve may fail beyond nu*dt ≈ "
            f"{MIDPOINT_SOLVER_LIMIT:g} (gyroscopic frequency {nu:.3g} rad/s); use dt < "
            f"{MIDPOINT_SOLVER_LIMIT / nu:.3g} s, exact_split or taylor"
        )
    if method not in ADAPTIVE and method != "exact" and rotation > ROTATION_PER_STEP_LIMIT:
        warnings.append(
            f"{method}: rotation per step {rotation:.3g} rad exceeds {ROTATION_PER_STEP_LIMIT:g} rad at "
            f"{omega_max:.3g} rad/s; the step error is large (bounded for structure-preserving methods) "
            f"and beyond pi the sampled attitude aliases; use dt < {ROTATION_PER_STEP_LIMIT / omega_max:.3g} s"
            + (" or exact" if method != "exact_split" else " or taylor")
        )
    return warnings


def choose_integrator(principal_moments: Any, omega_max: float, dt: float, torque_kind: str) -> str:
    """The scene's ``auto`` integrator for a body, spin-rate bound, node step and torque kind.

    * ``'none'``: ``'exact'`` (the elliptic-function flow: exact at any dt).
    * ``'gravity'``: ``'exact_split'`` (exact free flow with exact gravity kicks: a
      Lie-Poisson integrator, bounded at any dt and keeping the heavy top's invariants).
    * ``'constant'``, ``'schedule'``, ``'topic'`` (torque constant over each node step):
      ``'taylor'``, the adaptive method that expands a piecewise-constant torque exactly
      and controls its own error, so no dt / spin-rate combination is unstable.
    """
    _validated_moments(principal_moments)
    _validated_positive("omega_max", omega_max, allow_zero=True)
    _validated_positive("dt", dt)
    if torque_kind not in TORQUE_KINDS:
        raise ValueError(f"torque_kind must be one of {list(TORQUE_KINDS)}, got {torque_kind!r}")
    if torque_kind == "none":
        return "exact"
    if torque_kind == "gravity":
        return "exact_split"
    return "taylor"


def omega_bound(scene: Scene, body: RigidBody) -> float:
    """A bound on |ω| (rad/s) over a run of ``scene`` (exact where physics gives one).

    Free body: |L| / I_min (|L| is conserved). Gravity: energy conservation,
    ``T <= E - V_min`` so ``|ω| <= sqrt(2 (E + m g l) / I_min)``. Driven by
    torques: the initial |L| / I_min plus the schedules' total angular impulse /
    I_min; a topic-driven run has no a-priori bound (its commands are unknown).
    """
    i_min = float(np.min(body.principal_moments))
    omega0 = np.array(scene.initial.angular_velocity, dtype=float)
    l0 = float(np.linalg.norm(body.inertia_tensor @ omega0))
    if scene.gravity is not None:
        assert scene.body.mass is not None and scene.body.center_of_mass is not None
        com_body = np.array(scene.body.center_of_mass, dtype=float)
        weight = scene.body.mass * scene.gravity.acceleration
        v0 = weight * quat.rotate(scene.initial.orientation, com_body)[2]
        t0 = 0.5 * float(omega0 @ body.inertia_tensor @ omega0)
        reach = weight * float(np.linalg.norm(com_body))
        return math.sqrt(2.0 * max(t0 + v0 + reach, 0.0) / i_min)
    impulse = 0.0
    for schedule in scene.schedules:
        segments = schedule.segments
        for this, following in zip(segments, segments[1:], strict=False):  # pairwise
            impulse += math.hypot(*this.torque) * (following.start - this.start)
        if math.hypot(*segments[-1].torque) > 0.0 and scene.duration is not None:
            impulse += math.hypot(*segments[-1].torque) * max(scene.duration - segments[-1].start, 0.0)
    return (l0 + impulse) / i_min
