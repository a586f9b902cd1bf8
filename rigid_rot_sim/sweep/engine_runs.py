"""The runs of a sweep whose scene the batch kernel cannot run: the run engine itself, one sample at a time.

A scene with reaction wheels or the gravity gradient (features outside
:data:`~rigid_rot_sim.sweep.spec.BATCH_FEATURES`, those the rigid-body kernel of
:mod:`rigid_rot_sim.core.batch` runs) is swept by running :class:`~rigid_rot_sim.run.simulator.Simulator`
on each sample's dispersed copy of the scene (:func:`dispersed_scene`) with the grid point's method (a
name of the engine's registry: ``gyrostat_rk4`` or ``dopri5``) and step, to the checkpoints and the
duration. So an undispersed sample ends where the engine ends, bit for bit, by construction: the
engine is the one model of every source (wheels with their friction and limits, the wheel-torque
schedule, the gravity gradient, the torque schedules).

Dispersions map onto the scene: ``principal_moments`` and ``axis_misalignment`` give the body's
inertia tensor (``R diag(I) R^T``, which the engine diagonalises again; the wheels' validity is
then the engine's check, a body it refuses is a row with the reason), ``initial_omega``,
``initial_attitude`` and the grid's spin rate the initial state, ``orbit_phase`` the orbit's true anomaly
at t = 0 (the other elements and the J2 rates kept: the mean anomaly of the shifted true anomaly; the
gravity gradient follows), ``epoch`` the scene's epoch (an offset in whole microseconds, an ISO 8601
date as the scene writes one). ``torque_scale`` and ``torque_noise`` map onto no scene key: the spec refuses them for
such a scene. Each run also reports the true field at its end (T, body frame; NaN without a field): the
scene's :meth:`~rigid_rot_sim.scene.scene.Scene.orbit_field` at the end's time and attitude, as
``~/magnetic_field`` publishes it.

The verdict of a run under torque compares its largest ``|omega|`` with a bound of the physics:
``I omega = H - h_w`` (eq. (1) of :mod:`rigid_rot_sim.core.wheels`), with ``|H|`` growing at most by
the engine's bound on the torques times the duration and ``|h_w| <= sum J_i max_speed_i``.
"""

from __future__ import annotations

import dataclasses
import datetime
import math

import numpy as np

from rigid_rot_sim.core import orbit as core_orbit
from rigid_rot_sim.core.dynamics import RigidBody
from rigid_rot_sim.core.steps import step_grid
from rigid_rot_sim.run.simulator import Simulator
from rigid_rot_sim.scene.orbit import epoch_datetime
from rigid_rot_sim.scene.scene import InitialState, Scene
from rigid_rot_sim.sweep.bodies import Bodies, Outcome
from rigid_rot_sim.sweep.checkpoints import CheckpointTrack, checkpoint_steps, checkpoint_time
from rigid_rot_sim.sweep.spec import SweepSpec

__all__ = ["dispersed_scene", "simulate_engine"]


def dispersed_scene(spec: SweepSpec, bodies: Bodies, i: int) -> Scene:
    """The scene of body ``i``: the base scene with that body's inertia and initial state (see the module).

    What is not dispersed keeps the scene's own values (bits included): the nominal body is the scene.
    """
    scene = spec.scene
    body = scene.body
    nominal = RigidBody.from_inertia(body.inertia_array, "body.inertia").principal_moments
    if not (np.array_equal(bodies.moments[i], nominal) and bodies.misalignment[i] == 0.0):
        rotation = bodies.body_from_principal[i].as_matrix()
        tensor = rotation @ np.diag(bodies.moments[i]) @ rotation.T
        tensor = 0.5 * (tensor + tensor.T)
        r0, r1, r2 = ((float(r[0]), float(r[1]), float(r[2])) for r in tensor)
        body = dataclasses.replace(body, inertia=(r0, r1, r2), given_as="inertia_tensor")
    orientation = scene.initial.orientation
    if bodies.attitude0_error[i] != 0.0:
        qx, qy, qz, qw = (float(v) for v in bodies.q0_body[i])
        orientation = (qx, qy, qz, qw)
    omega = scene.initial.angular_velocity
    if not np.array_equal(bodies.omega0_body[i], omega):
        wx, wy, wz = (float(v) for v in bodies.omega0_body[i])
        omega = (wx, wy, wz)
    scene = dataclasses.replace(scene, body=body, initial=InitialState(orientation, omega))
    if bodies.orbit_phase[i] != 0.0:
        scene = _with_orbit(scene, _phase_shifted(scene, float(bodies.orbit_phase[i])))
    if bodies.epoch_offset[i] != 0.0:
        shifted = epoch_datetime(scene.epoch) + datetime.timedelta(seconds=float(bodies.epoch_offset[i]))
        scene = dataclasses.replace(scene, epoch=shifted.strftime("%Y-%m-%dT%H:%M:%S.%fZ"))
    return scene


def _with_orbit(scene: Scene, kepler: core_orbit.KeplerOrbit) -> Scene:
    """``scene`` on ``kepler``: its orbit, and the gravity gradient's where it follows the scene's orbit."""
    gradient = scene.spacecraft.gravity_gradient
    if gradient is not None and gradient.kepler is not None:
        spacecraft = dataclasses.replace(
            scene.spacecraft, gravity_gradient=dataclasses.replace(gradient, kepler=kepler)
        )
        scene = dataclasses.replace(scene, spacecraft=spacecraft)
    return dataclasses.replace(scene, orbit=kepler)


def _phase_shifted(scene: Scene, phase: float) -> core_orbit.KeplerOrbit:
    """The scene's orbit with ``phase`` rad added to its true anomaly at t = 0."""
    kepler = scene.orbit
    assert kepler is not None  # the spec refuses orbit_phase for a scene without an orbit
    nu = core_orbit.mean_to_true_anomaly(kepler.mean_anomaly, kepler.e) + phase
    # the rates depend on a, e and i alone: kept, bits included
    return dataclasses.replace(kepler, mean_anomaly=core_orbit.true_to_mean_anomaly(nu, kepler.e))


@dataclasses.dataclass
class _Run:
    """One sample's end: body-frame state, checkpoint figures, drifts, the omega bound, or the error."""

    q_body: np.ndarray
    omega_body: np.ndarray
    track: CheckpointTrack | None
    energy_drift: float = math.nan
    momentum_drift: float = math.nan
    omega_bound: float = math.nan
    field_body: np.ndarray = dataclasses.field(default_factory=lambda: np.full(3, np.nan))
    error: str | None = None


def _failed(message: str) -> _Run:
    return _Run(np.full(4, np.nan), np.full(3, np.nan), None, error=message)


def _principal_omega(sim: Simulator) -> np.ndarray:
    """(1, 3) rad/s: the engine's rate in its principal frame, as the checkpoints track it."""
    integrator = sim.stepper.integrator  # a dt change replaces it: read it each time
    assert integrator is not None
    return np.asarray(integrator.omega, dtype=float)[None, :]


def _run(scene: Scene, method: str, dt: float, duration: float, checkpoints: int) -> _Run:
    """The engine's run of ``scene`` over ``duration`` s, observed at the checkpoints (a last shorter step as
    a change of the engine's dt, as a node would make it)."""
    try:
        sim = Simulator(scene, method=method, dt=dt)
        field = scene.orbit_field()  # a dispersed epoch may leave the model's validity
    except ValueError as exc:
        return _failed(f"ValueError: {exc}")
    n_full, last = step_grid(duration, dt)
    track = CheckpointTrack(sim.body.principal_moments[None, :], _principal_omega(sim))
    track.observe(0.0, _principal_omega(sim))
    start = sim.snapshot()
    for k in checkpoint_steps(n_full, checkpoints)[1:]:
        sim.advance_to(k)
        if sim.failure is not None:
            return _failed(f"{sim.failure} (at t = {sim.clock.t:.9g} s, dt = {dt:.9g} s)")
        track.observe(checkpoint_time(duration, dt, n_full, last, k), _principal_omega(sim))
    if last > 0.0:
        sim.set_integrator(dt=last)
        sim.advance(1)
        if sim.failure is not None:
            return _failed(f"{sim.failure} (the last step, dt = {last:.9g} s)")
        track.observe(duration, _principal_omega(sim))
    end = sim.snapshot()
    wheels = sum(w.inertia * w.max_speed for w in scene.spacecraft.wheels)
    momentum = math.hypot(*start.angular_momentum_body.tolist()) + duration * sim.stepper._torque_bound() + wheels
    return _Run(
        q_body=np.asarray(end.orientation, dtype=float),
        omega_body=np.asarray(end.angular_velocity_body, dtype=float),
        track=track,
        energy_drift=abs(end.energy_drift),
        momentum_drift=abs(end.angular_momentum_drift),
        omega_bound=momentum / float(np.min(sim.body.principal_moments)),
        field_body=np.full(3, np.nan) if field is None else field.body(end.t, end.orientation),
    )


def simulate_engine(spec: SweepSpec, bodies: Bodies, method: str, dt: float) -> Outcome:
    """Run each body's scene (:func:`dispersed_scene`) in the engine; a failed run ends as NaN with its error."""
    runs = [
        _run(dispersed_scene(spec, bodies, i), method, dt, spec.duration, spec.checkpoints)
        for i in range(len(bodies.moments))
    ]

    def figure(name: str) -> np.ndarray:
        return np.array([np.nan if run.track is None else getattr(run.track, name)[0] for run in runs])

    return Outcome(
        q_body=np.array([run.q_body for run in runs]),
        omega_body=np.array([run.omega_body for run in runs]),
        errors={i: run.error for i, run in enumerate(runs) if run.error is not None},
        max_omega=figure("max_omega"),
        energy_drift=np.array([run.energy_drift for run in runs]),
        momentum_drift=np.array([run.momentum_drift for run in runs]),
        omega_bound=np.array([run.omega_bound for run in runs]),
        first_flip=figure("first_flip"),
        nutation_range=np.array([np.nan if run.track is None else run.track.nutation_range()[0] for run in runs]),
        field_body=np.array([run.field_body for run in runs]),
    )
