"""The rigid_rot_sim ROS 2 node.

Services
--------
~/compute_inertia (rigid_rot_msgs/srv/ComputeInertia)
    Mass properties of point masses (core: :mod:`rigid_rot_sim.core.inertia`). An invalid
    request is answered with ``success = false`` and the reason in ``message``.

The node only wires ROS interfaces to the core: numbers are computed in
``rigid_rot_sim.core`` and converted in ``rigid_rot_sim.conversions``.
"""

from __future__ import annotations

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rigid_rot_msgs.srv import ComputeInertia

from rigid_rot_sim import conversions
from rigid_rot_sim.core.inertia import mass_properties


class RigidRotSimNode(Node):
    """Node ``rigid_rot_sim``; keyword arguments go to :class:`rclpy.node.Node`."""

    def __init__(self, **kwargs) -> None:
        super().__init__("rigid_rot_sim", **kwargs)
        self.compute_inertia_service = self.create_service(
            ComputeInertia, "~/compute_inertia", self.compute_inertia_callback
        )

    def compute_inertia_callback(self, request, response):
        try:
            masses, positions, origin = conversions.compute_inertia_request_to_arrays(request)
            props = mass_properties(masses, positions, origin)
            conversions.fill_compute_inertia_response(response, props)
        except ValueError as exc:
            return self._reject(response, f"invalid request: {exc}")
        except Exception as exc:  # a callback must never raise: the node keeps serving
            self.get_logger().error(f"compute_inertia failed: {exc!r}")
            return self._reject(response, f"internal error: {exc!r}")
        response.success = True
        response.message = (
            f"{len(masses)} masses, {props.total_mass:.6g} kg, {props.symmetry}"
        )
        return response

    def _reject(self, response, message: str):
        self.get_logger().warning(message)
        response.success = False
        response.message = message
        return response


def main(args=None) -> None:
    rclpy.init(args=args)
    node = None
    try:
        node = RigidRotSimNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
