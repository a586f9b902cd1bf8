"""The stability suite's catalogue: stiff and extreme cases, each with its pass criterion (data).

A sibling of :mod:`rigid_rot_sim.analysis.problems`: every :class:`Case` is a
:class:`~rigid_rot_sim.analysis.problems.Problem` (body, initial state, horizon, torque,
reference) plus the step to run it at and what passing means. Running them is
:mod:`rigid_rot_sim.analysis.stability`'s job.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from rigid_rot_sim.analysis.problems import (
    P2,
    P3,
    P3B,
    P5,
    TOP,
    Problem,
    Reference,
    exact_reference,
    general_top_reference,
    scipy_rhs,
)
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.exact import torque_free_solution
from rigid_rot_sim.core.steps import steps_over
from rigid_rot_sim.core.torque import ConstantTorque
from rigid_rot_sim.core.wheels import hub_inertia, wheel_model


@dataclass(frozen=True)
class Criterion:
    """Pass thresholds (inclusive); None skips a check."""

    energy_drift: float | None = None
    momentum_drift: float | None = None
    quaternion_norm: float | None = 1e-12
    omega_error: float | None = None
    attitude_error: float | None = None
    text: str = ""

    def describe(self) -> str:
        parts = [self.text] if self.text else []
        for name, label in (
            ("energy_drift", "energy drift"),
            ("momentum_drift", "momentum drift"),
            ("quaternion_norm", "| |q| - 1 |"),
            ("omega_error", "ω error [rad/s]"),
            ("attitude_error", "attitude error [rad]"),
        ):
            value = getattr(self, name)
            if value is not None:
                parts.append(f"{label} ≤ {value:g}")
        return "; ".join(parts)


@dataclass(frozen=True)
class Case:
    """One stability case: a problem, the step, and what passing means.

    ``impulse`` (N*m, principal frame) is a torque applied for the first step only, as
    the node applies a one-step topic command (the integrator's torque is replaced after
    one step). ``reference`` says whether ``problem.reference()`` exists for this case.
    """

    name: str
    description: str
    problem: Problem
    dt: float
    criterion: Criterion
    reference: bool = True
    impulse: tuple[float, float, float] | None = None
    bisect: bool = False
    conserved: bool = True  # energy and momenta conserved (after the impulse, if any)
    same_as: Problem | None = None  # a problem whose omega(t), q(t) this case must reproduce
    same_tol: float = 1e-9  # relative omega and attitude agreement with ``same_as``, same method and dt
    options: dict[str, dict[str, Any]] = field(default_factory=dict)  # per-method options
    flip_time_tol: float | None = None  # s: the sign changes of omega_2 must match the exact solution's to this

    @property
    def n_steps(self) -> int:
        return steps_over(self.problem.t_end, self.dt)


def _triple(values: Any) -> tuple[float, float, float]:
    x, y, z = (float(v) for v in values)
    return (x, y, z)


def _free(key: str, title: str, moments, omega0, t_end: float, **kw: Any) -> Problem:
    return Problem(
        key=key,
        title=title,
        principal_moments=_triple(moments),
        omega0=_triple(omega0),
        t_end=t_end,
        reference_factory=exact_reference,
        **kw,
    )


#: The impulsive-torque case: this torque (N m, principal frame) over the first of its steps.
IMPULSE_TORQUE = (50.0, -20.0, 30.0)
IMPULSE_STEPS = 1000


def _impulse_reference(problem: Problem) -> Reference:
    """Constant torque over the first step (scipy DOP853 at 1e-13), then the exact free flow."""
    dt = problem.t_end / IMPULSE_STEPS
    kicked = dataclasses.replace(problem, torque=ConstantTorque(np.asarray(IMPULSE_TORQUE)))
    y = solve_ivp(
        scipy_rhs(kicked),
        (0.0, dt),
        np.concatenate((problem.q0, problem.omega0)),
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
    ).y[:, -1]
    q1 = np.asarray(quat.normalize(y[:4]))
    solution = torque_free_solution(problem.moments, y[4:], q1, t0=dt)
    q, omega = solution.state(problem.t_end)
    return Reference(np.asarray(q), np.asarray(omega), "DOP853 rtol=atol=1e-13 over the kick, then exact", 1e-12)


def _scaled_p2(scale: float) -> Problem:
    """P2 with every moment and the torque multiplied by ``scale``: omega(t) and q(t) are unchanged."""
    return dataclasses.replace(
        P2,
        key=f"P2x{scale:g}",
        title=f"P2 scaled by {scale:g}",
        principal_moments=_triple(scale * m for m in P2.principal_moments),
        torque=ConstantTorque(scale * P2.torque.value),
        reference_factory=lambda problem: P2.reference(),
    )


def catalogue(quick: bool = False) -> list[Case]:
    """The cases, shortened (fewer steps, same dt) in quick mode."""
    short = 0.2 if quick else 1.0
    top = TOP
    sleeping_q0, sleeping_w0 = top.state_from_euler(0.05, 0.0, 0.0, 0.0, 0.0, 300.0)
    bounded = Criterion(energy_drift=1e-3, momentum_drift=1e-3, text="bounded to 0.1 %")

    def accurate(problem: Problem) -> Criterion:
        """Bounded to 0.1 %, omega error <= 0.1 % of |omega0| and attitude error <= 0.01 rad at the end."""
        scale = float(np.linalg.norm(problem.omega0))
        return dataclasses.replace(
            bounded, omega_error=1e-3 * scale, attitude_error=1e-2, text="bounded to 0.1 %, ω error ≤ 0.1 % of |ω0|"
        )

    cases: list[Case] = []
    for ratio in (1e-2, 1e-4, 1e-6):
        cases.append(
            Case(
                name=f"thin rod {ratio:g}",
                description=f"slender body I = (1, 1 + {ratio / 2:g}, {ratio:g}) kg m², spinning 5 rad/s about its "
                "axis while tumbling, dt = 10 ms",
                problem=(
                    rod := _free(
                        f"rod{ratio:g}", "thin rod", (1.0, 1.0 + ratio / 2, ratio), (0.3, 0.2, 5.0), 10.0 * short
                    )
                ),
                dt=0.01,
                criterion=accurate(rod),
                bisect=True,
            )
        )
    cases += [
        Case(
            name="MuJoCo rod",
            description="MuJoCo's diverging case diaginertia (0.00017231, 0.00000658, 0.00017243) kg m², "
            "ω0 = (2, 50, 3) rad/s, dt = 1 ms",
            problem=(
                mujoco := _free(
                    "mujoco", "MuJoCo rod", (0.00017231, 0.00000658, 0.00017243), (2.0, 50.0, 3.0), 10.0 * short
                )
            ),
            dt=1e-3,
            criterion=accurate(mujoco),
            bisect=True,
        ),
        Case(
            name="near-spherical 1e-9",
            description="moments equal to 1e-9 relative: I = (1, 1 + 1e-9, 1 + 2e-9) kg m², dt = 10 ms",
            problem=(
                near := _free(
                    "nearsphere", "near-spherical", (1.0, 1.0 + 1e-9, 1.0 + 2e-9), (1.0, 2.0, 3.0), 100.0 * short
                )
            ),
            dt=0.01,
            criterion=accurate(near),
        ),
        Case(
            name="symmetric",
            description="exactly symmetric I = (2, 2, 1) kg m², ω0 = (0.5, 0.3, 4) rad/s, dt = 10 ms",
            problem=(sym := _free("symmetric", "symmetric", (2.0, 2.0, 1.0), (0.5, 0.3, 4.0), 100.0 * short)),
            dt=0.01,
            criterion=accurate(sym),
            bisect=True,
        ),
    ]
    for rotation in (1.0, 3.0, 10.0):
        omega0 = np.array([10.0, 1.0, 5.0])
        dt = rotation / float(np.linalg.norm(omega0))
        cases.append(
            Case(
                name=f"high spin {rotation:g} rad/step",
                description=f"I = (1, 2, 3) kg m², |ω| = {np.linalg.norm(omega0):.3g} rad/s, ω·dt = {rotation:g} rad "
                "per step, 1000 steps",
                problem=_free(f"spin{rotation:g}", "high spin", (1.0, 2.0, 3.0), omega0, dt * 1000 * short),
                dt=dt,
                criterion=Criterion(energy_drift=1e-2, momentum_drift=1e-2, text="bounded to 1 %"),
                bisect=rotation == 1.0,
            )
        )
    cases += [
        Case(
            name="intermediate-axis flips",
            description="ω0 = (1e-3, 1, 1e-3) rad/s about the intermediate axis of I = (1, 2, 3) kg m²: "
            "about 30 flips in 500 s, dt = 50 ms",
            problem=_free("flips", "flips", (1.0, 2.0, 3.0), (1e-3, 1.0, 1e-3), 500.0 * short),
            dt=0.05,
            criterion=dataclasses.replace(bounded, text="bounded to 0.1 %, flip times within 0.1 s"),
            flip_time_tol=0.1,
        ),
    ]
    for label, scale, note in (("1e-9", 1e-9, " (ω(t) unchanged)"), ("1e9", 1e9, "")):
        cases.append(
            Case(
                name=f"scale {label}",
                description=f"P2 with moments (1, 2, 3){label[1:]} kg m² and torque scaled alike{note}, dt = 10 ms",
                problem=_scaled_p2(scale),
                dt=0.01,
                criterion=Criterion(text="same ω(t), q(t) as the unit-scale run of the same method to 1e-9"),
                conserved=False,
                same_as=P2,
            )
        )
    cases += [
        Case(
            name="sleeping top",
            description="heavy top (P3's) at θ0 = 0.05 rad spinning 300 rad/s: stiff nutation "
            f"(~{300 * top.pivot_moments[2] / top.pivot_moments[0]:.0f} rad/s), dt = 1 ms",
            problem=dataclasses.replace(
                P3B,
                key="sleeping",
                title="sleeping top",
                q0=tuple(sleeping_q0.tolist()),
                omega0=tuple(sleeping_w0.tolist()),
                t_end=2.0 * short,
                reference_factory=general_top_reference,
            ),
            dt=1e-3,
            criterion=Criterion(
                energy_drift=1e-4,
                momentum_drift=1e-4,
                omega_error=0.3,
                text="E, p_φ, p_ψ to 1e-4, ω error ≤ 0.1 % of |ω0|",
            ),
        ),
        Case(
            name="separatrix top → θ = 0",
            description="P3's separatrix top run until θ ≈ 1e-3 rad (the z-x-z Euler-angle singularity), dt = 1 ms",
            problem=dataclasses.replace(P3, key="separatrix_long", t_end=1.6 if not quick else 1.0),
            dt=1e-3,
            criterion=Criterion(
                energy_drift=1e-4,
                momentum_drift=1e-4,
                omega_error=1e-2,
                text="E, p_φ, p_ψ to 1e-4, ω error ≤ 0.1 % of |ω0|",
            ),
        ),
        Case(
            name="impulsive torque",
            description=f"I = (1, 2, 3) kg m², ω0 = (1, 0.1, 0.5) rad/s, a torque {IMPULSE_TORQUE} N m for one "
            "10 ms step, then free",
            problem=_free(
                "impulse",
                "impulse",
                (1.0, 2.0, 3.0),
                (1.0, 0.1, 0.5),
                0.01 * IMPULSE_STEPS,
                reference_note="kick by DOP853, then exact",
            ),
            dt=0.01,
            impulse=IMPULSE_TORQUE,
            criterion=dataclasses.replace(
                bounded,
                omega_error=1e-3,
                attitude_error=1e-2,
                text="after the kick: bounded to 0.1 %; ω error ≤ 1e-3 rad/s",
            ),
        ),
    ]
    cases[-1] = dataclasses.replace(
        cases[-1], problem=dataclasses.replace(cases[-1].problem, reference_factory=_impulse_reference)
    )
    cases.append(_fast_wheel_case(quick))
    return cases


def nutation_rate(moments: Any, wheels: Any, speeds: Any) -> float:
    """The gyroscopic nutation rate (rad/s) of a slow body carrying wheel momentum ``h = sum J Omega g``.

    With |h| much larger than the body's own momentum, eq. (4) of :mod:`rigid_rot_sim.core.wheels`
    linearised in omega reads ``I_s domega/dt = h x omega`` (``I_s = I - sum J g g^T``): omega along h
    stays, the rest turns on an ellipse at ``lambda = sqrt(h . I_s h / det I_s)``.
    """
    hub = hub_inertia(moments, wheels)
    h = np.asarray(speeds, dtype=float) * wheels.spin_inertia @ wheels.axes
    return float(np.sqrt(h @ hub @ h / np.linalg.det(hub)))


def rk4_nutation_error(rate: float, dt: float, steps: int, amplitude: float) -> float:
    """Upper bound (rad/s) on RK4's omega error after ``steps`` steps of a nutation of ``rate`` and ``amplitude``.

    RK4 multiplies the mode e^{i rate t} per step by ``R(i theta) = sum_{k<=4} (i theta)^k / k!``,
    ``theta = rate dt``: its phase lags by ``delta = theta - arg R`` (~theta^5 / 120) and its modulus
    shrinks to ``|R|`` (1 - ~theta^6 / 144). After n steps the mode is off by ``|1 - |R|^n e^{-i n delta}|``
    of its amplitude.
    """
    theta = rate * dt
    z = 1j * theta
    r = 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24
    delta = theta - float(np.angle(r))
    return amplitude * abs(1.0 - abs(r) ** steps * np.exp(-1j * steps * delta))


def _fast_wheel_case(quick: bool) -> Case:
    """A slow body with a big, fast wheel: stiff, the step is set by the wheel's nutation, not by the motion.

    What it proves: the gyrostat methods stay stable and as accurate as their order says when the
    gyroscopic nutation (~25 rad/s, 0.25 rad per 10 ms step) is a thousand times the body's rate.
    Limits, from the physics and RK4's known error (no fitting to our own output):

    * omega error <= :func:`rk4_nutation_error` at the nutation rate of :func:`nutation_rate` with
      amplitude ``sqrt(I_max / I_min) |omega0 - (omega0 . h^) h^|`` (the part of omega0 across h
      nutates, on an ellipse whose axes differ by at most that factor); the slow motion's own
      RK4 error is (0.02 rad/s * dt)^4 smaller. dopri5 (order 5, rtol 1e-10) lies far below.
    * total E and |H| (body + wheel) to 1e-8: both are dominated by the wheel (|h| = 3000 N m s against
      |I omega| ~ 2.4 N m s); a method that stays stable damps the nutation by ~theta^6 / 144 per step
      and moves them ~1e-9 at most; one that goes unstable blows past it within a few steps.
    """
    moments = (100.0, 120.0, 150.0)
    wheels = wheel_model(np.diag(moments), ["fast"], [[1.0, 1.0, 1.0]], [5.0], [1.0], [1000.0])
    speeds = (600.0,)
    omega0 = np.array([0.01, 0.02, 0.005])
    dt = 0.01
    problem = dataclasses.replace(
        P5,
        key="fast_wheel",
        title="fast wheel on a slow body",
        principal_moments=moments,
        omega0=tuple(omega0.tolist()),
        wheel_speeds0=speeds,
        wheels=wheels,
        t_end=5.0 if quick else 20.0,
    )
    rate = nutation_rate(moments, wheels, speeds)
    axis = wheels.axes[0]
    across = float(np.linalg.norm(omega0 - (omega0 @ axis) * axis))
    hub = np.linalg.eigvalsh(hub_inertia(moments, wheels))
    amplitude = float(np.sqrt(hub[-1] / hub[0])) * across
    steps = steps_over(problem.t_end, dt)
    limit = rk4_nutation_error(rate, dt, steps, amplitude)
    return Case(
        name="fast wheel, slow body",
        description=f"gyrostat: I = (100, 120, 150) kg m², ω0 ≈ 0.02 rad/s, a 5 kg m² wheel about (1, 1, 1) at "
        f"600 rad/s (nutation {rate:.3g} rad/s, {rate * dt:.2g} rad per step), dt = 10 ms; "
        "run by gyrostat_rk4 and dopri5",
        problem=problem,
        dt=dt,
        criterion=Criterion(
            energy_drift=1e-8,
            momentum_drift=1e-8,
            omega_error=limit,
            text="total E and |H| (body + wheel); the ω limit is RK4's nutation phase error (linear theory)",
        ),
    )


def case_named(name: str, quick: bool) -> Case:
    """The catalogue's case ``name`` (rebuilt, as a Dask worker does)."""
    return next(case for case in catalogue(quick) if case.name == name)
