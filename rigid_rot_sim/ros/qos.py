"""QoS profiles of the node's topics, and the configurable profile of its state-like outputs.

The README (section "The simulation node") documents each profile and why:

* state-like outputs (``~/state``, ``~/orientation``, ``~/angular_velocity``,
  ``~/angular_momentum``, ``~/top_state``): reliable, keep last 10, volatile by default;
  ``qos.reliability`` and ``qos.depth`` (scene ``qos:`` or parameters) change them.
* ``/tf``: reliable, keep last 100, volatile, and ``/tf_static``: reliable, keep last 1,
  transient local: what tf2_ros's TransformBroadcaster and StaticTransformBroadcaster offer,
  so every tf2 listener matches. Not configurable.
* ``/clock``: reliable, keep last 1 (rclpy's TimeSource subscribes best effort, depth 1).
* ``~/mass_properties``: reliable, keep last 1, transient local (published once, latched).
* ``~/rejected``: reliable, keep last 50: a burst of bad commands is reported in full.
* torque inputs: reliable, keep last ``commands.qos_depth`` (default limits.DEFAULT_COMMAND_DEPTH).
"""

from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from rigid_rot_sim.core import limits
from rigid_rot_sim.scene.scene import MAX_QOS_DEPTH, QOS_RELIABILITIES, OutputQos

STATE_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
LATCHED_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
REJECTED_QOS = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
COMMAND_QOS = QoSProfile(
    depth=limits.DEFAULT_COMMAND_DEPTH, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE
)
TF_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
TF_STATIC_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)

_RELIABILITY = {"reliable": ReliabilityPolicy.RELIABLE, "best_effort": ReliabilityPolicy.BEST_EFFORT}


def output_qos(settings: OutputQos) -> QoSProfile:
    """The profile of the state-like outputs: keep last ``settings.depth``, volatile.

    ValueError (naming the parameter) for an unknown reliability or a depth out of range:
    parameters given on the command line bypass the scene's validation.
    """
    if settings.reliability not in QOS_RELIABILITIES:
        raise ValueError(f"qos.reliability must be one of {', '.join(QOS_RELIABILITIES)}, got {settings.reliability!r}")
    depth = settings.depth
    if isinstance(depth, bool) or not isinstance(depth, int) or not 1 <= depth <= MAX_QOS_DEPTH:
        raise ValueError(f"qos.depth must be an integer from 1 to {MAX_QOS_DEPTH}, got {depth!r}")
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=depth,
        reliability=_RELIABILITY[settings.reliability],
        durability=DurabilityPolicy.VOLATILE,
    )


def describe(profile: QoSProfile) -> str:
    """Short text of a profile for the start-up line, e.g. ``reliable, depth 10``."""
    parts = [
        "reliable" if profile.reliability == ReliabilityPolicy.RELIABLE else "best effort",
        f"depth {profile.depth}",
    ]
    if profile.durability == DurabilityPolicy.TRANSIENT_LOCAL:
        parts.append("transient local")
    return ", ".join(parts)
