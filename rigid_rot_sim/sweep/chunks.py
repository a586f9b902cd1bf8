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

import math
import time
from dataclasses import dataclass, fields
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
from rigid_rot_sim.sweep.checkpoints import CheckpointTrack, row_norms
from rigid_rot_sim.sweep.draws import StreamDraws
from rigid_rot_sim.sweep.spec import NORMAL_CUT_SIGMAS, Dispersion, SweepSpec

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
)

#: Output columns in order, with their Arrow types. I1, I2, I3 are the run's principal moments
#: (kg*m^2) about the base body's principal axes, numbered by the base body's ascending moments; omega
#: columns are rad/s in the body frame; event columns are NaN unless the spec asks for them.
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
    body), ``torque_scale`` (relative, per body axis), ``noise`` ((intervals, 3) N*m, body).
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

    def stream(name: str, dispersion: Dispersion | None) -> np.ndarray:
        if not dispersion:
            return np.zeros((n, 3))
        k = _STREAMS.index(name)
        if dispersion.distribution == "uniform":
            z = draws.uniforms(spec.seed, samples, k, 3, -1.0, 1.0)
        else:
            z = draws.normals(spec.seed, samples, k, 3, cut=NORMAL_CUT_SIGMAS)
        return z * np.asarray(dispersion.size)

    out = {
        "moments": stream("principal_moments", d.principal_moments),
        "misalignment": stream("axis_misalignment", d.axis_misalignment),
        "omega": stream("initial_omega", d.initial_omega),
        "attitude": stream("initial_attitude", d.initial_attitude),
        "torque_scale": stream("torque_scale", d.torque_scale),
    }
    if d.torque_noise_sigma is not None:
        intervals = math.ceil(spec.duration / d.torque_noise_interval)
        sigma = np.asarray(d.torque_noise_sigma)
        z = draws.normals(spec.seed, samples, _STREAMS.index("torque_noise"), 3 * intervals)
        out["noise"] = z.reshape(n, intervals, 3) * sigma
    else:
        out["noise"] = np.zeros((n, 0, 3))
    return out


@dataclass
class _Bodies:
    """N bodies' inputs, as the batch runs them (principal frames) and as rows report them."""

    moments: np.ndarray  # (N, 3) kg*m^2, principal
    body_from_principal: Rotation  # N rotations
    q0_body: np.ndarray  # (N, 4)
    omega0_body: np.ndarray  # (N, 3)
    torque_scale: np.ndarray  # (N, 3) multiplies the scheduled body torque
    noise: np.ndarray  # (N, intervals, 3) N*m, body
    misalignment: np.ndarray  # (N,) rad
    attitude0_error: np.ndarray  # (N,) rad


def _nominal_omega0(spec: SweepSpec, spin_rate: float | None) -> np.ndarray:
    omega = np.array(spec.scene.initial.angular_velocity, dtype=float)
    if spin_rate is not None:
        omega *= spin_rate / np.linalg.norm(omega)
    return omega


def _bodies(spec: SweepSpec, spin_rate: float | None, samples: range | None) -> _Bodies:
    """The dispersed bodies of ``samples``, or the nominal body (``samples`` None)."""
    body = RigidBody.from_inertia(spec.scene.body.inertia_array, "body.inertia")
    draws = _sample_draws(spec, np.arange(samples.start, samples.stop)) if samples is not None else None
    n = len(samples) if samples is not None else 1
    zeros = np.zeros((n, 3))

    def stack(key: str) -> np.ndarray:
        return draws[key] if draws is not None else zeros

    misalignment = stack("misalignment")
    attitude = stack("attitude")
    moments = np.asarray(body.principal_moments) * (1.0 + stack("moments"))
    body_from_principal = quat.compose_rotations(
        Rotation.from_quat(body.body_from_principal), Rotation.from_rotvec(misalignment)
    )
    q0 = quat.compose_rotations(
        Rotation.from_quat(spec.scene.initial.orientation), Rotation.from_rotvec(attitude)
    ).as_quat()
    d = spec.dispersions
    intervals = math.ceil(spec.duration / d.torque_noise_interval) if d.torque_noise_sigma is not None else 0
    noise = draws["noise"] if draws is not None else np.zeros((1, intervals, 3))
    return _Bodies(
        moments=moments,
        body_from_principal=body_from_principal,
        q0_body=q0,
        omega0_body=_nominal_omega0(spec, spin_rate) + stack("omega"),
        torque_scale=1.0 + stack("torque_scale"),
        noise=noise,
        misalignment=row_norms(misalignment),
        attitude0_error=row_norms(attitude),
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


def _boundaries(
    spec: SweepSpec, dt: float, n_full: int, timeline: tuple[Stretch, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """Step indices where the torque may change (the timeline's, the noise's) or a checkpoint is taken, and the
    checkpoint steps."""
    checkpoints = np.unique(np.linspace(0, n_full, spec.checkpoints + 1).round().astype(np.int64))
    marks = {0, n_full, *checkpoints.tolist(), *(stretch.start for stretch in timeline)}
    if follows_attitude(spec.scene.schedules):
        marks.update(range(n_full + 1))
    if spec.dispersions.torque_noise_sigma is not None:
        interval = spec.dispersions.torque_noise_interval
        marks.update(step_at_or_after(k * interval, dt) for k in range(math.ceil(spec.duration / interval)))
    within = [min(max(mark, 0), n_full) for mark in marks]
    return np.array(sorted(set(within)), dtype=np.int64), checkpoints


def _rows(helper: Any, *arrays: np.ndarray) -> np.ndarray:
    """A :mod:`~rigid_rot_sim.core.quaternion` helper applied row by row: (N, 4) / (N, 3) in, (N, 3 or 4) out.

    The helpers' scalar formulas run on columns, so each row gets the bits the engine's
    per-body call gives it.
    """
    return np.stack(helper(*(array.T for array in arrays)), axis=-1)


def _body_torque(
    spec: SweepSpec,
    bodies: _Bodies,
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


@dataclass
class _Outcome:
    q_body: np.ndarray
    omega_body: np.ndarray
    errors: dict[int, str]
    max_omega: np.ndarray
    energy_drift: np.ndarray
    momentum_drift: np.ndarray
    omega_bound: np.ndarray
    first_flip: np.ndarray
    nutation_range: np.ndarray


def _simulate(spec: SweepSpec, bodies: _Bodies, method: str, dt: float) -> _Outcome:
    """Run the bodies over the spec's duration; failed bodies end as NaN with their error."""
    n = bodies.moments.shape[0]
    n_full, last = step_grid(spec.duration, dt)
    timeline = stretches(spec.scene.schedules, dt, n_full + (last > 0.0))
    marks, checkpoints = _boundaries(spec, dt, n_full, timeline)
    checkpoint_set = set(checkpoints.tolist())
    bp = bodies.body_from_principal
    principal_from_body = _rows(frames.principal_from_body, bp.as_quat(canonical=False))
    moments = bodies.moments
    q = quat.compose_rotations(Rotation.from_quat(bodies.q0_body), bp).as_quat()  # principal -> world
    omega = bp.apply(bodies.omega0_body, inverse=True)
    alive = np.ones(n, dtype=bool)
    errors: dict[int, str] = {}

    def invariants(omega_p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        momentum = moments * omega_p
        return 0.5 * np.einsum("ij,ij->i", momentum, omega_p), row_norms(momentum)

    def time_of(step_end: int) -> float:
        """s: the time at the end of a full step (the duration itself at the last, with no shorter step after)."""
        return spec.duration if step_end == n_full and last == 0.0 else step_end * dt

    energy0, momentum0 = invariants(omega)
    track = CheckpointTrack(moments, omega)
    impulse = np.zeros(n)
    track.observe(0.0, omega)
    last_torque: tuple[Any, np.ndarray, np.ndarray] = (None, np.empty(0), np.empty(0))
    world_frame = any(stretch.world is not None for stretch in timeline)  # torques that depend on the state
    segments = [(int(a), int(b)) for a, b in zip(marks[:-1], marks[1:], strict=False) if b > a]
    if last > 0.0:
        segments.append((n_full, n_full + 1))  # the last, shorter step landing on the duration
    k = 0
    cut_until = 0  # segments before this one run one call each (a joined call failed there)
    max_joined = max(2, _RECORDED_BYTES // (3 * 8 * n))  # the recorded rates of a call stay small
    while k < len(segments) and alive.any():
        a, b = segments[k]
        t_a = a * dt
        partial = a == n_full
        step = last if partial else dt
        everyone = len(errors) == 0  # no body has failed yet: no subsets to copy
        live = slice(None) if everyone else alive
        attitude = (q[live], principal_from_body[live]) if world_frame else None
        live_bodies = bodies if everyone else _subset(bodies, alive)
        torque_body = _body_torque(spec, live_bodies, stretch_at(timeline, a), a, dt, attitude)
        # most segments of a run repeat the last one's torques (a torque-free run: all of them)
        key = (step, torque_body.tobytes()) if everyone else None
        if key is None or key != last_torque[0]:
            last_torque = (
                key,
                row_norms(torque_body) * step,
                _rows(frames.vector_to_principal, principal_from_body[live], torque_body),
            )
        _, impulse_rate, torque_p = last_torque
        # the following segments under the same torques join this one in a call that records the
        # checkpoints' rates (a return to Python at each costs ~5 % of a short run); their torques
        # do not depend on the state unless a schedule is in the world frame
        joined = [(a, b)]
        if key is not None and not world_frame and not partial and k >= cut_until:  # key: no body has failed
            joined = _same_torques(spec, bodies, timeline, segments[k : k + max_joined], dt, n_full, key)
        if len(joined) > 1:
            try:
                q, omega, omega_at = advance_batch_recording(
                    method, moments, q, omega, dt, [end - a for _, end in joined], torque_p, normalize_q=a == 0
                )
            except (NonFiniteStateError, ArithmeticError):
                cut_until = k + len(joined)  # run them one at a time: the failing bodies fail alone
                continue
            for (a_j, b_j), omega_j in zip(joined, omega_at, strict=True):
                impulse += impulse_rate * (b_j - a_j)
                if b_j in checkpoint_set:
                    track.observe(time_of(b_j), omega_j)
            k += len(joined)
            continue
        impulse[live] += impulse_rate * (b - a)
        # the first call normalises q as an integrator's set_state does; later ones continue from it
        q_new, omega_new, failed = _advance_isolated(
            method, moments[live], q[live], omega[live], step, b - a, torque_p, normalize_q=a == 0
        )
        if everyone:
            q, omega = q_new, omega_new  # fresh arrays: no copy back
        else:
            q[live], omega[live] = q_new, omega_new
        if failed:
            index = np.flatnonzero(alive)
            for i, message in failed.items():
                errors[int(index[i])] = f"{message} (segment from t = {t_a:.9g} s, dt = {step:.9g} s)"
                alive[index[i]] = False
        if b in checkpoint_set or partial:
            t_b = spec.duration if partial else time_of(b)
            track.observe(t_b, omega if not errors else np.where(alive[:, None], omega, np.nan))
        k += 1

    energy, momentum = invariants(omega)
    with np.errstate(divide="ignore", invalid="ignore"):
        energy_drift = np.abs(energy - energy0) / np.where(energy0 > 0, energy0, 1.0)
        momentum_drift = np.abs(momentum - momentum0) / np.where(momentum0 > 0, momentum0, 1.0)
    q_alive = np.where(alive[:, None], q, [0.0, 0.0, 0.0, 1.0])
    q_body = _rows(frames.attitude_from_principal, q_alive, principal_from_body)
    q_body[~alive] = np.nan
    omega_body = _rows(frames.vector_from_principal, bp.as_quat(canonical=False), np.where(alive[:, None], omega, 0.0))
    omega_body[~alive] = np.nan
    omega_bound = (momentum0 + impulse) / moments.min(axis=1)
    return _Outcome(
        q_body=q_body,
        omega_body=omega_body,
        errors=errors,
        max_omega=np.where(alive, track.max_omega, np.nan),
        energy_drift=energy_drift,
        momentum_drift=momentum_drift,
        omega_bound=omega_bound,
        first_flip=track.first_flip,
        nutation_range=np.where(alive, track.nutation_range(), np.nan),
    )


def _same_torques(
    spec: SweepSpec,
    bodies: _Bodies,
    timeline: tuple[Stretch, ...],
    segments: list[tuple[int, int]],
    dt: float,
    n_full: int,
    key: tuple[float, bytes],
) -> list[tuple[int, int]]:
    """The first of ``segments`` and those right after it whose torques are the first's (``key``: its step and
    torques' bytes), full steps only; the torques must not depend on the state (no world-frame schedule)."""
    joined = segments[:1]
    for a, b in segments[1:]:
        if a == n_full or (dt, _body_torque(spec, bodies, stretch_at(timeline, a), a, dt, None).tobytes()) != key:
            break
        joined.append((a, b))
    return joined


def _subset(bodies: _Bodies, mask: np.ndarray) -> _Bodies:
    """The bodies selected by ``mask``."""
    return _Bodies(**{f.name: getattr(bodies, f.name)[mask] for f in fields(_Bodies)})


def _concat(a: _Bodies, b: _Bodies) -> _Bodies:
    """The bodies of ``a``, then those of ``b``."""

    def join(x: Any, y: Any) -> Any:
        return Rotation.concatenate([x, y]) if isinstance(x, Rotation) else np.concatenate((x, y))

    return _Bodies(**{f.name: join(getattr(a, f.name), getattr(b, f.name)) for f in fields(_Bodies)})


def _split(outcome: _Outcome, n: int) -> tuple[_Outcome, _Outcome]:
    """The first n bodies' outcome and the rest's."""

    def part(select: slice, offset: int) -> _Outcome:
        return _Outcome(
            q_body=outcome.q_body[select],
            omega_body=outcome.omega_body[select],
            errors={i - offset: m for i, m in outcome.errors.items() if select.start <= i < (select.stop or 1 << 62)},
            max_omega=outcome.max_omega[select],
            energy_drift=outcome.energy_drift[select],
            momentum_drift=outcome.momentum_drift[select],
            omega_bound=outcome.omega_bound[select],
            first_flip=outcome.first_flip[select],
            nutation_range=outcome.nutation_range[select],
        )

    return part(slice(0, n), 0), part(slice(n, None), n)


def _torque_free(spec: SweepSpec) -> bool:
    schedules = any(any(s.torque) for sched in spec.scene.schedules for s in sched.segments)
    return not schedules and spec.dispersions.torque_noise_sigma is None


def run_nominal(spec: SweepSpec, spin_rate: float | None) -> _Outcome:
    """The undispersed run at ``spin_rate`` with the spec's ``nominal`` integrator.

    One task per spin rate when the spec names a nominal integrator; its result is passed
    to every chunk of that spin rate. Otherwise each chunk runs its nominal body itself.
    """
    if spec.nominal_method is None or spec.nominal_dt is None:
        raise ValueError("the spec names no nominal integrator: each chunk runs its nominal body")
    return _simulate(spec, _bodies(spec, spin_rate, None), spec.nominal_method, spec.nominal_dt)


def run_chunk(spec: SweepSpec, chunk: Chunk, nominal: _Outcome | None = None) -> dict[str, Any]:
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
        both = _simulate(spec, _concat(bodies, _bodies(spec, spin_rate, None)), method, dt)
        outcome, nominal = _split(both, n)
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


def choose_chunk_size(
    spec: SweepSpec, workers: int, target_seconds: float = 5.0, tasks_per_worker: int = 4
) -> tuple[int, dict[str, float]]:
    """Bodies per task from the measured step cost, and the figures it was chosen from.

    A batch step costs ``fixed + per_body * N``: the fixed part (Python and numpy call
    overhead) is paid once per batch, so the fewer and larger the batches the better,
    as long as every worker gets ``tasks_per_worker`` tasks (load balance, and little
    work lost when a worker dies) and no task runs longer than about ``target_seconds``.
    """
    fixed, per_body = measure_step_cost(spec.methods[0])
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
