"""What a viewer draws of the body: its inertia box and the arrows of omega and L (no ROS).

One drawing for every viewer: ``~/markers`` (RViz, Foxglove from a file) and the Foxglove live
server's scene entity are both built from a :class:`BodyView` and a state.

* **The box**: the uniform box with the body's principal moments (and mass; a stated nominal
  size when the scene gives none, :data:`~rigid_rot_sim.core.inertia.NOMINAL_BOX_SIZE`), in the
  body frame, centred on the centre of mass and aligned with the principal axes. Its longest
  side is along the smallest moment: a flat spin or an intermediate-axis flip shows at a glance.
* **omega** (body frame), from the centre of mass: ``OMEGA_COLOR``; its length is
  ``omega_scale * |omega|`` m.
* **L** (world frame, angular momentum; fixed while torque-free), from the world origin:
  ``MOMENTUM_COLOR``; its length is ``momentum_scale * |L|`` m.

* **Reaction wheels** (a scene with ``actuators.reaction_wheels``): a disc on each wheel's
  axis (body frame), just outside the box, ``WHEEL_COLOR``.
* **The trail**: the tip of the box's longest side (the axis of the smallest moment, where a
  flat spin or a flip shows first), in the world frame: :meth:`BodyView.major_axis_tip`.

The scales are fixed for a run (from the initial state), so that arrow lengths compare over
time: the initial omega (or 1 rad/s for a body at rest) is drawn as long as the box's longest
side, the initial L (or that of 1 rad/s about the largest moment) 1.5 times as long.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigid_rot_sim.core.inertia import equivalent_box, principal_frame, principal_orientation
from rigid_rot_sim.core.quaternion import rotate, rotate_inverse
from rigid_rot_sim.scene.scene import Scene

__all__ = ["BOX_COLOR", "MOMENTUM_COLOR", "OMEGA_COLOR", "TRAIL_COLOR", "WHEEL_COLOR", "BodyView", "body_view"]

#: RGBA, 0..1: the body's box (translucent grey), omega (orange), L (blue).
BOX_COLOR = (0.62, 0.66, 0.72, 0.55)
OMEGA_COLOR = (1.0, 0.55, 0.0, 1.0)
MOMENTUM_COLOR = (0.15, 0.45, 1.0, 1.0)
#: RGBA, 0..1: reaction wheel discs (dark teal), the trail of the major axis tip (magenta).
WHEEL_COLOR = (0.1, 0.5, 0.5, 1.0)
TRAIL_COLOR = (0.85, 0.1, 0.6, 1.0)
#: Wheel disc radius and thickness as fractions of the box's longest side.
WHEEL_RADIUS = 0.12
WHEEL_THICKNESS = 0.03
#: Arrow shaft diameter and head size as fractions of the box's longest side.
ARROW_SHAFT = 0.04
ARROW_HEAD = 0.09
#: Arrows of a body at rest: the rate (rad/s) drawn as long as the box.
RESTING_RATE = 1.0


@dataclass(frozen=True)
class BodyView:
    """Geometry of the drawing, fixed for a run: sizes in m, scales in m per SI unit."""

    box_sides: tuple[float, float, float]
    box_center: tuple[float, float, float]  # m, body frame (the centre of mass)
    box_orientation: tuple[float, float, float, float]  # principal axes -> body frame, x y z w
    omega_scale: float  # m per rad/s
    momentum_scale: float  # m per kg*m^2/s
    shaft_diameter: float
    head_size: float
    #: Reaction wheels: unit spin axes (body frame) and the disc centres on them (m, body frame).
    wheel_axes: tuple[tuple[float, float, float], ...] = ()
    wheel_centers: tuple[tuple[float, float, float], ...] = ()
    wheel_radius: float = 0.0
    wheel_thickness: float = 0.0

    @property
    def size(self) -> float:
        """The box's longest side, m (the unit of every other length of the drawing)."""
        return max(self.box_sides)

    def major_axis(self) -> np.ndarray:
        """Half the box's longest side as a vector from the centre of mass (m, body frame)."""
        local = np.zeros(3)
        local[int(np.argmax(self.box_sides))] = 0.5 * self.size
        return np.array(rotate(self.box_orientation, local))

    def major_axis_tip(self, orientation: np.ndarray) -> np.ndarray:
        """Where the tip of the box's longest side is (m, world frame) at ``orientation`` (x, y, z, w, body -> world).

        The body frame's origin is at the world origin (a rotation-only simulation).
        """
        tip_body = np.asarray(self.box_center, dtype=float) + self.major_axis()
        return np.array(rotate(np.asarray(orientation, dtype=float), tip_body))

    def omega_arrow(self, omega_body: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tail and tip (m, body frame) of the omega arrow."""
        tail = np.asarray(self.box_center, dtype=float)
        return tail, tail + self.omega_scale * np.asarray(omega_body, dtype=float)

    def momentum_arrow(self, momentum_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tail and tip (m, world frame) of the L arrow."""
        return np.zeros(3), self.momentum_scale * np.asarray(momentum_world, dtype=float)


def body_view(scene: Scene) -> BodyView:
    """The drawing of ``scene``'s body (box from its inertia about the centre of mass)."""
    mass, com, tensor = scene.mass_properties_about_com()
    moments, axes = principal_frame(tensor)
    sides = equivalent_box(moments, mass or None)
    q = principal_orientation(axes)
    size = float(sides.max())
    omega0 = np.asarray(scene.initial.angular_velocity, dtype=float)
    rate = float(np.linalg.norm(omega0)) or RESTING_RATE
    momentum = float(np.linalg.norm(tensor @ omega0)) or RESTING_RATE * float(moments.max())
    axes_body = [np.asarray(wheel.axis, dtype=float) / np.linalg.norm(wheel.axis) for wheel in scene.spacecraft.wheels]
    centers = [com + (_half_extent(sides, q, axis) + WHEEL_THICKNESS * size) * axis for axis in axes_body]
    return BodyView(
        box_sides=(float(sides[0]), float(sides[1]), float(sides[2])),
        box_center=(float(com[0]), float(com[1]), float(com[2])),
        box_orientation=(float(q[0]), float(q[1]), float(q[2]), float(q[3])),
        omega_scale=size / rate,
        momentum_scale=1.5 * size / momentum,
        shaft_diameter=ARROW_SHAFT * size,
        head_size=ARROW_HEAD * size,
        wheel_axes=tuple((float(a[0]), float(a[1]), float(a[2])) for a in axes_body),
        wheel_centers=tuple((float(c[0]), float(c[1]), float(c[2])) for c in centers),
        wheel_radius=WHEEL_RADIUS * size if axes_body else 0.0,
        wheel_thickness=WHEEL_THICKNESS * size if axes_body else 0.0,
    )


def _half_extent(sides: np.ndarray, box_orientation: np.ndarray, direction: np.ndarray) -> float:
    """How far the box reaches from its centre along the unit ``direction`` (body frame), m."""
    local = np.array(rotate_inverse(box_orientation, direction))
    return 0.5 * float(np.abs(local) @ np.asarray(sides, dtype=float))
