"""The fit: an equation-error start, an output-error refinement, the covariance and its verdicts.

1. **Equation error** (no differentiated noise): over short windows ``[a, b]`` Euler's
   equations integrated in time are linear in the tensor and the torque bias::

       J (w(b) - w(a)) + int_a^b w x (J w) dt = int_a^b tau dt + tau_b (b - a)

   with the measured ``w`` (trapezoid rule) and the torque integrated exactly. A linear least
   squares gives the starting tensor (moved into the physical set if noise left it outside).
2. **Output error**: the window is cut into segments (``segment`` s each), each re-simulated
   from its own initial angular velocity by :func:`rigid_rot_sim.core.sensitivities.integrate_segments`;
   the residuals ``w_model + gyro_bias - w_measured``, weighted per axis by the noise measured in
   them, are minimised over (tensor, torque bias, gyro bias, initial rates) by
   ``scipy.optimize.least_squares`` with the exact Jacobian (forward sensitivities).
3. **Covariance** (Gauss-Newton / Cramer-Rao for white gyro noise): ``(J_r^T J_r)^-1`` of the
   weighted residual Jacobian at the optimum, the weights being the measured per-axis noise.
   The information matrix with its columns normalised shows what the data cannot tell apart:
   a direction with a relative singular value below :data:`UNOBSERVABLE` is reported with the
   parameters in it.

Without torque in the window the scale of the tensor is unobservable (``J`` and ``c J`` give
the same motion): the tensor is fitted with unit trace and reported as ``identifiable="ratios"``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from rigid_rot_sim.core.sensitivities import integrate_segments
from rigid_rot_sim.identify.data import Measurements

#: Names of the tensor's six values, the order of the covariance matrices.
INERTIA_NAMES = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
#: What can be estimated besides the tensor.
ESTIMATES = ("inertia", "torque_bias", "gyro_bias")
#: A direction of the normalised information matrix with a singular value below this fraction
#: of the largest is not determined by the data.
UNOBSERVABLE = 1e-6
#: The residual of a model that could not be integrated (a trial step the fit then rejects).
_FAILED = 1e150
#: Fewer samples than this in the window is an error.
MIN_SAMPLES = 20


def _unit(i: int, j: int) -> np.ndarray:
    e = np.zeros((3, 3))
    e[i, j] = e[j, i] = 1.0
    return e


@dataclass(frozen=True)
class Basis:
    """``J = J0 + sum_i theta_i E[i]``, and the map ``values = M theta + v0`` to the six values."""

    J0: np.ndarray
    E: np.ndarray
    M: np.ndarray
    v0: np.ndarray

    @classmethod
    def full(cls) -> Basis:
        """The six values themselves."""
        return cls(np.zeros((3, 3)), np.array([_unit(i, j) for i, j in _PAIRS]), np.eye(6), np.zeros(6))

    @classmethod
    def unit_trace(cls) -> Basis:
        """Five values with ``Izz = 1 - Ixx - Iyy``."""
        E = [_unit(0, 0) - _unit(2, 2), _unit(1, 1) - _unit(2, 2), _unit(0, 1), _unit(0, 2), _unit(1, 2)]
        M = np.zeros((6, 5))
        M[0, 0] = M[1, 1] = M[3, 2] = M[4, 3] = M[5, 4] = 1.0
        M[2, 0] = M[2, 1] = -1.0
        v0 = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0])
        return cls(np.diag([0.0, 0.0, 1.0]), np.array(E), M, v0)

    def tensor(self, theta: np.ndarray) -> np.ndarray:
        return self.J0 + np.tensordot(theta, self.E, axes=1)

    def theta(self, tensor: np.ndarray) -> np.ndarray:
        """The parameters of a tensor (least squares; exact when the tensor is in the family)."""
        values = np.array([tensor[i, j] for i, j in _PAIRS]) - self.v0
        return np.linalg.lstsq(self.M, values, rcond=None)[0]


@dataclass(frozen=True)
class Identification:
    """The identified model and how sure it is. SI units, body frame of the measurements.

    :param inertia: (3, 3) kg*m^2 (unit trace, dimensionless, when ``identifiable == "ratios"``).
    :param inertia_sigma: (3, 3) one sigma of each entry, same unit.
    :param inertia_covariance: (6, 6) covariance of (Ixx, Iyy, Izz, Ixy, Ixz, Iyz).
    :param principal_moments: (3,) ascending; ``principal_moments_sigma``: (3,) first-order sigma.
    :param principal_axes: (3, 3) columns: the axes of ``principal_moments``, body frame.
    :param identifiable: ``"full"`` or ``"ratios"`` (no torque in the window: scale unknown).
    :param torque_bias: (3,) N*m body frame (per unit trace for ratios), or None when not estimated.
    :param gyro_bias: (3,) rad/s, or None. ``*_sigma``: their one sigma.
    :param residual_rms: rad/s, RMS over all axes of ``w_model + gyro_bias - w_measured``.
    :param noise_sigma: (3,) rad/s, the per-axis residual deviation used as the noise.
    :param unobservable: what the data cannot determine, one sentence each (empty: all of it).
    :param warnings: anything else the user should know (not positive definite, ...).
    :param start_inertia: the equation-error tensor the refinement started from.
    :param segment_starts: (S,) s, first sample time of each output-error segment;
        ``segment_omega0``: (S, 3) rad/s, the fitted true rate there.
    """

    inertia: np.ndarray
    inertia_sigma: np.ndarray
    inertia_covariance: np.ndarray
    principal_moments: np.ndarray
    principal_moments_sigma: np.ndarray
    principal_axes: np.ndarray
    identifiable: str
    torque_bias: np.ndarray | None
    torque_bias_sigma: np.ndarray | None
    gyro_bias: np.ndarray | None
    gyro_bias_sigma: np.ndarray | None
    residual_rms: float
    noise_sigma: np.ndarray
    unobservable: tuple[str, ...]
    warnings: tuple[str, ...]
    start_inertia: np.ndarray
    segment_starts: np.ndarray
    segment_omega0: np.ndarray
    n_samples: int
    iterations: int
    extra: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Grid:
    """The integration grid of a window: samples, torque changes and sub-steps."""

    node_t: np.ndarray
    node_torque: np.ndarray
    node_sample: np.ndarray
    segment_nodes: np.ndarray
    segment_samples: np.ndarray


def build_grid(measurements: Measurements, segment: float, max_step: float) -> Grid:
    """Nodes at every sample and torque change, steps no longer than ``max_step`` (s)."""
    t = measurements.t
    changes = measurements.torque.times
    nodes = np.union1d(t, changes[(changes > t[0]) & (changes < t[-1])])
    gaps = np.diff(nodes)
    pieces = np.maximum(1, np.ceil(gaps / max_step - 1e-9).astype(np.int64))
    if np.any(pieces > 1):
        fine = [np.linspace(a, b, p, endpoint=False) for a, b, p in zip(nodes[:-1], nodes[1:], pieces, strict=True)]
        nodes = np.append(np.concatenate(fine), nodes[-1])
    node_sample = np.full(nodes.shape[0], -1, dtype=np.int64)
    at = np.searchsorted(nodes, t)
    node_sample[at] = np.arange(t.shape[0])
    n_segments = max(1, int(round((t[-1] - t[0]) / segment)))
    segment_samples = np.unique(np.searchsorted(t, t[0] + (t[-1] - t[0]) * np.arange(n_segments) / n_segments))
    segment_nodes = np.append(at[segment_samples], nodes.shape[0]).astype(np.int64)
    return Grid(nodes, measurements.torque.at(nodes), node_sample, segment_nodes, segment_samples)


def equation_error(
    measurements: Measurements, basis: Basis, torque_bias: bool, window: float = 1.0
) -> tuple[np.ndarray, np.ndarray]:
    """The starting tensor and torque bias from the integrated equations over windows of ``window`` s.

    Long windows (at least 20 samples) keep the noise of the rate differences small against the
    change of rate they measure, which a least squares with noise in its regressors needs.
    """
    t, w = measurements.t, measurements.omega
    n = t.shape[0]
    window = max(20, int(round(window / max(float(np.median(np.diff(t))), 1e-300))))
    edges = np.arange(0, n, window)
    if edges[-1] != n - 1:
        edges = np.append(edges, n - 1)
    k = basis.E.shape[0]
    # trapezoid integral of w x (E w) for every basis matrix, cumulative over the samples
    dt = np.diff(t)[:, None]

    def cumulative(matrix: np.ndarray) -> np.ndarray:
        g = np.cross(w, w @ matrix.T)
        return np.concatenate([np.zeros((1, 3)), np.cumsum(0.5 * dt * (g[1:] + g[:-1]), axis=0)])

    a, b = edges[:-1], edges[1:]
    columns = []
    for i in range(k):
        c = cumulative(basis.E[i])
        columns.append((w[b] - w[a]) @ basis.E[i].T + c[b] - c[a])
    c0 = cumulative(basis.J0)
    tau = measurements.torque.integral(t)
    rhs = (tau[b] - tau[a]) - ((w[b] - w[a]) @ basis.J0.T + c0[b] - c0[a])
    A = np.stack(columns, axis=-1)  # (windows, 3, k)
    if torque_bias:
        A = np.concatenate([A, -(t[b] - t[a])[:, None, None] * np.eye(3)[None]], axis=-1)
    solution = np.linalg.lstsq(A.reshape(-1, A.shape[-1]), rhs.reshape(-1), rcond=None)[0]
    tensor = _physical(basis.tensor(solution[:k]))
    return tensor, (solution[k:] if torque_bias else np.zeros(3))


def _physical(tensor: np.ndarray) -> np.ndarray:
    """The nearest tensor (same axes) with positive moments that keep the triangle inequality.

    Noise, or data that say nothing about an axis, can leave the equation-error tensor outside
    the physical set; a start there may not even be integrable (a body with two tiny moments spins
    up about them exponentially), so the moments are moved in before the output-error fit.
    """
    values, vectors = np.linalg.eigh(0.5 * (tensor + tensor.T))
    largest = max(float(abs(values).max()), 1e-300)
    values = np.maximum(values, 1e-3 * largest)
    if values[0] + values[1] < values[2]:
        values[:2] = np.maximum(values[:2], 0.55 * values[2])
    return (vectors * values) @ vectors.T


class _Problem:
    """Residuals and their Jacobian for ``least_squares``, the simulation shared between the two."""

    def __init__(self, m: Measurements, grid: Grid, basis: Basis, est_tau: bool, est_gyro: bool) -> None:
        self.m, self.grid, self.basis = m, grid, basis
        self.k = basis.E.shape[0]
        self.est_tau, self.est_gyro = est_tau, est_gyro
        self.n_seg = grid.segment_samples.shape[0]
        self.n_par = self.k + 3 * est_tau + 3 * est_gyro + 3 * self.n_seg
        self.weights = np.ones(3)
        self.seg_of_sample = np.searchsorted(grid.segment_samples, np.arange(m.t.shape[0]), side="right") - 1
        self._key: bytes | None = None
        self._has_sens = False
        self._omega = self._sens = np.zeros(0)

    def split(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        k, i = self.k, self.k
        tau_b = x[i : i + 3] if self.est_tau else np.zeros(3)
        i += 3 * self.est_tau
        gyro_b = x[i : i + 3] if self.est_gyro else np.zeros(3)
        i += 3 * self.est_gyro
        return x[:k], tau_b, gyro_b, x[i:].reshape(self.n_seg, 3)

    def _simulate(self, x: np.ndarray, with_sens: bool) -> None:
        key = x.tobytes()
        if key == self._key and (self._has_sens or not with_sens):
            return
        theta, tau_b, _, omega0 = self.split(x)
        g = self.grid
        q0 = np.tile([0.0, 0.0, 0.0, 1.0], (self.n_seg, 1))
        self._omega, self._sens, _ = integrate_segments(
            g.node_t, g.node_torque, g.node_sample, g.segment_nodes, self.basis.tensor(theta),
            self.basis.E, tau_b, omega0, q0, self.m.t.shape[0], with_sens,
        )  # fmt: skip
        self._key, self._has_sens = key, with_sens

    def residuals(self, x: np.ndarray) -> np.ndarray:
        try:
            self._simulate(x, with_sens=False)
        except (ZeroDivisionError, np.linalg.LinAlgError):
            return np.full(3 * self.m.t.shape[0], _FAILED)
        gyro_b = self.split(x)[2]
        r = (self._omega + gyro_b - self.m.omega) * self.weights
        return np.where(np.isfinite(r), r, _FAILED).reshape(-1)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        self._simulate(x, with_sens=True)
        n, k = self.m.t.shape[0], self.k
        jac = np.zeros((n, 3, self.n_par))
        jac[:, :, :k] = self._sens[:, :, :k]
        col = k
        if self.est_tau:
            jac[:, :, col : col + 3] = self._sens[:, :, k : k + 3]
            col += 3
        if self.est_gyro:
            jac[:, :, col : col + 3] = np.eye(3)
            col += 3
        rows = np.arange(n)
        for j in range(3):
            jac[rows, :, col + 3 * self.seg_of_sample + j] = self._sens[:, :, k + 3 + j]
        jac *= self.weights[None, :, None]
        jac[~np.isfinite(jac)] = 0.0
        return jac.reshape(3 * n, self.n_par)


def identify(
    measurements: Measurements,
    estimate: Sequence[str] = ("inertia",),
    segment: float = 10.0,
    max_step: float = 0.005,
) -> Identification:
    """Identify the inertia tensor (and optionally a torque bias and a gyro bias) from one window.

    :param measurements: gyro readings and the body-frame torque (:class:`Measurements`).
    :param estimate: any of :data:`ESTIMATES`; ``"inertia"`` is always estimated.
    :param segment: s, length of the output-error segments (each restarts from a fitted rate).
    :param max_step: s, the longest integration step.
    :raises ValueError: too few samples, an unknown estimate, a non-positive ``segment``/``max_step``.
    """
    unknown = sorted(set(estimate) - set(ESTIMATES))
    if unknown:
        raise ValueError(f"estimate: unknown {', '.join(unknown)} (choose from {', '.join(ESTIMATES)})")
    if not (segment > 0.0 and max_step > 0.0):
        raise ValueError("segment and max_step must be > 0 s")
    n = measurements.t.shape[0]
    if n < MIN_SAMPLES:
        raise ValueError(f"the window holds {n} samples; at least {MIN_SAMPLES} are needed")
    est_tau, est_gyro = "torque_bias" in estimate, "gyro_bias" in estimate
    ratios = not measurements.has_torque()
    basis = Basis.unit_trace() if ratios else Basis.full()
    grid = build_grid(measurements, segment, max_step)
    start, tau0 = equation_error(measurements, basis, est_tau)
    if ratios:
        start = start / np.trace(start)
    problem = _Problem(measurements, grid, basis, est_tau, est_gyro)
    x0 = np.concatenate(
        [basis.theta(start), tau0 if est_tau else [], np.zeros(3) if est_gyro else []]
        + [measurements.omega[grid.segment_samples].reshape(-1)]
    )
    nfev = 0
    x = x0
    for _ in range(3):  # refit with the per-axis noise found in the residuals of the last fit
        fit = least_squares(problem.residuals, x, jac=problem.jacobian, method="lm", xtol=1e-12, ftol=1e-12)
        x, nfev = fit.x, nfev + fit.nfev
        if not np.isfinite(fit.cost) or np.max(np.abs(fit.fun)) >= _FAILED:
            raise ValueError(
                "the output-error fit found no model that can be integrated over the window "
                "(check the torque topics and frames, or try a shorter --segment)"
            )
        raw = fit.fun.reshape(-1, 3) / problem.weights
        dof = max(n - problem.n_par / 3.0, 1.0)
        sigma = np.sqrt(np.sum(raw**2, axis=0) / dof)
        # noise-free data (or an axis that never moves) leaves no noise to measure: a floor far below any gyro's
        sigma = np.maximum(sigma, 1e-12 * max(float(np.sqrt(np.mean(measurements.omega**2))), 1e-300))
        converged = np.allclose(1.0 / sigma, problem.weights, rtol=0.2)
        problem.weights = 1.0 / sigma
        if converged:
            break
    return _result(problem, x, start, ratios, raw, sigma, nfev)


def _result(
    problem: _Problem,
    x: np.ndarray,
    start: np.ndarray,
    ratios: bool,
    raw: np.ndarray,
    sigma: np.ndarray,
    nfev: int,
) -> Identification:
    basis, k = problem.basis, problem.k
    jac = problem.jacobian(x)
    scale = _parameter_scales(problem, basis.tensor(x[:k]))
    normalised = jac * scale
    information = normalised.T @ normalised  # eigenvalues: the squared singular values of ``normalised``
    eigenvalues, eigenvectors = np.linalg.eigh(information)
    singular = np.sqrt(np.maximum(eigenvalues, 0.0))
    names = _parameter_names(problem)
    weak = singular < UNOBSERVABLE * singular[-1]
    cov = np.linalg.pinv(information, hermitian=True) * np.outer(scale, scale)
    theta, tau_b, gyro_b, omega0 = problem.split(x)
    tensor = basis.tensor(theta)
    cov6 = basis.M @ cov[:k, :k] @ basis.M.T
    sigma6 = np.sqrt(np.maximum(np.diag(cov6), 0.0))
    inertia_sigma = np.zeros((3, 3))
    for value, (i, j) in zip(sigma6, _PAIRS, strict=True):
        inertia_sigma[i, j] = inertia_sigma[j, i] = value
    moments, axes = np.linalg.eigh(tensor)
    # d lambda / d (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) = (vx^2, vy^2, vz^2, 2 vx vy, 2 vx vz, 2 vy vz)
    grad = np.array([[v[i] * v[j] * (1.0 if i == j else 2.0) for i, j in _PAIRS] for v in axes.T])
    moments_sigma = np.sqrt(np.maximum(np.einsum("ai,ij,aj->a", grad, cov6, grad), 0.0))
    i = k
    tau_sigma = gyro_sigma = None
    if problem.est_tau:
        tau_sigma = np.sqrt(np.diag(cov)[i : i + 3])
        i += 3
    if problem.est_gyro:
        gyro_sigma = np.sqrt(np.diag(cov)[i : i + 3])
    unobservable = _unobservable(eigenvectors[:, weak], names, problem.m)
    warnings = []
    if ratios:
        warnings.append("no torque in the window: the scale of the inertia is unobservable; reported with unit trace")
    floor = _noise_floor(problem.m.omega)
    if np.any(sigma > 3.0 * floor + 1e-12 * np.abs(problem.m.omega).max()):
        warnings.append(
            f"the fit stays above the noise floor (residual per axis {', '.join(f'{v:.3g}' for v in sigma)} rad/s, "
            f"the readings' own noise about {', '.join(f'{v:.3g}' for v in floor)}): unmodelled torque, a wrong "
            "torque frame or time offset, or a local minimum (try a shorter --segment)"
        )
    if moments[0] <= 0.0 or moments[2] > moments[0] + moments[1] * (1 + 1e-9):
        warnings.append(f"the identified tensor is not physical (principal moments {moments.tolist()})")
    return Identification(
        inertia=tensor,
        inertia_sigma=inertia_sigma,
        inertia_covariance=cov6,
        principal_moments=moments,
        principal_moments_sigma=moments_sigma,
        principal_axes=axes,
        identifiable="ratios" if ratios else "full",
        torque_bias=tau_b.copy() if problem.est_tau else None,
        torque_bias_sigma=tau_sigma,
        gyro_bias=gyro_b.copy() if problem.est_gyro else None,
        gyro_bias_sigma=gyro_sigma,
        residual_rms=float(np.sqrt(np.mean(raw**2))),
        noise_sigma=sigma,
        unobservable=tuple(unobservable),
        warnings=tuple(warnings),
        start_inertia=start,
        segment_starts=problem.m.t[problem.grid.segment_samples],
        segment_omega0=omega0.copy(),
        n_samples=problem.m.t.shape[0],
        iterations=nfev,
    )


def _noise_floor(omega: np.ndarray) -> np.ndarray:
    """Per-axis white noise of the readings from their second differences (rad/s; an upper bound for rough signals)."""
    if omega.shape[0] < 3:
        return np.full(3, np.inf)
    second = omega[2:] - 2.0 * omega[1:-1] + omega[:-2]
    return np.sqrt(np.mean(second**2, axis=0) / 6.0)


def _parameter_scales(problem: _Problem, tensor: np.ndarray) -> np.ndarray:
    """Each parameter's physical size, so that the information matrix compares like with like.

    Inertia: a third of the trace; rates (gyro bias, initial rates): the RMS measured rate; torque
    bias: the larger of the commanded torque and the gyroscopic torque ``J w^2``. A direction is
    unobservable when moving the parameters by their sizes along it changes the weighted readings
    by less than :data:`UNOBSERVABLE` of the best determined direction.
    """
    inertia = float(np.trace(tensor)) / 3.0
    rate = max(float(np.sqrt(np.mean(np.sum(problem.m.omega**2, axis=1)))), 1e-300)
    torque = max(inertia * rate**2, float(np.abs(problem.m.torque.values).max(initial=0.0)), 1e-300)
    scales = [inertia] * problem.k + [torque] * (3 * problem.est_tau) + [rate] * (3 * problem.est_gyro)
    return np.array(scales + [rate] * (3 * problem.n_seg))


def _parameter_names(problem: _Problem) -> list[str]:
    inertia = ["Ixx-Izz", "Iyy-Izz", "Ixy", "Ixz", "Iyz"] if problem.k == 5 else list(INERTIA_NAMES)
    names = inertia
    if problem.est_tau:
        names += ["torque_bias.x", "torque_bias.y", "torque_bias.z"]
    if problem.est_gyro:
        names += ["gyro_bias.x", "gyro_bias.y", "gyro_bias.z"]
    for s in range(problem.n_seg):
        names += [f"omega0[{s}].{axis}" for axis in "xyz"]
    return names


def _unobservable(directions: np.ndarray, names: list[str], m: Measurements) -> list[str]:
    """One sentence naming the parameters the null directions mix, and what in the data leaves them free."""
    if directions.shape[1] == 0:
        return []
    weight = np.sqrt(np.sum(directions**2, axis=1))
    involved = [names[i] for i in range(len(names)) if weight[i] > 0.2]
    singular = np.linalg.svd(m.omega, compute_uv=False)
    axes = int(np.sum(singular > 1e-3 * singular[0])) if singular[0] > 0.0 else 0
    if axes < 3:
        why = f"the body turned about {axes} independent axis{'es' if axes != 1 else ''} only"
    else:
        why = "the excitation changes no reading along these combinations"
    count = directions.shape[1]
    return [f"not observable: {', '.join(involved)} ({count} direction{'s' if count > 1 else ''}; {why})"]
