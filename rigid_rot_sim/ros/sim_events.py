"""``~/sim_events``, live: every change made to the simulation from outside the physics, as it happens.

The same ``diagnostic_msgs/msg/DiagnosticStatus`` events a recording holds on ``~/sim_events``
(:mod:`rigid_rot_sim.recording.events`: a torque or wheel command accepted, ``~/apply_torque``,
``set_state``, ``reset``, an integrator change, a lockstep turn that timed out), published by the
node whether it records or not, made by the recording's own observer
(:class:`~rigid_rot_sim.ros.recording.NodeRecording`) so that the live topic and the file never
differ (that observer lives with the recording, whose module needs the ``mcap`` packages: without
them, optional at run time, there is no live topic either, and the log says so). QoS: reliable,
transient local, keep-last :data:`HISTORY`: the recent history is latched,
so a tool that starts late (``ros2 topic echo``, Foxglove) still gets the last events. The
recording writes its copy itself: the live messages are not recorded twice.
"""

from __future__ import annotations

from typing import Any

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from rigid_rot_sim.recording.events import event_fields
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.run.simulator import Simulator

TOPIC = "~/sim_events"
#: Events a late subscriber receives on joining.
HISTORY = 100
QOS = QoSProfile(depth=HISTORY, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


class _Publishing:
    """The part of :class:`~rigid_rot_sim.recording.session.RunRecorder` that NodeRecording's events use."""

    active = True

    def __init__(self, publisher: Any) -> None:
        self.publisher = publisher

    def record_event(self, kind: str, step: int, summary: str, **values: Any) -> None:
        fields = event_fields(kind, step, summary, **values)
        msg = DiagnosticStatus(
            level=bytes([fields["level"]]),
            name=fields["name"],
            message=fields["message"],
            hardware_id=fields["hardware_id"],
            values=[KeyValue(key=pair["key"], value=pair["value"]) for pair in fields["values"]],
        )
        self.publisher.publish(msg)


def start(node: Node, sim: Simulator) -> SimulationObserver | None:
    """The live ``~/sim_events`` publisher, added to ``sim``'s observers (None, logged, without mcap)."""
    try:
        from rigid_rot_sim.ros.recording import NodeRecording
    except ImportError as exc:
        missing = (exc.name or "").split(".")[0] or str(exc)
        node.get_logger().warning(f"no live {TOPIC}: {missing} is not installed (pip install mcap mcap-ros2-support)")
        return None

    publisher = node.create_publisher(DiagnosticStatus, TOPIC, QOS)
    # the observer only calls `active` and `record_event` (the events), which _Publishing has of a RunRecorder
    live = NodeRecording(_Publishing(publisher), sim, node.get_logger())  # type: ignore[arg-type]  # events only
    sim.add_observer(live)
    return live
