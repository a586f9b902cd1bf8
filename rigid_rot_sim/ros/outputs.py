"""What the node publishes: one table of outputs, one publishing path.

:data:`OUTPUTS` maps each scene output name (``scene.scene.OUTPUT_NAMES``) to its message
type and the function that builds its message from a
:class:`~rigid_rot_sim.run.simulator.StateSnapshot`. :class:`Outputs` creates a publisher
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

from typing import Any, Callable, Protocol, Sequence

from geometry_msgs.msg import InertiaStamped, QuaternionStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.serialization import serialize_message
from rigid_rot_msgs.msg import HeavyTopState, RejectedCommand, RigidBodyState, TorqueBreakdown
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu, JointState

from rigid_rot_sim import conversions
from rigid_rot_sim.core.inertia import principal_frame_pose
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.scene.scene import OUTPUT_NAMES, Frames, Scene
from rigid_rot_sim.run.simulator import StateSnapshot
from rigid_rot_sim.ros.qos import CLOCK_QOS, LATCHED_QOS, REJECTED_QOS, TF_QOS, TF_STATIC_QOS, describe as describe_qos

try:  # never required: /tf exists only where tf2_msgs is installed
    from tf2_msgs.msg import TFMessage
except ImportError:  # pragma: no cover - depends on the installation
    TFMessage = None

#: A message from the state, the frames and the ground-truth variance (imu, odom).
MessageBuilder = Callable[[StateSnapshot, Frames, float], Any]

#: Scene output name -> (message type, builder). Topics: :func:`output_topic`.
OUTPUTS: dict[str, tuple[Any, MessageBuilder]] = {
    "state": (RigidBodyState, lambda s, f, v: conversions.snapshot_to_state(s, f.world, f.body)),
    "orientation": (QuaternionStamped, lambda s, f, v: conversions.snapshot_to_orientation(s, f.world)),
    "angular_velocity": (Vector3Stamped, lambda s, f, v: conversions.vector_stamped(s.angular_velocity_body, s.t, f.body)),
    "angular_momentum": (Vector3Stamped, lambda s, f, v: conversions.vector_stamped(s.angular_momentum_world, s.t, f.world)),
    "top_state": (HeavyTopState, lambda s, f, v: conversions.snapshot_to_top_state(s, f.world)),
    "tf": (TFMessage, lambda s, f, v: TFMessage(transforms=[conversions.transform_stamped(s, f.world, f.body)])),
    "clock": (Clock, lambda s, f, v: conversions.clock_message(s.t)),
    "imu": (Imu, lambda s, f, v: conversions.snapshot_to_imu(s, f.body, v)),
    "odom": (Odometry, lambda s, f, v: conversions.snapshot_to_odometry(s, f.world, f.body, v)),
    "wheels": (JointState, lambda s, f, v: conversions.snapshot_to_joint_state(s, f.body)),
    "torque_breakdown": (TorqueBreakdown, lambda s, f, v: conversions.snapshot_to_torque_breakdown(s, f.body)),
}
assert tuple(OUTPUTS) == OUTPUT_NAMES, "one entry per scene output, in the scene's order"


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
    those built. ``built`` and ``left_out`` collect the start-up line.
    """

    def __init__(self, node: Node, scene: Scene, rates: dict[str, float], state_qos: Any,
                 ground_truth_variance: float, built: list[str], left_out: list[str]) -> None:
        self.scene = scene
        self.frames = scene.frames
        self.ground_truth_variance = ground_truth_variance
        self.listeners: list[PublishedListener] = []
        self.publishers: dict[str, Any] = {}
        self.rates: dict[str, float] = {}
        for name in OUTPUT_NAMES:
            rate = rates.get(name, 0.0)
            if name == "top_state" and not scene.is_top:
                continue  # listed with gravity by the node
            if name == "wheels" and not scene.spacecraft.wheels:
                continue  # listed with the wheels by the node
            if name == "torque_breakdown" and scene.torque_kind == "none":
                left_out.append("~/torque_breakdown (no torque acts on this scene)")
                continue
            if name == "tf" and TFMessage is None:
                left_out.append("/tf (tf2_msgs not installed)")
                continue
            if rate <= 0.0:
                left_out.append(f"{output_topic(name)} (rate 0)")
                continue
            qos = {"tf": TF_QOS, "clock": CLOCK_QOS}.get(name, state_qos)
            publisher = node.create_publisher(OUTPUTS[name][0], output_topic(name), qos)
            self.publishers[name] = publisher
            self.rates[name] = rate
            built.append(f"{output_topic(name)} {rate:g} Hz ({describe_qos(publisher.qos_profile)})")
        self.static_transforms = self._static_transforms(left_out)
        if self.static_transforms:
            self.publishers["tf_static"] = node.create_publisher(TFMessage, "/tf_static", TF_STATIC_QOS)
            built.append(f"/tf_static {self.frames.body} -> {self.frames.principal} ({describe_qos(TF_STATIC_QOS)})")
        self.publishers["mass_properties"] = node.create_publisher(InertiaStamped, "~/mass_properties", LATCHED_QOS)
        self.publishers["rejected"] = node.create_publisher(RejectedCommand, "~/rejected", REJECTED_QOS)
        built += ["~/mass_properties (transient local)", "~/rejected"]

    def _static_transforms(self, left_out: list[str]) -> list[Any]:
        """With /tf: body -> principal-axes frame, where the principal axes are not the body axes."""
        if "tf" not in self.publishers:
            return []
        _, com, tensor = self.scene.mass_properties_about_com()
        pose = principal_frame_pose(tensor, com)
        if pose is None:
            left_out.append(f"/tf_static (the body axes are the principal axes, {self.frames.principal} not needed)")
            return []
        return [conversions.static_transform(*pose, self.frames.body, self.frames.principal)]

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
            self.publish(name, OUTPUTS[name][1](snapshot, self.frames, self.ground_truth_variance))
