"""``rigid-rot-controller``: a quaternion-feedback attitude controller, and the template for your own.

It closes the loop around the simulation node: it subscribes to the node's ``~/state``
(rigid_rot_msgs/RigidBodyState) and answers each state with a torque on the node's
``~/torque`` (geometry_msgs/WrenchStamped, body frame), **stamped with the stamp of the state
it answers**. That one rule makes the same controller work in both of the node's modes:

* real time (no ``lockstep`` section): a stamp in the past acts when the command arrives;
* lockstep (the scene's ``lockstep`` section): the node waits at every turn t_k for a command
  stamped exactly t_k, applies it from t_k and only then goes on, so the closed loop is
  bit-identical on every repeat, as fast as this node answers.

Control law (Wie, *Space Vehicle Dynamics and Control*, quaternion feedback), body frame::

    q_e = conj(q_target) * q                     # attitude error, body -> target (x, y, z, w)
    tau = -kp * sign(w_e) * (x_e, y_e, z_e) - kd * omega_body,   clipped to |tau| <= max_torque

``sign(w_e)`` takes the short way round. Units: kp in N*m (per unit of quaternion vector part,
about half the error angle in rad), kd in N*m*s, omega in rad/s.

Parameters: ``target`` [x, y, z, w] (body -> world, normalised), ``kp``, ``kd``, ``max_torque``
(N*m; 0 = no clip), ``rate`` (Hz of sim time; 0 = answer every state; otherwise states closer
than 1/rate to the last answered one are skipped: do not set it below the lockstep turn rate),
``state_topic``, ``torque_topic``, ``frame_id`` (header.frame_id of the torque; the node's body
frame), ``rejected_topic`` (default: the ``rejected`` beside ``torque_topic``, the node's
``~/rejected``).

A command the node refuses (a frame it does not name, a torque above its ``commands.max_torque``,
a stamp lockstep cannot use) is said on the node's ``~/rejected``; the controller watches it and
logs a warning with the node's reason, the first time for each reason and then every
``REJECTION_LOG_EVERY``-th time, so that a loop that does nothing says why.

Writing your own, with rclpy or any DDS stack: subscribe to the state (reliable, keep-last
depth 10 is enough: one state per turn), compute, publish one WrenchStamped per state with
``header.stamp`` copied from the state, reliable (the node's torque subscription is reliable;
a best-effort publisher does not match it). Keep the callback free of waiting: in lockstep
the node waits for you. Run the node with ``-p lockstep.period:=...`` or a scene's
``lockstep`` section; see ``config/scenes/closed_loop_lockstep.yaml``.
"""

from __future__ import annotations

import math
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from typing import Any

import rclpy
from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions

from rigid_rot_msgs.msg import RejectedCommand, RigidBodyState
from rigid_rot_sim.core import quaternion as quat
from rigid_rot_sim.ros.qos import REJECTED_QOS
from rigid_rot_sim.share import ensure_ament_prefix_path

NODE_NAME = "attitude_controller"
#: After the first rejection for a reason, log every this many (a refused loop refuses every turn).
REJECTION_LOG_EVERY = 100
#: Reliable, keep-last 10: one state and one command per turn, nothing lost.
CONTROL_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


def attitude_torque(
    q: Sequence[float], omega: Sequence[float], target: Sequence[float], kp: float, kd: float, max_torque: float
) -> tuple[float, float, float]:
    """The quaternion-feedback torque (N*m, body frame) for attitude ``q`` and rate ``omega`` (rad/s, body)."""
    ex, ey, ez, ew = quat.multiply(quat.conjugate(target), q)
    sign = -1.0 if ew < 0.0 else 1.0
    torque = tuple(-kp * sign * e - kd * w for e, w in zip((ex, ey, ez), omega, strict=True))
    norm = math.hypot(*torque)
    if max_torque > 0.0 and norm > max_torque:
        torque = tuple(v * (max_torque / norm) for v in torque)
    return torque  # type: ignore[return-value]


class AttitudeController(Node):
    """Answers each ``~/state`` of the simulation node with a torque stamped with the state's stamp."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(NODE_NAME, **kwargs)

        def declare(name: str, value: Any, text: str) -> Any:
            return self.declare_parameter(name, value, ParameterDescriptor(description=text)).value

        target = declare("target", [0.0, 0.0, 0.0, 1.0], "Target attitude [x, y, z, w], body -> world")
        self.kp = float(declare("kp", 0.04, "Proportional gain, N*m per unit of the error quaternion's vector part"))
        self.kd = float(declare("kd", 0.04, "Rate gain, N*m*s"))
        self.max_torque = float(declare("max_torque", 0.1, "Largest |torque|, N*m (0 = no clip)"))
        self.rate = float(declare("rate", 0.0, "Answer at most this many states per s of sim time (0 = every state)"))
        state_topic = declare("state_topic", "/rigid_rot_sim/state", "The simulation node's state topic")
        torque_topic = declare("torque_topic", "/rigid_rot_sim/torque", "The simulation node's torque input")
        self.frame_id = declare("frame_id", "base_link", "header.frame_id of the torque (the body frame)")
        beside_torque = f"{torque_topic.rsplit('/', 1)[0]}/rejected" if "/" in torque_topic else "rejected"
        rejected_topic = declare("rejected_topic", beside_torque, "The node's ~/rejected (its refusals)")
        norm = math.sqrt(sum(float(v) * float(v) for v in target))
        if len(target) != 4 or not (norm > 0.0 and math.isfinite(norm)):
            raise ValueError(f"target must be a non-zero quaternion [x, y, z, w], got {list(target)}")
        self.target = tuple(float(v) / norm for v in target)
        self.last_answered_ns: int | None = None
        self.answered = 0
        self.publisher = self.create_publisher(WrenchStamped, torque_topic, CONTROL_QOS)
        self.subscription = self.create_subscription(RigidBodyState, state_topic, self.state_callback, CONTROL_QOS)
        #: Rejections of this controller's commands, by the node's reason.
        self.rejections: dict[str, int] = {}
        self.rejected_subscription = self.create_subscription(
            RejectedCommand, rejected_topic, self.rejected_callback, REJECTED_QOS
        )
        self.get_logger().info(
            f"attitude controller: {state_topic} -> {torque_topic}, target {list(self.target)}, kp {self.kp:g}, "
            f"kd {self.kd:g}, max_torque {self.max_torque:g}, "
            f"{'every state' if self.rate <= 0 else f'{self.rate:g} Hz'}"
        )

    def state_callback(self, msg: RigidBodyState) -> None:
        stamp_ns = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        last = self.last_answered_ns
        if self.rate > 0.0 and last is not None and stamp_ns - last < 1e9 / self.rate - 1:
            return
        o, w = msg.orientation, msg.angular_velocity_body
        torque = attitude_torque((o.x, o.y, o.z, o.w), (w.x, w.y, w.z), self.target, self.kp, self.kd, self.max_torque)
        command = WrenchStamped()
        command.header.stamp = msg.header.stamp  # the stamp of the state answered: the lockstep contract
        command.header.frame_id = self.frame_id
        command.wrench.torque.x, command.wrench.torque.y, command.wrench.torque.z = torque
        self.publisher.publish(command)
        self.last_answered_ns = stamp_ns
        self.answered += 1

    def rejected_callback(self, msg: RejectedCommand) -> None:
        """A refusal of one of this controller's commands (its frame_id): a warning with the node's reason."""
        if msg.header.frame_id != self.frame_id:
            return  # another client's command
        count = self.rejections.get(msg.reason, 0) + 1
        self.rejections[msg.reason] = count
        if count == 1 or count % REJECTION_LOG_EVERY == 0:
            self.get_logger().warning(
                f"the node rejected this controller's command on {msg.source} ({count} so far): {msg.reason}"
            )


def _executor() -> Executor:
    """rclpy's events executor where it has one (Jazzy's rclpy 7.1 and later): it takes each state and runs
    the callback in C++ with no wait set rebuilt per message, which is most of a Python executor's cost per
    turn; else a SingleThreadedExecutor."""
    try:
        from rclpy.experimental import EventsExecutor
    except ImportError:
        return SingleThreadedExecutor()
    return EventsExecutor()


def main(args: list[str] | None = None) -> int:
    """Run the controller until Ctrl-C / SIGTERM (exit 0); a bad parameter: one line on stderr, exit 2."""
    return run_node(AttitudeController, NODE_NAME, args)


def run_node(factory: Callable[[], Node], name: str, args: list[str] | None = None) -> int:
    """Spin the node ``factory`` builds until Ctrl-C / SIGTERM (exit 0); a ValueError: one line on stderr, exit 2."""
    ensure_ament_prefix_path()
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    stop = threading.Event()
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: stop.set())
    node = None
    try:
        node = factory()
        executor = _executor()
        executor.add_node(node)
        while rclpy.ok() and not stop.is_set():
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except ValueError as exc:
        print(f"{name}: error: {exc}", file=sys.stderr, flush=True)
        return 2
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
