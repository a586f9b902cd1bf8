"""What the node publishes: one table of outputs, one publishing path.

:data:`OUTPUTS` maps each scene output name (``scene.scene.OUTPUT_NAMES``) to its message
type and the function that builds its message from a
:class:`~rigid_rot_sim.run.simulator.StateSnapshot`; :data:`SENSOR_OUTPUTS` the outputs that
carry a sensor's reading instead (``~/imu`` with a gyro, ``~/star_tracker``), drawn from the
run's :class:`~rigid_rot_sim.run.sensors.SensorSuite` once per message. :class:`Outputs` creates a publisher
for each output the scene asks for (rate > 0), plus ``~/mass_properties`` (latched, once),
``~/rejected`` and ``/tf_static`` (the principal-axes frame, where it differs from the body
frame), all in :attr:`Outputs.publishers`, keyed on those names.

:meth:`Outputs.publish` is the only way a message leaves the node: with no listener it
publishes the message; with listeners (the recorder) it serialises the message once, hands
the bytes to every listener, then publishes the same bytes. The run driver tells
:meth:`Outputs.outputs_due` (a :class:`~rigid_rot_sim.run.observer.SimulationObserver`)
which outputs are due at a step.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, Protocol

import numpy as np
from geometry_msgs.msg import InertiaStamped, PoseWithCovarianceStamped, QuaternionStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import QoSProfile
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu, JointState, MagneticField
from tf2_msgs.msg import TFMessage  # built into the venv by `make setup` (vendored), a ROS dependency
from visualization_msgs.msg import MarkerArray

from rigid_rot_msgs.msg import HeavyTopState, RejectedCommand, RigidBodyState, TorqueBreakdown
from rigid_rot_sim import conversions
from rigid_rot_sim.core.inertia import principal_frame_pose
from rigid_rot_sim.core.orbit import days_since_j2000, earth_rotation_angle
from rigid_rot_sim.ros.qos import CLOCK_QOS, LATCHED_QOS, REJECTED_QOS, TF_QOS, TF_STATIC_QOS
from rigid_rot_sim.ros.qos import describe as describe_qos
from rigid_rot_sim.run.body_view import BodyView, body_view
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.run.sensors import SensorSuite
from rigid_rot_sim.run.simulator import StateSnapshot
from rigid_rot_sim.scene.orbit import epoch_datetime
from rigid_rot_sim.scene.scene import OUTPUT_NAMES, Frames, Scene

#: A message from the state and the outputs' settings (frames, ground-truth variance, body view).
MessageBuilder = Callable[[StateSnapshot, "Outputs"], Any]

#: Scene output name -> (message type, builder). Topics: :func:`output_topic`.
OUTPUTS: dict[str, tuple[Any, MessageBuilder | None]] = {
    "state": (RigidBodyState, lambda s, o: conversions.snapshot_to_state(s, o.frames.world, o.frames.body)),
    "orientation": (QuaternionStamped, lambda s, o: conversions.snapshot_to_orientation(s, o.frames.world)),
    "angular_velocity": (
        Vector3Stamped,
        lambda s, o: conversions.vector_stamped(s.angular_velocity_body, s.t, o.frames.body),
    ),
    "angular_momentum": (
        Vector3Stamped,
        lambda s, o: conversions.vector_stamped(s.angular_momentum_world, s.t, o.frames.world),
    ),
    "top_state": (HeavyTopState, lambda s, o: conversions.snapshot_to_top_state(s, o.frames.world)),
    "tf": (TFMessage, lambda s, o: TFMessage(transforms=o.transforms(s))),
    "clock": (Clock, lambda s, o: conversions.clock_message(s.t)),
    "imu": (Imu, lambda s, o: conversions.snapshot_to_imu(s, o.frames.body, o.ground_truth_variance)),
    "odom": (
        Odometry,
        lambda s, o: conversions.snapshot_to_odometry(s, o.frames.world, o.frames.body, o.ground_truth_variance),
    ),
    "markers": (MarkerArray, lambda s, o: conversions.body_markers(o.body_view, s, o.frames.world, o.frames.body)),
    "star_tracker": (PoseWithCovarianceStamped, None),  # a sensor's reading: SENSOR_OUTPUTS
    "wheels": (JointState, lambda s, o: conversions.snapshot_to_joint_state(s, o.frames.body)),
    "magnetometer": (MagneticField, None),  # a sensor's reading: SENSOR_OUTPUTS
    "magnetic_field": (MagneticField, lambda s, o: o.true_field(s)),
    "orbit": (Odometry, lambda s, o: conversions.orbit_odometry(s, *o.orbit_state(s.t), o.frames.world, o.frames.body)),
    "torque_breakdown": (TorqueBreakdown, lambda s, o: conversions.snapshot_to_torque_breakdown(s, o.frames.body)),
}
assert tuple(OUTPUTS) == OUTPUT_NAMES, "one entry per scene output, in the scene's order"

#: The outputs published at the step rate in a typical run, refilled in place instead of built anew
#: (builder's twin: every field written, so the bytes are those of a fresh message; rclpy serialises
#: at publish and no listener keeps the message): output name -> filler.
REFILLED: dict[str, Callable[[Any, StateSnapshot, Outputs], Any]] = {
    "state": lambda m, s, o: conversions.fill_rigid_body_state(m, s, o.frames.world, o.frames.body),
    "angular_velocity": lambda m, s, o: conversions.fill_vector_stamped(m, s.angular_velocity_body, s.t, o.frames.body),
    "angular_momentum": lambda m, s, o: conversions.fill_vector_stamped(
        m, s.angular_momentum_world, s.t, o.frames.world
    ),
}

#: A sensor reading's message from the sensors, the state, the frames and the ground-truth variance.
SensorBuilder = Callable[[SensorSuite, StateSnapshot, Frames, float], Any]


#: Outputs that carry a sensor's reading when the scene has that sensor (``~/imu``: the gyro's,
#: instead of the ideal rate): output name -> (sensor, builder). Each message is one reading.
def _gyro_reading(sensors: SensorSuite, s: StateSnapshot, f: Frames, v: float) -> Any:
    assert sensors.gyro is not None  # built only when the scene has the gyro
    return conversions.gyro_to_imu(sensors.read_gyro(s), s.t, f.body, sensors.gyro.reading_variance or v)


def _star_tracker_reading(sensors: SensorSuite, s: StateSnapshot, f: Frames, v: float) -> Any:
    assert sensors.star_tracker is not None  # built only when the scene has the star tracker
    return conversions.star_tracker_pose(sensors.read_star_tracker(s), s.t, f.world, sensors.star_tracker.covariance)


def _magnetometer_reading(sensors: SensorSuite, s: StateSnapshot, f: Frames, v: float) -> Any:
    assert sensors.magnetometer is not None  # built only when the scene has the magnetometer
    return conversions.magnetic_field_message(
        sensors.read_magnetometer(s), s.t, f.body, sensors.magnetometer.covariance
    )


SENSOR_OUTPUTS: dict[str, tuple[str, SensorBuilder]] = {
    "imu": ("gyro", _gyro_reading),
    "star_tracker": ("star_tracker", _star_tracker_reading),
    "magnetometer": ("magnetometer", _magnetometer_reading),
}

#: The REP 105 name of the Earth-fixed frame (ECEF) that /tf hangs under the world (ECI) of a scene with an orbit.
EARTH_FRAME = "earth"


def output_topic(name: str) -> str:
    """The topic of output ``name``: ``/tf``, ``/clock``, else ``~/<name>``."""
    return {"tf": "/tf", "clock": "/clock"}.get(name, f"~/{name}")


class PublishedListener(Protocol):
    """Receives every message the node publishes, serialised once (the recorder)."""

    def published(self, name: str, topic: str, data: bytes, msg: Any) -> None:
        """``msg`` was published on ``topic`` (output ``name``) as the CDR bytes ``data``."""


class Outputs(SimulationObserver):
    """The node's publishers, keyed on output name, and the one path that publishes to them.

    ``rates`` (Hz of sim time) says which outputs to build (rate > 0); :attr:`rates` keeps
    those built. ``state_qos``: the profile of the state-like outputs.
    """

    # declared here: the builders of OUTPUTS, above, read them
    frames: Frames
    ground_truth_variance: float
    body_view: BodyView

    def __init__(
        self,
        node: Node,
        scene: Scene,
        rates: Mapping[str, float],
        state_qos: QoSProfile,
        ground_truth_variance: float,
        sensors: SensorSuite | None = None,
    ) -> None:
        self.scene = scene
        self.sensors = sensors
        #: Output name -> the builder of its sensor reading (the outputs whose sensor the scene has).
        self.readings = {
            name: builder
            for name, (sensor, builder) in SENSOR_OUTPUTS.items()
            if sensors is not None and sensor in sensors.names
        }
        self.frames = scene.frames
        self.ground_truth_variance = ground_truth_variance
        self.body_view = body_view(scene)
        self.field = scene.orbit_field()
        self.listeners: list[PublishedListener] = []
        self.publishers: dict[str, Publisher] = {}
        self.rates: dict[str, float] = {}
        for name in self._offered():
            rate = rates.get(name, 0.0)
            if rate > 0.0:
                qos = {"tf": TF_QOS, "clock": CLOCK_QOS}.get(name, state_qos)
                self.publishers[name] = node.create_publisher(OUTPUTS[name][0], output_topic(name), qos)
                self.rates[name] = rate
        self.static_transforms = self._static_transforms()
        if self.static_transforms:
            self.publishers["tf_static"] = node.create_publisher(TFMessage, "/tf_static", TF_STATIC_QOS)
        self.publishers["mass_properties"] = node.create_publisher(InertiaStamped, "~/mass_properties", LATCHED_QOS)
        self.publishers["rejected"] = node.create_publisher(RejectedCommand, "~/rejected", REJECTED_QOS)
        #: The one message of each REFILLED output built (refilled at each publish).
        self.refilled = {name: OUTPUTS[name][0]() for name in REFILLED if name in self.publishers}

    def _offered(self) -> list[str]:
        """The outputs this scene can have (``top_state`` only with gravity, ``wheels`` only with reaction
        wheels, ``torque_breakdown`` only where a torque acts)."""
        return [
            name
            for name in OUTPUT_NAMES
            if (name != "top_state" or self.scene.is_top)
            and (name != "star_tracker" or name in self.readings)
            and (name != "wheels" or bool(self.scene.spacecraft.wheels))
            and (name != "torque_breakdown" or self.scene.torque_kind != "none")
            and (name != "magnetometer" or name in self.readings)
            and (name != "magnetic_field" or self.field is not None)
            and (name != "orbit" or self.scene.orbit is not None)
        ]

    def orbit_state(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Position (m) and velocity (m/s) of the centre of mass at sim time ``t``, world frame (ECI)."""
        assert self.scene.orbit is not None  # ~/orbit and its /tf are built only with an orbit
        return self.scene.orbit.state(t)

    def true_field(self, s: StateSnapshot) -> Any:
        """~/magnetic_field: the true field (T, body frame) at the state ``s``; covariance zero (the truth)."""
        assert self.field is not None  # built only with a field
        return conversions.magnetic_field_message(
            self.field.body(s.t, s.orientation), s.t, self.frames.body, np.zeros(9)
        )

    def transforms(self, s: StateSnapshot) -> list[Any]:
        """/tf: world -> body; with an orbit, the body at its ECI position and world -> earth (ECEF)."""
        if self.scene.orbit is None:
            return [conversions.transform_stamped(s, self.frames.world, self.frames.body)]
        position, _ = self.orbit_state(s.t)
        era = earth_rotation_angle(days_since_j2000(epoch_datetime(self.scene.epoch)) + s.t / 86400.0)
        return [
            conversions.transform_stamped(s, self.frames.world, self.frames.body, position),
            conversions.earth_transform(s.t, self.frames.world, EARTH_FRAME, era),
        ]

    def _static_transforms(self) -> list[Any]:
        """With /tf: body -> principal-axes frame, where the principal axes are not the body axes."""
        if "tf" not in self.publishers:
            return []
        _, com, tensor = self.scene.mass_properties_about_com()
        pose = principal_frame_pose(tensor, com)
        if pose is None:
            return []
        return [conversions.static_transform(*pose, self.frames.body, self.frames.principal)]

    def describe(self, dt: float | None = None) -> tuple[list[str], list[str]]:
        """For the start-up line: (what was built, what was left out and why). ``dt`` (s): a rate above
        the step rate is said as what it is, one message per step."""
        built: list[str] = []
        left_out: list[str] = []
        for name in self._offered():
            if name in self.publishers:
                qos = describe_qos(self.publishers[name].qos_profile)
                rate = self.rates[name]
                if dt is not None and rate * dt > 1.0:
                    said = f"{1.0 / dt:g} Hz (every step; {rate:g} Hz asked)"
                else:
                    said = f"{rate:g} Hz"
                built.append(f"{output_topic(name)} {said} ({qos})")
            else:
                left_out.append(f"{output_topic(name)} (rate 0)")
        if self.static_transforms:
            built.append(f"/tf_static {self.frames.body} -> {self.frames.principal} ({describe_qos(TF_STATIC_QOS)})")
        elif "tf" in self.publishers:
            left_out.append(f"/tf_static (the body axes are the principal axes, {self.frames.principal} not needed)")
        built += ["~/mass_properties (transient local)", "~/rejected"]
        return built, left_out

    def publish(self, name: str, msg: Any) -> None:
        """Publish ``msg`` on output ``name``: serialised once when someone listens, the same bytes to each."""
        publisher = self.publishers[name]
        if not self.listeners:
            publisher.publish(msg)
            return
        data = serialize_message(msg)
        # listeners first: a message seen on the wire is already in the recording, even when a
        # SIGTERM during start-up interrupts right after the publish
        for listener in self.listeners:
            listener.published(name, publisher.topic_name, data, msg)
        publisher.publish(data)

    def publish_latched(self, t: float) -> None:
        """The once-only outputs: ~/mass_properties (at sim time ``t``) and /tf_static."""
        mass, com, tensor = self.scene.mass_properties_about_com()
        self.publish("mass_properties", conversions.inertia_stamped(mass, com, tensor, t, self.frames.body))
        if self.static_transforms:
            self.publish("tf_static", TFMessage(transforms=self.static_transforms))

    def outputs_due(self, step: int, snapshot: StateSnapshot, names: Sequence[str]) -> None:
        for name in names:
            reading = self.readings.get(name)
            if reading is not None:
                assert self.sensors is not None  # readings are built from the sensors
                self.publish(name, reading(self.sensors, snapshot, self.frames, self.ground_truth_variance))
            elif name in self.refilled:
                self.publish(name, REFILLED[name](self.refilled[name], snapshot, self))
            else:
                builder = OUTPUTS[name][1]
                assert builder is not None  # a sensor's output is built only with its sensor
                self.publish(name, builder(snapshot, self))
