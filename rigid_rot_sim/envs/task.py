"""The slew task's settings, its episode draws and the bodies it steps (one or many, the same code).

:class:`SlewTask` holds every argument of the environments (SI units); :func:`draw_episode`
draws an episode's inertia, target, initial attitude and rate (and its sensor-noise seed) from
the episode's generator, always in the same order; :class:`SlewBodies` holds N bodies and steps
them all at once on the compiled batch kernels (:func:`rigid_rot_sim.core.batch.advance_batch`,
or :func:`rigid_rot_sim.core.batch_gyrostat.advance_gyrostats` with wheels) and the compiled task
kernel (:func:`rigid_rot_sim.core.slew.slew_update`). The single environment is a
:class:`SlewBodies` of one, the vector environment one of N: a body has the same bits either way.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rigid_rot_sim.core import geomagnetic
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.core.batch import advance_batch
from rigid_rot_sim.core.batch_gyrostat import advance_gyrostats, hub_inverses
from rigid_rot_sim.core.sensors import (
    GyroModel,
    GyroState,
    StarTrackerModel,
    gyro_sample,
    gyro_turn_on_bias,
    star_tracker_sample,
)
from rigid_rot_sim.core.slew import slew_update
from rigid_rot_sim.core.steps import whole_steps
from rigid_rot_sim.core.wheels import WheelModel, wheel_model

__all__ = [
    "SlewTask",
    "ObservationSensors",
    "Episode",
    "draw_episode",
    "SlewBodies",
    "DEFAULT_SENSORS",
    "world_field",
    "FIELD_POINT",
]

#: Where the observed field is taken (``field_observation``): geodetic latitude and longitude (deg), height (m)
#: and decimal year, in the centred dipole of IGRF-14's degree-1 terms (docs/gym.md says why a fixed point).
FIELD_POINT = (0.0, 0.0, 500e3, 2026.0)

_SQRT3 = math.sqrt(3.0)


@dataclass(frozen=True)
class ObservationSensors:
    """The seeded sensors that replace the true state in the observation (models of :mod:`rigid_rot_sim.core.sensors`).

    Both are sampled once per control period (sample k at the end of period k, sample 0 at the
    reset), whatever their own ``rate``; the gyro's ``saturation`` (rad/s, > 0) bounds the rate
    observation.
    """

    gyro: GyroModel
    star_tracker: StarTrackerModel


#: A tactical-grade gyro and an arc-second-class star tracker.
DEFAULT_SENSORS = ObservationSensors(
    GyroModel(
        rate=10.0,
        angle_random_walk=5e-5,
        bias_instability=5e-6,
        turn_on_bias_sigma=1e-4,
        saturation=10.0,
    ),
    StarTrackerModel(rate=10.0, noise_equivalent_angle=(2e-5, 2e-5, 1e-4)),
)


@dataclass(frozen=True)
class SlewTask:
    """Every setting of a slew episode (SI units; frames: body = principal, quaternions x, y, z, w body -> world).

    Dynamics: ``control_period`` (s), a whole number of steps of ``dt`` (s): the rigid body's ``rk4`` (RKMK,
    :func:`~rigid_rot_sim.core.batch.advance_batch`) or, with wheels, the gyrostat's classical RK4;
    ``max_torque`` (N*m): the full-scale body torque per axis, or each wheel's motor torque.
    Dispersions, drawn per episode: principal moments ``principal_moments * (1 + d u)``, ``u``
    uniform in [-1, 1] per axis, ``d = inertia_dispersion``; a uniformly random target attitude;
    an initial attitude ``target (x) exp(angle axis)`` with a uniformly random axis and ``angle``
    uniform in [0, ``max_initial_error``] rad; initial rates uniform in ``[-max_initial_rate,
    max_initial_rate]`` rad/s per axis. Reward weights and the hold test: :mod:`rigid_rot_sim.core.slew`.
    ``max_episode_steps``: control periods before truncation. ``observation_horizon``: the
    episode length (control periods) the observation's rate bounds are sized for, so that the
    spaces never depend on the episode length (``max_episode_steps`` may not exceed it).
    Wheels (wheel environment only): three wheels on the body axes of spin inertia
    ``wheel_inertia`` (kg*m^2) and ``wheel_max_speed`` (rad/s), frictionless, starting at rest.
    ``field_observation``: the observation ends with the true magnetic field in the body axes (T), the
    constant world field :func:`world_field` seen at the true attitude (docs/gym.md).
    """

    control_period: float = 0.1
    dt: float = 0.01
    max_torque: float = 0.2
    principal_moments: tuple[float, float, float] = (0.8, 1.0, 1.2)
    inertia_dispersion: float = 0.1
    max_initial_error: float = math.pi
    max_initial_rate: float = 0.05
    w_attitude: float = 1.0
    w_rate: float = 0.1
    w_effort: float = 0.01
    angle_tolerance: float = 0.01
    rate_tolerance: float = 0.005
    hold_periods: int = 10
    max_episode_steps: int = 300
    observation_horizon: int = 300
    wheel_inertia: float = 0.005
    wheel_max_speed: float = 300.0
    field_observation: bool = False
    sensors: ObservationSensors | None = field(default=None)

    def __post_init__(self) -> None:
        for name in ("control_period", "dt", "max_torque", "wheel_inertia", "wheel_max_speed"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be finite and > 0, got {value!r}")
        for name in ("max_initial_rate", "w_attitude", "w_rate", "w_effort", "angle_tolerance", "rate_tolerance"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be finite and >= 0, got {value!r}")
        if not 0.0 <= self.max_initial_error <= math.pi:
            raise ValueError(f"max_initial_error must be in [0, pi] rad, got {self.max_initial_error!r}")
        if whole_steps(self.control_period, self.dt) is None:
            raise ValueError(f"control_period ({self.control_period} s) must be a whole number of dt ({self.dt} s)")
        for name in ("hold_periods", "max_episode_steps", "observation_horizon"):
            if int(getattr(self, name)) != getattr(self, name) or getattr(self, name) < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {getattr(self, name)!r}")
        if self.max_episode_steps > self.observation_horizon:
            raise ValueError(
                f"max_episode_steps ({self.max_episode_steps}) exceeds observation_horizon "
                f"({self.observation_horizon}), the episode length the observation bounds are sized for: "
                "pass observation_horizon >= max_episode_steps"
            )
        moments = np.asarray(self.principal_moments, dtype=float)
        if moments.shape != (3,) or not np.all(np.isfinite(moments) & (moments > 0.0)):
            raise ValueError(f"principal_moments must be three finite values > 0, got {self.principal_moments!r}")
        d = self.inertia_dispersion
        if not 0.0 <= d < 1.0:
            raise ValueError(f"inertia_dispersion must be in [0, 1), got {d!r}")
        low, high = np.sort(moments * (1.0 - d)), np.sort(moments * (1.0 + d))
        if low[0] + low[1] < high[2]:
            raise ValueError(
                "principal_moments with inertia_dispersion can break the triangle inequality (I1 + I2 >= I3) "
                "that every rigid body obeys: make the dispersion smaller"
            )
        if self.sensors is not None and not self.sensors.gyro.saturation > 0.0:
            raise ValueError("the sensors' gyro needs a saturation > 0 rad/s: it bounds the rate observation")
        if self.wheel_inertia >= low[0]:
            raise ValueError("wheel_inertia must be smaller than the smallest principal moment")
        if not isinstance(self.field_observation, bool):
            raise ValueError(f"field_observation must be True or False, got {self.field_observation!r}")

    @property
    def substeps(self) -> int:
        """Integrator steps per control period (checked whole in ``__post_init__``)."""
        steps = whole_steps(self.control_period, self.dt)
        assert steps is not None
        return steps

    @property
    def horizon(self) -> float:
        """The time (s) the observation bounds are sized for: ``observation_horizon`` periods (>= any episode)."""
        return self.observation_horizon * self.control_period

    def wheels(self) -> WheelModel:
        """Three frictionless wheels along the body (principal) axes."""
        nominal = np.diag(np.asarray(self.principal_moments, dtype=float) * (1.0 - self.inertia_dispersion))
        j, speed, torque = self.wheel_inertia, self.wheel_max_speed, self.max_torque
        return wheel_model(nominal, ("x", "y", "z"), np.eye(3), [j] * 3, [torque] * 3, [speed] * 3)

    def rate_bound(self, with_wheels: bool) -> float:
        """A bound (rad/s) on every rate component over :attr:`horizon`, from the momentum it can gain.

        Without wheels ``|H|`` grows by at most ``sqrt(3) max_torque`` per second from ``|H0| <=
        I_max sqrt(3) max_initial_rate``, and ``|omega| <= |H| / I_min``. With wheels the total
        momentum is constant and each wheel's axial momentum ``a_i = J (g_i . omega + Omega_i)``
        changes by its motor torque only: ``|omega| <= (|H0| + sum |a_i|) / (I_min - J)``.
        A 1 % margin covers the integrator's round-off.
        """
        moments = np.asarray(self.principal_moments, dtype=float)
        i_min = float(moments.min()) * (1.0 - self.inertia_dispersion)
        i_max = float(moments.max()) * (1.0 + self.inertia_dispersion)
        rate0 = _SQRT3 * self.max_initial_rate
        h0 = i_max * rate0
        if not with_wheels:
            return 1.01 * (h0 + _SQRT3 * self.max_torque * self.horizon) / i_min
        return 1.01 * (h0 + 3.0 * self._axial_bound()) / (i_min - self.wheel_inertia)

    def _axial_bound(self) -> float:
        return self.wheel_inertia * _SQRT3 * self.max_initial_rate + self.max_torque * self.horizon

    def wheel_speed_bound(self) -> float:
        """A bound (rad/s) on every wheel speed: ``|Omega_i| <= |a_i| / J + |omega|``."""
        return 1.01 * (self._axial_bound() / self.wheel_inertia + self.rate_bound(True))


@functools.lru_cache(maxsize=1)
def world_field() -> tuple[float, float, float]:
    """The field (T) in the environments' world axes, taken as north, east, down at :data:`FIELD_POINT`:
    IGRF-14's centred dipole there (:func:`rigid_rot_sim.core.geomagnetic.field_ned`), constant over an episode."""
    north, east, down = (float(v) * 1e-9 for v in geomagnetic.field_ned("dipole", *FIELD_POINT))
    return (north, east, down)


@dataclass(frozen=True)
class Episode:
    """One episode's draws: principal moments (3,) kg*m^2, target and initial attitude (4,),
    initial rate (3,) rad/s, and the seed of its sensor noise."""

    principal_moments: np.ndarray
    target: np.ndarray
    q0: np.ndarray
    omega0: np.ndarray
    sensor_seed: int

    def info(self) -> dict[str, Any]:
        """The reset ``info``: the episode's inertia (principal moments and the 3x3 tensor, body frame) and target."""
        return {
            "principal_moments": self.principal_moments.copy(),
            "inertia": np.diag(self.principal_moments),
            "target": self.target.copy(),
        }


def draw_episode(task: SlewTask, rng: np.random.Generator) -> Episode:
    """An episode's draws from ``rng``: ``u = rng.random(7)``, ``z = rng.normal(size=7)``, then the sensor seed.

    Moments ``principal_moments * (1 + d (2 u[0:3] - 1))``; target ``z[0:4] / |z[0:4]|`` (uniform on the
    rotations); axis ``z[4:7] / |z[4:7]|``, angle ``max_initial_error * u[3]``; rates
    ``max_initial_rate * (2 u[4:7] - 1)``; sensor seed ``rng.integers(0, 2**63)``. Three calls on the
    generator: an episode's draws cost ~10 us, which matters when thousands of slots restart.
    """
    u = rng.random(7).tolist()  # Python floats: the arithmetic below costs ~1 us instead of ~20 on numpy scalars
    z = rng.normal(size=7).tolist()
    sensor_seed = int(rng.integers(0, 2**63, dtype=np.int64))
    d = task.inertia_dispersion
    moments = [m * (1.0 + d * (2.0 * x - 1.0)) for m, x in zip(task.principal_moments, u[0:3], strict=True)]
    target = quat.normalize(z[0:4])
    ax, ay, az = z[4:7]
    scale = task.max_initial_error * u[3] / math.sqrt(ax * ax + ay * ay + az * az)
    q0 = quat.normalize(quat.multiply(target, quat.exp_rotation_vector((scale * ax, scale * ay, scale * az))))
    omega0 = [task.max_initial_rate * (2.0 * x - 1.0) for x in u[4:7]]
    return Episode(np.array(moments), np.array(target), np.array(q0), np.array(omega0), sensor_seed)


class SlewBodies:
    """N bodies on the slew task, stepped together (the state of the single and the vector environment).

    ``with_wheels``: the torque comes from three reaction wheels (the action: motor torques) instead
    of the body torque (the action: body torque). Observation columns: ``q`` (4), ``omega`` (3), the
    error rotation vector (3), with wheels the wheel speeds (3), and with ``field_observation`` the
    field in the body axes (3, T).
    """

    def __init__(self, task: SlewTask, n: int, with_wheels: bool) -> None:
        self.task = task
        self.n = n
        self.with_wheels = with_wheels
        self.wheel_model = task.wheels() if with_wheels else None
        self.moments = np.tile(np.asarray(task.principal_moments, dtype=float), (n, 1))
        self.q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
        self.omega = np.zeros((n, 3))
        self.speeds = np.zeros((n, 3))
        self.target = self.q.copy()
        self.hub_inverse = hub_inverses(self.moments, self.wheel_model) if self.wheel_model is not None else None
        self.hold = np.zeros(n, dtype=np.int64)
        self.steps = np.zeros(n, dtype=np.int64)
        self.field_world = world_field() if task.field_observation else None
        width = 10 + (3 if with_wheels else 0) + (3 if self.field_world is not None else 0)
        self.observation = np.zeros((n, width))
        self._weights = np.array([task.w_attitude, task.w_rate, task.w_effort])
        self._tolerances = np.array([task.angle_tolerance, task.rate_tolerance, float(task.hold_periods)])
        self._sensor_seed = [0] * n
        self._gyro_state = [GyroState()] * n
        self._gyro_bias = [np.zeros(3)] * n

    def reset(self, slots: Any, rngs: Sequence[np.random.Generator]) -> list[Episode]:
        """Start a new episode in each of ``slots`` from its generator in ``rngs``; returns the episodes.

        Their observations are in :attr:`observation`. The task kernel runs once for all the slots
        (a body's numbers do not depend on the others).
        """
        rows = np.asarray(slots, dtype=np.int64).reshape(-1)
        episodes = [draw_episode(self.task, rng) for rng in rngs]
        self.moments[rows] = [episode.principal_moments for episode in episodes]
        self.q[rows] = [episode.q0 for episode in episodes]
        self.omega[rows] = [episode.omega0 for episode in episodes]
        self.speeds[rows] = 0.0
        self.target[rows] = [episode.target for episode in episodes]
        self.hold[rows] = 0
        self.steps[rows] = 0
        if self.wheel_model is not None and self.hub_inverse is not None:
            self.hub_inverse[rows] = hub_inverses(self.moments[rows], self.wheel_model)
        if self.task.sensors is not None:
            for slot, episode in zip(rows.tolist(), episodes, strict=True):
                self._sensor_seed[slot] = episode.sensor_seed
                self._gyro_state[slot] = GyroState()
                self._gyro_bias[slot] = gyro_turn_on_bias(self.task.sensors.gyro, episode.sensor_seed)
        q_seen, omega_seen = self._observed(rows)
        scratch_hold = np.zeros(len(rows), dtype=np.int64)  # the reset is no control period: the hold stays 0
        self._update(rows, q_seen, omega_seen, np.zeros((len(rows), 3)), scratch_hold)
        return episodes

    def step(self, action: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One control period of every body under ``action`` (N, 3) in [-1, 1] (clipped there).

        Returns ``(reward, terminated, truncated)`` (N,); the observations are in :attr:`observation`.
        """
        action = np.asarray(action, dtype=float)
        if action.size != 3 * self.n:
            raise ValueError(f"the action must hold 3 values per body ({self.n}, 3), got shape {action.shape}")
        action = action.reshape(self.n, 3)
        if not np.all(np.isfinite(action)):
            raise ValueError(f"the action must be finite, got {action[~np.isfinite(action).all(axis=1)][0]}")
        action = np.clip(action, -1.0, 1.0)
        torque = action * self.task.max_torque
        task = self.task
        if self.wheel_model is None:
            self.q, self.omega = advance_batch(
                "rk4", self.moments, self.q, self.omega, task.dt, task.substeps, torque, normalize_q=False
            )
        else:
            self.q, self.omega, self.speeds = advance_gyrostats(
                self.moments,
                self.wheel_model,
                self.q,
                self.omega,
                self.speeds,
                torque,
                task.dt,
                task.substeps,
                hub_inverse=self.hub_inverse,
            )
        self.steps += 1
        rows = slice(None)
        q_seen, omega_seen = self._observed(rows)
        reward, terminated = self._update(rows, q_seen, omega_seen, action, self.hold)
        truncated = self.steps >= task.max_episode_steps  # also when it terminates there, as TimeLimit says
        return reward, terminated, truncated

    def _observed(self, rows: np.ndarray | slice) -> tuple[np.ndarray, np.ndarray]:
        """The attitude and rate the observation reports for ``rows``: the truth, or the sensors' readings."""
        sensors = self.task.sensors
        if sensors is None:
            return self.q[rows], self.omega[rows]
        bodies = np.arange(self.n)[rows]
        q_seen = np.empty((len(bodies), 4))
        omega_seen = np.empty((len(bodies), 3))
        for j, b in enumerate(bodies):  # per body: the noise of each comes from its own seed
            seed = self._sensor_seed[b]
            t = float(self.steps[b]) * self.task.control_period
            omega_seen[j], self._gyro_state[b] = gyro_sample(
                sensors.gyro, seed, self._gyro_bias[b], self._gyro_state[b], self.omega[b], t
            )
            q_seen[j] = star_tracker_sample(sensors.star_tracker, seed, int(self.steps[b]), self.q[b])
        return q_seen, omega_seen

    def _update(
        self, rows: np.ndarray | slice, q_seen: np.ndarray, omega_seen: np.ndarray, action: np.ndarray, hold: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The task kernel on ``rows``: observations into :attr:`observation`; returns (reward, terminated)."""
        count = q_seen.shape[0]
        observation = np.empty((count, 10))
        reward = np.empty(count)
        terminated = slew_update(
            np.ascontiguousarray(q_seen),
            np.ascontiguousarray(omega_seen),
            np.ascontiguousarray(self.q[rows]),
            np.ascontiguousarray(self.omega[rows]),
            np.ascontiguousarray(self.target[rows]),
            np.ascontiguousarray(action),
            self._weights,
            self._tolerances,
            hold,
            observation,
            reward,
            self.task.sensors is None,
        )
        self.observation[rows, :10] = observation
        if self.with_wheels:
            self.observation[rows, 10:13] = self.speeds[rows]
        if self.field_world is not None:  # the true field at the true attitude: R(q)^T B_world
            self.observation[rows, -3:] = np.column_stack(quat.rotate_inverse(self.q[rows].T, self.field_world))
        return reward, terminated
