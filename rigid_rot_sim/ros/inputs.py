"""What the node receives: torque commands, and the ``~/rejected`` report of those refused.

:class:`TorqueInputs` subscribes to each topic input of the scene (WrenchStamped or
Vector3Stamped); :meth:`TorqueInputs.torque_callback` converts the message
(:func:`~rigid_rot_sim.conversions.torque_command_from_msg`), hands it to
:meth:`Simulator.receive_torque <rigid_rot_sim.run.simulator.Simulator.receive_torque>`
and, when the simulator refuses it, to :meth:`Rejections.reject`. Then it hands the message
as received to its listeners (the recorder), with the wall-clock receive time. The
subscriptions are the run loop's (:mod:`.intake`): every command is taken, in arrival order,
and a command lost before it could be taken is counted and reported (:meth:`Rejections.lost`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any, Protocol

from geometry_msgs.msg import Vector3Stamped, WrenchStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.subscription import Subscription

from rigid_rot_sim import conversions
from rigid_rot_sim.core import limits
from rigid_rot_sim.ros.intake import CommandIntake
from rigid_rot_sim.ros.outputs import Outputs
from rigid_rot_sim.ros.qos import COMMAND_QOS
from rigid_rot_sim.run.simulator import CommandRejected, Simulator
from rigid_rot_sim.scene.scene import Scene

#: Seconds between two warnings about rejected commands from the same source.
REJECT_WARN_PERIOD = 2.0


class ReceivedListener(Protocol):
    """Receives every torque command message as it arrived (the recorder)."""

    def received(self, topic: str, msg: Any, received_ns: int) -> None:
        """``msg`` arrived on ``topic`` at wall-clock ``received_ns`` (ns since the epoch)."""


class Rejections:
    """``~/rejected``: a RejectedCommand per refused command, and a warning at most every
    ``REJECT_WARN_PERIOD`` s per source (with the count of those not warned about)."""

    def __init__(self, node: Node, sim: Simulator, outputs: Outputs) -> None:
        self.logger = node.get_logger()
        self.sim = sim
        self.outputs = outputs
        self._warned: dict[str, tuple[float, int]] = {}
        #: Commands lost before the node could take them (every topic; 0 unless a bound was hit).
        self.lost_total = 0

    def reject(self, source: str, reason: str, frame_id: str, torque: Any) -> None:
        # the frame_id is echoed, but never more than MAX_NAME_LENGTH characters of it
        frame_id = limits.clip_text(frame_id)
        reason = limits.clip_text(reason, limits.MAX_TEXT_LENGTH)
        self.outputs.publish(
            "rejected", conversions.rejected_command(source, reason, self.sim.clock.t, frame_id, torque)
        )
        now = time.monotonic()
        last, suppressed = self._warned.get(source, (-math.inf, 0))
        if now - last >= REJECT_WARN_PERIOD:
            more = f" ({suppressed} more rejected since the last warning)" if suppressed else ""
            self.logger.warning(f"rejected command on {source}: {reason}{more}")
            self._warned[source] = (now, 0)
        else:
            self._warned[source] = (last, suppressed + 1)

    def lost(self, topic: str, count: int, why: str) -> None:
        """``count`` commands on ``topic`` never reached the node's handler (a bound was hit): one
        RejectedCommand (its reason says how many and why; no frame, zero torque) and a warning."""
        reason = limits.clip_text(f"lost: {why}", limits.MAX_TEXT_LENGTH)
        self.outputs.publish(
            "rejected", conversions.rejected_command(topic, reason, self.sim.clock.t, "", (0.0, 0.0, 0.0))
        )
        self.lost_total += count
        self.logger.warning(f"{topic}: {why} ({self.lost_total} lost in all)")


class TorqueInputs:
    """One subscription per topic input of ``scene`` (none for a torque-free scene).

    ``depth``: keep-last depth of the subscriptions (``commands.qos_depth``).
    """

    def __init__(self, intake: CommandIntake, sim: Simulator, scene: Scene, depth: int, rejections: Rejections) -> None:
        node = intake.node
        self.sim = sim
        self.rejections = rejections
        self.listeners: list[ReceivedListener] = []
        self.subscriptions: list[Subscription] = []
        self.topic_inputs = scene.topic_inputs
        qos = QoSProfile(depth=depth, reliability=COMMAND_QOS.reliability, durability=COMMAND_QOS.durability)
        for spec in scene.topic_inputs:
            msg_type = WrenchStamped if spec.message_type == "WrenchStamped" else Vector3Stamped
            topic = node.resolve_topic_name(spec.topic)
            subscription = intake.subscribe(msg_type, spec.topic, self._handler(spec.topic, topic), qos)
            self.subscriptions.append(subscription)
            if spec.message_type == "WrenchStamped":
                node.get_logger().info(
                    f"{topic}: only wrench.torque acts on the body; a command with a non-zero wrench.force is rejected"
                )

    def _handler(self, source: str, topic: str) -> Callable[[Any, int], None]:
        """The intake's handler of one topic input: its messages to :meth:`torque_callback`."""

        def handle(msg: Any, received_ns: int) -> None:
            self.torque_callback(msg, source, topic, received_ns)

        return handle

    def describe(self) -> tuple[list[str], list[str]]:
        """For the start-up line: (what was built, what was left out and why)."""
        if not self.subscriptions:
            return [], ["torque subscriptions (no topic input)"]
        built = []
        for spec, subscription in zip(self.topic_inputs, self.subscriptions, strict=True):
            hold = "hold until replaced" if spec.timeout is None else f"zero {spec.timeout:g} s after the last command"
            depth = subscription.qos_profile.depth
            built.append(
                f"torque input {subscription.topic_name} ({spec.message_type}, frame {spec.frame}, {hold}, "
                f"depth {depth})"
            )
        return built, []

    def torque_callback(self, msg: Any, source: str, topic: str, received_ns: int | None = None) -> None:
        """A command on ``source`` (the scene's topic; ``topic`` fully qualified): to the simulator, or rejected.

        ``received_ns``: when DDS received it (ns since the epoch; default now).
        """
        received_ns = time.time_ns() if received_ns is None else received_ns
        torque, force, frame_id, stamp = conversions.torque_command_from_msg(msg)
        try:
            self.sim.receive_torque(source, torque, frame_id, stamp, force)
        except CommandRejected as exc:
            self.rejections.reject(topic, exc.reason, frame_id, torque)
        except Exception as exc:  # never out of a callback: rejected with the reason
            self.rejections.reject(topic, f"internal error: {exc!r}", frame_id, torque)
        for listener in self.listeners:
            listener.received(topic, msg, received_ns)
