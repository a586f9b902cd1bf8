"""The runs of a sweep: their random inputs, how they are chunked, and the simulation of one chunk.

A chunk is a vectorised batch (:func:`rigid_rot_sim.core.batch.advance_batch`) of the
bodies of one grid point (same method and dt). :func:`run_chunk` is a pure function of
the spec and the chunk: it is what a Dask task runs, and running it twice, elsewhere or
with other neighbours gives the same bits, because

* sample ``s``'s random inputs come from ``SeedSequence(seed, spawn_key=(s, k))``, one
  stream ``k`` per kind of dispersion (so switching one dispersion on does not change the
  others' draws). The key is the sample index, not the run index: the same sample has
  the same inputs at every grid point (common random numbers), so differences between
  grid points are the method's, the step's or the spin's, not the dice's;
* a body's arithmetic in the batch core does not depend on the other bodies of its
  batch (tested in test/core/test_batch.py), so chunk sizes are free;
* a body whose state becomes non-finite (or whose implicit solve fails) is isolated by
  re-running its half of the batch, so it becomes a row with its error and the others
  keep their bits.

Frames: inputs and outputs are in the scene's body frame; the batch runs in each
body's own (dispersed) principal frame. Quaternions scalar-last, body -> world.

Time: a schedule segment acts from the step its scene says
(:meth:`~rigid_rot_sim.scene.scene.TorqueSchedule.change_steps`, the run engine's rule),
and torques and states change frames with the engine's quaternion formulas
(:mod:`rigid_rot_sim.core.quaternion`), so an undispersed body is the node's body, bit for
bit (``test/sweep/test_sweep_matches_engine.py``).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from rigid_rot_sim.core import frames
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.batch import advance_batch, advance_batch_recording
from rigid_rot_sim.core.dynamics import RigidBody
from rigid_rot_sim.core.integrators.base import NonFiniteStateError
from rigid_rot_sim.core.steps import step_at_or_after, step_at_or_before, step_grid
from rigid_rot_sim.run.timeline import Stretch, follows_attitude, stretch_at, stretches, world_in_body
from rigid_rot_sim.scene.features import features_of
from rigid_rot_sim.sweep.bodies import Bodies, Outcome, concat, split, subset
from rigid_rot_sim.sweep.checkpoints import CheckpointTrack, checkpoint_steps, checkpoint_time, row_norms
from rigid_rot_sim.sweep.draws import StreamDraws
from rigid_rot_sim.sweep.engine_runs import simulate_engine
from rigid_rot_sim.sweep.spec import NORMAL_CUT_SIGMAS, Dispersion, SweepSpec, runs_per_sample

__all__ = [
    "Chunk",
    "plan_chunks",
    "run_chunk",
    "run_nominal",
    "sample_inputs",
    "COLUMNS",
    "measure_step_cost",
    "choose_chunk_size",
]

# Streams of SeedSequence(seed, spawn_key=(sample, k)): one per kind of dispersion.
_STREAMS = (
    "principal_moments",
    "axis_misalignment",
    "initial_omega",
    "initial_attitude",
    "torque_scale",
    "torque_noise",
    "orbit_phase",
    "epoch",
)

#: Output columns in order, with their Arrow types. I1, I2, I3 are the run's principal moments
#: (kg*m^2) about the base body's principal axes, numbered by the base body's ascending moments; omega
#: columns are rad/s in the body frame; event columns are NaN unless the spec asks for them; ``orbit_phase`` rad
#: and ``epoch_offset`` s are the dispersions of the orbit and the epoch; ``final_field_*`` T, body frame, the true
#: field at the end (NaN for a scene without a field).
COLUMNS: dict[str, str] = {
    "run": "int64",
    "grid_point": "int32",
    "sample": "int64",
    "method": "string",
    "dt": "float64",
    "spin_rate": "float64",
    "I1": "float64",
    "I2": "float64",
    "I3": "float64",
    "misalignment": "float64",
    "omega0_x": "float64",
    "omega0_y": "float64",
    "omega0_z": "float64",
    "attitude0_error": "float64",
    "torque_scale_x": "float64",
    "torque_scale_y": "float64",
    "torque_scale_z": "float64",
    "torque_noise_rms": "float64",
    "orbit_phase": "float64",
    "epoch_offset": "float64",
    "final_attitude_error": "float64",
    "final_omega_x": "float64",
    "final_omega_y": "float64",
    "final_omega_z": "float64",
    "final_omega_error": "float64",
    "max_omega": "float64",
    "energy_drift": "float64",
    "momentum_drift": "float64",
    "first_flip": "float64",
    "nutation_range": "float64",
    "final_field_x": "float64",
    "final_field_y": "float64",
    "final_field_z": "float64",
    "verdict": "string",
    "error": "string",
}


@dataclass(frozen=True)
class Chunk:
    """Samples ``start`` to ``stop`` (exclusive) of grid point ``grid_point`` (method, dt, spin)."""

    grid_point: int
    start: int
    stop: int

    @property
    def size(self) -> int:
        return self.stop - self.start


def plan_chunks(spec: SweepSpec, chunk_size: int) -> list[Chunk]:
    """Every grid point's samples cut into chunks of at most ``chunk_size`` bodies."""
    if chunk_size < 1:
        raise ValueError(f"chunk_size must be >= 1, got {chunk_size}")
    return [
        Chunk(g, start, min(start + chunk_size, spec.samples))
        for g in range(len(spec.grid))
        for start in range(0, spec.samples, chunk_size)
    ]


# ----------------------------------------------------------------------------- inputs


def sample_inputs(spec: SweepSpec, sample: int) -> dict[str, np.ndarray]:
    """The random perturbations of ``sample`` (zeros where not dispersed), from its own seed.

    Keys: ``moments`` (relative, per principal axis), ``misalignment`` (rotation vector,
    rad, principal frame), ``omega`` (rad/s, body), ``attitude`` (rotation vector, rad,
    body), ``torque_scale`` (relative, per body axis), ``noise`` ((intervals, 3) N*m, body),
    ``orbit_phase`` (rad) and ``epoch`` (s), one number each.
    """
    return {key: value[0] for key, value in _sample_draws(spec, np.array([sample])).items()}


def _sample_draws(spec: SweepSpec, samples: np.ndarray) -> dict[str, np.ndarray]:
    """:func:`sample_inputs` of many samples, stacked: (N, 3) per key, noise (N, intervals, 3).

    Stream ``k`` of sample ``s`` is ``PCG64(SeedSequence(seed, spawn_key=(s, k)))``, built for
    all the samples at once (:mod:`~rigid_rot_sim.sweep.draws`); only the dispersed
    streams are built, and each one's draws are its own either way.
    """
    d = spec.dispersions
    n = len(samples)
    draws = StreamDraws()

    def stream(name: str, dispersion: Dispersion | None, count: int = 3) -> np.ndarray:
        if not dispersion:
            return np.zeros((n, count))
        k = _STREAMS.index(name)
        if dispersion.distribution == "uniform":
            z = draws.uniforms(spec.seed, samples, k, count, -1.0, 1.0)
        else:
            z = draws.normals(spec.seed, samples, k, count, cut=NORMAL_CUT_SIGMAS)
        return z * np.asarray(dispersion.size)

    out = {
        "moments": stream("principal_moments", d.principal_moments),
        "misalignment": stream("axis_misalignment", d.axis_misalignment),
        "omega": stream("initial_omega", d.initial_omega),
        "attitude": stream("initial_attitude", d.initial_attitude),
        "torque_scale": stream("torque_scale", d.torque_scale),
        "orbit_phase": stream("orbit_phase", d.orbit_phase, 1)[:, 0],
        "epoch": np.round(stream("epoch", d.epoch, 1)[:, 0], 6),  # whole microseconds: what a datetime holds
    }
    if d.torque_noise_sigma is not None:
        intervals = math.ceil(spec.duration / d.torque_noise_interval)
        sigma = np.asarray(d.torque_noise_sigma)
        z = draws.normals(spec.seed, samples, _STREAMS.index("torque_noise"), 3 * intervals)
        out["noise"] = z.reshape(n, intervals, 3) * sigma
    else:
        out["noise"] = np.zeros((n, 0, 3))
    return out


def _nominal_omega0(spec: SweepSpec, spin_rate: float | None) -> np.ndarray:
    omega = np.array(spec.scene.initial.angular_velocity, dtype=float)
    if spin_rate is not None:
        omega *= spin_rate / np.linalg.norm(omega)
    return omega


def _bodies(spec: SweepSpec, spin_rate: float | None, samples: range | None) -> Bodies:
    """The dispersed bodies of ``samples``, or the nominal body (``samples`` None)."""
    body = RigidBody.from_inertia(spec.scene.body.inertia_array, "body.inertia")
    draws = _sample_draws(spec, np.arange(samples.start, samples.stop)) if samples is not None else None
    n = len(samples) if samples is not None else 1
    zeros = np.zeros((n, 3))

    def stack(key: str) -> np.ndarray:
        return draws[key] if draws is not None else zeros

    def one(key: str) -> np.ndarray:
        return draws[key] if draws is not None else np.zeros(n)

    misalignment = stack("misalignment")
    attitude = stack("attitude")
    moments = np.asarray(body.principal_moments) * (1.0 + stack("moments"))
    d = spec.dispersions
    # composed only where dispersed: a composition with the identity renormalises (an ulp), the engine's does not
    body_from_principal_quat = np.tile(body.body_from_principal, (n, 1))
    body_from_principal = Rotation.from_quat(body_from_principal_quat)
    if d.axis_misalignment is not None:
        body_from_principal = quat.compose_rotations(
            Rotation.from_quat(body.body_from_principal), Rotation.from_rotvec(misalignment)
        )
        body_from_principal_quat = body_from_principal.as_quat(canonical=False)
    q0 = np.tile(np.asarray(spec.scene.initial.orientation, dtype=float), (n, 1))
    if d.initial_attitude is not None:
        q0 = quat.compose_rotations(
            Rotation.from_quat(spec.scene.initial.orientation), Rotation.from_rotvec(attitude)
        ).as_quat()
    intervals = math.ceil(spec.duration / d.torque_noise_interval) if d.torque_noise_sigma is not None else 0
    noise = draws["noise"] if draws is not None else np.zeros((1, intervals, 3))
    return Bodies(
        moments=moments,
        body_from_principal=body_from_principal,
        body_from_principal_quat=body_from_principal_quat,
        q0_body=q0,
        omega0_body=_nominal_omega0(spec, spin_rate) + stack("omega"),
        torque_scale=1.0 + stack("torque_scale"),
        noise=noise,
        misalignment=row_norms(misalignment),
        attitude0_error=row_norms(attitude),
        orbit_phase=one("orbit_phase"),
        epoch_offset=one("epoch"),
    )


# ----------------------------------------------------------------------------- simulation


def _advance_isolated(
    method: str, moments, q, omega, dt: float, n_steps: int, torque, normalize_q: bool
) -> tuple[np.ndarray, np.ndarray, dict[int, str]]:
    """advance_batch, but a body that fails only fails itself: ``(q, omega, {index: error})``.

    A failing batch is split in halves and each half re-run (a body's bits do not depend
    on its neighbours); a single failing body is stepped once at a time to say when.
    ``normalize_q``: as for advance_batch (False when continuing from its own states).
    """
    try:
        q_new, omega_new = advance_batch(method, moments, q, omega, dt, n_steps, torque, normalize_q=normalize_q)
        return q_new, omega_new, {}
    except (NonFiniteStateError, ArithmeticError) as exc:
        first_error = exc
    n = q.shape[0]
    if n == 1:
        q_k, omega_k = q, omega
        for k in range(n_steps):
            try:
                q_k, omega_k = advance_batch(
                    method, moments, q_k, omega_k, dt, 1, torque, normalize_q=normalize_q and k == 0
                )
            except (NonFiniteStateError, ArithmeticError) as exc:
                reason = " ".join(str(exc).split())
                return (
                    np.full_like(q, np.nan),
                    np.full_like(omega, np.nan),
                    {0: f"{type(exc).__name__} at step {k + 1} of the segment: {reason}"},
                )
        return np.full_like(q, np.nan), np.full_like(omega, np.nan), {0: f"{type(first_error).__name__}: {first_error}"}
    half = n // 2
    parts = [slice(0, half), slice(half, n)]
    qs, omegas, errors = [], [], {}
    for part in parts:
        q_p, omega_p, err = _advance_isolated(
            method, moments[part], q[part], omega[part], dt, n_steps, torque[part], normalize_q
        )
        qs.append(q_p)
        omegas.append(omega_p)
        errors.update({part.start + i: message for i, message in err.items()})
    return np.concatenate(qs), np.concatenate(omegas), errors


def _rows(helper: Any, *arrays: np.ndarray) -> np.ndarray:
    """A :mod:`~rigid_rot_sim.core.quaternion` helper applied row by row: (N, 4) / (N, 3) in, (N, 3 or 4) out.

    The helpers' scalar formulas run on columns, so each row gets the bits the engine's
    per-body call gives it.
    """
    return np.stack(helper(*(array.T for array in arrays)), axis=-1)


def _body_torque(
    spec: SweepSpec,
    bodies: Bodies,
    stretch: Stretch,
    k: int,
    dt: float,
    attitude: tuple[np.ndarray, np.ndarray] | None,
) -> np.ndarray:
    """(N, 3) N*m in the body frame acting over step k (of ``dt`` s, in ``stretch``): schedules (scaled) plus noise.

    ``attitude`` (q principal -> world (N, 4), principal_from_body (N, 4)) is needed for
    world-frame schedules only: as in the run engine, the world-frame sum is re-expressed
    (:func:`rigid_rot_sim.run.timeline.world_in_body`) and added to the body-frame one.
    """
    n = bodies.moments.shape[0]
    torque = np.zeros((n, 3)) + np.asarray(stretch.body, dtype=float)
    if stretch.world is not None and any(stretch.world):
        assert attitude is not None
        torque += _rows(world_in_body, *attitude, np.broadcast_to(np.asarray(stretch.world, dtype=float), (n, 3)))
    torque *= bodies.torque_scale
    if bodies.noise.shape[1]:
        index = min(step_at_or_before(k * dt, spec.dispersions.torque_noise_interval), bodies.noise.shape[1] - 1)
        torque += bodies.noise[:, index, :]
    return torque


#: At most this many bytes of recorded rates (N bodies x 3 x 8 bytes per checkpoint) per kernel call:
#: a run of many checkpoints is joined into several calls (a few calls cost no more than one).
_RECORDED_BYTES = 8 * 2**20


@dataclass(frozen=True)
class _Plan:
    """The segment plan of a run of ``spec.duration`` s at ``dt``: the step ranges ``segments`` between the boundaries
    where the torque may change (the timeline's, the noise's) or a checkpoint is taken, the last shorter step
    (``last`` s, 0 for none) as a segment of its own."""

    spec: SweepSpec
    dt: float
    n_full: int
    last: float
    timeline: tuple[Stretch, ...]
    segments: tuple[tuple[int, int], ...]
    checkpoints: frozenset[int]
    world_frame: bool  # torques that depend on the state

    def step(self, a: int) -> float:
        """s: the step of the segment starting at boundary ``a``."""
        return self.last if a == self.n_full else self.dt

    def time_of(self, step_end: int) -> float:
        """s: the time at the end of a step (the duration itself at the last, shorter or full)."""
        return checkpoint_time(self.spec.duration, self.dt, self.n_full, self.last, step_end)

    def torque(self, bodies: Bodies, a: int, attitude: tuple[np.ndarray, np.ndarray] | None) -> np.ndarray:
        """(N, 3) N*m, body frame: :func:`_body_torque` over the segment starting at ``a``."""
        return _body_torque(self.spec, bodies, stretch_at(self.timeline, a), a, self.dt, attitude)


def _plan(spec: SweepSpec, dt: float) -> _Plan:
    n_full, last = step_grid(spec.duration, dt)
    timeline = stretches(spec.scene.schedules, dt, n_full + (last > 0.0))
    checkpoints = checkpoint_steps(n_full, spec.checkpoints)
    marks = {0, n_full, *checkpoints.tolist(), *(stretch.start for stretch in timeline)}
    if follows_attitude(spec.scene.schedules):
        marks.update(range(n_full + 1))
    if spec.dispersions.torque_noise_sigma is not None:
        interval = spec.dispersions.torque_noise_interval
        marks.update(step_at_or_after(k * interval, dt) for k in range(math.ceil(spec.duration / interval)))
    bounds = sorted({min(max(mark, 0), n_full) for mark in marks})
    segments = [(a, b) for a, b in zip(bounds[:-1], bounds[1:], strict=False) if b > a]
    if last > 0.0:
        segments.append((n_full, n_full + 1))  # the last, shorter step landing on the duration
    return _Plan(
        spec=spec,
        dt=dt,
        n_full=n_full,
        last=last,
        timeline=timeline,
        segments=tuple(segments),
        checkpoints=frozenset(checkpoints.tolist()) | ({n_full + 1} if last > 0.0 else set()),
        world_frame=any(stretch.world is not None for stretch in timeline),
    )


class _BatchRun:
    """N bodies stepped through a :class:`_Plan` by the batch kernel (principal frames); see :func:`simulate_batch`."""

    def __init__(self, plan: _Plan, bodies: Bodies, method: str) -> None:
        self.plan, self.bodies, self.method = plan, bodies, method
        n = bodies.moments.shape[0]
        bp = bodies.body_from_principal
        self.principal_from_body = _rows(frames.principal_from_body, bodies.body_from_principal_quat)
        self.q = quat.compose_rotations(Rotation.from_quat(bodies.q0_body), bp).as_quat()  # principal -> world
        self.omega = bp.apply(bodies.omega0_body, inverse=True)
        self.alive = np.ones(n, dtype=bool)
        self.errors: dict[int, str] = {}
        self.energy0, self.momentum0 = self.invariants()
        self.track = CheckpointTrack(bodies.moments, self.omega)
        self.track.observe(0.0, self.omega)
        self.impulse = np.zeros(n)
        self.cached: tuple[Any, np.ndarray, np.ndarray] = (None, np.empty(0), np.empty(0))
        self.cut_until = 0  # segments before this one run one call each (a joined call failed there)
        self.max_joined = max(2, _RECORDED_BYTES // (3 * 8 * n))  # the recorded rates of a call stay small

    def invariants(self) -> tuple[np.ndarray, np.ndarray]:
        momentum = self.bodies.moments * self.omega
        return 0.5 * np.einsum("ij,ij->i", momentum, self.omega), row_norms(momentum)

    def torques(self, a: int, live: Any) -> tuple[Any, np.ndarray, np.ndarray]:
        """(key, |torque| x step, principal-frame torque) of the live bodies over the segment from ``a``; key None
        once a body failed. Most segments repeat the last one's torques (a torque-free run: all of them)."""
        plan, everyone = self.plan, not self.errors
        attitude = (self.q[live], self.principal_from_body[live]) if plan.world_frame else None
        torque_body = plan.torque(self.bodies if everyone else subset(self.bodies, self.alive), a, attitude)
        key = (plan.step(a), torque_body.tobytes()) if everyone else None
        if key is None or key != self.cached[0]:
            principal = _rows(frames.vector_to_principal, self.principal_from_body[live], torque_body)
            self.cached = (key, row_norms(torque_body) * plan.step(a), principal)
        return self.cached

    def joinable(self, k: int, key: Any) -> list[tuple[int, int]]:
        """Segment k and those right after it under the same torques (full steps, no body failed, torques that do
        not depend on the state): one kernel call that records the checkpoints' rates runs them."""
        plan = self.plan
        first = plan.segments[k]
        if key is None or plan.world_frame or first[0] == plan.n_full or k < self.cut_until:
            return [first]
        joined = [first]
        for a, b in plan.segments[k + 1 : k + self.max_joined]:
            if a == plan.n_full or (plan.dt, plan.torque(self.bodies, a, None).tobytes()) != key:
                break
            joined.append((a, b))
        return joined

    def run_joined(self, joined: list[tuple[int, int]], impulse_rate: np.ndarray, torque_p: np.ndarray) -> bool:
        """Run ``joined`` in one recording call; False (nothing changed) when it fails."""
        a = joined[0][0]
        try:
            self.q, self.omega, omega_at = advance_batch_recording(
                self.method, self.bodies.moments, self.q, self.omega, self.plan.dt,
                [end - a for _, end in joined], torque_p, normalize_q=a == 0,
            )  # fmt: skip
        except (NonFiniteStateError, ArithmeticError):
            return False
        for (a_j, b_j), omega_j in zip(joined, omega_at, strict=True):
            self.impulse += impulse_rate * (b_j - a_j)
            if b_j in self.plan.checkpoints:
                self.track.observe(self.plan.time_of(b_j), omega_j)
        return True

    def run_one(self, a: int, b: int, live: Any, impulse_rate: np.ndarray, torque_p: np.ndarray) -> None:
        """Run the segment (a, b) of the live bodies; a failing body fails alone (NaN, its error kept)."""
        step = self.plan.step(a)
        self.impulse[live] += impulse_rate * (b - a)
        # the first call normalises q as an integrator's set_state does; later ones continue from it
        q_new, omega_new, failed = _advance_isolated(
            self.method, self.bodies.moments[live], self.q[live], self.omega[live], step, b - a, torque_p, a == 0
        )
        if isinstance(live, slice):
            self.q, self.omega = q_new, omega_new  # fresh arrays: no copy back
        else:
            self.q[live], self.omega[live] = q_new, omega_new
        index = np.flatnonzero(self.alive) if failed else np.empty(0, dtype=np.int64)
        for i, message in failed.items():
            self.errors[int(index[i])] = f"{message} (segment from t = {a * self.plan.dt:.9g} s, dt = {step:.9g} s)"
            self.alive[index[i]] = False
        if b in self.plan.checkpoints:
            omega = self.omega if not self.errors else np.where(self.alive[:, None], self.omega, np.nan)
            self.track.observe(self.plan.time_of(b), omega)

    def outcome(self) -> Outcome:
        alive = self.alive
        energy, momentum = self.invariants()
        with np.errstate(divide="ignore", invalid="ignore"):
            energy_drift = np.abs(energy - self.energy0) / np.where(self.energy0 > 0, self.energy0, 1.0)
            momentum_drift = np.abs(momentum - self.momentum0) / np.where(self.momentum0 > 0, self.momentum0, 1.0)
        q_alive = np.where(alive[:, None], self.q, [0.0, 0.0, 0.0, 1.0])
        q_body = _rows(frames.attitude_from_principal, q_alive, self.principal_from_body)
        q_body[~alive] = np.nan
        omega_alive = np.where(alive[:, None], self.omega, 0.0)
        omega_body = _rows(frames.vector_from_principal, self.bodies.body_from_principal_quat, omega_alive)
        omega_body[~alive] = np.nan
        return Outcome(
            q_body=q_body,
            omega_body=omega_body,
            errors=self.errors,
            max_omega=np.where(alive, self.track.max_omega, np.nan),
            energy_drift=energy_drift,
            momentum_drift=momentum_drift,
            omega_bound=(self.momentum0 + self.impulse) / self.bodies.moments.min(axis=1),
            first_flip=self.track.first_flip,
            nutation_range=np.where(alive, self.track.nutation_range(), np.nan),
            field_body=np.full((len(alive), 3), np.nan),  # a batch scene has no field (an orbit runs per sample)
        )


def simulate_batch(spec: SweepSpec, bodies: Bodies, method: str, dt: float) -> Outcome:
    """Run the bodies over the spec's duration with the batch kernel; failed bodies end as NaN with their error."""
    plan = _plan(spec, dt)
    run = _BatchRun(plan, bodies, method)
    k = 0
    while k < len(plan.segments) and run.alive.any():
        a, b = plan.segments[k]
        live = slice(None) if not run.errors else run.alive
        key, impulse_rate, torque_p = run.torques(a, live)
        joined = run.joinable(k, key)
        if len(joined) > 1:
            if run.run_joined(joined, impulse_rate, torque_p):
                k += len(joined)
                continue
            run.cut_until = k + len(joined)  # run them one at a time: the failing bodies fail alone
        run.run_one(a, b, live, impulse_rate, torque_p)
        k += 1
    return run.outcome()


def _simulate(spec: SweepSpec, bodies: Bodies, method: str, dt: float) -> Outcome:
    """The bodies' runs: the batch kernel for a rigid-body scene, the run engine per sample for the others."""
    if runs_per_sample(spec.scene):
        return simulate_engine(spec, bodies, method, dt)
    return simulate_batch(spec, bodies, method, dt)


#: Sources that change the energy or the momentum of a scene besides its schedules: a run with one is not torque-free.
_SOURCES = ("spacecraft.wheels.friction", "spacecraft.wheel_schedule", "spacecraft.gravity_gradient")


def _torque_free(spec: SweepSpec) -> bool:
    """Whether the energy and |L| (with wheels: eqs. (1), (6) of core.wheels) are the physics' invariants."""
    schedules = any(any(s.torque) for sched in spec.scene.schedules for s in sched.segments)
    sources = set(_SOURCES) & set(features_of(spec.scene))
    return not schedules and not sources and spec.dispersions.torque_noise_sigma is None


def run_nominal(spec: SweepSpec, spin_rate: float | None) -> Outcome:
    """The undispersed run at ``spin_rate`` with the spec's ``nominal`` integrator.

    One task per spin rate when the spec names a nominal integrator; its result is passed
    to every chunk of that spin rate. Otherwise each chunk runs its nominal body itself.
    """
    if spec.nominal_method is None or spec.nominal_dt is None:
        raise ValueError("the spec names no nominal integrator: each chunk runs its nominal body")
    return _simulate(spec, _bodies(spec, spin_rate, None), spec.nominal_method, spec.nominal_dt)


def run_chunk(spec: SweepSpec, chunk: Chunk, nominal: Outcome | None = None) -> dict[str, Any]:
    """Simulate one chunk; returns its rows as columns (:data:`COLUMNS`), one row per sample.

    ``nominal``: :func:`run_nominal` of the chunk's spin rate, required when the spec
    names a nominal integrator (else the nominal body runs in this chunk's batch).
    """
    method, dt, spin_rate = spec.grid[chunk.grid_point]
    samples = range(chunk.start, chunk.stop)
    bodies = _bodies(spec, spin_rate, samples)
    n = chunk.size
    if spec.nominal_method is None:
        # the nominal body rides along in the same batch (its bits do not depend on the others)
        both = _simulate(spec, concat(bodies, _bodies(spec, spin_rate, None)), method, dt)
        outcome, nominal = split(both, n)
    else:
        if nominal is None:
            nominal = run_nominal(spec, spin_rate)
        outcome = _simulate(spec, bodies, method, dt)
    attitude_error = quat.compose_rotations(
        Rotation.from_quat(np.nan_to_num(nominal.q_body[0], nan=1.0)).inv(),
        Rotation.from_quat(np.nan_to_num(outcome.q_body, nan=1.0)),
    ).magnitude()
    failed = np.isnan(outcome.q_body).any(axis=1) | np.isnan(nominal.q_body[0]).any()
    attitude_error = np.where(failed, np.nan, attitude_error)
    omega_error = row_norms(outcome.omega_body - nominal.omega_body[0])
    torque_free = _torque_free(spec)
    tolerance = spec.energy_tolerance
    if torque_free:
        drifting = np.maximum(outcome.energy_drift, outcome.momentum_drift) > tolerance
    else:
        drifting = outcome.max_omega > outcome.omega_bound * (1.0 + tolerance)
    verdicts = np.where(drifting, "drifting", "stable").astype(object)
    error: list[str | None] = [f"nominal run failed: {nominal.errors[0]}" if nominal.errors else None] * n
    for i, message in outcome.errors.items():
        verdicts[i], error[i] = "unstable", message
    verdict = verdicts.tolist()
    nan = np.full(n, np.nan)
    grid_point = chunk.grid_point
    return {
        "run": np.arange(chunk.start, chunk.stop, dtype=np.int64) + grid_point * spec.samples,
        "grid_point": np.full(n, grid_point, dtype=np.int32),
        "sample": np.arange(chunk.start, chunk.stop, dtype=np.int64),
        "method": [method] * n,
        "dt": np.full(n, dt),
        "spin_rate": np.full(n, np.nan if spin_rate is None else spin_rate),
        "I1": bodies.moments[:, 0],
        "I2": bodies.moments[:, 1],
        "I3": bodies.moments[:, 2],
        "misalignment": bodies.misalignment,
        "omega0_x": bodies.omega0_body[:, 0],
        "omega0_y": bodies.omega0_body[:, 1],
        "omega0_z": bodies.omega0_body[:, 2],
        "attitude0_error": bodies.attitude0_error,
        "torque_scale_x": bodies.torque_scale[:, 0],
        "torque_scale_y": bodies.torque_scale[:, 1],
        "torque_scale_z": bodies.torque_scale[:, 2],
        "torque_noise_rms": np.sqrt(np.mean(bodies.noise**2, axis=(1, 2))) if bodies.noise.shape[1] else np.zeros(n),
        "orbit_phase": bodies.orbit_phase,
        "epoch_offset": bodies.epoch_offset,
        "final_attitude_error": attitude_error,
        "final_omega_x": outcome.omega_body[:, 0],
        "final_omega_y": outcome.omega_body[:, 1],
        "final_omega_z": outcome.omega_body[:, 2],
        "final_omega_error": omega_error,
        "max_omega": outcome.max_omega,
        "energy_drift": outcome.energy_drift if torque_free else nan,
        "momentum_drift": outcome.momentum_drift if torque_free else nan,
        "first_flip": outcome.first_flip if "first_flip" in spec.events else nan,
        "nutation_range": outcome.nutation_range if "nutation_range" in spec.events else nan,
        "final_field_x": outcome.field_body[:, 0],
        "final_field_y": outcome.field_body[:, 1],
        "final_field_z": outcome.field_body[:, 2],
        "verdict": verdict,
        "error": error,
    }


# ----------------------------------------------------------------------------- chunk size


def measure_step_cost(method: str, sizes: tuple[int, int] = (1, 256), steps: int = 20) -> tuple[float, float]:
    """(fixed, per-body) cost of one batch step, s: ``step time = fixed + per_body * N``.

    Measured here with a short run of a generic body at each size (best of 3).
    """
    times = []
    for n in sizes:
        moments = np.tile([1.0, 2.0, 2.5], (n, 1))
        q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
        omega = np.tile([0.1, 1.0, 0.1], (n, 1))
        best = math.inf
        for _ in range(3):
            start = time.perf_counter()
            advance_batch(method, moments, q, omega, 1e-3, steps, np.zeros((n, 3)))
            best = min(best, time.perf_counter() - start)
        times.append(best / steps)
    per_body = max((times[1] - times[0]) / (sizes[1] - sizes[0]), 1e-12)
    fixed = max(times[0] - per_body * sizes[0], 0.0)
    return fixed, per_body


def measure_engine_step_cost(spec: SweepSpec, steps: int = 200) -> tuple[float, float]:
    """(0, per-body) cost of one step of a sweep run by the engine per sample, s: a short nominal run of the scene.

    The engine's runs are one per body, so there is no fixed part shared by a batch.
    """
    dt = min(spec.dts)
    scene = dataclasses.replace(spec.scene, duration=None)
    start = time.perf_counter()
    simulate_engine(
        dataclasses.replace(spec, scene=scene, duration=steps * dt, checkpoints=1),
        _bodies(spec, None, None),
        spec.methods[0],
        dt,
    )
    return 0.0, max((time.perf_counter() - start) / steps, 1e-12)


def choose_chunk_size(
    spec: SweepSpec, workers: int, target_seconds: float = 5.0, tasks_per_worker: int = 4
) -> tuple[int, dict[str, float]]:
    """Bodies per task from the measured step cost, and the figures it was chosen from.

    A batch step costs ``fixed + per_body * N``: the fixed part (Python and numpy call
    overhead) is paid once per batch, so the fewer and larger the batches the better,
    as long as every worker gets ``tasks_per_worker`` tasks (load balance, and little
    work lost when a worker dies) and no task runs longer than about ``target_seconds``.
    """
    fixed, per_body = (
        measure_engine_step_cost(spec) if runs_per_sample(spec.scene) else measure_step_cost(spec.methods[0])
    )
    steps = max(spec.duration / min(spec.dts), 1.0)
    bounded = max(1, math.floor(target_seconds / (steps * per_body)))
    balanced = math.ceil(spec.n_runs / (tasks_per_worker * max(workers, 1)))
    size = int(max(1, min(spec.samples, bounded, balanced)))
    figures = {
        "fixed_step_seconds": fixed,
        "per_body_step_seconds": per_body,
        "overhead_fraction": fixed / (fixed + per_body * size),
    }
    return size, figures
