"""The sensors of a run: the scene's models, their seed, and each sensor's sample sequence.

:class:`SensorSuite` holds what a sensor remembers between readings (the gyro's
Gauss-Markov bias and sample count, the star tracker's sample count, the magnetometer's sample count and
last reading, the field along the orbit it measures) and reads the state
snapshots it is given, one reading per call, in the order of the calls. The node calls
it for each ~/imu and ~/star_tracker message it publishes; resim calls it for each such
message in the recording, in file order, at the same steps: the same seed then gives
the same bits (:mod:`rigid_rot_sim.core.sensors`: the noise of sample k is a function of
(seed, sensor, k); the bias evolves by the sim times of the samples).
"""

from __future__ import annotations

import secrets

import numpy as np

from rigid_rot_sim.core import sensors as models
from rigid_rot_sim.core.geomagnetic import OrbitField
from rigid_rot_sim.run.observables import StateSnapshot
from rigid_rot_sim.scene.scene import Sensors

__all__ = ["SensorSuite"]


class SensorSuite:
    """The sensors a scene names, with noise from ``seed`` (None: the scene's, else drawn now)."""

    def __init__(self, sensors: Sensors, seed: int | None = None, field: OrbitField | None = None) -> None:
        if seed is None:
            seed = sensors.seed if sensors.seed is not None else secrets.randbits(64)
        self.seed = int(seed)
        self.gyro = sensors.gyro
        self.star_tracker = sensors.star_tracker
        self.gyro_state = models.GyroState()
        self.turn_on_bias = None if self.gyro is None else models.gyro_turn_on_bias(self.gyro, self.seed)
        self.star_tracker_index = 0
        self.magnetometer = sensors.magnetometer
        self.magnetometer_state = models.MagnetometerState()
        if self.magnetometer is not None and field is None:
            raise ValueError("sensors.magnetometer: the run has no field to measure (environment.magnetic_field)")
        self.field = field

    @property
    def names(self) -> list[str]:
        """The sensors built, for the start-up line."""
        named = (("gyro", self.gyro), ("star_tracker", self.star_tracker), ("magnetometer", self.magnetometer))
        return [name for name, model in named if model]

    def read_gyro(self, snapshot: StateSnapshot) -> np.ndarray:
        """The next gyro reading (rad/s, body axes) of the state ``snapshot``."""
        if self.gyro is None:
            raise ValueError("the scene has no sensors.gyro")
        assert self.turn_on_bias is not None  # drawn with the gyro
        reading, self.gyro_state = models.gyro_sample(
            self.gyro, self.seed, self.turn_on_bias, self.gyro_state, snapshot.angular_velocity_body, snapshot.t
        )
        return reading

    def read_star_tracker(self, snapshot: StateSnapshot) -> np.ndarray:
        """The next star tracker attitude (x, y, z, w; body -> world) of the state ``snapshot``."""
        if self.star_tracker is None:
            raise ValueError("the scene has no sensors.star_tracker")
        index, self.star_tracker_index = self.star_tracker_index, self.star_tracker_index + 1
        return models.star_tracker_sample(self.star_tracker, self.seed, index, snapshot.orientation)

    def read_magnetometer(self, snapshot: StateSnapshot) -> np.ndarray:
        """The next magnetometer reading (T, sensor axes) of the field at the state ``snapshot``."""
        if self.magnetometer is None or self.field is None:
            raise ValueError("the scene has no sensors.magnetometer")
        truth = self.field.body(snapshot.t, snapshot.orientation)
        reading, self.magnetometer_state = models.magnetometer_sample(
            self.magnetometer, self.seed, self.magnetometer_state, truth, snapshot.t
        )
        return reading
